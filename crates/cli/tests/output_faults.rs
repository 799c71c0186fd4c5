//! Output that survives faults, at the level of the program: devices, FIFOs
//! and standard output are written, not replaced; a failed or interrupted
//! run keeps its samples in `<name>.partial.csv` and leaves no temporary
//! file; a full disk and a file-size limit are errors with a message; a
//! closed pipe ends quietly; absurd runs are refused before they start.
// Signals, devices, FIFOs, tmpfs and resource limits by Unix calls: Unix only.
#![cfg(unix)]

#[allow(dead_code)] // (not every helper is used here)
mod common;

use std::io::{BufRead as _, BufReader, Read as _};
use std::os::unix::fs::FileTypeExt as _;
use std::os::unix::process::ExitStatusExt as _;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};

use common::{mstar, scratch, sh, text};

const BIN: &str = env!("CARGO_BIN_EXE_mstar");

fn path(p: &Path) -> String {
    p.display().to_string()
}

/// The hidden temporary files in `dir`.
fn temporaries(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .expect("the scratch directory")
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.') && n.contains(".tmp"))
        .collect()
}

/// The CSV's rows after the header, each checked to have the header's number
/// of fields, and the time (first column) of the last row.
fn rows(csv: &str) -> (usize, f64) {
    let mut lines = csv.lines();
    let fields = lines.next().map_or(0, |h| h.split(',').count());
    assert!(fields > 1, "no header: {csv:.200}");
    let mut n = 0;
    let mut last = f64::NAN;
    for line in lines {
        assert_eq!(line.split(',').count(), fields, "a cut row: {line}");
        last = line
            .split(',')
            .next()
            .and_then(|t| t.parse().ok())
            .unwrap_or(f64::NAN);
        n += 1;
    }
    assert!(csv.ends_with('\n'), "the last row is cut");
    (n, last)
}

fn is_char_device(p: &Path) -> bool {
    std::fs::symlink_metadata(p).is_ok_and(|m| m.file_type().is_char_device())
}

/// Makes a character device `major, minor` at `p` (root only).
fn mknod(p: &Path, major: u32, minor: u32) -> bool {
    Command::new("mknod")
        .arg(p)
        .args(["c", &major.to_string(), &minor.to_string()])
        .status()
        .is_ok_and(|s| s.success())
}

#[test]
#[ignore = "needs root (mknod, mount): cargo test -p mstar-cli --test output_faults -- --ignored"]
fn devices_are_written_not_replaced() {
    let dir = scratch("faults-devices");
    let (null, full) = (dir.join("null"), dir.join("full"));
    assert!(
        mknod(&null, 1, 3) && mknod(&full, 1, 7),
        "mknod is not allowed here (not root, or no CAP_MKNOD)"
    );
    let ok = mstar(&["pendulum", "--t-end", "0.5", "--out", &path(&null)]);
    assert!(ok.status.success(), "{}", text(&ok.stderr));
    assert!(is_char_device(&null), "the device node was replaced");
    let failed = mstar(&["pendulum", "--t-end", "0.5", "--out", &path(&full)]);
    let err = text(&failed.stderr);
    assert_eq!(failed.status.code(), Some(1), "{err}");
    assert!(
        err.contains(&format!("could not write {}", path(&full)))
            && err.contains("No space left on device"),
        "{err}"
    );
    assert!(is_char_device(&full), "the device node was replaced");
    assert!(temporaries(&dir).is_empty(), "{:?}", temporaries(&dir));
    assert!(is_char_device(Path::new("/dev/null")));
}

#[test]
fn a_fifo_is_written_not_replaced() {
    let dir = scratch("faults-fifo");
    let fifo = dir.join("pipe.csv");
    let made = Command::new("mkfifo").arg(&fifo).status();
    if !made.is_ok_and(|s| s.success()) {
        eprintln!("skipped: mkfifo failed here");
        return;
    }
    // The reader: opening blocks until the program opens the FIFO to write.
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || std::fs::read_to_string(fifo).unwrap_or_default())
    };
    let run = mstar(&["pendulum", "--t-end", "0.1", "--out", &path(&fifo)]);
    let kind = std::fs::symlink_metadata(&fifo).map(|m| m.file_type());
    assert!(kind.is_ok_and(|k| k.is_fifo()), "the FIFO was replaced");
    assert!(run.status.success(), "{}", text(&run.stderr));
    let csv = reader.join().unwrap_or_default();
    assert_eq!(rows(&csv), (11, 0.1));
    assert!(temporaries(&dir).is_empty(), "{:?}", temporaries(&dir));
}

