//! `mstar sweep` as a user meets it: the runs a grid or a zip makes, each
//! run's CSV file byte for byte the one `mstar run --set …` writes, shards
//! that merge into the unsharded summary, failed runs reported and counted
//! in the exit code, reruns that skip complete runs, and bad parameters
//! refused before anything runs.
//!
//! The model is the double pendulum of `models/` over 0.05 s: with a fixed
//! step h every run takes t_end / h steps (50 for h = 1e-3, 100 for
//! h = 5e-4), a figure the summary must show independently of the masses.

mod common;

use std::path::Path;

use common::{model, mstar, scratch, text};

/// `mstar sweep` of the double pendulum over 0.05 s with `args` into `out`.
fn sweep(out: &Path, args: &[&str]) -> std::process::Output {
    let model = model("double-pendulum.toml");
    let out = out.display().to_string();
    let mut all = vec![
        "sweep",
        &model,
        "--set",
        "simulation.t_end=0.05",
        "--set",
        "output.every=10",
        "--out",
        &out,
    ];
    all.extend_from_slice(args);
    mstar(&all)
}

/// The summary's rows as fields by column name (header first).
fn summary(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(path).expect("a summary");
    let mut reader = csv::Reader::from_reader(text.as_bytes());
    let header = reader
        .headers()
        .expect("a header")
        .iter()
        .map(String::from)
        .collect();
    let rows = reader
        .records()
        .map(|r| r.expect("a row").iter().map(String::from).collect())
        .collect();
    (header, rows)
}

/// The fields of `column` in `rows`.
fn column(header: &[String], rows: &[Vec<String>], column: &str) -> Vec<String> {
    let k = header
        .iter()
        .position(|h| h == column)
        .unwrap_or_else(|| panic!("no column {column} in {header:?}"));
    rows.iter().map(|r| r[k].clone()).collect()
}

/// A summary's text without its last column (the wall time, never quoted).
fn without_wall_time(path: &Path) -> String {
    std::fs::read_to_string(path)
        .expect("a summary")
        .lines()
        .map(|l| l.rsplit_once(',').map_or(l, |(rest, _)| rest).to_string() + "\n")
        .collect()
}

