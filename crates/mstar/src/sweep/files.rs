//! The files of a sweep's directory: `sweep.toml` (the plan), `runs/` (each
//! run's CSV file and summary row), the summaries, and their merge.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use super::{Combine, Param, Plan, RunOutcome, SweepError};

/// `sweep.toml`'s `format`.
const FORMAT: &str = "mstar.sweep/1";

/// The summary's columns: `index`, each swept key, `status` (`ok` or why
/// the run failed), `t` (the time reached), `u:<coordinate>` for each
/// coordinate (its last value), `max_constraint` (max ‖Φ‖∞), `energy_drift`
/// (max |E − E₀|, J), `steps` (accepted; empty for a failed run), and last
/// `wall_time_s`, the only column that differs between two sweeps of one
/// plan.
#[must_use]
pub fn summary_header(plan: &Plan) -> Vec<String> {
    let mut h = vec!["index".to_string()];
    h.extend(plan.params().iter().map(|p| p.key.clone()));
    h.extend(["status", "t"].map(String::from));
    h.extend(plan.coords.iter().map(|c| format!("u:{c}")));
    h.extend(plan.sensors.iter().cloned());
    h.extend(["max_constraint", "energy_drift", "steps", WALL].map(String::from));
    h
}

/// The wall-time column.
const WALL: &str = "wall_time_s";

/// What `sweep.toml` records: what a rerun and a merge check.
#[derive(Debug, PartialEq, serde::Serialize, serde::Deserialize)]
struct Record {
    format: String,
    /// The model file as given (for people; not compared).
    model: String,
    /// FNV-1a of the model file's text and of the files it reads, in hex
    /// ([`fingerprint`]).
    model_fnv1a: String,
    combine: Combine,
    runs: usize,
    /// The summary's header.
    columns: Vec<String>,
    param: Vec<Param>,
}

impl Record {
    fn of(plan: &Plan) -> Self {
        Self {
            format: FORMAT.to_string(),
            model: plan.model().display().to_string(),
            model_fnv1a: format!("{:016x}", fingerprint(plan)),
            combine: plan.combine(),
            runs: plan.len(),
            columns: summary_header(plan),
            param: plan.params().to_vec(),
        }
    }

    /// Whether `self` is the plan `other` (the model's path aside).
    fn same_plan(&self, other: &Self) -> bool {
        (
            &self.format,
            &self.model_fnv1a,
            self.combine,
            self.runs,
            &self.param,
        ) == (
            &other.format,
            &other.model_fnv1a,
            other.combine,
            other.runs,
            &other.param,
        )
    }

    fn read(dir: &Path) -> Result<Self, SweepError> {
        let path = dir.join("sweep.toml");
        let text = std::fs::read_to_string(&path).map_err(|e| io(&path, e))?;
        toml::from_str(&text).map_err(|e| SweepError::Corrupt {
            path,
            why: format!("not a sweep's record: {}", e.message()),
        })
    }
}

/// The model's fingerprint: FNV-1a of the model file's text, continued
/// over the text of each file it reads (a spatial file's URDF,
/// [`mstar_file::included_files`]): a rerun after either changed would mix
/// another model's runs in. A model that reads no other file keeps the
/// fingerprint of its text alone.
fn fingerprint(plan: &Plan) -> u64 {
    let mut h = fnv1a(FNV_OFFSET, plan.text.as_bytes());
    for path in mstar_file::included_files(plan.model()) {
        // (A file that cannot be read fingerprints as empty; the run then
        // reports it.)
        h = fnv1a(h, &std::fs::read(&path).unwrap_or_default());
    }
    h
}

/// FNV-1a's offset basis.
const FNV_OFFSET: u64 = 0xcbf2_9ce4_8422_2325;

/// 64-bit FNV-1a of `bytes`, from the state `h`: a stable fingerprint.
fn fnv1a(h: u64, bytes: &[u8]) -> u64 {
    bytes
        .iter()
        .fold(h, |h, &b| (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3))
}

