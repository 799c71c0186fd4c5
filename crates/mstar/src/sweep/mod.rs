//! Sweeps: one model file run for many values of its keys, the runs spread
//! over the cores, optionally split into shards for a cluster, and resumable
//! (`docs/sweeps.md`; the command line is `mstar sweep`).
//!
//! A [`Plan`] is the model and its swept [`Param`]s, combined as a grid
//! (every combination; the first key varies slowest) or zipped (the i-th
//! value of every key). [`run_plan`] runs the plan's runs of one [`Shard`]
//! into a directory:
//!
//! - `runs/<index>.csv`: each run's CSV file, as `mstar run --set … --out`
//!   writes it (`[output]` honoured); a run that fails keeps what it
//!   computed in `runs/<index>.partial.csv`;
//! - `runs/<index>.row`: its summary row, written once its CSV file is in
//!   place (a run is complete when it has both; a rerun skips it);
//! - `summary.csv` (or `summary.<I>of<N>.csv` for shard I of N): one row per
//!   run, in index order (see [`summary_header`]);
//! - `sweep.toml`: the plan, which a rerun and [`merge`] check.
//!
//! ```no_run
//! use mstar::sweep::{Combine, Options, Param, Plan, run_plan};
//! use std::path::Path;
//!
//! let params = vec![
//!     Param::new("body.upper.mass", [1.0, 2.0])?,
//!     Param::parse("simulation.h=1e-3,5e-4")?,
//! ];
//! let plan = Plan::new(Path::new("models/double-pendulum.toml"), params, Combine::Grid)?;
//! assert_eq!(plan.len(), 4);
//! let report = run_plan(&plan, &Options::new("sweep-out"), &())?;
//! println!("{} runs, {} failed", report.ran + report.skipped, report.failed.len());
//! # Ok::<(), mstar::sweep::SweepError>(())
//! ```

mod files;
mod one;
mod spec;

use std::path::{Path, PathBuf};

use mstar_file::{FileError, Format, MechanismFile};

pub use files::{Merged, merge, summary_header};
pub use spec::Param;

/// Why a sweep does not run (or a merge does not complete).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SweepError {
    /// A parameter as written is malformed.
    #[error("--set {spec}: {why}")]
    Spec {
        /// The parameter as given.
        spec: String,
        /// What is wrong, and the form to use.
        why: String,
    },
    /// Something else about the plan: no parameters, a key given twice,
    /// zipped lists of different lengths, a bad shard.
    #[error("{0}")]
    Plan(String),
    /// The model file cannot be read, or a key does not lead to anything in
    /// it (an unknown element or key: [`FileError::in_override`]).
    #[error(transparent)]
    Model(#[from] FileError),
    /// The runs would not fit: their files on the output directory's file
    /// system, or the summary in memory (the estimate and what to change).
    #[error("{0}")]
    TooLarge(String),
    /// The output directory holds another sweep's files.
    #[error(
        "{} holds another sweep (its sweep.toml records another model file or other parameters): give another --out, or remove the directory to start afresh",
        .0.display()
    )]
    OtherSweep(PathBuf),
    /// A file could not be read or written.
    #[error("{}: {source}", .path.display())]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// A file of the sweep is not what the sweep writes (edited by hand?).
    #[error("{}: {why}", .path.display())]
    Corrupt {
        /// The file.
        path: PathBuf,
        /// What is wrong with it.
        why: String,
    },
    /// `merge` found runs that no shard's summary has.
    #[error(
        "{} of {runs} runs have no row in the shards' summaries (first: {}); run the shards that are missing (the same command with their --shard), then merge again",
        .missing.len(),
        .missing.iter().take(10).map(ToString::to_string).collect::<Vec<_>>().join(", ")
    )]
    Incomplete {
        /// The plan's number of runs.
        runs: usize,
        /// The indices without a row.
        missing: Vec<usize>,
    },
}

impl SweepError {
    /// Whether the sweep was refused before running anything because of the
    /// command line or the model file (the `mstar sweep` exit code 2), rather
    /// than a failure of files (1).
    #[must_use]
    pub fn is_usage(&self) -> bool {
        matches!(
            self,
            Self::Spec { .. } | Self::Plan(_) | Self::Model(_) | Self::OtherSweep(_)
        )
    }
}