#[test]
fn a_grid_runs_every_combination_and_a_zip_pairs_values() {
    let dir = scratch("sweep-grid");
    let grid = dir.join("grid");
    let done = sweep(
        &grid,
        &[
            "--set",
            "body.upper.mass=1,2",
            "--set",
            "simulation.h=1e-3,5e-4",
        ],
    );
    assert_eq!(done.status.code(), Some(0), "{}", text(&done.stderr));
    let (h, rows) = summary(&grid.join("summary.csv"));
    assert_eq!(column(&h, &rows, "index"), ["0", "1", "2", "3"]);
    assert_eq!(column(&h, &rows, "body.upper.mass"), ["1", "1", "2", "2"]);
    assert_eq!(
        column(&h, &rows, "simulation.h"),
        ["1e-3", "5e-4", "1e-3", "5e-4"]
    );
    assert_eq!(column(&h, &rows, "steps"), ["50", "100", "50", "100"]);
    assert_eq!(column(&h, &rows, "status"), ["ok"; 4]);
    assert_eq!(column(&h, &rows, "t"), ["0.05"; 4]);
    assert_eq!(h.last().map(String::as_str), Some("wall_time_s"));
    for i in 0..4 {
        assert!(grid.join(format!("runs/{i}.csv")).is_file(), "run {i}");
    }

    let zip = dir.join("zip");
    let done = sweep(
        &zip,
        &[
            "--zip",
            "--set",
            "body.upper.mass=1:2:3",
            "--set",
            "simulation.h=1e-3,5e-4,1e-3",
        ],
    );
    assert_eq!(done.status.code(), Some(0), "{}", text(&done.stderr));
    let (h, rows) = summary(&zip.join("summary.csv"));
    assert_eq!(column(&h, &rows, "body.upper.mass"), ["1", "1.5", "2"]);
    assert_eq!(column(&h, &rows, "simulation.h"), ["1e-3", "5e-4", "1e-3"]);
    assert_eq!(column(&h, &rows, "steps"), ["50", "100", "50"]);
    // A heavier upper bar changes the motion: the final angles differ.
    let theta = column(&h, &rows, "u:upper.theta");
    assert_ne!(theta[0], theta[2]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_run_s_csv_is_the_one_mstar_run_writes() {
    let dir = scratch("sweep-same");
    let out = dir.join("s");
    let done = sweep(
        &out,
        &[
            "--set",
            "body.lower.mass=0.5,0.7",
            "--set",
            "simulation.h=5e-4",
        ],
    );
    assert_eq!(done.status.code(), Some(0), "{}", text(&done.stderr));
    let single = dir.join("one.csv");
    let run = mstar(&[
        "run",
        &model("double-pendulum.toml"),
        "--set",
        "simulation.t_end=0.05",
        "--set",
        "output.every=10",
        "--set",
        "body.lower.mass=0.7",
        "--set",
        "simulation.h=5e-4",
        "--out",
        &single.display().to_string(),
    ]);
    assert!(run.status.success(), "{}", text(&run.stderr));
    let expected = std::fs::read(&single).expect("mstar run's CSV");
    let swept = std::fs::read(out.join("runs/1.csv")).expect("the sweep's CSV");
    assert_eq!(swept, expected);
    // and the other run is another motion.
    let other = std::fs::read(out.join("runs/0.csv")).expect("the sweep's CSV");
    assert_ne!(other, expected);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn two_shards_merged_equal_the_unsharded_sweep() {
    let dir = scratch("sweep-shards");
    let params = [
        "--set",
        "body.upper.mass=-1,1:2:3",
        "--set",
        "simulation.h=1e-3,5e-4",
    ];
    let whole = dir.join("whole");
    let done = sweep(&whole, &params);
    assert_eq!(done.status.code(), Some(12), "{}", text(&done.stderr));
    let sharded = dir.join("sharded");
    for shard in ["1/2", "0/2"] {
        let mut args = params.to_vec();
        args.extend(["--shard", shard]);
        let done = sweep(&sharded, &args);
        // Runs 0 and 1 (mass −1) fail, one in each shard.
        assert_eq!(done.status.code(), Some(11), "{}", text(&done.stderr));
    }
    assert!(sharded.join("summary.0of2.csv").is_file());
    assert!(!sharded.join("summary.csv").exists());
    let merged = mstar(&["sweep", "--merge", &sharded.display().to_string()]);
    assert_eq!(merged.status.code(), Some(12), "{}", text(&merged.stderr));
    let a = without_wall_time(&whole.join("summary.csv"));
    let b = without_wall_time(&sharded.join("summary.csv"));
    assert_eq!(a.lines().count(), 9);
    assert_eq!(a, b);
    for i in 0..8 {
        let name = format!("runs/{i}.csv");
        assert_eq!(
            std::fs::read(whole.join(&name)).ok(),
            std::fs::read(sharded.join(&name)).ok(),
            "{name}"
        );
    }
    // A shard missing: the merge says which runs have no row.
    std::fs::remove_file(sharded.join("summary.1of2.csv")).expect("remove");
    let incomplete = mstar(&["sweep", "--merge", &sharded.display().to_string()]);
    assert_eq!(incomplete.status.code(), Some(1));
    let e = text(&incomplete.stderr);
    assert!(e.contains("4 of 8 runs have no row"), "{e}");
    assert!(e.contains("(first: 1, 3, 5, 7)"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_failed_run_is_reported_and_counted_in_the_exit_code() {
    let dir = scratch("sweep-fail");
    let out = dir.join("s");
    // A negative mass is a model error; a local error tolerance of 1e-12
    // with strict error control fails the first step (its error is about
    // 1.5e-12).
    let done = sweep(
        &out,
        &[
            "--zip",
            "--set",
            "body.upper.mass=-1,1,1",
            "--set",
            "simulation.error_control=monitor,monitor,strict",
            "--set",
            "simulation.rtol=1e-12",
            "--set",
            "simulation.atol=1e-12",
        ],
    );
    assert_eq!(done.status.code(), Some(12), "{}", text(&done.stderr));
    let (h, rows) = summary(&out.join("summary.csv"));
    let status = column(&h, &rows, "status");
    assert!(
        status[0].contains("body 'upper': mass: must be positive, in kg (got -1)"),
        "{status:?}"
    );
    assert_eq!(status[1], "ok");
    assert_ne!(status[2], "ok");
    assert!(
        status[2].starts_with("the estimated local error exceeds the tolerance at t = 0.001 s"),
        "{status:?}"
    );
    assert_eq!(column(&h, &rows, "steps")[2], "");
    assert!(!out.join("runs/2.csv").exists());
    assert!(out.join("runs/2.partial.csv").is_file());
    let e = text(&done.stderr);
    assert!(e.contains("run 0 failed: "), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_rerun_skips_complete_runs_and_completes_the_others() {
    let dir = scratch("sweep-resume");
    let out = dir.join("s");
    let params = ["--set", "body.upper.mass=1:2:4", "--jobs", "2"];
    let done = sweep(&out, &params);
    assert_eq!(done.status.code(), Some(0), "{}", text(&done.stderr));
    let before = without_wall_time(&out.join("summary.csv"));
    let run2 = std::fs::read(out.join("runs/2.csv")).expect("run 2");
    // A marker in run 0's file: a run that is skipped is not rewritten.
    std::fs::write(out.join("runs/0.csv"), "marker").expect("mark");
    // Run 1 lost its row, run 2 its CSV file: both incomplete.
    std::fs::remove_file(out.join("runs/1.row")).expect("remove");
    std::fs::remove_file(out.join("runs/2.csv")).expect("remove");
    let again = sweep(&out, &params);
    assert_eq!(again.status.code(), Some(0), "{}", text(&again.stderr));
    let said = text(&again.stdout);
    assert!(said.contains("2 run now, 2 complete before"), "{said}");
    assert_eq!(
        std::fs::read_to_string(out.join("runs/0.csv"))
            .ok()
            .as_deref(),
        Some("marker")
    );
    assert_eq!(std::fs::read(out.join("runs/2.csv")).ok(), Some(run2));
    assert_eq!(without_wall_time(&out.join("summary.csv")), before);
    // Other parameters into the same directory: refused, nothing touched.
    let other = sweep(&out, &["--set", "body.upper.mass=1,2"]);
    assert_eq!(other.status.code(), Some(2));
    assert!(text(&other.stderr).contains("holds another sweep"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_parameters_are_refused_before_anything_runs() {
    let dir = scratch("sweep-bad");
    let out = dir.join("s");
    for (args, message) in [
        (
            vec!["--set", "body.uper.mass=1,2"],
            "no element of 'body' is named 'uper'; the names are: upper, lower",
        ),
        (
            vec!["--set", "body.upper.mas=1,2"],
            "body 'upper': unknown key 'mas' (given by --set) (did you mean 'mass'?)",
        ),
        (
            vec!["--set", "simulation.hh=1e-3"],
            "[simulation]: unknown key 'hh' (given by --set)",
        ),
        (
            vec!["--set", "body.upper.mass=1:2"],
            "is not a range START:STOP:COUNT",
        ),
        (
            vec!["--set", "body.upper.mass=1:2:0"],
            "COUNT must be a whole number ≥ 2",
        ),
        (
            vec![
                "--zip",
                "--set",
                "body.upper.mass=1,2",
                "--set",
                "simulation.h=1e-3,5e-4,2e-4",
            ],
            "--zip pairs the i-th values of every key, and simulation.h has 3 values where body.upper.mass has 2",
        ),
        (
            vec!["--set", "body.upper.mass=1,2", "--shard", "2/2"],
            "--shard 2/2: I must be at least 0 and less than N",
        ),
        (
            vec!["--set", "body.upper.mass=1,2", "--shard", "x"],
            "--shard x: expected I/N",
        ),
        (
            vec!["--set", "body.upper.mass=1", "--set", "body.upper.mass=2"],
            "the key body.upper.mass is given twice",
        ),
    ] {
        let done = sweep(&out, &args);
        let e = text(&done.stderr);
        assert_eq!(done.status.code(), Some(2), "{args:?}: {e}");
        assert!(e.contains(message), "{args:?}: {e}");
        assert!(!out.exists(), "{args:?}: the sweep started");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