fn io(path: &Path, source: std::io::Error) -> SweepError {
    SweepError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// A sweep's output directory, checked against the plan.
#[derive(Debug)]
pub(super) struct Dir {
    path: PathBuf,
    columns: usize,
}

impl Dir {
    /// Creates `out/runs` and records the plan in `out/sweep.toml`, or
    /// checks that the one recorded there is this plan.
    pub(super) fn prepare(out: &Path, plan: &Plan) -> Result<Self, SweepError> {
        let runs = out.join("runs");
        std::fs::create_dir_all(&runs).map_err(|e| io(&runs, e))?;
        let record = Record::of(plan);
        let path = out.join("sweep.toml");
        if path.exists() {
            if !Record::read(out)?.same_plan(&record) {
                return Err(SweepError::OtherSweep(out.to_path_buf()));
            }
        } else {
            let text = toml::to_string(&record).map_err(|e| SweepError::Corrupt {
                path: path.clone(),
                why: e.to_string(),
            })?;
            crate::csv::write_atomically(&path, text.as_bytes()).map_err(|e| io(&path, e))?;
        }
        Ok(Self {
            path: out.to_path_buf(),
            columns: record.columns.len(),
        })
    }

    /// The directory.
    pub(super) fn path(&self) -> &Path {
        &self.path
    }

    /// Run `index`'s CSV file.
    pub(super) fn csv(&self, index: usize) -> PathBuf {
        self.path.join("runs").join(format!("{index}.csv"))
    }

    /// Where a failed run `index` keeps its samples.
    pub(super) fn partial(&self, index: usize) -> PathBuf {
        self.path.join("runs").join(format!("{index}.partial.csv"))
    }

    fn row_path(&self, index: usize) -> PathBuf {
        self.path.join("runs").join(format!("{index}.row"))
    }

    /// Run `index`'s summary row when the run is complete: its row file
    /// holds the row of this run of this plan (`values`: the plan's values
    /// of run `index`), and for a run that reached its end `runs/<index>.csv`
    /// is in place with the size its row file records. Otherwise what is
    /// missing or wrong, naming the file.
    pub(super) fn check(&self, index: usize, values: &[&str]) -> Result<Row, String> {
        let path = self.row_path(index);
        let text = std::fs::read_to_string(&path)
            .map_err(|e| format!("{}: {e} (the run has not finished)", path.display()))?;
        let k = values.len();
        let row = Row::parse_file(&text, k)
            .filter(|r| r.index == index && r.fields.len() == self.columns)
            .ok_or_else(|| format!("{} is not a row of run {index}", path.display()))?;
        if !row.fields[1..=k].iter().zip(values).all(|(a, b)| a == b) {
            return Err(format!(
                "{} holds the values {} where this sweep's plan (sweep.toml) has {}",
                path.display(),
                row.fields[1..=k].join(", "),
                values.join(", ")
            ));
        }
        if row.error().is_some() {
            return Ok(row);
        }
        let csv = self.csv(index);
        let size = std::fs::metadata(&csv)
            .map_err(|e| format!("{}: {e}", csv.display()))?
            .len();
        match row.csv_bytes {
            Some(n) if n == size => Ok(row),
            Some(n) => Err(format!(
                "{} has {size} bytes where {} records {n}: it is incomplete or not this run's",
                csv.display(),
                path.display()
            )),
            None => Err(format!(
                "{} records no size of {}",
                path.display(),
                csv.display()
            )),
        }
    }

    /// Writes run `index`'s row file (after its CSV file is in place): the
    /// summary row, then `csv_bytes,<size of runs/<index>.csv>` when it has
    /// one.
    pub(super) fn save(&self, row: &Row) -> Result<(), SweepError> {
        let path = self.row_path(row.index);
        let mut text = line(&row.fields)?;
        if let Some(n) = row.csv_bytes {
            text.push_str(&format!("{CSV_BYTES},{n}\n"));
        }
        crate::csv::write_atomically(&path, text.as_bytes()).map_err(|e| io(&path, e))
    }
}

/// The row file's second line: the size of the run's CSV file.
const CSV_BYTES: &str = "csv_bytes";

/// A run's status when it reached its end within the error tolerance.
pub(super) const OK: &str = "ok";

/// The start of a run's status when it reached its end with steps beyond
/// the error tolerance (followed by `mstar run`'s warning).
pub(super) const BEYOND: &str = "beyond tolerance: ";

/// One row of a summary.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Row {
    pub(super) index: usize,
    /// Where `status` is in `fields`.
    status: usize,
    pub(super) fields: Vec<String>,
    /// The size of the run's CSV file, bytes (none for a failed run).
    pub(super) csv_bytes: Option<u64>,
}

impl Row {
    /// The row of run `index`: `fields`, the status at `status`.
    pub(super) fn new(index: usize, status: usize, fields: Vec<String>) -> Self {
        Self {
            index,
            status,
            fields,
            csv_bytes: None,
        }
    }

