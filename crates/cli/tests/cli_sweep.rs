//! `mstar sweep` as a user meets it: the runs a grid or a zip makes, each
//! run's CSV file byte for byte the one `mstar run --set …` writes, shards
//! that merge into the unsharded summary, failed runs reported and counted
//! in the exit code, reruns that skip complete runs, and bad parameters
//! refused before anything runs.
//!
//! The model is the double pendulum of `models/` over 0.05 s: with a fixed
//! step h every run takes t_end / h steps (50 for h = 1e-3, 100 for
//! h = 5e-4), a figure the summary must show independently of the masses.
// Signals (kill), inodes and process setup by Unix calls: Unix only.
#![cfg(unix)]

mod common;

use std::path::Path;

use common::{model, mstar, scratch, sh, text};

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
    // Monitored, the same tolerance: the run reaches its end beyond it.
    assert!(status[1].starts_with("beyond tolerance: "), "{status:?}");
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
    // Run 0's file is not rewritten when skipped: the same inode (a
    // rewrite renames a new file into place).
    let inode =
        |p: &Path| std::os::unix::fs::MetadataExt::ino(&std::fs::metadata(p).expect("a file"));
    let run0 = inode(&out.join("runs/0.csv"));
    // Run 1 lost its row, run 2 its CSV file: both incomplete.
    std::fs::remove_file(out.join("runs/1.row")).expect("remove");
    std::fs::remove_file(out.join("runs/2.csv")).expect("remove");
    let again = sweep(&out, &params);
    assert_eq!(again.status.code(), Some(0), "{}", text(&again.stderr));
    let said = text(&again.stdout);
    assert!(said.contains("2 run now, 2 complete before"), "{said}");
    assert_eq!(inode(&out.join("runs/0.csv")), run0);
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

/// `mstar sweep` of `models/pendulum.toml` (10 s) with `args` into `out`.
fn pendulum_sweep(out: &Path, args: &[&str]) -> std::process::Output {
    let model = model("pendulum.toml");
    let out = out.display().to_string();
    let mut all = vec!["sweep", &model, "--out", &out];
    all.extend_from_slice(args);
    mstar(&all)
}