#[test]
fn dash_is_standard_output() {
    let dir = scratch("faults-dash");
    let run = Command::new(BIN)
        .args(["pendulum", "--t-end", "0.05", "--out", "-"])
        .current_dir(&dir)
        .output()
        .expect("runs");
    assert!(run.status.success(), "{}", text(&run.stderr));
    let out = text(&run.stdout);
    assert!(out.starts_with("t,u:x,u:y,u:theta,"), "{out}");
    assert_eq!(rows(&out), (6, 0.05));
    // The report goes to standard error, and no file is made.
    assert!(text(&run.stderr).contains("pendulum m = 1 kg"));
    assert!(!dir.join("-").exists());
}

#[test]
fn a_directory_is_refused_with_a_file_name_that_works() {
    let dir = scratch("faults-dir");
    let out = dir.join("results");
    std::fs::create_dir(&out).expect("a directory");
    let refused = mstar(&["pendulum", "--t-end", "0.1", "--out", &path(&out)]);
    let err = text(&refused.stderr);
    assert_eq!(refused.status.code(), Some(1), "{err}");
    let suggested = out.join("run.csv");
    assert!(
        err.contains("is a directory") && err.contains(&path(&suggested)),
        "{err}"
    );
    assert!(temporaries(&dir).is_empty() && temporaries(&out).is_empty());
    let ok = mstar(&["pendulum", "--t-end", "0.1", "--out", &path(&suggested)]);
    assert!(ok.status.success(), "{}", text(&ok.stderr));
    assert!(suggested.is_file());
}

#[test]
fn a_failed_chain_keeps_its_samples() {
    let dir = scratch("faults-chain");
    let out = dir.join("w.csv");
    let run = mstar(&[
        "chain",
        "--links",
        "20",
        "--h",
        "0.1",
        "--t-end",
        "5",
        "--out",
        &path(&out),
    ]);
    let err = text(&run.stderr);
    assert_eq!(run.status.code(), Some(1), "{err}");
    assert!(!out.exists());
    let partial = dir.join("w.partial.csv");
    assert!(err.contains(&path(&partial)), "{err}");
    let (n, last) = rows(&std::fs::read_to_string(&partial).expect("the partial file"));
    assert!(n >= 2 && last > 0.0 && last < 5.0, "{n} rows to t = {last}");
    assert!(temporaries(&dir).is_empty(), "{:?}", temporaries(&dir));
}

/// A rerun that completes removes the `.partial.csv` its stopped run left
/// (and says so), so that a complete file never stands beside a stale one.
#[test]
fn a_completed_rerun_removes_the_stale_partial_file() {
    let dir = scratch("faults-stale-partial");
    let out = dir.join("w.csv");
    let run = |h: &str, t_end: &str| {
        let out = path(&out);
        let args = [
            "chain", "--links", "20", "--h", h, "--t-end", t_end, "--out", &out,
        ];
        mstar(&args)
    };
    let failed = run("0.1", "5");
    assert_eq!(failed.status.code(), Some(1), "{}", text(&failed.stderr));
    let partial = dir.join("w.partial.csv");
    assert!(partial.is_file(), "the failed run keeps its samples");
    let ok = run("0.002", "0.2");
    let err = text(&ok.stderr);
    assert!(ok.status.success(), "{err}");
    assert!(out.is_file());
    assert!(!partial.exists(), "{err}");
    assert!(
        err.contains(&format!("removed {}", path(&partial))),
        "{err}"
    );
    // A file of other columns under that name is not this output's: kept.
    std::fs::write(&partial, "a,b\n1,2\n").expect("a user's file");
    let ok = run("0.002", "0.2");
    assert!(ok.status.success(), "{}", text(&ok.stderr));
    assert_eq!(
        std::fs::read_to_string(&partial).ok().as_deref(),
        Some("a,b\n1,2\n")
    );
}