    /// A row of `fields` (index first, then `k` values, then the status).
    pub(super) fn from_fields(fields: Vec<String>, k: usize) -> Option<Self> {
        let index = fields.first()?.parse().ok()?;
        (fields.len() > k + 1).then_some(Self {
            index,
            status: k + 1,
            fields,
            csv_bytes: None,
        })
    }

    /// A row file's row and the size of the CSV file it records.
    fn parse_file(text: &str, k: usize) -> Option<Self> {
        let mut r = ::csv::ReaderBuilder::new()
            .has_headers(false)
            .flexible(true)
            .from_reader(text.as_bytes());
        let mut records = r.records();
        let fields = records.next()?.ok()?.iter().map(str::to_string).collect();
        let mut row = Self::from_fields(fields, k)?;
        if let Some(size) = records.next() {
            let size = size.ok()?;
            if size.len() != 2 || &size[0] != CSV_BYTES {
                return None;
            }
            row.csv_bytes = Some(size[1].parse().ok()?);
        }
        Some(row)
    }

    fn status(&self) -> &str {
        &self.fields[self.status]
    }

    /// Why the run failed, if it did.
    pub(super) fn error(&self) -> Option<&str> {
        Some(self.status()).filter(|s| *s != OK && !s.starts_with(BEYOND))
    }

    /// The accuracy warning of a run that reached its end beyond the error
    /// tolerance.
    pub(super) fn beyond(&self) -> Option<&str> {
        self.status().strip_prefix(BEYOND)
    }

    /// The outcome, for progress reports.
    pub(super) fn outcome(&self) -> RunOutcome {
        RunOutcome {
            index: self.index,
            error: self.error().map(str::to_string),
            beyond: self.beyond().map(str::to_string),
            wall: self
                .fields
                .last()
                .and_then(|w| w.parse().ok())
                .unwrap_or(f64::NAN),
        }
    }
}

/// One CSV line of `fields` (quoted where needed), with its newline.
fn line(fields: &[String]) -> Result<String, SweepError> {
    let mut w = ::csv::WriterBuilder::new()
        .terminator(::csv::Terminator::Any(b'\n'))
        .from_writer(Vec::new());
    w.write_record(fields).map_err(csv_error)?;
    let bytes = w
        .into_inner()
        .map_err(|e| csv_error(e.into_error().into()))?;
    String::from_utf8(bytes).map_err(|e| csv_error(::csv::Error::from(std::io::Error::other(e))))
}

fn csv_error(e: ::csv::Error) -> SweepError {
    SweepError::Io {
        path: PathBuf::from("<summary row>"),
        source: std::io::Error::other(e.to_string()),
    }
}

/// Writes a summary: `header`, then `rows` (in index order).
pub(super) fn write_summary(
    path: &Path,
    header: &[String],
    rows: &[Row],
) -> Result<(), SweepError> {
    let mut text = line(header)?;
    for row in rows {
        text.push_str(&line(&row.fields)?);
    }
    crate::csv::write_atomically(path, text.as_bytes()).map_err(|e| io(path, e))
}

/// What [`merge`] wrote.
#[derive(Clone, Debug, PartialEq)]
pub struct Merged {
    /// `DIR/summary.csv`.
    pub summary: PathBuf,
    /// The plan's number of runs.
    pub runs: usize,
    /// The failed runs: index and why.
    pub failed: Vec<(usize, String)>,
    /// The runs that reached their end beyond the error tolerance: index
    /// and `mstar run`'s warning.
    pub beyond: Vec<(usize, String)>,
}

/// Joins the summaries of a sharded sweep's shards (`summary.<I>of<N>.csv`
/// in `dir`) into `dir/summary.csv`, ordered by index: the file the sweep
/// would have written unsharded (the same bytes but the wall times). Every
/// row is checked against the plan of `dir/sweep.toml` and the run's files
/// in `dir/runs` (its row file, and its CSV file complete).
///
/// # Errors
/// [`SweepError::Incomplete`] when a run has no row (a shard that has not
/// run or finished), [`SweepError::Corrupt`] for summaries of different
/// splits or columns, or a row that is not of this sweep or whose run's
/// files are missing or incomplete (naming the row and the file),
/// [`SweepError::Io`] when a file cannot be read or written.
pub fn merge(dir: &Path) -> Result<Merged, SweepError> {
    let record = Record::read(dir)?;
    let shards = shard_summaries(dir)?;
    let files = Dir {
        path: dir.to_path_buf(),
        columns: record.columns.len(),
    };
    let mut rows = BTreeMap::new();
    for path in &shards {
        for row in shard_rows(path, &record, &files)? {
            rows.insert(row.index, row);
        }
    }
    let missing: Vec<usize> = (0..record.runs).filter(|i| !rows.contains_key(i)).collect();
    if !missing.is_empty() {
        return Err(SweepError::Incomplete {
            runs: record.runs,
            missing,
        });
    }
    let rows: Vec<Row> = rows.into_values().collect();
    let summary = dir.join("summary.csv");
    write_summary(&summary, &record.columns, &rows)?;
    Ok(Merged {
        summary,
        runs: record.runs,
        failed: listed(&rows, Row::error),
        beyond: listed(&rows, Row::beyond),
    })
}