#[test]
fn a_run_beyond_the_error_tolerance_is_not_ok_and_exits_3() {
    let dir = scratch("sweep-beyond");
    // h = 0.2 is far too large for the pendulum: `mstar run` exits 3.
    let single = mstar(&["run", &model("pendulum.toml"), "--h", "0.2"]);
    assert_eq!(single.status.code(), Some(3), "{}", text(&single.stderr));
    let out = dir.join("s");
    let done = pendulum_sweep(&out, &["--set", "simulation.h=0.001,0.2"]);
    assert_eq!(done.status.code(), Some(3), "{}", text(&done.stderr));
    let (h, rows) = summary(&out.join("summary.csv"));
    let status = column(&h, &rows, "status");
    assert_eq!(status[0], "ok");
    assert!(
        status[1].starts_with("beyond tolerance: the estimated local error exceeded the tolerance"),
        "{status:?}"
    );
    // It reached its end: its steps and CSV file are there.
    assert_eq!(column(&h, &rows, "t"), ["10", "10"]);
    assert!(out.join("runs/1.csv").is_file());
    assert!(text(&done.stdout).contains("0 failed, 1 beyond the error tolerance"));
    // A rerun skips both and keeps the verdict.
    let again = pendulum_sweep(&out, &["--set", "simulation.h=0.001,0.2"]);
    assert_eq!(again.status.code(), Some(3), "{}", text(&again.stderr));
    // A failed run outweighs one beyond the tolerance: 10 + 1.
    let mixed = pendulum_sweep(&dir.join("m"), &["--set", "simulation.h=0.001,0.2,-1"]);
    assert_eq!(mixed.status.code(), Some(11), "{}", text(&mixed.stderr));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_merge_refuses_rows_of_another_sweep_or_without_run_files() {
    let dir = scratch("sweep-mix");
    let ours = dir.join("ours");
    let theirs = dir.join("theirs");
    for shard in ["0/2", "1/2"] {
        let done = sweep(&ours, &["--set", "body.upper.mass=1,2", "--shard", shard]);
        assert_eq!(done.status.code(), Some(0), "{}", text(&done.stderr));
    }
    let done = sweep(&theirs, &["--set", "body.upper.mass=3,4", "--shard", "1/2"]);
    assert_eq!(done.status.code(), Some(0), "{}", text(&done.stderr));
    let merge = || mstar(&["sweep", "--merge", &ours.display().to_string()]);
    // Another sweep's shard summary copied in.
    std::fs::copy(
        theirs.join("summary.1of2.csv"),
        ours.join("summary.1of2.csv"),
    )
    .expect("copy");
    let mixed = merge();
    let e = text(&mixed.stderr);
    assert_eq!(mixed.status.code(), Some(1), "{e}");
    assert!(e.contains("summary.1of2.csv: line 2 (run 1) has the values 0.05, 10, 4 where this sweep's plan (sweep.toml) has 0.05, 10, 2"), "{e}");
    assert!(!ours.join("summary.csv").exists(), "{e}");
    // The advice: run that shard here, then merge.
    let redo = sweep(&ours, &["--set", "body.upper.mass=1,2", "--shard", "1/2"]);
    assert_eq!(redo.status.code(), Some(0), "{}", text(&redo.stderr));
    assert_eq!(merge().status.code(), Some(0));
    // A row whose run file is gone, or cut short.
    std::fs::remove_file(ours.join("runs/1.csv")).expect("remove");
    let gone = merge();
    let e = text(&gone.stderr);
    assert_eq!(gone.status.code(), Some(1), "{e}");
    assert!(
        e.contains("line 2 (run 1)") && e.contains("runs/1.csv"),
        "{e}"
    );
    let csv0 = ours.join("runs/0.csv");
    let bytes = std::fs::read(&csv0).expect("run 0");
    std::fs::write(&csv0, &bytes[..bytes.len() / 2]).expect("cut");
    let cut = merge();
    let e = text(&cut.stderr);
    assert_eq!(cut.status.code(), Some(1), "{e}");
    assert!(
        e.contains("runs/0.csv has") && e.contains("incomplete"),
        "{e}"
    );
    for shard in ["0/2", "1/2"] {
        let redo = sweep(&ours, &["--set", "body.upper.mass=1,2", "--shard", shard]);
        assert_eq!(redo.status.code(), Some(0), "{}", text(&redo.stderr));
    }
    let merged = merge();
    assert_eq!(merged.status.code(), Some(0), "{}", text(&merged.stderr));
    assert_eq!(std::fs::read(&csv0).ok(), Some(bytes));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_truncated_run_file_is_run_again() {
    let dir = scratch("sweep-truncated");
    let out = dir.join("s");
    let params = ["--set", "body.upper.mass=1,2"];
    let done = sweep(&out, &params);
    assert_eq!(done.status.code(), Some(0), "{}", text(&done.stderr));
    let csv0 = out.join("runs/0.csv");
    let whole = std::fs::read(&csv0).expect("run 0");
    std::fs::write(&csv0, &whole[..whole.len() - 10]).expect("cut");
    let again = sweep(&out, &params);
    assert_eq!(again.status.code(), Some(0), "{}", text(&again.stderr));
    assert!(text(&again.stdout).contains("1 run now, 1 complete before"));
    assert_eq!(std::fs::read(&csv0).ok(), Some(whole));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn jobs_beyond_the_runs_and_cores_are_capped() {
    let dir = scratch("sweep-jobs");
    let out = dir.join("s");
    let model = model("pendulum.toml");
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_mstar"))
        .args(["sweep", &model, "--set", "simulation.h=1e-4,2e-4,3e-4"])
        .args(["--jobs", "1000000", "--out", &out.display().to_string()])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("mstar starts");
    let tasks = std::path::PathBuf::from(format!("/proc/{}/task", child.id()));
    let mut most = 0;
    let status = loop {
        if let Some(status) = child.try_wait().expect("wait") {
            break status;
        }
        if let Ok(entries) = std::fs::read_dir(&tasks) {
            most = most.max(entries.count());
        }
        std::thread::sleep(std::time::Duration::from_millis(5));
    };
    let output = child.wait_with_output().expect("output");
    let e = text(&output.stderr);
    assert_eq!(status.code(), Some(0), "{e}");
    let cores = std::thread::available_parallelism().map_or(1, usize::from);
    let threads = cores.min(3);
    // The main thread, the program's own pool (one thread per core: it runs
    // on one of them) and the sweep's pool of `threads`.
    assert!(
        most >= 1 && most <= threads + cores + 1,
        "{most} threads: {e}"
    );
    assert!(
        e.contains(&format!("note: --jobs 1000000 capped to {threads}")),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn sigint_and_sigterm_stop_a_sweep_with_its_summary_so_far() {
    use std::os::unix::process::CommandExt as _;
    let dir = scratch("sweep-signal");
    let model = model("pendulum.toml");
    for (signal, code) in [(libc::SIGINT, 130), (libc::SIGTERM, 143)] {
        let out = dir.join(format!("s{signal}"));
        let mut command = std::process::Command::new(env!("CARGO_BIN_EXE_mstar"));
        command
            .args(["sweep", &model, "--set", "simulation.h=1e-3,1e-5,1e-5,1e-5"])
            .args(["--jobs", "1", "--out", &out.display().to_string()])
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped());
        if signal == libc::SIGTERM {
            // As a shell starts a job in the background: SIGINT ignored.
            // SAFETY: signal is async-signal-safe.
            unsafe {
                command.pre_exec(|| {
                    libc::signal(libc::SIGINT, libc::SIG_IGN);
                    Ok(())
                });
            }
        }
        let child = command.spawn().expect("mstar starts");
        // Run 0 (10 000 steps) completes; run 1 takes 10⁶ steps.
        let row0 = out.join("runs/0.row");
        let clock = std::time::Instant::now();
        while !row0.exists() && clock.elapsed().as_secs() < 60 {
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
        std::thread::sleep(std::time::Duration::from_millis(200));
        let pid = i32::try_from(child.id()).expect("a pid");
        // SAFETY: kill has no memory effects.
        assert_eq!(unsafe { libc::kill(pid, signal) }, 0);
        let output = child.wait_with_output().expect("output");
        let e = text(&output.stderr);
        assert_eq!(output.status.code(), Some(code), "{e}");
        assert!(
            e.contains("the summary holds the runs complete so far"),
            "{e}"
        );
        let (h, rows) = summary(&out.join("summary.csv"));
        assert_eq!(column(&h, &rows, "index"), ["0"], "{e}");
        assert_eq!(column(&h, &rows, "status"), ["ok"]);
        assert!(!out.join("runs/1.row").exists());
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn ranges_of_large_floats_are_floats_that_run() {
    let dir = scratch("sweep-large");
    let out = dir.join("s");
    // Relative tolerances of 1e19 and 2e19: floats (an integer that large
    // does not read as a TOML value).
    let done = pendulum_sweep(&out, &["--set", "simulation.rtol=1e19:2e19:2"]);
    assert_eq!(done.status.code(), Some(0), "{}", text(&done.stderr));
    let (h, rows) = summary(&out.join("summary.csv"));
    assert_eq!(column(&h, &rows, "simulation.rtol"), ["1e19", "2e19"]);
    assert_eq!(column(&h, &rows, "status"), ["ok", "ok"]);
    // The middle of ±1e308 is 0 (not NaN), each a float.
    let wide = pendulum_sweep(&dir.join("w"), &["--set", "body.bob.mass=1e308:-1e308:3"]);
    let (h, rows) = summary(&dir.join("w/summary.csv"));
    let masses = column(&h, &rows, "body.bob.mass");
    assert_eq!(masses, ["1e308", "0.0", "-1e308"], "{}", text(&wide.stderr));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn sweeps_of_too_many_runs_are_refused_before_they_start() {
    let dir = scratch("sweep-huge");
    let out = dir.join("s");
    // 10⁵ values each of three keys: 10¹⁵ runs.
    let done = pendulum_sweep(
        &out,
        &[
            "--set",
            "simulation.rtol=1:2:100000",
            "--set",
            "simulation.atol=1:2:100000",
            "--set",
            "simulation.tol=1:2:100000",
        ],
    );
    let e = text(&done.stderr);
    assert_eq!(done.status.code(), Some(2), "{e}");
    assert!(
        e.contains("the plan has 1.0e15 runs, more than the 1000000"),
        "{e}"
    );
    assert!(!out.exists(), "{e}");
    // A range of 10¹⁵ values is refused before a value is made.
    let done = pendulum_sweep(&out, &["--set", "simulation.rtol=1:2:1000000000000000"]);
    let e = text(&done.stderr);
    assert_eq!(done.status.code(), Some(2), "{e}");
    assert!(
        e.contains("COUNT 1000000000000000 is more than the 1000000 runs"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 21 (24): sweeping the integrator of a file that sets `rho`
/// (models/double-pendulum.toml) failed every HHT run; the override takes
/// the file's `rho` out, and both runs are ok.
#[test]
fn sweeping_the_integrator_of_a_file_with_rho_runs() {
    let dir = scratch("sweep-integrator");
    let out = dir.join("s");
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_mstar"))
        .args(["sweep", &model("double-pendulum.toml")])
        .args(["--set", "simulation.integrator=hht,generalized-alpha"])
        .args([
            "--set",
            "simulation.t_end=0.05",
            "--out",
            &out.display().to_string(),
        ])
        .output()
        .expect("mstar runs");
    let e = text(&run.stderr);
    assert_eq!(run.status.code(), Some(0), "{e}{}", text(&run.stdout));
    let summary = std::fs::read_to_string(out.join("summary.csv")).expect("summary");
    assert_eq!(
        summary.lines().filter(|l| l.contains(",ok")).count(),
        2,
        "{summary}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 21 (16): `--shard -1/2` was refused by the argument parser as an
/// unexpected argument; it reaches the range check, which names the option.
#[test]
fn negative_sweep_options_get_a_range_error() {
    let dir = scratch("sweep-negative");
    let out = dir.join("s").display().to_string();
    let pendulum = model("pendulum.toml");
    for (option, value, says) in [
        (
            "--shard",
            "-1/2",
            "--shard -1/2: I and N must be whole numbers",
        ),
        ("--jobs", "-1", "'-1' for '--jobs <N>'"),
    ] {
        let run = mstar(&[
            "sweep",
            &pendulum,
            "--set",
            "simulation.h=0.01",
            option,
            value,
            "--out",
            &out,
        ]);
        let e = text(&run.stderr);
        assert_eq!(run.status.code(), Some(2), "{e}");
        assert!(e.contains(says), "{e}");
        assert!(!e.contains("unexpected argument"), "{e}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A sweep whose files would not fit on the disk (12 TB of rows) or whose
/// summary would not fit in memory (10⁶ runs under a 400 MB address-space
/// limit) is refused before anything runs, exit 1, with the estimate and
/// what fits. (The disk advice is run on a small tmpfs in
/// output_faults.rs: `a_sweep_larger_than_the_disk_is_refused_and_the_advice_fits`.)
#[test]
fn sweeps_larger_than_the_disk_or_the_memory_are_refused_up_front() {
    let dir = scratch("sweep-too-large");
    let out = dir.join("disk");
    let done = pendulum_sweep(
        &out,
        &[
            "--set",
            "simulation.t_end=1e3:1e4:1000",
            "--set",
            "simulation.h=1e-4",
        ],
    );
    let e = text(&done.stderr);
    assert_eq!(done.status.code(), Some(1), "{e}");
    assert!(
        e.contains("the 1000 runs would write about 12.3 TB (5.5e10 rows")
            && e.contains("--set output.every_time="),
        "{e}"
    );
    assert!(!out.exists(), "the sweep started");
    let model = model("pendulum.toml");
    let script = format!(
        "ulimit -v 400000 && exec \"$M\" sweep '{model}' --set body.bob.mass=1:2:1000 \
         --set simulation.t_end=0.01:0.02:1000 --set output.every_time=0.01 --out memory"
    );
    let done = sh(&script, &dir);
    let e = text(&done.stderr);
    assert_eq!(done.status.code(), Some(1), "{e}");
    assert!(
        e.contains("the summary of 1000000 runs would take about 624.0 MB of memory")
            && e.contains("give fewer runs (at most"),
        "{e}"
    );
    assert!(!dir.join("memory").exists(), "the sweep started");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A rerun after the URDF a spatial model file reads has changed is
/// refused (exit 2) rather than reusing the other model's runs, naming the
/// URDF; the advice (another --out, or removing the directory) works.
#[test]
fn a_rerun_after_the_model_s_urdf_changed_is_refused() {
    let dir = scratch("sweep-urdf");
    for name in ["two-link-arm-start.toml", "two-link-arm.urdf"] {
        std::fs::copy(model(&format!("urdf/{name}")), dir.join(name)).expect("copied");
    }
    let cmd = |out: &str| {
        format!("$M sweep two-link-arm-start.toml --set simulation.t_end=0.01,0.02 --out {out}")
    };
    let first = sh(&cmd("D"), &dir);
    assert!(first.status.success(), "{}", text(&first.stderr));
    let same = sh(&cmd("D"), &dir);
    assert!(
        text(&same.stdout).contains("0 run now, 2 complete before"),
        "{}",
        text(&same.stdout)
    );
    let urdf = dir.join("two-link-arm.urdf");
    let mut text_now = std::fs::read_to_string(&urdf).expect("read");
    text_now.push_str("<!-- edited -->\n");
    std::fs::write(&urdf, text_now).expect("edited");
    let rerun = sh(&cmd("D"), &dir);
    let err = text(&rerun.stderr);
    assert_eq!(rerun.status.code(), Some(2), "{err}");
    assert!(
        err.contains("D holds another sweep (its sweep.toml records another model file")
            && err.contains("give another --out, or remove the directory"),
        "{err}"
    );
    for advice in [cmd("E"), format!("rm -r D && {}", cmd("D"))] {
        let r = sh(&advice, &dir);
        assert!(
            r.status.success() && text(&r.stdout).contains("2 run now, 0 complete before"),
            "{advice}: {}",
            text(&r.stderr)
        );
    }
}

/// An `--out` that names an existing file is refused before anything runs,
/// saying that it is a directory; the file is untouched and a directory
/// works.
#[test]
fn an_out_naming_an_existing_file_is_refused() {
    let dir = scratch("sweep-out-file");
    std::fs::write(dir.join("fb.csv"), "kept\n").expect("written");
    let cmd = |out: &str| {
        format!(
            "$M sweep {} --set simulation.t_end=0.01,0.02 --out {out}",
            model("pendulum.toml")
        )
    };
    let r = sh(&cmd("fb.csv"), &dir);
    let err = text(&r.stderr);
    assert_eq!(r.status.code(), Some(2), "{err}");
    assert!(
        err.contains(
            "--out fb.csv names an existing file: the --out of mstar sweep is a directory"
        ) && err.contains("name a new directory"),
        "{err}"
    );
    assert!(!err.contains("Not a directory"), "{err}");
    assert_eq!(
        std::fs::read_to_string(dir.join("fb.csv")).expect("kept"),
        "kept\n"
    );
    let r = sh(&cmd("fb"), &dir);
    assert!(r.status.success(), "{}", text(&r.stderr));
    assert!(dir.join("fb/summary.csv").is_file());
}

/// A run resumed after an interrupt (its row and file gone, the samples
/// the interrupt kept in `runs/<i>.partial.csv`): once it completes, the
/// stale partial file is removed, as `mstar run` removes its own.
#[test]
fn a_resumed_run_removes_the_partial_file_the_interrupt_left() {
    let dir = scratch("sweep-resume-partial");
    let out = dir.join("s");
    let args = ["--set", "simulation.h=1e-2,5e-3"];
    let done = pendulum_sweep(&out, &args);
    assert_eq!(done.status.code(), Some(0), "{}", text(&done.stderr));
    let runs = out.join("runs");
    let (row, csv, partial) = (
        runs.join("1.row"),
        runs.join("1.csv"),
        runs.join("1.partial.csv"),
    );
    let kept = std::fs::read_to_string(&csv).expect("run 1's file");
    std::fs::remove_file(&row).expect("row removed");
    std::fs::remove_file(&csv).expect("file removed");
    let cut: String = kept.lines().take(5).map(|l| format!("{l}\n")).collect();
    std::fs::write(&partial, cut).expect("partial written");
    let again = pendulum_sweep(&out, &args);
    assert_eq!(again.status.code(), Some(0), "{}", text(&again.stderr));
    assert!(csv.is_file() && row.is_file(), "run 1 complete again");
    assert!(
        !partial.exists(),
        "the stale partial file is left beside the complete one"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A run beyond the tolerance is told what to set in the sweep's own
/// options (`--set simulation.h=…`), not `mstar run`'s `--h`.
#[test]
fn a_sweep_s_accuracy_advice_names_its_settings() {
    let dir = scratch("sweep-advice");
    let out = dir.join("s");
    let done = pendulum_sweep(&out, &["--set", "simulation.h=0.03,0.02"]);
    let e = text(&done.stderr);
    let (h, rows) = summary(&out.join("summary.csv"));
    let status = column(&h, &rows, "status");
    assert!(
        status.iter().all(|s| s.starts_with("beyond tolerance")),
        "{status:?} {e}"
    );
    for s in &status {
        assert!(
            s.contains("--set simulation.h=") && !s.contains("--h "),
            "{s}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
