//! CSV output with one column scheme for every model, written atomically.

use std::fmt::Write as _;
use std::io::{self, Write as _};
use std::path::{Path, PathBuf};

use mstar_model::{Sample, SampleRef, System, coord_names};
use mstar_newmark::Observer;

use crate::columns::Selection;

/// The CSV header: `t`, then `u:<name>`, `v:<name>`, `a:<name>` for each
/// coordinate, `lambda:<row>` for each multiplier (its constraint row's
/// name, [`System::constraint_name`]; `lambda:<i>`, 0-based, for a model
/// whose row names repeat), then `energy`, `iterations`, `residual`,
/// `constraint`.
#[must_use]
pub fn header<S: System + ?Sized>(sys: &S) -> Vec<String> {
    let names = coord_names(sys);
    let mut h = vec!["t".to_string()];
    for prefix in ["u", "v", "a"] {
        h.extend(names.iter().map(|n| format!("{prefix}:{n}")));
    }
    h.extend(multiplier_names(sys));
    h.extend(["energy", "iterations", "residual", "constraint"].map(String::from));
    h
}

/// `lambda:<row name>` per constraint row, or `lambda:<i>` for all when two
/// rows share a name.
fn multiplier_names<S: System + ?Sized>(sys: &S) -> Vec<String> {
    let m = sys.n_constraints();
    let named: Vec<String> = (0..m)
        .map(|i| format!("lambda:{}", sys.constraint_name(i)))
        .collect();
    let mut seen = std::collections::HashSet::with_capacity(m);
    if named.iter().all(|n| seen.insert(n.as_str())) {
        named
    } else {
        (0..m).map(|i| format!("lambda:{i}")).collect()
    }
}

/// How many fields [`header`] names, without naming them.
#[must_use]
pub fn header_len<S: System + ?Sized>(sys: &S) -> usize {
    1 + 3 * sys.n_coords() + sys.n_constraints() + 4
}

pub use crate::columns::Columns;

/// The header as one CSV line (without the newline): names from model files
/// may hold commas or quotes, so such fields are quoted (RFC 4180: in double
/// quotes, inner quotes doubled).
#[must_use]
pub fn header_line<S: System + ?Sized>(sys: &S) -> String {
    join_fields(&header(sys))
}

/// `names` as one CSV line, without the newline: the `csv` crate's writer,
/// quoting a field only where it holds a comma, a quote or a line break.
fn join_fields(names: &[String]) -> String {
    let mut w = ::csv::WriterBuilder::new()
        .terminator(::csv::Terminator::Any(b'\n'))
        .from_writer(Vec::new());
    // Writing to memory does not fail, and UTF-8 fields make a UTF-8 line.
    let line = w
        .write_record(names)
        .ok()
        .and_then(|()| w.into_inner().ok())
        .and_then(|bytes| String::from_utf8(bytes).ok())
        .unwrap_or_default();
    line.strip_suffix('\n').unwrap_or(&line).to_string()
}

/// A number in shortest round-trip form: plain for `1e-4 ≤ |x| < 1e15` (and 0),
/// exponent notation otherwise.
/// −0 reads as 0 (a multiplier of an unloaded joint).
fn number(out: &mut String, x: f64) {
    crate::decimal::push_number(out, x);
}

/// `x` as the CSV files write it (see [`to_csv`]): shortest round-trip form,
/// plain for `1e-4 ≤ |x| < 1e15` (and 0), exponent notation otherwise.
#[must_use]
pub fn format_number(x: f64) -> String {
    let mut out = String::new();
    number(&mut out, x);
    out
}

/// Appends one sample as a CSV row, `extra` values after the standard ones.
fn row(out: &mut String, s: &SampleRef<'_>, extra: &[f64]) {
    number(out, s.t);
    for &x in s.u.iter().chain(s.v).chain(s.a).chain(s.lambda) {
        out.push(',');
        number(out, x);
    }
    out.push(',');
    number(out, s.energy());
    let _ = write!(out, ",{},", s.iterations);
    number(out, s.residual);
    out.push(',');
    number(out, s.constraint);
    for &x in extra {
        out.push(',');
        number(out, x);
    }
    out.push('\n');
}