/// `(index, text)` of the rows for which `pick` gives a text.
pub(super) fn listed(rows: &[Row], pick: fn(&Row) -> Option<&str>) -> Vec<(usize, String)> {
    rows.iter()
        .filter_map(|r| pick(r).map(|e| (r.index, e.to_string())))
        .collect()
}

/// The rows of the shard summary `path`, each checked against the plan
/// `record` and the run's files in `files`.
fn shard_rows(path: &Path, record: &Record, files: &Dir) -> Result<Vec<Row>, SweepError> {
    let text = std::fs::read_to_string(path).map_err(|e| io(path, e))?;
    let mut lines = ::csv::ReaderBuilder::new()
        .has_headers(false)
        .from_reader(text.as_bytes());
    let corrupt = |why: String| SweepError::Corrupt {
        path: path.to_path_buf(),
        why,
    };
    let k = record.param.len();
    let mut rows = Vec::new();
    for (n, line) in lines.records().enumerate() {
        let fields: Vec<String> = line
            .map_err(|e| corrupt(e.to_string()))?
            .iter()
            .map(str::to_string)
            .collect();
        if n == 0 {
            if fields != record.columns {
                return Err(corrupt("its columns are not those of sweep.toml".into()));
            }
            continue;
        }
        let row = Row::from_fields(fields, k)
            .filter(|r| r.fields.len() == record.columns.len() && r.index < record.runs)
            .ok_or_else(|| corrupt(format!("line {} is not a row of this sweep", n + 1)))?;
        let values = super::values_of(&record.param, record.combine, row.index);
        if row.fields[1..=k].iter().zip(&values).any(|(a, b)| a != b) {
            return Err(corrupt(format!(
                "line {} (run {}) has the values {} where this sweep's plan (sweep.toml) has {}: it is another sweep's summary; run that shard here (the same mstar sweep command with its --shard), which rewrites it, then merge again",
                n + 1,
                row.index,
                row.fields[1..=k].join(", "),
                values.join(", ")
            )));
        }
        let checked = files.check(row.index, &values).and_then(|ours| {
            (ours.fields == row.fields).then_some(()).ok_or_else(|| {
                format!(
                    "it is not the row {} holds",
                    files.row_path(row.index).display()
                )
            })
        });
        if let Err(why) = checked {
            return Err(corrupt(format!(
                "line {} (run {}): {why}; rerun that shard here (the same mstar sweep command with its --shard), which completes its runs and rewrites its summary, then merge again",
                n + 1,
                row.index
            )));
        }
        rows.push(row);
    }
    Ok(rows)
}

/// The shards' summaries in `dir`, all of one split `…of<N>`.
fn shard_summaries(dir: &Path) -> Result<Vec<PathBuf>, SweepError> {
    let entries = std::fs::read_dir(dir).map_err(|e| io(dir, e))?;
    let mut found: Vec<(usize, usize, PathBuf)> = Vec::new();
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        let split = name
            .strip_prefix("summary.")
            .and_then(|s| s.strip_suffix(".csv"))
            .and_then(|s| s.split_once("of"));
        if let Some((i, n)) = split
            && let (Ok(i), Ok(n)) = (i.parse::<usize>(), n.parse::<usize>())
        {
            found.push((n, i, entry.path()));
        }
    }
    found.sort();
    let splits: Vec<usize> = found.iter().map(|f| f.0).collect();
    match (splits.first(), splits.last()) {
        (None, _) => Err(SweepError::Corrupt {
            path: dir.to_path_buf(),
            why: "no shard summaries (summary.<I>of<N>.csv) to merge: run mstar sweep … --shard I/N first".into(),
        }),
        (Some(a), Some(b)) if a != b => Err(SweepError::Corrupt {
            path: dir.to_path_buf(),
            why: format!(
                "summaries of different splits (…of{a}.csv and …of{b}.csv): remove those of the split not wanted"
            ),
        }),
        _ => Ok(found.into_iter().map(|f| f.2).collect()),
    }
}