/// Starts `args` in `dir` and reads its standard output up to a line that
/// starts with `ready` (the run has its output open and is integrating).
fn start(args: &[&str], dir: &Path, ready: &str) -> (Child, String) {
    let mut child = Command::new(BIN)
        .args(args)
        .current_dir(dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("starts");
    let mut seen = String::new();
    if let Some(out) = child.stdout.as_mut() {
        let mut lines = BufReader::new(out);
        let mut line = String::new();
        while lines.read_line(&mut line).unwrap_or(0) > 0 {
            seen.push_str(&line);
            if line.starts_with(ready) {
                break;
            }
            line.clear();
        }
    }
    (child, seen)
}

fn signal(child: &Child, sig: i32) {
    let pid = i32::try_from(child.id()).expect("a pid");
    // SAFETY: kill has no memory effects.
    assert_eq!(unsafe { libc::kill(pid, sig) }, 0);
}

/// (Runs of seconds, with outputs of some hundred megabytes estimated: the
/// signal arrives within milliseconds of the first step.)
#[test]
fn sigint_and_sigterm_keep_the_samples_so_far() {
    let dir = scratch("faults-signals");
    let cases: [(&[&str], &str, i32, i32); 3] = [
        (
            &["chain", "--links", "10", "--t-end", "100", "--out", "x.csv"],
            "KKT",
            libc::SIGINT,
            130,
        ),
        (
            &[
                "run",
                "--builtin",
                "chain",
                "--t-end",
                "100",
                "--out",
                "x.csv",
            ],
            "KKT",
            libc::SIGTERM,
            143,
        ),
        (
            &["pendulum", "--t-end", "10000", "--out", "x.csv"],
            "pendulum",
            libc::SIGINT,
            130,
        ),
    ];
    for (args, ready, sig, code) in cases {
        let _ = std::fs::remove_file(dir.join("x.partial.csv"));
        let (child, seen) = start(args, &dir, ready);
        assert!(seen.contains(ready), "{args:?}: {seen}");
        signal(&child, sig);
        let run = child.wait_with_output().expect("ends");
        let err = text(&run.stderr);
        assert_eq!(run.status.code(), Some(code), "{args:?}: {err}");
        assert!(
            err.contains("x.partial.csv") && err.contains("interrupted"),
            "{err}"
        );
        let partial = std::fs::read_to_string(dir.join("x.partial.csv")).expect("kept");
        let (n, _) = rows(&partial);
        assert!(n >= 1, "{args:?}");
        assert!(!dir.join("x.csv").exists());
        assert!(temporaries(&dir).is_empty(), "{:?}", temporaries(&dir));
    }
}

#[test]
fn kill_9_leftovers_are_removed_by_the_next_run() {
    let dir = scratch("faults-kill9");
    let (mut child, seen) = start(
        &["chain", "--links", "10", "--t-end", "100", "--out", "k.csv"],
        &dir,
        "KKT",
    );
    assert!(seen.contains("KKT"), "{seen}");
    let _ = child.kill();
    let _ = child.wait();
    let left = temporaries(&dir);
    assert_eq!(left, [format!(".k.csv.{}.tmp", child.id())]);
    // A temporary file of a process that is alive (this test) is kept.
    let alive = dir.join(format!(".k.csv.{}.tmp", std::process::id()));
    std::fs::write(&alive, "x").expect("written");
    let run = Command::new(BIN)
        .args(["pendulum", "--t-end", "0.1", "--out", "k.csv"])
        .current_dir(&dir)
        .output()
        .expect("runs");
    assert!(run.status.success());
    assert!(
        text(&run.stderr).contains(&left[0]),
        "{}",
        text(&run.stderr)
    );
    assert_eq!(
        temporaries(&dir),
        [format!(".k.csv.{}.tmp", std::process::id())]
    );
    assert!(dir.join("k.csv").is_file());
}

#[test]
fn a_file_size_limit_is_an_error_and_whole_rows_are_kept() {
    let dir = scratch("faults-fsize");
    let run = sh(
        "ulimit -f 100 && exec \"$M\" pendulum --t-end 100 --out big.csv",
        &dir,
    );
    let err = text(&run.stderr);
    assert_eq!(run.status.signal(), None, "killed by a signal: {err}");
    assert_eq!(run.status.code(), Some(1), "{err}");
    assert!(
        err.contains("could not write big.csv") && err.contains("File too large"),
        "{err}"
    );
    assert!(err.contains("big.partial.csv"), "{err}");
    let (n, last) = rows(&std::fs::read_to_string(dir.join("big.partial.csv")).expect("kept"));
    assert!(n >= 10 && last < 100.0, "{n} rows to {last}");
    assert!(!dir.join("big.csv").exists());
    assert!(temporaries(&dir).is_empty(), "{:?}", temporaries(&dir));
}

/// A tmpfs of `size` at `dir/<size>` (root only), unmounted on drop.
struct Tmpfs(PathBuf);

impl Tmpfs {
    fn mount(dir: &Path, size: &str) -> Self {
        let at = dir.join(size);
        std::fs::create_dir_all(&at).expect("a mount point");
        let ok = Command::new("mount")
            .args(["-t", "tmpfs", "-o", &format!("size={size}"), "tmpfs"])
            .arg(&at)
            .status()
            .is_ok_and(|s| s.success());
        assert!(
            ok,
            "cannot mount a tmpfs here (not root, or no CAP_SYS_ADMIN)"
        );
        Self(at)
    }
}

impl Drop for Tmpfs {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg(&self.0).status();
    }
}