/// A sample's full row of values: the standard columns (`iterations` as a
/// number), then `extra`.
fn row_values(out: &mut Vec<f64>, s: &SampleRef<'_>, extra: &[f64]) {
    out.clear();
    out.push(s.t);
    out.extend(s.u.iter().chain(s.v).chain(s.a).chain(s.lambda));
    #[allow(clippy::cast_precision_loss)] // (iteration counts are small)
    out.extend([s.energy(), s.iterations as f64, s.residual, s.constraint]);
    out.extend_from_slice(extra);
}

/// The samples as CSV text (header first), numbers in shortest round-trip form.
#[must_use]
pub fn to_csv<S: System + ?Sized>(sys: &S, samples: &[Sample]) -> String {
    let mut out = header_line(sys);
    out.push('\n');
    for s in samples {
        row(&mut out, &s.view(), &[]);
    }
    out
}

/// Where an output file goes, by what its path names now.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Target {
    /// A new path or a regular file (the file a symbolic link names, for a
    /// link to one): written to a hidden temporary file beside it and renamed
    /// over it at the end, so that it is complete or untouched.
    Replace(PathBuf),
    /// Standard output: `-` or `/dev/stdout`.
    Stdout,
    /// Anything else that exists (a device such as `/dev/null`, a FIFO, a
    /// socket): written directly, never replaced.
    Direct,
}

/// How `path` is to be written (see [`Target`]).
///
/// # Errors
/// A directory (with a file name to use instead), or a path whose kind
/// cannot be read (permissions), with the path in the message.
pub fn target(path: &Path) -> io::Result<Target> {
    if path.as_os_str() == "-" || path == Path::new("/dev/stdout") {
        return Ok(Target::Stdout);
    }
    let kind = match std::fs::symlink_metadata(path) {
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(Target::Replace(path.into())),
        Err(e) => return Err(described(path, e)),
        Ok(m) => m.file_type(),
    };
    if kind.is_file() {
        return Ok(Target::Replace(path.into()));
    }
    if kind.is_symlink() {
        // Replace the file a link names (keeping the link), unless it leads
        // into /dev or /proc (`/dev/stderr`, `/proc/self/fd/1`): those are
        // written through the link.
        return match (std::fs::canonicalize(path), std::fs::metadata(path)) {
            (Ok(real), Ok(m))
                if m.is_file()
                    && !["/dev", "/proc"]
                        .iter()
                        .any(|d| path.starts_with(d) || real.starts_with(d)) =>
            {
                Ok(Target::Replace(real))
            }
            (_, Ok(m)) if m.is_dir() => Err(directory(path)),
            _ => Ok(Target::Direct),
        };
    }
    if kind.is_dir() {
        return Err(directory(path));
    }
    Ok(Target::Direct)
}

/// Refuses, before anything is written, an output `path` that names a
/// file its owner could not write (what writing it would refuse, for an
/// output written by other means: a picture, a model, a JSON file).
///
/// # Errors
/// `could not write P: it is read-only (mode 444); make it writable (chmod
/// u+w P) or name another file`.
pub fn refuse_read_only(path: &Path) -> io::Result<()> {
    match target(path) {
        Ok(Target::Replace(real)) => check_writable(path, &real),
        _ => Ok(()),
    }
}

/// Refuses to replace a file its owner could not write: one without write
/// permission (mode 444, even for root, who could), or one the user may not
/// write (access(2)); the rename would replace it all the same.
fn check_writable(path: &Path, target: &Path) -> io::Result<()> {
    let Ok(m) = std::fs::metadata(target) else {
        return Ok(());
    };
    if !m.permissions().readonly() && !access_denied(target) {
        return Ok(());
    }
    Err(io::Error::new(
        io::ErrorKind::PermissionDenied,
        format!(
            "could not write {}: it is read-only{}; make it writable (chmod u+w {}) or name another file",
            display(path),
            mode(&m),
            target.display()
        ),
    ))
}

/// Whether access(2) denies the user writing `target`.
#[cfg(unix)]
fn access_denied(target: &Path) -> bool {
    let c = std::ffi::CString::new(target.as_os_str().as_encoded_bytes()).ok();
    // SAFETY: `c` is a NUL-terminated path.
    c.is_some_and(|c| unsafe { libc::access(c.as_ptr(), libc::W_OK) } != 0)
}

/// Outside Unix, the read-only attribute alone says it.
#[cfg(not(unix))]
fn access_denied(_: &Path) -> bool {
    false
}

