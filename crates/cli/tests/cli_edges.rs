//! The command line's edges (issue 21): outputs that would overwrite an
//! input or each other, values out of range named by their option (negative
//! ones too) with exit 2, absurd requests refused with advice that works,
//! numbers of at most 6 significant digits, a thread pool under `ulimit -v`,
//! a closed standard output, a read-only output file, and SIGHUP.
// Signals (kill), symbolic links and permission bits by Unix calls: Unix only.
#![cfg(unix)]

#[allow(dead_code)] // (not every helper is used here)
mod common;

use std::io::{BufRead as _, BufReader};
use std::path::Path;
use std::process::{Command, Output, Stdio};

use common::{model, scratch, sh, text};

const BIN: &str = env!("CARGO_BIN_EXE_mstar");

fn path(p: &Path) -> String {
    p.display().to_string()
}

/// Runs `mstar args` in `dir`.
fn mstar_in(dir: &Path, args: &[&str]) -> Output {
    Command::new(BIN)
        .args(args)
        .current_dir(dir)
        .output()
        .expect("runs")
}

/// The longest run of digits in `s`.
fn longest_number(s: &str) -> usize {
    s.split(|c: char| !c.is_ascii_digit())
        .map(str::len)
        .max()
        .unwrap_or(0)
}

/// A directory with the four-bar model as `fb.toml` and a short run of it
/// as `fb.csv`.
fn four_bar(tag: &str) -> common::Scratch {
    let dir = scratch(tag);
    std::fs::copy(model("four-bar.toml"), dir.join("fb.toml")).expect("copied");
    let ok = mstar_in(
        &dir,
        &["run", "fb.toml", "--t-end", "0.01", "--out", "fb.csv"],
    );
    assert!(ok.status.success(), "{}", text(&ok.stderr));
    dir
}

#[test]
fn an_output_that_names_an_input_or_another_output_is_refused() {
    let dir = four_bar("edges-clobber");
    std::os::unix::fs::symlink("fb.toml", dir.join("link.toml")).expect("a link");
    std::fs::hard_link(dir.join("fb.csv"), dir.join("hard.csv")).expect("a hard link");
    let model_before = std::fs::read(dir.join("fb.toml")).expect("the model");
    let csv_before = std::fs::read(dir.join("fb.csv")).expect("the results");
    let cases: [(&[&str], &str); 8] = [
        (
            &["--html", "fb.toml"],
            "--html fb.toml names the model file",
        ),
        (&["--gif", "fb.toml"], "--gif fb.toml names the model file"),
        (
            &["--html", "fb.csv"],
            "--html fb.csv names the results file",
        ),
        (&["--gif", "fb.csv"], "--gif fb.csv names the results file"),
        (&["--png", "link.toml"], "names the model file"),
        (&["--gif", "hard.csv"], "names the results file"),
        (&["--gif", "./fb.csv"], "names the results file"),
        (
            &["--html", "s.html", "--gif", "./s.html"],
            "names the same file as",
        ),
    ];
    for (outputs, message) in cases {
        let mut args = vec!["animate", "fb.toml", "fb.csv"];
        args.extend_from_slice(outputs);
        let run = mstar_in(&dir, &args);
        let err = text(&run.stderr);
        assert_eq!(run.status.code(), Some(2), "{outputs:?}: {err}");
        assert!(err.contains(message), "{outputs:?}: {err}");
        assert!(!dir.join("s.html").exists(), "{outputs:?}");
    }
    assert_eq!(
        std::fs::read(dir.join("fb.toml")).expect("model"),
        model_before
    );
    assert_eq!(
        std::fs::read(dir.join("fb.csv")).expect("results"),
        csv_before
    );
    // `mstar run --out` through a link to the model file: the same check.
    let run = mstar_in(
        &dir,
        &["run", "fb.toml", "--t-end", "0.01", "--out", "link.toml"],
    );
    assert_eq!(run.status.code(), Some(2), "{}", text(&run.stderr));
    assert!(text(&run.stderr).contains("names the model file"));
    assert_eq!(
        std::fs::read(dir.join("fb.toml")).expect("model"),
        model_before
    );
}