/// How the values of several keys make runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Combine {
    /// Every combination (default): the runs of keys with n₁, n₂, … values
    /// number n₁ n₂ …; the first key varies slowest.
    #[default]
    Grid,
    /// The i-th value of every key in run i: lists of one length (a key with
    /// a single value keeps it in every run).
    Zip,
}

/// Which of a plan's runs one process runs: those whose index ≡ `index`
/// (mod `count`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// I, from 0.
    pub index: usize,
    /// N ≥ 1.
    pub count: usize,
}

impl Shard {
    /// All runs (shard 0 of 1).
    pub const ALL: Self = Self { index: 0, count: 1 };

    /// Parses `I/N` (`0 ≤ I < N`), e.g. `$SLURM_ARRAY_TASK_ID/$SLURM_ARRAY_TASK_COUNT`.
    ///
    /// # Errors
    /// [`SweepError::Plan`] for anything else.
    pub fn parse(text: &str) -> Result<Self, SweepError> {
        let bad = |why: &str| {
            SweepError::Plan(format!(
                "--shard {text}: {why} (I/N runs the runs whose index is I mod N, 0 ≤ I < N, e.g. --shard 0/4)"
            ))
        };
        let (i, n) = text.split_once('/').ok_or_else(|| bad("expected I/N"))?;
        let (Ok(index), Ok(count)) = (i.trim().parse::<usize>(), n.trim().parse::<usize>()) else {
            return Err(bad("I and N must be whole numbers"));
        };
        if count == 0 || index >= count {
            return Err(bad("I must be at least 0 and less than N"));
        }
        Ok(Self { index, count })
    }

    /// Whether run `i` is this shard's.
    #[must_use]
    pub fn contains(&self, i: usize) -> bool {
        i % self.count == self.index
    }

    /// The name of this shard's summary: `summary.csv` for all runs,
    /// `summary.<I>of<N>.csv` for one shard of several.
    #[must_use]
    pub fn summary_name(&self) -> String {
        if self.count == 1 {
            "summary.csv".to_string()
        } else {
            format!("summary.{}of{}.csv", self.index, self.count)
        }
    }
}

/// A model file and the values of its keys to run it with.
#[derive(Clone, Debug)]
pub struct Plan {
    model: PathBuf,
    text: String,
    format: Format,
    params: Vec<Param>,
    combine: Combine,
    /// The coordinates' names (the summary's `u:` columns).
    coords: Vec<String>,
    /// The sensors' column names (the summary's `sensor:` columns).
    sensors: Vec<String>,
    /// The model file's own output settings, for [`Plan::estimate`].
    base: OutputSettings,
}

/// What decides the size of a run's CSV file: `t_end`, `h`, rows every
/// `every` steps or every `every_time` seconds, and the fields of a row.
#[derive(Clone, Copy, Debug, PartialEq)]
struct OutputSettings {
    t_end: f64,
    h: f64,
    every: f64,
    every_time: Option<f64>,
    fields: usize,
}

impl OutputSettings {
    /// With the swept value `value` of `key`, if it is one of these and
    /// reads as a number (else the run fails on it: no file).
    fn with(mut self, key: &str, value: &str) -> Self {
        let Ok(x) = value.trim().parse::<f64>() else {
            return self;
        };
        match key {
            "simulation.t_end" => self.t_end = x,
            "simulation.h" => self.h = x,
            "output.every" => self.every = x,
            "output.every_time" => self.every_time = Some(x),
            _ => {}
        }
        self
    }

    /// Rows of the CSV file: the steps (as `mstar run` estimates them; a
    /// step halved where Newton fails adds rows), or the grid's.
    fn rows(&self) -> f64 {
        match self.every_time {
            Some(dt) => self.t_end / dt + 2.0,
            None => self.t_end / self.h / self.every.max(1.0) + 1.0,
        }
    }
}