/// ` (mode 444)`: the file's permission bits, for the message.
#[cfg(unix)]
fn mode(m: &std::fs::Metadata) -> String {
    use std::os::unix::fs::PermissionsExt as _;
    format!(" (mode {:o})", m.permissions().mode() & 0o7777)
}

/// Nothing outside Unix (no permission bits).
#[cfg(not(unix))]
fn mode(_: &std::fs::Metadata) -> String {
    String::new()
}

/// Refuses standard output when it was closed (`>&-`): Rust's start-up
/// code then opens `/dev/null` in its place, read-write, and the rows would
/// be lost with a report of success. (A shell's `>/dev/null` opens it
/// write-only, and is written.)
#[cfg(unix)]
fn check_stdout() -> io::Result<()> {
    use std::os::unix::fs::MetadataExt as _;
    // SAFETY: fcntl(F_GETFL) only reads the descriptor's flags.
    let flags = unsafe { libc::fcntl(1, libc::F_GETFL) };
    let null = std::fs::metadata("/dev/null").map(|m| m.rdev()).ok();
    let stdout = std::fs::metadata("/proc/self/fd/1").map(|m| m.rdev()).ok();
    let replaced =
        flags != -1 && flags & libc::O_ACCMODE == libc::O_RDWR && null.is_some() && null == stdout;
    if flags == -1 || replaced {
        return Err(io::Error::new(
            io::ErrorKind::BrokenPipe,
            "could not write standard output: it was closed when mstar started",
        ));
    }
    Ok(())
}

/// Outside Unix a closed standard output is not told from an open one: a
/// failed write reports it.
#[cfg(not(unix))]
#[allow(clippy::unnecessary_wraps)]
fn check_stdout() -> io::Result<()> {
    Ok(())
}

/// The error for an output path that names a directory, with a file to name
/// instead.
fn directory(path: &Path) -> io::Error {
    io::Error::new(
        io::ErrorKind::IsADirectory,
        format!(
            "could not write {}: it is a directory; name a file in it, e.g. {}",
            path.display(),
            path.join("run.csv").display()
        ),
    )
}

/// `e` with the output's name in front.
fn described(path: &Path, e: io::Error) -> io::Error {
    io::Error::new(e.kind(), format!("could not write {}: {e}", display(path)))
}

/// An output path for messages: `-` is standard output.
#[must_use]
pub fn display(path: &Path) -> String {
    if path.as_os_str() == "-" {
        "standard output".to_string()
    } else {
        path.display().to_string()
    }
}

/// Rows are handed to the target in chunks of about this many bytes: whole
/// rows, so that a failed write leaves the file at a row boundary.
const CHUNK: usize = 1 << 16;

/// A CSV file written sample by sample (for runs too large to keep in
/// memory). A regular file is complete or not at all: rows go to a hidden
/// temporary file beside the target (`.<name>.<pid>.tmp`), which
/// [`finish`](Self::finish) renames into place, and which is removed when the
/// stream is dropped unfinished; [`keep_partial`](Self::keep_partial) keeps
/// the rows written so far under another name instead. Devices, FIFOs and
/// standard output are written directly (see [`Target`]).
///
/// The first I/O error is kept: [`failed`](Self::failed) tells a run to stop,
/// and every later row is dropped.
#[derive(Debug)]
pub struct CsvStream {
    path: PathBuf,
    /// The `.npz` layout, for an `.npz` path (rows as doubles, not text).
    npz: Option<crate::npz::Npz>,
    /// The columns written (indices into the full row), `None`: all.
    selection: Option<Vec<usize>>,
    /// How many standard columns a full row has (the extra ones follow).
    standard: usize,
    /// A full row's values, when a selection picks from them.
    values: Vec<f64>,
    sink: Option<Sink>,
    line: String,
    /// Whole rows not yet handed to the target.
    buffer: Vec<u8>,
    buffered_rows: usize,
    /// Rows pushed, and rows (and their bytes, the header included) that
    /// reached the target.
    rows: usize,
    rows_out: usize,
    bytes_out: u64,
    error: Option<io::Error>,
    removed: Vec<PathBuf>,
}

/// Where a [`CsvStream`]'s bytes go.
enum Sink {
    Temporary {
        file: std::fs::File,
        tmp: PathBuf,
        target: PathBuf,
    },
    Direct(Box<dyn io::Write>),
}