#[test]
fn command_line_values_are_named_and_refused_with_exit_2() {
    let dir = four_bar("edges-values");
    let cases: [(&[&str], &str); 12] = [
        (
            &["--h", "nan"],
            "--h must be a finite positive number (got NaN)",
        ),
        (
            &["--t-end", "nan"],
            "--t-end must be a finite positive number (got NaN)",
        ),
        (
            &["--tol", "nan"],
            "--tol must be a finite positive number (got NaN)",
        ),
        (
            &["--h", "-inf"],
            "--h must be a finite positive number (got -inf)",
        ),
        (
            &["--rtol", "-1"],
            "--rtol must be a finite number ≥ 0 (got -1)",
        ),
        (
            &["--atol", "-1"],
            "--atol must be a finite number ≥ 0 (got -1)",
        ),
        (
            &["--tol", "-1"],
            "--tol must be a finite positive number (got -1)",
        ),
        (
            &["--output-every", "-1", "--out", "x.csv"],
            "--output-every must be a finite positive number (got -1)",
        ),
        (
            &["--output-every", "0", "--out", "x.csv"],
            "--output-every must be a finite positive number (got 0)",
        ),
        (
            &["--output-every", "nan", "--out", "x.csv"],
            "--output-every must be a finite positive number (got NaN)",
        ),
        (&["--t-end", "1e-300"], "within the time resolution"),
        (
            &["--adaptive", "--rtol", "1e-300", "--atol", "1e-300"],
            "below what double precision resolves",
        ),
    ];
    for (options, message) in cases {
        let mut args = vec!["run", "fb.toml"];
        args.extend_from_slice(options);
        let run = mstar_in(&dir, &args);
        let err = text(&run.stderr);
        assert_eq!(run.status.code(), Some(2), "{options:?}: {err}");
        assert!(err.contains(message), "{options:?}: {err}");
        assert!(!err.contains("fb.toml:"), "blames the file: {err}");
        assert!(longest_number(&err) <= 6, "{options:?}: {err}");
    }
    // The advice of the two refusals works.
    let run = mstar_in(&dir, &["run", "fb.toml", "--t-end", "2e-12"]);
    assert!(run.status.code() != Some(2), "{}", text(&run.stderr));
    assert!(
        text(&run.stdout).contains("t reached: 2e-12 s"),
        "{}",
        text(&run.stdout)
    );
    let tiny = [
        "run", "fb.toml", "--t-end", "0.01", "--rtol", "1e-300", "--atol", "1e-300",
    ];
    let err = text(&mstar_in(&dir, &tiny).stderr);
    let advised = |option: &str| -> String {
        err.split(&format!("use {option} "))
            .nth(1)
            .or_else(|| err.split(&format!("or {option} ")).nth(1))
            .and_then(|rest| rest.split(' ').next())
            .unwrap_or_else(|| panic!("no {option} in {err}"))
            .to_string()
    };
    for (option, other) in [("--rtol", "--atol"), ("--atol", "--rtol")] {
        let value = advised(option);
        let args = [
            "run", "fb.toml", "--t-end", "0.01", option, &value, other, "1e-300",
        ];
        let run = mstar_in(&dir, &args);
        assert!(
            run.status.code() != Some(2),
            "{args:?}: {}",
            text(&run.stderr)
        );
    }
    // Negative values reach the range checks of animate (and of chain).
    let cases: [&[&str]; 3] = [
        &[
            "animate", "fb.toml", "fb.csv", "--gif", "x.gif", "--fps", "-1",
        ],
        &[
            "animate", "fb.toml", "fb.csv", "--gif", "x.gif", "--speed", "-1",
        ],
        &[
            "animate", "fb.toml", "fb.csv", "--png", "x.png", "--at", "nan",
        ],
    ];
    for args in cases {
        let run = mstar_in(&dir, args);
        let err = text(&run.stderr);
        assert_eq!(run.status.code(), Some(2), "{args:?}: {err}");
        assert!(!err.contains("unexpected argument"), "{args:?}: {err}");
    }
    // (`mstar chain` refuses its integrator options with exit 1.)
    let run = mstar_in(&dir, &["chain", "--links", "3", "--rtol", "-1"]);
    let err = text(&run.stderr);
    assert!(err.contains("rtol must be finite and ≥ 0"), "{err}");
}