/// The size of what a sweep's runs would write, from each run's `t_end`,
/// `h`, `output.every` and `output.every_time` (swept or the file's): what
/// `mstar sweep` compares with the free space and the memory before it
/// starts (`docs/sweeps.md`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    /// Runs of the shard.
    pub runs: usize,
    /// Rows of all their CSV files together.
    pub rows: f64,
    /// Fields of a row of a run's CSV file (without reaction columns: a
    /// low estimate).
    pub fields: usize,
    /// Fields of a row of the summary, which is kept in memory until the
    /// sweep ends.
    pub summary_fields: usize,
    /// The largest `t_end` of the runs, s (for the advice of a time grid).
    pub t_end: f64,
    /// Whether some run writes rows every step (not on a time grid).
    pub every_step: bool,
}

impl Plan {
    /// Reads the model file and checks the plan before anything runs: the
    /// file reads, every key leads to something in it (an element name or a
    /// key it does not have is an error naming the ones it has), zipped
    /// lists have one length. A value out of range (a negative mass) is not
    /// checked here: it is that run's failure.
    ///
    /// # Errors
    /// [`SweepError::Model`] for a file that does not read or a key that
    /// leads nowhere, [`SweepError::Plan`] for no keys, a key given twice or
    /// zipped lists of different lengths.
    pub fn new(model: &Path, params: Vec<Param>, combine: Combine) -> Result<Self, SweepError> {
        check_params(&params, combine)?;
        let origin = model.display().to_string();
        let text = std::fs::read_to_string(model).map_err(|e| SweepError::Io {
            path: model.to_path_buf(),
            source: e,
        })?;
        let format = Format::of(model);
        let base = MechanismFile::parse(&text, &origin, format)?;
        // Each key alone with its first value: an error of the override
        // itself refuses the plan; an error of the value is the run's.
        for p in &params {
            let set = [format!("{}={}", p.key, p.values[0])];
            match MechanismFile::parse_with(&text, &origin, format, &set) {
                Err(e) if e.in_override => return Err(e.into()),
                _ => {}
            }
        }
        let sys = base.mechanism.system();
        let coords = mstar_model::coord_names(sys);
        let sensors = crate::columns::SensorColumns::new(
            crate::run::lookup(&base.mechanism),
            &base.output.sensors,
        )
        .map(|c| crate::columns::Columns::names(&c))
        .map_err(|e| SweepError::Plan(format!("{}: {e}", model.display())))?;
        let base = OutputSettings {
            t_end: base.simulation.t_end.unwrap_or(crate::run::defaults::T_END),
            h: base.simulation.h.unwrap_or(crate::run::defaults::H),
            every: base.output.every as f64,
            every_time: base.output.every_time,
            // t, u, v, a, λ, energy, iterations, residual, constraint.
            fields: 1 + 3 * sys.n_coords() + sys.n_constraints() + 4,
        };
        Ok(Self {
            model: model.to_path_buf(),
            text,
            format,
            params,
            combine,
            coords,
            sensors,
            base,
        })
    }

    /// The model file.
    #[must_use]
    pub fn model(&self) -> &Path {
        &self.model
    }

    /// The swept keys and their values.
    #[must_use]
    pub fn params(&self) -> &[Param] {
        &self.params
    }

    /// How the values combine.
    #[must_use]
    pub fn combine(&self) -> Combine {
        self.combine
    }

    /// The number of runs.
    #[must_use]
    pub fn len(&self) -> usize {
        match self.combine {
            Combine::Grid => self.params.iter().map(|p| p.values.len()).product(),
            Combine::Zip => self
                .params
                .iter()
                .map(|p| p.values.len())
                .max()
                .unwrap_or(0),
        }
    }

    /// Whether the plan has no runs (never, for a plan [`new`](Self::new) made).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The value of each key in run `index` (< [`len`](Self::len)).
    #[must_use]
    pub fn values(&self, index: usize) -> Vec<&str> {
        values_of(&self.params, self.combine, index)
    }