impl std::fmt::Debug for Sink {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Temporary { tmp, target, .. } => f
                .debug_struct("Temporary")
                .field("tmp", tmp)
                .field("target", target)
                .finish_non_exhaustive(),
            Self::Direct(_) => f.write_str("Direct"),
        }
    }
}

/// What [`CsvStream::keep_partial`] kept.
#[derive(Debug)]
pub enum Kept {
    /// The rows that reached the disk, under the partial file's name.
    File {
        /// The partial file.
        path: PathBuf,
        /// Its rows (after the header).
        rows: usize,
    },
    /// The rows went straight to a device, a FIFO or standard output.
    Streamed {
        /// How many reached it.
        rows: usize,
    },
    /// Nothing could be kept: why.
    Nothing(io::Error),
}

impl CsvStream {
    /// Opens the output (see [`Target`]) and writes the header.
    ///
    /// # Errors
    /// Any I/O error, with the path in the message.
    pub fn create<S: System + ?Sized>(path: &Path, sys: &S) -> io::Result<Self> {
        Self::create_with(path, sys, &[])
    }

    /// [`create`](Self::create) with `extra` column names after the standard
    /// ones (their values go to [`push_with`](Self::push_with)).
    ///
    /// # Errors
    /// Any I/O error, with the path in the message.
    pub fn create_with<S: System + ?Sized>(
        path: &Path,
        sys: &S,
        extra: &[String],
    ) -> io::Result<Self> {
        Self::create_selected(path, sys, extra, None)
    }

    /// [`create_with`](Self::create_with) writing only the columns of
    /// `selection` (indices into the standard header followed by `extra`;
    /// `None`: all of them).
    ///
    /// # Errors
    /// Any I/O error, with the path in the message.
    pub fn create_selected<S: System + ?Sized>(
        path: &Path,
        sys: &S,
        extra: &[String],
        selection: Option<&Selection>,
    ) -> io::Result<Self> {
        let mut removed = Vec::new();
        let binary = is_npz(path);
        let sink = match target(path)? {
            Target::Stdout | Target::Direct if binary => {
                return Err(io::Error::new(
                    io::ErrorKind::InvalidInput,
                    format!(
                        "{}: an .npz output must be a regular file (its end is written last); \
                         write CSV to a pipe or standard output",
                        path.display()
                    ),
                ));
            }
            Target::Replace(target) => {
                check_writable(path, &target)?;
                removed = remove_leftovers(&target);
                let tmp = temporary_path(&target);
                // (Read too: a partial `.npz` reads its rows back for their CRC.)
                let file = std::fs::OpenOptions::new()
                    .read(true)
                    .write(true)
                    .create(true)
                    .truncate(true)
                    .open(&tmp)
                    .map_err(|e| described(path, e))?;
                // A replaced file keeps its permissions.
                if let Ok(m) = std::fs::metadata(&target) {
                    let _ = file.set_permissions(m.permissions());
                }
                Sink::Temporary { file, tmp, target }
            }
            Target::Stdout => {
                check_stdout()?;
                Sink::Direct(Box::new(io::stdout()))
            }
            Target::Direct => Sink::Direct(Box::new(
                std::fs::File::create(path).map_err(|e| described(path, e))?,
            )),
        };
        let mut names = header(sys);
        names.extend_from_slice(extra);
        let standard = header_len(sys);
        let selection = selection.map(|s| s.indices().to_vec());
        if let Some(chosen) = &selection {
            names = chosen
                .iter()
                .filter_map(|&i| names.get(i).cloned())
                .collect();
        }
        let (npz, head, line) = if binary {
            let (npz, head) = crate::npz::Npz::head(&names);
            (Some(npz), head, String::new())
        } else {
            let mut line = join_fields(&names);
            line.push('\n');
            (None, line.clone().into_bytes(), line)
        };
        Ok(Self {
            path: path.to_path_buf(),
            npz,
            selection,
            standard,
            values: Vec::new(),
            sink: Some(sink),
            buffer: head,
            line,
            buffered_rows: 0,
            rows: 0,
            rows_out: 0,
            bytes_out: 0,
            error: None,
            removed,
        })
    }

    /// Temporary files of earlier runs on the same target that were killed
    /// before they could clean up, removed by [`create`](Self::create).
    #[must_use]
    pub fn removed_leftovers(&self) -> &[PathBuf] {
        &self.removed
    }

    /// Appends a sample.
    pub fn push(&mut self, s: &SampleRef<'_>) {
        self.push_with(s, &[]);
    }