#[test]
#[ignore = "needs root (mknod, mount): cargo test -p mstar-cli --test output_faults -- --ignored"]
fn a_full_disk_is_an_error_and_an_oversized_run_is_refused() {
    let dir = scratch("faults-tmpfs");
    let fs = Tmpfs::mount(&dir, "1m");
    let out = fs.0.join("run.csv");
    // About 1.25 MB of rows, estimated below the 1 MiB free: written until
    // the disk is full.
    let full = mstar(&["pendulum", "--t-end", "44", "--out", &path(&out)]);
    let err = text(&full.stderr);
    assert_eq!(full.status.code(), Some(1), "{err}");
    assert!(
        err.contains(&format!("could not write {}", path(&out)))
            && err.contains("No space left on device"),
        "{err}"
    );
    let partial = fs.0.join("run.partial.csv");
    let (n, _) = rows(&std::fs::read_to_string(&partial).expect("kept on a full disk"));
    assert!(n > 100, "{n}");
    assert!(temporaries(&fs.0).is_empty(), "{:?}", temporaries(&fs.0));
    std::fs::remove_file(&partial).expect("removed");
    // Far beyond the free space: refused before it starts, and the shorter
    // run it suggests fits.
    let refused = mstar(&["pendulum", "--t-end", "1000", "--out", &path(&out)]);
    let err = text(&refused.stderr);
    assert_eq!(refused.status.code(), Some(1), "{err}");
    assert!(err.contains("free on its file system"), "{err}");
    assert!(!refused.status.success() && !out.exists());
    let every = advised(&err, "--output-every ");
    let ok = mstar(&[
        "pendulum",
        "--t-end",
        "1000",
        "--output-every",
        every,
        "--out",
        &path(&out),
    ]);
    assert!(
        ok.status.success(),
        "--output-every {every}: {}",
        text(&ok.stderr)
    );
}

/// On a full disk an `.npz` output ends with the rows that fit: a valid
/// archive (its end records in place, its row count patched) named
/// `<stem>.partial.npz`, whose rows are a prefix of the run's.
#[test]
#[ignore = "needs root (mknod, mount): cargo test -p mstar-cli --test output_faults -- --ignored"]
fn a_full_disk_keeps_a_valid_partial_npz() {
    let dir = scratch("faults-npz");
    let fs = Tmpfs::mount(&dir, "256k");
    let out = fs.0.join("run.npz");
    // 16 doubles a row, 128 B: 2 048 rows are estimated at 256 KiB, the
    // free space, and start; with the archive's head and end they do not
    // fit.
    let full = mstar(&["pendulum", "--t-end", "20.47", "--out", &path(&out)]);
    let err = text(&full.stderr);
    assert_eq!(full.status.code(), Some(1), "{err}");
    assert!(err.contains("No space left on device"), "{err}");
    let partial = fs.0.join("run.partial.npz");
    let bytes = std::fs::read(&partial).expect("kept on a full disk");
    // The end of central directory record, and the ZIP64 locator before it.
    let eocd = bytes.len() - 22;
    assert_eq!(&bytes[eocd..eocd + 4], b"PK\x05\x06");
    assert_eq!(&bytes[eocd - 20..eocd - 16], b"PK\x06\x07");
    assert!(temporaries(&fs.0).is_empty(), "{:?}", temporaries(&fs.0));
}