    /// The size of what the runs of `shard` would write, leaving out those
    /// for which `done` says they are complete (a rerun skips them).
    #[must_use]
    pub fn estimate(&self, shard: Shard, done: &dyn Fn(usize) -> bool) -> Estimate {
        let mut e = Estimate {
            runs: 0,
            rows: 0.0,
            fields: self.base.fields,
            summary_fields: summary_header(self).len(),
            t_end: 0.0,
            every_step: false,
        };
        for i in (0..self.len()).filter(|&i| shard.contains(i) && !done(i)) {
            let run = self
                .params
                .iter()
                .zip(self.values(i))
                .fold(self.base, |s, (p, v)| s.with(&p.key, v));
            e.runs += 1;
            e.rows += run.rows();
            e.t_end = e.t_end.max(run.t_end);
            e.every_step |= run.every_time.is_none();
        }
        e
    }

    /// The overrides of run `index`, `KEY=VALUE` as `mstar run --set` takes them.
    #[must_use]
    pub fn overrides(&self, index: usize) -> Vec<String> {
        self.params
            .iter()
            .zip(self.values(index))
            .map(|(p, v)| format!("{}={v}", p.key))
            .collect()
    }
}

/// The value of each key of `params` in run `index` of a plan combining
/// them by `combine`.
pub(crate) fn values_of(params: &[Param], combine: Combine, index: usize) -> Vec<&str> {
    match combine {
        Combine::Grid => {
            // Row-major: the last key varies fastest.
            let mut rest = index;
            let mut values: Vec<&str> = params
                .iter()
                .rev()
                .map(|p| {
                    let v = &p.values[rest % p.values.len()];
                    rest /= p.values.len();
                    v.as_str()
                })
                .collect();
            values.reverse();
            values
        }
        Combine::Zip => params
            .iter()
            .map(|p| p.values[index.min(p.values.len() - 1)].as_str())
            .collect(),
    }
}

/// The most runs a plan may have: each run writes two files into one
/// directory (`runs/`) and its summary row is kept in memory, and 10⁶ runs
/// of even a millisecond are a quarter of an hour of computing; a larger
/// count is a mistake in a range far more often than it is meant.
pub const MAX_RUNS: usize = 1_000_000;

/// Refuses a plan of more than [`MAX_RUNS`] runs (counted without
/// overflow), with the number of values of its longest list that fits.
fn check_runs(params: &[Param], combine: Combine) -> Result<(), SweepError> {
    let mut counts = params.iter().map(|p| p.values.len());
    let runs = match combine {
        Combine::Grid => counts.try_fold(1usize, usize::checked_mul),
        Combine::Zip => counts.max(),
    };
    if runs.is_some_and(|r| r <= MAX_RUNS) {
        return Ok(());
    }
    let Some(longest) = params.iter().max_by_key(|p| p.values.len()) else {
        return Ok(());
    };
    // The runs of the other keys together (at most MAX_RUNS + 1 counted).
    let others = match combine {
        Combine::Grid => params
            .iter()
            .filter(|p| p.key != longest.key)
            .fold(1usize, |r, p| r.saturating_mul(p.values.len())),
        Combine::Zip => 1,
    };
    let runs = runs.map_or_else(|| "more than 1.8e19".to_string(), |r| format!("{r:.1e}"));
    let fits = MAX_RUNS / others.max(1);
    let advice = if fits >= 1 {
        format!("give {} at most {fits} values", longest.key)
    } else {
        "give fewer keys or values".to_string()
    };
    Err(SweepError::Plan(format!(
        "the plan has {runs} runs, more than the {MAX_RUNS} a sweep takes: {advice}"
    )))
}

/// No keys, a key twice, zipped lists of different lengths, too many runs.
fn check_params(params: &[Param], combine: Combine) -> Result<(), SweepError> {
    if params.is_empty() {
        return Err(SweepError::Plan(
            "nothing to sweep: give at least one --set KEY=V1,V2,…".into(),
        ));
    }
    for (i, p) in params.iter().enumerate() {
        if params[..i].iter().any(|q| q.key == p.key) {
            return Err(SweepError::Plan(format!(
                "the key {} is given twice: give all its values in one --set {}=V1,V2,…",
                p.key, p.key
            )));
        }
    }
    let lists: Vec<&Param> = params.iter().filter(|p| p.values.len() > 1).collect();
    if combine == Combine::Zip
        && let Some(other) = lists
            .iter()
            .find(|p| p.values.len() != lists[0].values.len())
    {
        return Err(SweepError::Plan(format!(
            "--zip pairs the i-th values of every key, and {} has {} values where {} has {}: give lists of one length (or use --grid for every combination)",
            other.key,
            other.values.len(),
            lists[0].key,
            lists[0].values.len()
        )));
    }
    check_runs(params, combine)
}