    /// Appends a sample and the values of the extra columns (nothing once a
    /// write has failed).
    pub fn push_with(&mut self, s: &SampleRef<'_>, extra: &[f64]) {
        if self.error.is_some() {
            return;
        }
        if self.npz.is_some() {
            self.push_binary(s, extra);
            return;
        }
        self.line.clear();
        match &self.selection {
            None => row(&mut self.line, s, extra),
            Some(chosen) => {
                row_values(&mut self.values, s, extra);
                let mut first = true;
                for &i in chosen {
                    if !first {
                        self.line.push(',');
                    }
                    first = false;
                    number(
                        &mut self.line,
                        self.values.get(i).copied().unwrap_or(f64::NAN),
                    );
                }
                self.line.push('\n');
            }
        }
        self.buffer.extend_from_slice(self.line.as_bytes());
        self.rows += 1;
        self.buffered_rows += 1;
        if self.buffer.len() >= CHUNK {
            self.flush_buffer();
        }
    }

    /// Appends a sample's row as doubles (`.npz`).
    fn push_binary(&mut self, s: &SampleRef<'_>, extra: &[f64]) {
        row_values(&mut self.values, s, extra);
        let values = &self.values;
        match &self.selection {
            None => crate::npz::Npz::encode(values.iter().copied(), &mut self.buffer),
            Some(chosen) => crate::npz::Npz::encode(
                chosen
                    .iter()
                    .map(|&i| values.get(i).copied().unwrap_or(f64::NAN)),
                &mut self.buffer,
            ),
        }
        self.rows += 1;
        self.buffered_rows += 1;
        if self.buffer.len() >= CHUNK {
            self.flush_buffer();
        }
    }

    /// Which extra columns the rows write (`None`: all of them), for
    /// [`Columns::values_wanted`].
    #[must_use]
    pub fn extra_wanted(&self, extra: usize) -> Option<Vec<bool>> {
        let chosen = self.selection.as_ref()?;
        let mut wanted = vec![false; extra];
        for &i in chosen {
            if let Some(w) = i.checked_sub(self.standard).and_then(|k| wanted.get_mut(k)) {
                *w = true;
            }
        }
        Some(wanted)
    }

    /// Whether the rows need the extra columns' values (a selection may
    /// leave them all out, and save computing them).
    #[must_use]
    pub fn needs_extra(&self) -> bool {
        self.selection
            .as_ref()
            .is_none_or(|chosen| chosen.last().is_some_and(|&i| i >= self.standard))
    }

    /// Hands the buffered rows to the target now; `false` when a write has
    /// failed (then [`keep_partial`](Self::keep_partial) keeps what got
    /// through).
    pub fn write_pending(&mut self) -> bool {
        self.flush_buffer();
        self.error.is_none()
    }

    /// Whether a write has failed (the run should stop: later rows are lost).
    #[must_use]
    pub fn failed(&self) -> bool {
        self.error.is_some()
    }

    /// The rows pushed so far (after the header).
    #[must_use]
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// Hands the buffered rows to the target; on an error, keeps it.
    fn flush_buffer(&mut self) {
        if self.error.is_some() || self.buffer.is_empty() {
            return;
        }
        let (done, result) = match self.sink.as_mut() {
            Some(Sink::Temporary { file, .. }) => write_counted(file, &self.buffer),
            Some(Sink::Direct(w)) => match write_counted(w, &self.buffer) {
                (done, Ok(())) => (done, w.flush()),
                failed => failed,
            },
            None => (self.buffer.len(), Ok(())),
        };
        match result {
            Ok(()) => {
                if let Some(npz) = &mut self.npz {
                    // (The first chunk begins with the head.)
                    let head = npz.rows_at().saturating_sub(self.bytes_out);
                    let head = usize::try_from(head)
                        .unwrap_or(usize::MAX)
                        .min(self.buffer.len());
                    npz.written(&self.buffer[head..]);
                }
                self.bytes_out += self.buffer.len() as u64;
                self.rows_out += self.buffered_rows;
            }
            Err(e) if self.npz.is_some() => {
                // Whole rows after the head; the CRC is worked out again
                // from the file when it is kept ([`keep_partial`]).
                self.bytes_out += done as u64;
                let rows_at = self.npz.as_ref().map_or(0, crate::npz::Npz::rows_at);
                let row = self.npz.as_ref().map_or(1, crate::npz::Npz::row_bytes) as u64;
                self.rows_out =
                    usize::try_from(self.bytes_out.saturating_sub(rows_at) / row.max(1))
                        .unwrap_or(usize::MAX);
                self.error = Some(e);
            }
            Err(e) => {
                // The whole rows that got through (a full disk takes part
                // of a chunk): the partial file ends after them.
                let cut = self.buffer[..done]
                    .iter()
                    .rposition(|&b| b == b'\n')
                    .map_or(0, |i| i + 1);
                let lines = self.buffer[..cut].iter().filter(|&&b| b == b'\n').count();
                let header = usize::from(self.bytes_out == 0 && cut > 0);
                self.rows_out += lines - header;
                self.bytes_out += cut as u64;
                self.error = Some(e);
            }
        }
        self.buffer.clear();
        self.buffered_rows = 0;
    }