#[test]
fn rows_at_a_tiny_interval_are_refused_also_for_devices() {
    let dir = four_bar("edges-rows");
    for out in ["/dev/null", "-"] {
        let run = mstar_in(
            &dir,
            &["run", "fb.toml", "--output-every", "1e-300", "--out", out],
        );
        let err = text(&run.stderr);
        assert_eq!(run.status.code(), Some(1), "{out}: {err}");
        assert!(err.contains("rows, more than the 1e9"), "{err}");
        assert!(err.contains("--output-every 2.1e-9 or more"), "{err}");
    }
    // The advice passes the check (and the run with the default t_end of
    // 2 s would write 10⁹ rows: cut short with --t-end).
    let run = mstar_in(
        &dir,
        &[
            "run",
            "fb.toml",
            "--output-every",
            "2.1e-9",
            "--t-end",
            "1e-7",
            "--out",
            "/dev/null",
        ],
    );
    assert!(run.status.success(), "{}", text(&run.stderr));
    // Beyond the range of model files' numbers: the option is named.
    let run = mstar_in(&dir, &["run", "fb.toml", "--t-end", "1e308"]);
    let err = text(&run.stderr);
    assert_eq!(run.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--t-end 1e308 is out of range: at most 1e100") && !err.contains("fb.toml"),
        "{err}"
    );
    let run = mstar_in(&dir, &["run", "fb.toml", "--t-end", "1e99"]);
    let err = text(&run.stderr);
    assert!(
        err.contains("about 1e102 steps, more than the 1e9") && !err.contains("inf"),
        "{err}"
    );
}

#[test]
fn animate_messages_are_in_words_and_absurd_gifs_are_refused() {
    let dir = four_bar("edges-animate");
    let run = mstar_in(&dir, &["animate", "fb.toml", "fb.csv", "--png", "x.csv"]);
    let err = text(&run.stderr);
    assert_eq!(run.status.code(), Some(2), "{err}");
    assert!(err.contains("--png x.csv") && err.contains(".png"), "{err}");
    assert!(!dir.join("x.csv").exists());
    let run = mstar_in(
        &dir,
        &["animate", "fb.toml", "fb.csv", "--gif", "/dev/full"],
    );
    let err = text(&run.stderr);
    assert_eq!(run.status.code(), Some(1), "{err}");
    assert!(
        err.contains("/dev/full") && err.contains("No space left on device"),
        "{err}"
    );
    assert!(!err.contains("Os {") && !err.contains("Error("), "{err}");
    let run = mstar_in(
        &dir,
        &[
            "animate", "fb.toml", "fb.csv", "--png", "x.png", "--at", "1e308",
        ],
    );
    let err = text(&run.stderr);
    assert!(
        err.contains("--at 1e308") && longest_number(&err) <= 6,
        "{err}"
    );
    let run = mstar_in(
        &dir,
        &[
            "animate",
            "fb.toml",
            "fb.csv",
            "--gif",
            "x.gif",
            "--max-frames",
            "100000000",
            "--speed",
            "1e-9",
        ],
    );
    let err = text(&run.stderr);
    assert_eq!(run.status.code(), Some(1), "{err}");
    assert!(err.contains("--max-frames 325520 or fewer"), "{err}");
    assert!(!dir.join("x.gif").exists());
}

/// Under an address-space limit that leaves no room for the threads of the
/// pool, the program runs on fewer threads or on the main thread alone.
#[test]
fn run_and_check_work_when_threads_cannot_start() {
    let dir = four_bar("edges-threads");
    let mut ran = 0;
    for limit in [15_000, 17_000, 19_000, 22_000] {
        for command in ["run fb.toml --t-end 0.01", "check fb.toml"] {
            let run = sh(&format!("ulimit -v {limit} && exec \"$M\" {command}"), &dir);
            let err = text(&run.stderr);
            if err.contains("error while loading shared libraries")
                || (err.contains("memory allocation of") && err.contains("failed"))
            {
                // Below what the dynamic loader, or the program's own data
                // before any thread, needs (the binary grows with the code).
                continue;
            }
            ran += 1;
            assert!(!err.contains("panicked"), "-v {limit} {command}: {err}");
            assert_eq!(run.status.code(), Some(0), "-v {limit} {command}: {err}");
        }
    }
    assert!(ran >= 4, "only {ran} runs started");
}

