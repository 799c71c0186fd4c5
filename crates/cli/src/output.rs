//! What the program writes, and how a run ends: report lines that survive a
//! closed pipe, the integration loop that stops on a signal or a failed
//! write, and what a stopped run keeps.

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

use mstar::csv::{CsvStream, Kept};
use mstar::{IntegrationError, Integrator, System};

use crate::signals::{self, Interrupted};

/// The report goes to standard error: standard output carries the CSV.
static REPORT_ON_STDERR: AtomicBool = AtomicBool::new(false);

/// An output file's write failed: the run stops at the next step.
static WRITE_FAILED: AtomicBool = AtomicBool::new(false);

/// Sends the report to standard error from now on (`--out -`).
pub fn report_on_stderr() {
    REPORT_ON_STDERR.store(true, Ordering::Relaxed);
}

/// Whether `out` is standard output (`-`, `/dev/stdout`).
pub fn is_stdout(out: Option<&Path>) -> bool {
    out.is_some_and(|p| p.as_os_str() == "-" || p == Path::new("/dev/stdout"))
}

/// A report line (`say!` in this program): on standard output, or on
/// standard error when standard output carries the CSV. A closed pipe
/// (`mstar chain | head -1`) or a full disk loses the report, never the run,
/// and is not a panic.
pub fn say(args: std::fmt::Arguments<'_>) {
    if REPORT_ON_STDERR.load(Ordering::Relaxed) {
        return note(args);
    }
    let _ = writeln!(std::io::stdout().lock(), "{args}");
}

/// A line on standard error (`note!` in this program), never a panic.
pub fn note(args: std::fmt::Arguments<'_>) {
    let _ = writeln!(std::io::stderr().lock(), "{args}");
}

/// Tells the loop to stop when `stream`'s last write failed.
pub fn watch(stream: &CsvStream) {
    if stream.failed() {
        WRITE_FAILED.store(true, Ordering::Relaxed);
    }
}

/// Why a run stopped before its end.
#[derive(Debug)]
pub enum Stop {
    /// A step failed.
    Failed(IntegrationError),
    /// An output file could not be written (the stream has the error).
    Write,
    /// SIGINT or SIGTERM.
    Signal(i32),
}