    /// Writes what is left and renames the file into place; returns the rows
    /// written (after the header).
    ///
    /// # Errors
    /// The first I/O error of the whole stream, with the path; a replaced
    /// file is then untouched.
    pub fn finish(mut self) -> io::Result<usize> {
        self.flush_buffer();
        if let Some(e) = self.error.take() {
            return Err(described(&self.path, e));
        }
        match self.sink.take() {
            Some(Sink::Temporary {
                mut file,
                tmp,
                target,
            }) => {
                let ended = match &mut self.npz {
                    Some(npz) => npz.finish(&mut file, self.rows_out as u64, false),
                    None => Ok(()),
                };
                let done = ended
                    .and_then(|()| file.sync_all())
                    .and_then(|()| std::fs::rename(&tmp, &target));
                if let Err(e) = done {
                    let _ = std::fs::remove_file(&tmp);
                    return Err(described(&self.path, e));
                }
            }
            Some(Sink::Direct(mut w)) => w.flush().map_err(|e| described(&self.path, e))?,
            None => {}
        }
        Ok(self.rows)
    }

    /// Keeps the rows that reached the disk (or as many whole rows as a full
    /// disk let through) as `partial` instead of the target: for a run that
    /// stopped before its end. A device, FIFO or standard output has had the
    /// rows as they came.
    pub fn keep_partial(mut self, partial: &Path) -> Kept {
        self.flush_buffer();
        match self.sink.take() {
            Some(Sink::Temporary { mut file, tmp, .. }) => {
                // A failed write may have left part of a chunk: cut it off.
                let ended = match &mut self.npz {
                    _ if self.bytes_out == 0 => {
                        Err(io::Error::other("not even the header reached the disk"))
                    }
                    Some(npz) => end_partial_npz(npz, &mut file, &mut self.rows_out),
                    None => file.set_len(self.bytes_out),
                };
                let kept = ended
                    .and_then(|()| file.sync_all())
                    .and_then(|()| std::fs::rename(&tmp, partial));
                match kept {
                    Ok(()) => Kept::File {
                        path: partial.to_path_buf(),
                        rows: self.rows_out,
                    },
                    Err(e) => {
                        let _ = std::fs::remove_file(&tmp);
                        Kept::Nothing(described(partial, e))
                    }
                }
            }
            Some(Sink::Direct(mut w)) => {
                let _ = w.flush();
                Kept::Streamed {
                    rows: self.rows_out,
                }
            }
            None => Kept::Streamed { rows: 0 },
        }
    }

    /// The first write error, with the path, if any.
    #[must_use]
    pub fn error(&self) -> Option<io::Error> {
        self.error
            .as_ref()
            .map(|e| described(&self.path, io::Error::new(e.kind(), e.to_string())))
    }
}

impl Observer for CsvStream {
    /// Appends every observed sample ([`push`](Self::push)).
    fn observe(&mut self, sample: &SampleRef<'_>) {
        self.push(sample);
    }
}

impl Drop for CsvStream {
    fn drop(&mut self) {
        if let Some(Sink::Temporary { tmp, .. }) = self.sink.take() {
            let _ = std::fs::remove_file(&tmp);
        }
    }
}