/// The value a message advises for `option`.
fn advised<'a>(message: &'a str, option: &str) -> &'a str {
    message
        .split(option)
        .nth(1)
        .and_then(|s| s.split(' ').next())
        .unwrap_or_else(|| panic!("no {option} in: {message}"))
}

#[test]
#[ignore = "needs root (mknod, mount): cargo test -p mstar-cli --test output_faults -- --ignored"]
fn advice_for_a_full_disk_works_where_steps_are_halved() {
    // The advice must hold whatever the steps: the double pendulum at
    // steps of 0.028 s (a larger --h, the advice this replaced) has Newton
    // failures that halve steps, 500 rows by t = 7 s where t_end / h gives
    // 359.
    let dir = scratch("faults-tmpfs-halved");
    let fs = Tmpfs::mount(&dir, "300k");
    let model = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../models/double-pendulum.toml"
    );
    let out = path(&fs.0.join("full.csv"));
    let refused = mstar(&["run", model, "--t-end", "10", "--out", &out]);
    let err = text(&refused.stderr);
    assert_eq!(refused.status.code(), Some(1), "{err}");
    assert!(
        err.contains("free on its file system") && !err.contains("--h "),
        "{err}"
    );
    let every = advised(&err, "--output-every ");
    for h in ["0.001", "0.028"] {
        let run = mstar(&[
            "run",
            model,
            "--t-end",
            "10",
            "--h",
            h,
            "--output-every",
            every,
            "--out",
            &out,
        ]);
        // (Exit 3 at the large step: beyond the error tolerance, the file
        // complete.)
        let err = text(&run.stderr);
        assert!(matches!(run.status.code(), Some(0 | 3)), "--h {h}: {err}");
        assert!(
            !err.contains("No space") && !err.contains("partial"),
            "--h {h}: {err}"
        );
        let (n, last) = rows(&std::fs::read_to_string(fs.0.join("full.csv")).expect("written"));
        assert!(
            n > 300 && (last - 10.0).abs() < 1e-9,
            "--h {h}: {n} rows to {last}"
        );
        assert!(temporaries(&fs.0).is_empty(), "{:?}", temporaries(&fs.0));
        std::fs::remove_file(fs.0.join("full.csv")).expect("removed");
    }
}

#[test]
#[ignore = "needs root (mknod, mount): cargo test -p mstar-cli --test output_faults -- --ignored"]
fn a_disk_that_fills_at_the_last_rows_keeps_them() {
    let dir = scratch("faults-tmpfs-end");
    let fs = Tmpfs::mount(&dir, "32k");
    // About 37 kB of rows, fewer than the program holds before writing:
    // the disk fills when the run has ended.
    let out = fs.0.join("end.csv");
    let run = mstar(&["pendulum", "--t-end", "1.3", "--out", &path(&out)]);
    let err = text(&run.stderr);
    assert_eq!(run.status.code(), Some(1), "{err}");
    assert!(err.contains("No space left on device"), "{err}");
    let partial = fs.0.join("end.partial.csv");
    let (n, _) = rows(&std::fs::read_to_string(&partial).expect("kept"));
    assert!(n > 50 && err.contains(&path(&partial)), "{n}: {err}");
    assert!(!out.exists() && temporaries(&fs.0).is_empty());
}