/// Integrates to `t_end`, handing the initial state and every accepted step
/// to `each` (as `Integrator::run` does), and stops at the next step when a
/// stop signal arrives or a write fails ([`watch`]).
///
/// # Errors
/// Why it stopped; every step before it has been observed.
pub fn drive<S: System + ?Sized>(
    integ: &mut Integrator<'_, S>,
    t_end: f64,
    each: &mut dyn FnMut(&Integrator<'_, S>),
) -> Result<(), Stop> {
    drive_with(integ, t_end, &mut |integ, t_end| integ.step(t_end), each)
}

/// [`drive`] with `step` taking each step (e.g. with sensitivities,
/// [`Integrator::step_with`]).
///
/// # Errors
/// As [`drive`].
// (The closure's type is spelled out once, here.)
#[allow(clippy::type_complexity)]
pub fn drive_with<S: System + ?Sized>(
    integ: &mut Integrator<'_, S>,
    t_end: f64,
    step: &mut dyn FnMut(&mut Integrator<'_, S>, f64) -> Result<(), IntegrationError>,
    each: &mut dyn FnMut(&Integrator<'_, S>),
) -> Result<(), Stop> {
    each(integ);
    loop {
        if WRITE_FAILED.load(Ordering::Relaxed) {
            return Err(Stop::Write);
        }
        if integ.reached(t_end) {
            return Ok(());
        }
        if let Some(signal) = signals::received() {
            return Err(Stop::Signal(signal));
        }
        step(integ, t_end).map_err(Stop::Failed)?;
        each(integ);
    }
}

/// `<stem>.partial.csv` beside `out` (`.partial.npz` for an `.npz` output).
pub fn partial_path(out: &Path) -> PathBuf {
    let stem = out
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    let ext = if mstar::csv::is_npz(out) {
        "npz"
    } else {
        "csv"
    };
    out.with_file_name(format!("{stem}.partial.{ext}"))
}

/// Ends a run: with `Ok`, writes the file into place; with a stop, keeps the
/// samples so far in `<name>.partial.csv` (saying so) and returns why it
/// stopped (`t`: how far it got). Without an output, only the why.
///
/// # Errors
/// The stop's cause ([`Interrupted`] for a signal), or the output's error.
pub fn conclude(
    stream: Option<CsvStream>,
    out: Option<&Path>,
    ended: Result<(), Stop>,
    t: f64,
) -> anyhow::Result<()> {
    let (Some(mut stream), Some(out)) = (stream, out) else {
        return ended.map_err(|stop| cause(stop, None, t));
    };
    // The last rows may still fail (a disk that fills at the end): then the
    // rows that got through are kept as for a write error during the run.
    let ended = match ended {
        Ok(()) if !stream.write_pending() => Err(Stop::Write),
        other => other,
    };
    let stop = match ended {
        Ok(()) => {
            let rows = stream.finish()?;
            say(format_args!(
                "wrote {} ({rows} rows)",
                mstar::csv::display(out)
            ));
            remove_stale_partial(out);
            return Ok(());
        }
        Err(stop) => stop,
    };
    let error = stream.error();
    let why = cause(stop, error, t);
    let quiet = why
        .downcast_ref::<Interrupted>()
        .is_some_and(|i| i.signal == signals::SIGPIPE);
    let kept = stream.keep_partial(&partial_path(out));
    if !quiet {
        tell_kept(out, &kept);
    }
    Err(why)
}

/// Removes the `<name>.partial.csv` an earlier stopped run of the same
/// output left, now that the whole file is written (saying so): beside a
/// complete file it would only pass for this run's. Only for a file output,
/// and a CSV file only when its header is this output's.
fn remove_stale_partial(out: &Path) {
    // Only a file output keeps a partial file (not standard output, a FIFO
    // or a device).
    if !matches!(mstar::csv::target(out), Ok(mstar::csv::Target::Replace(_))) {
        return;
    }
    let partial = partial_path(out);
    if !std::fs::symlink_metadata(&partial).is_ok_and(|m| m.is_file()) {
        return;
    }
    // A CSV file of other columns is not this output's samples (a file a
    // user named so): left alone.
    if !mstar::csv::is_npz(out) && first_line(&partial) != first_line(out) {
        return;
    }
    match std::fs::remove_file(&partial) {
        Ok(()) => note(format_args!(
            "note: removed {}, the samples of an earlier run of this output that stopped",
            partial.display()
        )),
        Err(e) => note(format_args!(
            "note: {} is from an earlier run of this output that stopped, and could not be removed: {e}",
            partial.display()
        )),
    }
}

/// The first line of the text file `path` (empty when it cannot be read).
fn first_line(path: &Path) -> String {
    use std::io::BufRead as _;
    let mut line = String::new();
    if let Ok(f) = std::fs::File::open(path) {
        let _ = std::io::BufReader::new(f).read_line(&mut line);
    }
    line
}

/// The error a stop ends the program with: a write error on a closed pipe
/// reads as SIGPIPE (a quiet end).
fn cause(stop: Stop, write: Option<std::io::Error>, t: f64) -> anyhow::Error {
    match (stop, write) {
        (Stop::Failed(e), _) => e.into(),
        (Stop::Signal(signal), _) => Interrupted { signal, t }.into(),
        (Stop::Write, Some(e)) if e.kind() == std::io::ErrorKind::BrokenPipe => Interrupted {
            signal: signals::SIGPIPE,
            t,
        }
        .into(),
        (Stop::Write, Some(e)) => e.into(),
        (Stop::Write, None) => {
            anyhow::anyhow!("a write failed at t = {} s", mstar::newmark::Short(t))
        }
    }
}

/// Says where the samples of a stopped run are.
fn tell_kept(out: &Path, kept: &Kept) {
    let out = mstar::csv::display(out);
    match kept {
        Kept::File { path, rows } => note(format_args!(
            "note: {out} was not written; {} written before the run stopped {} in {}",
            crate::messages::samples_phrase(*rows),
            if *rows == 1 { "is" } else { "are" },
            path.display()
        )),
        Kept::Streamed { rows: 0 } => {}
        Kept::Streamed { rows } => note(format_args!(
            "note: {out} received {} before the run stopped",
            crate::messages::samples_phrase(*rows)
        )),
        Kept::Nothing(e) => note(format_args!(
            "note: {out} was not written, and the samples so far could not be kept: {e}"
        )),
    }
}

/// The exit status of a command's result, with the error (and a hint for a
/// failed step, `files`: in terms of model-file keys) on standard error: 0,
/// 128 + the signal for an interrupted run (quietly for a closed pipe), else
/// `failure`.
pub fn exit_code(result: anyhow::Result<()>, files: bool, failure: u8) -> u8 {
    let Err(e) = result else {
        return 0;
    };
    // The warning has said why.
    if e.downcast_ref::<mstar::accuracy::Inaccurate>().is_some() {
        return mstar::accuracy::EXIT_INACCURATE;
    }
    if e.downcast_ref::<Usage>().is_some() {
        note(format_args!("error: {e}"));
        return 2;
    }
    if let Some(i) = e.downcast_ref::<Interrupted>() {
        if i.signal != signals::SIGPIPE {
            note(format_args!("mstar: {i}"));
        }
        return i.code();
    }
    note(format_args!("error: {}", crate::messages::report(&e)));
    if let Some(hint) = e
        .downcast_ref::<IntegrationError>()
        .and_then(|e| crate::messages::hint(e, files))
    {
        note(format_args!("hint: {hint}"));
    }
    failure
}

pub use mstar::record::Grid;

/// A command line the program refuses before doing anything (a value out of
/// range, an output that would overwrite an input): exit 2.
#[derive(Debug)]
pub struct Usage(pub String);

impl std::fmt::Display for Usage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Usage {}

/// A usage error ([`Usage`]) with `message`.
pub fn usage(message: String) -> anyhow::Error {
    Usage(message).into()
}

/// Which file a path names, to tell whether two paths are one file: the
/// device and inode of an existing regular file (through symbolic and hard
/// links), the canonical directory and name of a new path, standard output;
/// `None` for what is written directly and never replaced (a device, a FIFO).
#[derive(Debug, PartialEq, Eq)]
enum Identity {
    #[cfg(unix)]
    Inode(u64, u64),
    New(PathBuf),
    Stdout,
}

fn identity(path: &Path) -> Option<Identity> {
    if is_stdout(Some(path)) {
        return Some(Identity::Stdout);
    }
    match std::fs::metadata(path) {
        Ok(m) if m.is_file() => file_identity(path, &m),
        Ok(_) => None,
        Err(_) => {
            let dir = match path.parent() {
                Some(d) if !d.as_os_str().is_empty() => d,
                _ => Path::new("."),
            };
            let name = path.file_name()?;
            Some(Identity::New(std::fs::canonicalize(dir).ok()?.join(name)))
        }
    }
}

/// An existing regular file: its device and inode.
#[cfg(unix)]
fn file_identity(_: &Path, m: &std::fs::Metadata) -> Option<Identity> {
    use std::os::unix::fs::MetadataExt as _;
    Some(Identity::Inode(m.dev(), m.ino()))
}

/// An existing regular file outside Unix: its canonical path (hard links to
/// one file are then two files).
#[cfg(not(unix))]
fn file_identity(path: &Path, _: &std::fs::Metadata) -> Option<Identity> {
    std::fs::canonicalize(path).ok().map(Identity::New)
}

/// Refuses an output that names one of the inputs or another output, by
/// [`Identity`] (through symbolic links, hard links and relative paths):
/// writing it would destroy the input, or one output would overwrite the
/// other. Each path comes with what it is for messages (`"--gif"`, `"the
/// model file"`).
///
/// # Errors
/// [`Usage`], naming both.
pub fn refuse_overwrites(
    inputs: &[(&str, &Path)],
    outputs: &[(&str, &Path)],
) -> anyhow::Result<()> {
    let ids: Vec<Option<Identity>> = outputs.iter().map(|(_, p)| identity(p)).collect();
    for (k, ((option, path), id)) in outputs.iter().zip(&ids).enumerate() {
        let Some(id) = id else { continue };
        for (what, input) in inputs {
            if identity(input).as_ref() == Some(id) {
                return Err(usage(format!(
                    "{option} {} names {what} {}: name another file for the output",
                    path.display(),
                    input.display()
                )));
            }
        }
        if let Some(((other, earlier), _)) = outputs[..k]
            .iter()
            .zip(&ids)
            .find(|(_, e)| e.as_ref() == Some(id))
        {
            return Err(usage(format!(
                "{option} {} names the same file as {other} {}: name another file for each output",
                path.display(),
                earlier.display()
            )));
        }
    }
    Ok(())
}

/// [`refuse_overwrites`] for a command that reads the model file `model`:
/// its inputs are the model, every file the model reads (the URDF a spatial
/// file starts from, [`mstar::file::included_files`]) and `others` (the
/// results `animate` reads, a `fit:` objective's CSV).
///
/// # Errors
/// [`Usage`], naming both.
pub fn refuse_overwriting_model(
    model: &Path,
    others: &[(&str, &Path)],
    outputs: &[(&str, &Path)],
) -> anyhow::Result<()> {
    let included = mstar::file::included_files(model);
    let mut inputs = vec![("the model file", model)];
    inputs.extend(included.iter().map(|p| ("the URDF file", p.as_path())));
    inputs.extend_from_slice(others);
    refuse_overwrites(&inputs, outputs)
}

/// Refuses, before any work, an output that is a read-only file (mode 444,
/// even for root, whom the rename into place would let replace it) or one
/// the user may not write: the check `mstar::csv` makes for `--out`
/// ([`mstar::csv::refuse_read_only`]), for the outputs written otherwise
/// (pictures, JSON, a model).
///
/// # Errors
/// `could not write P: it is read-only (mode 444); make it writable
/// (chmod u+w P) or name another file`.
pub fn refuse_read_only(outputs: &[(&str, &Path)]) -> anyhow::Result<()> {
    for (_, path) in outputs {
        mstar::csv::refuse_read_only(path)?;
    }
    Ok(())
}