/// Ends a partial `.npz` after the rows that reached the disk; when the
/// disk has no room for the archive's end, with as many rows fewer as free
/// its room.
fn end_partial_npz(
    npz: &mut crate::npz::Npz,
    file: &mut std::fs::File,
    rows: &mut usize,
) -> io::Result<()> {
    let row = npz.row_bytes().max(1);
    let fewer = npz.tail_len().div_ceil(row);
    match npz.finish(file, *rows as u64, true) {
        Ok(()) => Ok(()),
        Err(e) if *rows >= fewer && is_full(&e) => {
            *rows -= fewer;
            npz.finish(file, *rows as u64, true)
        }
        Err(e) => Err(e),
    }
}

/// Whether `e` says the disk (or the quota) is full.
fn is_full(e: &io::Error) -> bool {
    matches!(
        e.kind(),
        io::ErrorKind::StorageFull | io::ErrorKind::QuotaExceeded | io::ErrorKind::WriteZero
    )
}

/// Whether `path` names an `.npz` file (the binary output; any case).
#[must_use]
pub fn is_npz(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("npz"))
}

/// Writes `buf` as `write_all` does, and tells how many bytes got through
/// when it fails.
fn write_counted(w: &mut dyn io::Write, buf: &[u8]) -> (usize, io::Result<()>) {
    let mut done = 0;
    while done < buf.len() {
        match w.write(&buf[done..]) {
            Ok(0) => return (done, Err(io::ErrorKind::WriteZero.into())),
            Ok(n) => done += n,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) => return (done, Err(e)),
        }
    }
    (done, Ok(()))
}

/// The temporary file beside `path`: `.<name>.<pid>.tmp`, hidden, and
/// recognisable by [`remove_leftovers`] when a killed run leaves it behind.
fn temporary_path(path: &Path) -> PathBuf {
    let (dir, name) = dir_and_name(path);
    dir.join(format!(".{name}.{}.tmp", std::process::id()))
}

fn dir_and_name(path: &Path) -> (PathBuf, String) {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "output".into());
    (dir, name)
}

/// Removes the temporary files of `path` that runs killed outright
/// (`kill -9`, a power cut) left behind: `.<name>.<pid>.tmp` beside it whose
/// process no longer exists. Returns what it removed. Where the processes
/// cannot be listed (no `/proc`), nothing is removed.
pub fn remove_leftovers(path: &Path) -> Vec<PathBuf> {
    let proc = Path::new("/proc");
    if !proc.join("self").exists() {
        return Vec::new();
    }
    let (dir, name) = dir_and_name(path);
    let prefix = format!(".{name}.");
    let Ok(entries) = std::fs::read_dir(&dir) else {
        return Vec::new();
    };
    let mut removed = Vec::new();
    for entry in entries.flatten() {
        let file = entry.file_name().to_string_lossy().into_owned();
        let Some(pid) = file
            .strip_prefix(&prefix)
            .and_then(|rest| rest.strip_suffix(".tmp"))
        else {
            continue;
        };
        let is_pid = !pid.is_empty() && pid.bytes().all(|b| b.is_ascii_digit());
        let regular = entry.file_type().is_ok_and(|t| t.is_file());
        if is_pid && regular && pid != std::process::id().to_string() && !proc.join(pid).exists() {
            let leftover = dir.join(&file);
            if std::fs::remove_file(&leftover).is_ok() {
                removed.push(leftover);
            }
        }
    }
    removed
}

/// Writes `contents` to `path`: a new path or a regular file completely or
/// not at all (to a temporary file in the same directory first, then renamed
/// over `path`); a device, FIFO or standard output directly (see [`Target`]).
///
/// # Errors
/// Any I/O error, with the path in the message; a regular file is then
/// untouched.
pub fn write_atomically(path: &Path, contents: &[u8]) -> io::Result<()> {
    let target = match target(path)? {
        Target::Replace(target) => target,
        Target::Stdout => {
            check_stdout()?;
            let mut out = io::stdout().lock();
            return out
                .write_all(contents)
                .and_then(|()| out.flush())
                .map_err(|e| described(path, e));
        }
        Target::Direct => {
            return std::fs::File::create(path)
                .and_then(|mut f| f.write_all(contents))
                .map_err(|e| described(path, e));
        }
    };
    check_writable(path, &target)?;
    remove_leftovers(&target);
    let tmp = temporary_path(&target);
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        if let Ok(m) = std::fs::metadata(&target) {
            let _ = f.set_permissions(m.permissions());
        }
        f.write_all(contents)?;
        f.sync_all()?;
        std::fs::rename(&tmp, &target)
    })();
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(described(path, e));
    }
    Ok(())
}