#[test]
fn a_closed_pipe_ends_quietly() {
    for args in [
        &["chain", "--links", "20"][..],
        &["pendulum", "--out", "-"][..],
    ] {
        let mut child = Command::new(BIN)
            .args(args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("starts");
        // The reader goes away before the first line.
        drop(child.stdout.take());
        let mut err = String::new();
        if let Some(e) = child.stderr.as_mut() {
            let _ = e.read_to_string(&mut err);
        }
        let status = child.wait().expect("ends");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        assert!(!err.contains("error"), "{args:?}: {err}");
        assert!(
            matches!(status.code(), Some(0 | 141)) || status.signal() == Some(libc::SIGPIPE),
            "{args:?}: {status:?} {err}"
        );
    }
}

#[test]
fn absurd_runs_are_refused_up_front() {
    let dir = scratch("faults-absurd");
    // (Under an address-space limit, so that a program that tries does not
    // take the machine's memory.)
    let cases = [
        ("pendulum --t-end 1e308", "--h 1e299 or more"),
        ("pendulum --reference rk4 --h 1e-300", "--h 1e-8 or more"),
        ("chain --links 10000000", "memory"),
    ];
    for (args, advice) in cases {
        let run = sh(&format!("ulimit -v 4000000 && exec \"$M\" {args}"), &dir);
        let err = text(&run.stderr);
        assert_eq!(run.status.code(), Some(1), "{args}: {err}");
        assert!(
            err.starts_with("error: ") && err.contains(advice),
            "{args}: {err}"
        );
    }
    let run = sh(
        "ulimit -v 4000000 && exec \"$M\" chain --links 10000000",
        &dir,
    );
    let err = text(&run.stderr);
    assert!(err.contains("use at most --links"), "{err}");
}

#[test]
fn the_rk4_reference_ends_at_t_end() {
    let dir = scratch("faults-rk4");
    let out = dir.join("r.csv");
    for (h, t_end, want) in [("0.03", "0.1", 5), ("100", "10", 2)] {
        let run = mstar(&[
            "pendulum",
            "--reference",
            "rk4",
            "--h",
            h,
            "--t-end",
            t_end,
            "--out",
            &path(&out),
        ]);
        assert!(run.status.success(), "{}", text(&run.stderr));
        let csv = std::fs::read_to_string(&out).expect("written");
        let t: f64 = t_end.parse().expect("a number");
        assert_eq!(rows(&csv), (want, t), "--h {h} --t-end {t_end}");
    }
}

/// The peak resident size of the program running `args`, bytes.
#[allow(clippy::zombie_processes)] // reaped by wait4, which reports its resource use
fn peak_memory(args: &[&str]) -> i64 {
    let child = Command::new(BIN)
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("starts");
    let pid = i32::try_from(child.id()).expect("a pid");
    let mut status = 0;
    let mut usage = std::mem::MaybeUninit::<libc::rusage>::zeroed();
    // SAFETY: the buffers are of the right types; the child is ours.
    let usage = unsafe {
        assert_eq!(libc::wait4(pid, &mut status, 0, usage.as_mut_ptr()), pid);
        usage.assume_init()
    };
    assert!(libc::WIFEXITED(status) && libc::WEXITSTATUS(status) == 0);
    usage.ru_maxrss * 1024
}

#[test]
fn the_pendulum_streams_its_samples() {
    // 200 000 samples kept in memory took 55 MB more than 1000.
    let short = peak_memory(&["pendulum", "--t-end", "10"]);
    let long = peak_memory(&["pendulum", "--t-end", "2000"]);
    assert!(long - short < 10_000_000, "{short} B, then {long} B");
}

#[test]
#[ignore = "needs root (mknod, mount): cargo test -p mstar-cli --test output_faults -- --ignored"]
fn a_sweep_larger_than_the_disk_is_refused_and_the_advice_fits() {
    let dir = scratch("faults-tmpfs-sweep");
    let fs = Tmpfs::mount(&dir, "300k");
    let model = concat!(env!("CARGO_MANIFEST_DIR"), "/../../models/pendulum.toml");
    let out = path(&fs.0.join("s"));
    let sweep = |extra: &[&str]| {
        let mut args = vec![
            "sweep",
            model,
            "--set",
            "simulation.t_end=10,20",
            "--out",
            &out,
        ];
        args.extend_from_slice(extra);
        mstar(&args)
    };
    let refused = sweep(&[]);
    let err = text(&refused.stderr);
    assert_eq!(refused.status.code(), Some(1), "{err}");
    assert!(err.contains("free on the file system of --out"), "{err}");
    assert!(!fs.0.join("s").exists(), "the sweep started");
    let every = advised(&err, "--set output.every_time=");
    let set = format!("output.every_time={every}");
    let ok = sweep(&["--set", &set]);
    assert!(ok.status.success(), "{set}: {}", text(&ok.stderr));
    for run in ["0", "1"] {
        let csv = std::fs::read_to_string(fs.0.join(format!("s/runs/{run}.csv"))).expect("a run");
        assert!(rows(&csv).0 > 100, "{set}: run {run}");
    }
}