/// Where and how [`run_plan`] runs.
#[derive(Clone, Debug)]
pub struct Options {
    /// The output directory (created if need be).
    pub out: PathBuf,
    /// Runs at once (default: `None`, one per core).
    pub jobs: Option<usize>,
    /// The runs to run (default: [`Shard::ALL`]).
    pub shard: Shard,
}

impl Options {
    /// All runs into `out`, one at a time per core.
    #[must_use]
    pub fn new(out: impl Into<PathBuf>) -> Self {
        Self {
            out: out.into(),
            jobs: None,
            shard: Shard::ALL,
        }
    }
}

/// How one run ended.
#[derive(Clone, Debug, PartialEq)]
pub struct RunOutcome {
    /// Its index in the plan.
    pub index: usize,
    /// `None` when it reached its end; else why not (the summary's status).
    pub error: Option<String>,
    /// When it reached its end with steps beyond the error tolerance:
    /// `mstar run`'s warning (the summary's status after
    /// `beyond tolerance: `).
    pub beyond: Option<String>,
    /// Wall time, s.
    pub wall: f64,
}

/// What [`run_plan`] tells as it goes (implemented by `()` for nothing).
/// Called from the worker threads.
pub trait Progress: Sync {
    /// Before the first run: how many runs it will run and how many it
    /// skips, complete from an earlier call.
    fn planned(&self, to_run: usize, skipped: usize) {
        let _ = (to_run, skipped);
    }

    /// Before the first run: the runs at once (the pool's threads).
    fn started(&self, threads: usize) {
        let _ = threads;
    }

    /// After each run.
    fn finished(&self, outcome: &RunOutcome) {
        let _ = outcome;
    }

    /// Whether to stop (asked before every step of every run): the run in
    /// progress ends without a row (a rerun runs it again), no other run
    /// starts, and the summary of the runs complete so far is written.
    fn stop(&self) -> bool {
        false
    }
}

impl Progress for () {}

/// What [`run_plan`] did.
#[derive(Clone, Debug, PartialEq)]
pub struct Report {
    /// Runs run now.
    pub ran: usize,
    /// Runs skipped, complete from an earlier call.
    pub skipped: usize,
    /// The failed runs of the shard (now or before): index and why.
    pub failed: Vec<(usize, String)>,
    /// The runs of the shard (now or before) that reached their end with
    /// steps beyond the error tolerance: index and `mstar run`'s warning.
    pub beyond: Vec<(usize, String)>,
    /// Runs at once: `Options::jobs` (default one per core), at most the
    /// number of runs to run and the number of cores.
    pub threads: usize,
    /// Runs not run because [`Progress::stop`] said so (a signal): the
    /// summary holds the runs complete so far.
    pub stopped: usize,
    /// The summary written.
    pub summary: PathBuf,
}