#[test]
fn a_closed_standard_output_is_an_error() {
    let dir = four_bar("edges-closed");
    let run = sh("exec \"$M\" run fb.toml --t-end 0.01 --out - >&-", &dir);
    let err = text(&run.stderr);
    assert_eq!(run.status.code(), Some(1), "{err}");
    assert!(
        err.contains("standard output") && err.contains("closed"),
        "{err}"
    );
    assert!(!err.contains("wrote standard output"), "{err}");
    let run = sh(
        "exec \"$M\" run fb.toml --t-end 0.01 --out - >/dev/null",
        &dir,
    );
    assert!(run.status.success(), "{}", text(&run.stderr));
}

#[test]
fn a_read_only_output_file_is_refused() {
    use std::os::unix::fs::PermissionsExt as _;
    let dir = four_bar("edges-readonly");
    let ro = dir.join("ro.csv");
    std::fs::write(&ro, "kept\n").expect("written");
    std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o444)).expect("chmod");
    let run = mstar_in(
        &dir,
        &["run", "fb.toml", "--t-end", "0.01", "--out", "ro.csv"],
    );
    let err = text(&run.stderr);
    assert_eq!(run.status.code(), Some(1), "{err}");
    assert!(
        err.contains("read-only") && err.contains("chmod u+w ro.csv"),
        "{err}"
    );
    assert_eq!(std::fs::read_to_string(&ro).expect("kept"), "kept\n");
    // The advice works.
    let chmod = Command::new("chmod").args(["u+w", &path(&ro)]).status();
    assert!(chmod.is_ok_and(|s| s.success()));
    let run = mstar_in(
        &dir,
        &["run", "fb.toml", "--t-end", "0.01", "--out", "ro.csv"],
    );
    assert!(run.status.success(), "{}", text(&run.stderr));
}

#[test]
fn sighup_keeps_the_samples_so_far() {
    let dir = four_bar("edges-sighup");
    let mut child = Command::new(BIN)
        .args(["run", "fb.toml", "--t-end", "1000", "--out", "h.csv"])
        .current_dir(&dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("starts");
    if let Some(out) = child.stdout.as_mut() {
        let mut line = String::new();
        let mut lines = BufReader::new(out);
        while lines.read_line(&mut line).unwrap_or(0) > 0 && !line.starts_with("KKT") {
            line.clear();
        }
    }
    let pid = i32::try_from(child.id()).expect("a pid");
    // SAFETY: kill has no memory effects.
    assert_eq!(unsafe { libc::kill(pid, libc::SIGHUP) }, 0);
    let run = child.wait_with_output().expect("ends");
    let err = text(&run.stderr);
    assert_eq!(run.status.code(), Some(129), "{err}");
    assert!(
        err.contains("SIGHUP") && err.contains("h.partial.csv"),
        "{err}"
    );
    let partial = std::fs::read_to_string(dir.join("h.partial.csv")).expect("kept");
    assert!(partial.lines().count() >= 2, "{partial:.200}");
    let left: Vec<String> = std::fs::read_dir(&dir)
        .expect("dir")
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".tmp"))
        .collect();
    assert!(left.is_empty(), "{left:?}");
}

#[test]
fn numbers_in_the_summary_have_at_most_6_digits() {
    let dir = four_bar("edges-digits");
    let run = mstar_in(
        &dir,
        &["run", "fb.toml", "--t-end", "0.0000038756", "--h", "1e-6"],
    );
    let out = text(&run.stdout);
    assert!(out.contains("t reached: 3.8756e-6 s"), "{out}");
}

