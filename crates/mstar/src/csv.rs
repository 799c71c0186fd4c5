//! CSV output with one column scheme for every model, written atomically.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::Path;

use mstar_model::{Sample, SampleRef, System, coord_names};
use mstar_newmark::Observer;

/// The CSV header: `t`, then `u:<name>`, `v:<name>`, `a:<name>` for each
/// coordinate, `lambda:<i>` for each multiplier (0-based), then `energy`,
/// `iterations`, `residual`, `constraint`.
#[must_use]
pub fn header<S: System + ?Sized>(sys: &S) -> Vec<String> {
    let names = coord_names(sys);
    let mut h = vec!["t".to_string()];
    for prefix in ["u", "v", "a"] {
        h.extend(names.iter().map(|n| format!("{prefix}:{n}")));
    }
    h.extend((0..sys.n_constraints()).map(|i| format!("lambda:{i}")));
    h.extend(["energy", "iterations", "residual", "constraint"].map(String::from));
    h
}

/// Columns a model adds after the standard ones (e.g. reactions by joint,
/// see [`crate::run::ReactionColumns`]).
pub trait Columns {
    /// Their header names.
    fn names(&self) -> Vec<String>;

    /// Their values at a sample, appended to `out` (as many as `names`).
    fn values(&self, s: &SampleRef<'_>, out: &mut Vec<f64>);
}

/// The header as one CSV line (without the newline): names from model files
/// may hold commas or quotes, so such fields are quoted (RFC 4180: in double
/// quotes, inner quotes doubled).
#[must_use]
pub fn header_line<S: System + ?Sized>(sys: &S) -> String {
    join_fields(&header(sys))
}

fn join_fields(names: &[String]) -> String {
    names.iter().map(|f| field(f)).collect::<Vec<_>>().join(",")
}

/// One CSV field, quoted when it holds a comma, a quote or a line break.
fn field(s: &str) -> std::borrow::Cow<'_, str> {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\"")).into()
    } else {
        s.into()
    }
}

/// A number in shortest round-trip form: plain for `1e-4 ≤ |x| < 1e15` (and 0),
/// exponent notation otherwise.
fn number(out: &mut String, x: f64) {
    // −0 reads as 0 (a multiplier of an unloaded joint).
    let x = if x == 0.0 { 0.0 } else { x };
    let a = x.abs();
    if x == 0.0 || (1e-4..1e15).contains(&a) || !x.is_finite() {
        let _ = write!(out, "{x}");
    } else {
        let _ = write!(out, "{x:e}");
    }
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

/// A CSV file written sample by sample (for runs too large to keep in memory),
/// complete or not at all: rows go to a temporary file beside the target, which
/// [`CsvStream::finish`] renames into place; dropped unfinished, the temporary
/// file is removed.
#[derive(Debug)]
pub struct CsvStream {
    path: std::path::PathBuf,
    tmp: std::path::PathBuf,
    file: Option<std::io::BufWriter<std::fs::File>>,
    line: String,
    error: Option<std::io::Error>,
}

impl CsvStream {
    /// Creates the temporary file and writes the header.
    ///
    /// # Errors
    /// Any I/O error, with the path in the message.
    pub fn create<S: System + ?Sized>(path: &Path, sys: &S) -> std::io::Result<Self> {
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
    ) -> std::io::Result<Self> {
        let tmp = temporary_path(path);
        let with_path = |e: std::io::Error| {
            std::io::Error::new(e.kind(), format!("could not write {}: {e}", path.display()))
        };
        let mut file = std::io::BufWriter::new(std::fs::File::create(&tmp).map_err(with_path)?);
        let mut names = header(sys);
        names.extend_from_slice(extra);
        let mut line = join_fields(&names);
        line.push('\n');
        file.write_all(line.as_bytes()).map_err(with_path)?;
        Ok(Self {
            path: path.to_path_buf(),
            tmp,
            file: Some(file),
            line,
            error: None,
        })
    }

    /// Appends a sample (the first I/O error is kept and reported by `finish`).
    pub fn push(&mut self, s: &SampleRef<'_>) {
        self.push_with(s, &[]);
    }

    /// Appends a sample and the values of the extra columns.
    pub fn push_with(&mut self, s: &SampleRef<'_>, extra: &[f64]) {
        if self.error.is_some() {
            return;
        }
        self.line.clear();
        row(&mut self.line, s, extra);
        if let Some(f) = self.file.as_mut()
            && let Err(e) = f.write_all(self.line.as_bytes())
        {
            self.error = Some(e);
        }
    }

    /// Flushes and renames the file into place.
    ///
    /// # Errors
    /// The first I/O error of the whole stream, with the path; the target is
    /// then untouched.
    pub fn finish(self) -> std::io::Result<()> {
        let path = self.path.clone();
        self.finish_as(&path)
    }

    /// Flushes and renames the file to `path` instead of the target (e.g.
    /// `<name>.partial.csv` when a run fails).
    ///
    /// # Errors
    /// As [`finish`](Self::finish).
    pub fn finish_as(mut self, path: &Path) -> std::io::Result<()> {
        let result = match (self.error.take(), self.file.take()) {
            (Some(e), _) => Err(e),
            (None, Some(mut f)) => f
                .flush()
                .and_then(|()| f.get_ref().sync_all())
                .and_then(|()| std::fs::rename(&self.tmp, path)),
            (None, None) => Ok(()),
        };
        result.map_err(|e| {
            std::io::Error::new(e.kind(), format!("could not write {}: {e}", path.display()))
        })
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
        if self.file.take().is_some() || self.error.is_some() {
            let _ = std::fs::remove_file(&self.tmp);
        }
    }
}

fn temporary_path(path: &Path) -> std::path::PathBuf {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => std::path::PathBuf::from("."),
    };
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "output".into());
    dir.join(format!(".{name}.{}.tmp", std::process::id()))
}

/// Writes `contents` to `path` completely or not at all: to a temporary file in
/// the same directory first, then renamed over `path`.
///
/// # Errors
/// Any I/O error, with the path in the message; `path` is then untouched.
pub fn write_atomically(path: &Path, contents: &[u8]) -> std::io::Result<()> {
    let tmp = temporary_path(path);
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(contents)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(std::io::Error::new(
            e.kind(),
            format!("could not write {}: {e}", path.display()),
        ));
    }
    Ok(())
}

/// Writes the samples as CSV to `path`, atomically (see [`write_atomically`]).
///
/// # Errors
/// Any I/O error, with the path in the message.
pub fn write_csv<S: System + ?Sized>(
    path: &Path,
    sys: &S,
    samples: &[Sample],
) -> std::io::Result<()> {
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
            "t,u:x,u:y,u:theta,v:x,v:y,v:theta,a:x,a:y,a:theta,lambda:0,lambda:1,energy,iterations,residual,constraint"
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