/// Writes the samples as CSV to `path` (see [`write_atomically`]).
///
/// # Errors
/// Any I/O error, with the path in the message.
pub fn write_csv<S: System + ?Sized>(path: &Path, sys: &S, samples: &[Sample]) -> io::Result<()> {
    write_atomically(path, to_csv(sys, samples).as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;
    use mstar_model::PendulumChain;

    #[test]
    fn header_follows_the_column_scheme() {
        let sys = PendulumChain::paper(1.0, 1.0, 10.0);
        assert_eq!(
            header(&sys).join(","),
            "t,u:x,u:y,u:theta,v:x,v:y,v:theta,a:x,a:y,a:theta,lambda:rod.x,lambda:rod.y,energy,iterations,residual,constraint"
        );
        let s = Sample {
            t: 0.5,
            u: vec![1.0, 2.0, 3.0],
            v: vec![0.0; 3],
            a: vec![0.0; 3],
            lambda: vec![-10.0, 0.25],
            kinetic: 1.0,
            potential: 2.0,
            iterations: 3,
            residual: 1e-12,
            constraint: 0.0,
        };
        let text = to_csv(&sys, &[s]);
        let row = text.lines().nth(1).expect("one row");
        assert_eq!(row, "0.5,1,2,3,0,0,0,0,0,0,-10,0.25,3,3,1e-12,0");
        assert_eq!(header_len(&sys), header(&sys).len());
    }

    /// The counts without names are the numbers of names (a model with a
    /// driver: joints' reactions and the driver's effort).
    #[test]
    fn counts_are_those_of_the_names() {
        use mstar_file::{Format, MechanismFile};
        let text = include_str!("../../../models/slider-crank.toml");
        let file = MechanismFile::parse(text, "slider-crank.toml", Format::Toml).expect("valid");
        let sys = crate::run::lookup(&file.mechanism);
        assert_eq!(header_len(sys), header(sys).len());
        let columns = crate::columns::ReactionColumns::new(sys);
        let names = columns.names();
        assert!(names.iter().any(|n| n.starts_with("effort:")), "{names:?}");
        assert_eq!(columns.count(), names.len());
    }

    #[test]
    fn names_with_commas_and_quotes_are_quoted() {
        let sys = mstar_model::FnSystem::new(
            vec![1.0, 1.0],
            1,
            |_, u, p| p[0] = u[0],
            |_, _, b| b.copy_from_slice(&[1.0, 0.0]),
        )
        .with_names(&["a,b", "say \"hi\""], &["c"])
        .expect("names");
        let line = header_line(&sys);
        assert!(
            line.starts_with("t,\"u:a,b\",\"u:say \"\"hi\"\"\",\"v:a,b\""),
            "{line}"
        );
        // Nine fields once the quoted ones are taken whole.
        let mut fields = 0;
        let mut quoted = false;
        for c in line.chars() {
            match c {
                '"' => quoted = !quoted,
                ',' if !quoted => fields += 1,
                _ => {}
            }
        }
        assert_eq!(fields + 1, header(&sys).len());
    }

    #[test]
    fn stream_is_complete_or_absent() {
        let sys = PendulumChain::paper(1.0, 1.0, 10.0);
        let dir = std::env::temp_dir().join(format!("mstar-stream-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let path = dir.join("run.csv");
        let sample = Sample {
            u: vec![0.0; 3],
            v: vec![0.0; 3],
            a: vec![0.0; 3],
            lambda: vec![0.0; 2],
            ..Sample::default()
        };
        let mut unfinished = CsvStream::create(&path, &sys).expect("create");
        unfinished.push(&sample.view());
        drop(unfinished);
        assert!(!path.exists());
        assert_eq!(
            std::fs::read_dir(&dir).expect("dir").count(),
            0,
            "temporary file left"
        );
        let mut stream = CsvStream::create(&path, &sys).expect("create");
        stream.push(&sample.view());
        stream.observe(&sample.view());
        stream.finish().expect("finish");
        let text = std::fs::read_to_string(&path).expect("written");
        assert_eq!(text, to_csv(&sys, &[sample.clone(), sample]));
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn failed_write_leaves_nothing() {
        let dir = std::env::temp_dir().join(format!("mstar-csv-{}", std::process::id()));
        let missing = dir.join("no-such-dir").join("out.csv");
        assert!(write_atomically(&missing, b"x").is_err());
        assert!(!missing.exists());
    }
}