/// Ctrl-C while `mstar animate` draws a GIF: exit 130, no GIF and no
/// temporary file.
#[test]
fn an_interrupted_animation_leaves_no_temporary_file() {
    let dir = four_bar("edges-animate-signal");
    let child = Command::new(BIN)
        .args(["animate", "fb.toml", "fb.csv", "--gif", "long.gif"])
        .args(["--speed", "1e-6", "--max-frames", "20000"])
        .current_dir(&dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("starts");
    // (20 000 frames take minutes: the signal comes while it draws.)
    std::thread::sleep(std::time::Duration::from_millis(1500));
    let pid = i32::try_from(child.id()).expect("a pid");
    // SAFETY: kill has no memory effects.
    assert_eq!(unsafe { libc::kill(pid, libc::SIGINT) }, 0);
    let run = child.wait_with_output().expect("ends");
    let err = text(&run.stderr);
    assert_eq!(run.status.code(), Some(130), "{err}");
    assert!(err.contains("interrupted by SIGINT"), "{err}");
    let names: Vec<String> = std::fs::read_dir(&dir)
        .expect("dir")
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    assert!(!names.iter().any(|n| n.contains("long.gif")), "{names:?}");
}

/// Ctrl-C pressed twice while a GIF frame draws (4096×4096 frames take
/// about a second each): the second signal ends the program at once, as it
/// does a run, and the GIF's temporary file goes first; a GIF already
/// there is untouched.
#[test]
fn a_second_ctrl_c_during_a_gif_frame_leaves_no_temporary_file() {
    let dir = four_bar("edges-animate-second-signal");
    std::fs::write(dir.join("old.gif"), b"the GIF of an earlier animation").expect("written");
    let child = Command::new(BIN)
        .args(["animate", "fb.toml", "fb.csv", "--gif", "old.gif"])
        .args(["--size", "4096x4096", "--max-frames", "20"])
        .current_dir(&dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("starts");
    let temporary = |dir: &Path| -> Vec<String> {
        std::fs::read_dir(dir)
            .expect("dir")
            .flatten()
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .filter(|n| n.contains("tmp"))
            .collect()
    };
    // The temporary file exists once the first frame draws.
    let started = std::time::Instant::now();
    while temporary(&dir).is_empty() && started.elapsed().as_secs() < 60 {
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    assert!(
        !temporary(&dir).is_empty(),
        "no temporary file while drawing"
    );
    let pid = i32::try_from(child.id()).expect("a pid");
    for _ in 0..2 {
        // SAFETY: kill has no memory effects.
        assert_eq!(unsafe { libc::kill(pid, libc::SIGINT) }, 0);
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    let run = child.wait_with_output().expect("ends");
    // Ended by the second signal's default action.
    use std::os::unix::process::ExitStatusExt as _;
    assert_eq!(
        run.status.signal(),
        Some(libc::SIGINT),
        "{}",
        text(&run.stderr)
    );
    assert_eq!(temporary(&dir), Vec::<String>::new());
    assert_eq!(
        std::fs::read(dir.join("old.gif")).expect("the old GIF"),
        b"the GIF of an earlier animation"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Rows at a tiny `--output-every` into a regular file: the refusal's
/// `--output-every` fits the free space of the file system as well as the
/// 10⁹ rows, so the run given it is accepted (it starts integrating; it is
/// stopped there with Ctrl-C, its rows kept in the partial file).
#[test]
fn the_output_every_advised_for_too_many_rows_is_accepted() {
    let dir = four_bar("edges-rows-advice");
    let refused = mstar_in(
        &dir,
        &[
            "run",
            "fb.toml",
            "--output-every",
            "1e-300",
            "--out",
            "x.csv",
        ],
    );
    let err = text(&refused.stderr);
    assert_eq!(refused.status.code(), Some(1), "{err}");
    assert!(err.contains("rows, more than the 1e9"), "{err}");
    let every = err
        .split("--output-every ")
        .nth(2)
        .and_then(|s| s.split(' ').next())
        .unwrap_or_else(|| panic!("no advice in: {err}"))
        .to_string();
    let mut child = Command::new(BIN)
        .args(["run", "fb.toml", "--output-every", &every, "--out", "x.csv"])
        .current_dir(&dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("starts");
    let stdout = child.stdout.take().expect("piped");
    let started = BufReader::new(stdout)
        .lines()
        .map_while(Result::ok)
        .any(|line| line.starts_with("KKT solver:"));
    if started {
        let pid = i32::try_from(child.id()).expect("a pid");
        // SAFETY: kill has no memory effects.
        assert_eq!(unsafe { libc::kill(pid, libc::SIGINT) }, 0);
    }
    let run = child.wait_with_output().expect("ends");
    let err = text(&run.stderr);
    assert!(started, "--output-every {every} refused: {err}");
    assert_eq!(run.status.code(), Some(130), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}