/// Runs the runs of `options.shard` that are not complete in `options.out`,
/// `options.jobs` at a time (each whole run on one thread of a local pool),
/// and writes the shard's summary. A run that fails does not stop the
/// others: it is reported in the summary and in [`Report::failed`].
///
/// # Errors
/// [`SweepError::OtherSweep`] when the directory holds another plan's
/// files, [`SweepError::Io`] when a file cannot be written.
pub fn run_plan(
    plan: &Plan,
    options: &Options,
    progress: &dyn Progress,
) -> Result<Report, SweepError> {
    use rayon::prelude::*;
    let dir = files::Dir::prepare(&options.out, plan)?;
    let mut rows = Vec::new();
    let mut todo = Vec::new();
    for i in (0..plan.len()).filter(|&i| options.shard.contains(i)) {
        match dir.check(i, &plan.values(i)) {
            Ok(row) => rows.push(row),
            Err(_) => todo.push(i),
        }
    }
    let skipped = rows.len();
    progress.planned(todo.len(), skipped);
    let threads = threads(options.jobs, todo.len());
    progress.started(threads);
    // Runs that differ only in values analyse their KKT structure once.
    let _shared = mstar_kkt::SharedAnalyses::begin();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| SweepError::Plan(format!("--jobs {threads}: {e}")))?;
    let done: Vec<Result<Option<files::Row>, SweepError>> = pool.install(|| {
        todo.par_iter()
            .with_max_len(1)
            .map(|&i| {
                if progress.stop() {
                    return Ok(None);
                }
                let row = one::run(plan, &dir, i, &|| progress.stop())?;
                if let Some(row) = &row {
                    progress.finished(&row.outcome());
                }
                Ok(row)
            })
            .collect()
    });
    let mut ran = 0;
    for row in done {
        if let Some(row) = row? {
            rows.push(row);
            ran += 1;
        }
    }
    rows.sort_by_key(|r| r.index);
    let summary = dir.path().join(options.shard.summary_name());
    files::write_summary(&summary, &summary_header(plan), &rows)?;
    Ok(Report {
        ran,
        skipped,
        failed: files::listed(&rows, files::Row::error),
        beyond: files::listed(&rows, files::Row::beyond),
        threads,
        stopped: todo.len() - ran,
        summary,
    })
}

/// The threads of a sweep's pool: `jobs` (default one per core), at most
/// one per run to run and one per core (more only wait for a core, each
/// with its stack).
fn threads(jobs: Option<usize>, runs: usize) -> usize {
    let cores = std::thread::available_parallelism().map_or(1, usize::from);
    jobs.unwrap_or(cores).min(cores).min(runs).max(1)
}

/// The exit code of `mstar sweep` for `failed` failed runs and `beyond`
/// runs that reached their end beyond the error tolerance: 0 when every run
/// reached its end within it; 10 + the number of failed runs (at most 110:
/// 100 or more) when some failed; else 3 ([`crate::accuracy::EXIT_INACCURATE`],
/// as `mstar run`) when some ended beyond the tolerance. Distinct from 1 (a
/// file that cannot be written) and 2 (a bad model file or command line,
/// before anything ran), and below 126.
#[must_use]
pub fn exit_code(failed: usize, beyond: usize) -> u8 {
    if failed > 0 {
        10 + u8::try_from(failed.min(100)).unwrap_or(100)
    } else if beyond > 0 {
        crate::accuracy::EXIT_INACCURATE
    } else {
        0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A plan of `MAX_RUNS` runs and more is refused, and the advised count
    /// of values passes.
    #[test]
    fn too_many_runs_are_refused_with_a_count_that_passes() {
        let keys = |n: usize| -> Vec<Param> {
            ["a", "b", "c"]
                .iter()
                .map(|k| Param::parse(&format!("{k}=1:2:{n}")).expect("a range"))
                .collect()
        };
        let params = keys(200);
        let e = check_params(&params, Combine::Grid)
            .expect_err("8e6 runs")
            .to_string();
        assert!(e.contains("the plan has 8.0e6 runs"), "{e}");
        let fits: usize = e
            .rsplit("at most ")
            .next()
            .and_then(|t| t.split(' ').next())
            .and_then(|t| t.parse().ok())
            .unwrap_or_else(|| panic!("no count in: {e}"));
        let mut advised = params.clone();
        advised[0] = Param::parse(&format!("a=1:2:{fits}")).expect("a range");
        assert!(check_params(&advised, Combine::Grid).is_ok(), "{e}");
        advised[0] = Param::parse(&format!("a=1:2:{}", fits + 1)).expect("a range");
        assert!(check_params(&advised, Combine::Grid).is_err(), "{e}");
        assert!(check_params(&keys(100), Combine::Grid).is_ok());
        assert!(check_params(&keys(1000), Combine::Zip).is_ok());
        // Counts that overflow: refused, not wrapped.
        let many: Vec<Param> = (0..8)
            .map(|k| Param::parse(&format!("k{k}=1:2:300000")).expect("a range"))
            .collect();
        let e = check_params(&many, Combine::Grid)
            .expect_err("overflow")
            .to_string();
        assert!(e.contains("more than 1.8e19 runs"), "{e}");
    }
}
