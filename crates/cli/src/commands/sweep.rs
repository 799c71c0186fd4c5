//! `mstar sweep`: a model file run for many values of its keys
//! (`mstar::sweep`; `docs/sweeps.md`).

use std::io::IsTerminal as _;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use mstar::sweep::{Combine, Options, Param, Plan, Progress, RunOutcome, Shard, SweepError};

/// Arguments of `mstar sweep`.
#[derive(clap::Args, Debug)]
pub struct SweepArgs {
    /// The model file (TOML, JSON or URDF, as for `mstar run`).
    #[arg(required_unless_present = "merge")]
    model: Option<PathBuf>,
    /// A key to sweep and its values: KEY=V1,V2,… (TOML values, as
    /// `mstar run --set` takes them) or KEY=START:STOP:COUNT (COUNT values
    /// from START to STOP, both included). Keys are dotted paths into the
    /// model file, elements of arrays by name: body.upper.mass,
    /// force.drive.function.constant, simulation.h. Repeatable.
    #[arg(long = "set", value_name = "KEY=VALUES")]
    set: Vec<String>,
    /// Every combination of the values (the default); the first key varies
    /// slowest.
    #[arg(long, conflicts_with = "zip")]
    grid: bool,
    /// The i-th value of every key in run i (lists of one length).
    #[arg(long)]
    zip: bool,
    /// Runs at once (default: one per core).
    #[arg(long, value_name = "N", allow_negative_numbers = true)]
    jobs: Option<usize>,
    /// Run only the runs whose index is I mod N (0 ≤ I < N), e.g.
    /// --shard $SLURM_ARRAY_TASK_ID/$SLURM_ARRAY_TASK_COUNT; the shard's
    /// summary is DIR/summary.<I>of<N>.csv (join them with --merge DIR).
    #[arg(long, value_name = "I/N", allow_hyphen_values = true)]
    shard: Option<String>,
    /// The output directory: runs/<index>.csv, summary.csv, sweep.toml.
    /// Rerunning the same command into it skips the runs already complete.
    #[arg(long, value_name = "DIR", required_unless_present = "merge")]
    out: Option<PathBuf>,
    /// Join the shards' summaries of DIR into DIR/summary.csv (instead of
    /// running).
    #[arg(long, value_name = "DIR", conflicts_with_all = ["model", "set", "grid", "zip", "jobs", "shard", "out"])]
    merge: Option<PathBuf>,
}

/// `mstar sweep`: exit 0 when every run reached its end within the error
/// tolerance, 10 + n when n runs failed (110 for 100 or more), 3 when none
/// failed and some ended beyond the tolerance, 2 when nothing ran for a bad
/// model file or command line, 1 when a file could not be read or written
/// or the runs would not fit (their files on disk, the summary in memory),
/// 130/143 after SIGINT/SIGTERM (the summary of the runs complete so far
/// written).
pub fn sweep(args: &SweepArgs) -> ExitCode {
    let result = match &args.merge {
        Some(dir) => merge(dir),
        None => run(args),
    };
    match result {
        Ok(Ended::Counted { failed, beyond }) => {
            ExitCode::from(mstar::sweep::exit_code(failed, beyond))
        }
        Ok(Ended::Signal(signal)) => ExitCode::from(u8::try_from(128 + signal).unwrap_or(1)),
        Err(e) => {
            note!("error: {e}");
            ExitCode::from(if e.is_usage() { 2 } else { 1 })
        }
    }
}

/// How a sweep ended, for its exit code.
enum Ended {
    /// Every run of the shard (or the merge) done: the failed runs and the
    /// runs beyond the error tolerance.
    Counted { failed: usize, beyond: usize },
    /// Stopped by this signal.
    Signal(i32),
}

/// Plans and runs the sweep.
fn run(args: &SweepArgs) -> Result<Ended, SweepError> {
    let (Some(model), Some(out)) = (&args.model, &args.out) else {
        return Err(SweepError::Plan("give a model file and --out DIR".into()));
    };
    // (Else `DIR/runs: Not a directory` after the plan.)
    if out.exists() && !out.is_dir() {
        return Err(SweepError::Plan(format!(
            "--out {} names an existing file: the --out of mstar sweep is a directory (it will hold runs/, summary.csv and sweep.toml); name a new directory or one of an earlier sweep",
            out.display()
        )));
    }
    let shard = match &args.shard {
        Some(s) => Shard::parse(s)?,
        None => Shard::ALL,
    };
    if args.jobs == Some(0) {
        return Err(SweepError::Plan(
            "--jobs 0: give at least 1 (the default is one per core)".into(),
        ));
    }
    let params = args
        .set
        .iter()
        .map(|s| Param::parse(s))
        .collect::<Result<Vec<_>, _>>()?;
    let combine = if args.zip {
        Combine::Zip
    } else {
        Combine::Grid
    };
    let plan = Plan::new(model, params, combine)?;
    // (Runs complete from an earlier call are skipped: not counted.)
    let runs = out.join("runs");
    let grid_swept = plan.params().iter().any(|p| p.key == "output.every_time");
    crate::limits::check_sweep(
        &plan.estimate(shard, &|i| {
            runs.is_dir() && runs.join(format!("{i}.row")).exists()
        }),
        grid_swept,
        crate::limits::free_space_of(out),
        crate::limits::available_memory(),
    )?;
    let options = Options {
        out: out.clone(),
        jobs: args.jobs,
        shard,
    };
    let progress = Bar::new(args.jobs);
    let report = mstar::sweep::run_plan(&plan, &options, &progress)?;
    progress.bar.finish_and_clear();
    let (failed, beyond) = (report.failed.len(), report.beyond.len());
    say!(
        "{} runs of {} in this shard: {} run now, {} complete before; {} failed, {} beyond the error tolerance",
        report.ran + report.skipped + report.stopped,
        plan.len(),
        report.ran,
        report.skipped,
        failed,
        beyond
    );
    say!("wrote {}", report.summary.display());
    if let Some(signal) = crate::signals::received() {
        note!(
            "interrupted by {}: {} runs not run; the summary holds the runs complete so far; rerun the same command to run the others",
            signal_name(signal),
            report.stopped
        );
        return Ok(Ended::Signal(signal));
    }
    Ok(Ended::Counted { failed, beyond })
}

/// SIGINT or SIGTERM as messages name them.
fn signal_name(signal: i32) -> String {
    match signal {
        signal_hook::consts::SIGINT => "SIGINT (Ctrl-C)".to_string(),
        signal_hook::consts::SIGTERM => "SIGTERM".to_string(),
        s => format!("signal {s}"),
    }
}

/// `--merge DIR`.
fn merge(dir: &std::path::Path) -> Result<Ended, SweepError> {
    let merged = mstar::sweep::merge(dir)?;
    say!(
        "wrote {} ({} runs, {} failed, {} beyond the error tolerance)",
        merged.summary.display(),
        merged.runs,
        merged.failed.len(),
        merged.beyond.len()
    );
    Ok(Ended::Counted {
        failed: merged.failed.len(),
        beyond: merged.beyond.len(),
    })
}

/// Runs completed of the total with an estimate of the time left: a bar on
/// a terminal, else a line per run on standard error.
struct Bar {
    bar: ProgressBar,
    plain: bool,
    total: AtomicUsize,
    done: AtomicUsize,
    start: Instant,
    /// `--jobs`, to say so when the pool has fewer threads.
    jobs: Option<usize>,
}

impl Bar {
    fn new(jobs: Option<usize>) -> Self {
        let plain = !std::io::stderr().is_terminal();
        let target = if plain {
            ProgressDrawTarget::hidden()
        } else {
            ProgressDrawTarget::stderr()
        };
        let bar = ProgressBar::with_draw_target(Some(0), target);
        bar.set_style(
            ProgressStyle::with_template(
                "{bar:40} {pos}/{len} runs [{elapsed_precise}, {eta} left]",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        Self {
            bar,
            plain,
            total: AtomicUsize::new(0),
            done: AtomicUsize::new(0),
            start: Instant::now(),
            jobs,
        }
    }
}

impl Progress for Bar {
    fn planned(&self, to_run: usize, skipped: usize) {
        if skipped > 0 {
            note!("{skipped} runs complete from an earlier sweep: skipped");
        }
        self.total.store(to_run, Ordering::Relaxed);
        self.bar.set_length(to_run as u64);
    }

    fn started(&self, threads: usize) {
        if let Some(jobs) = self.jobs.filter(|&j| j > threads) {
            note!(
                "note: --jobs {jobs} capped to {threads} (at most one run at once per run to run and per core)"
            );
        }
    }

    fn stop(&self) -> bool {
        crate::signals::received().is_some()
    }

    fn finished(&self, o: &RunOutcome) {
        let done = self.done.fetch_add(1, Ordering::Relaxed) + 1;
        self.bar.inc(1);
        let status = match (&o.error, &o.beyond) {
            (Some(why), _) => format!("failed: {why}"),
            (None, Some(warning)) => format!("beyond the error tolerance: {warning}"),
            (None, None) => "ok".to_string(),
        };
        if self.plain {
            let total = self.total.load(Ordering::Relaxed);
            let elapsed = self.start.elapsed().as_secs_f64();
            let left = elapsed / done as f64 * total.saturating_sub(done) as f64;
            note!(
                "run {} {status} ({:.2} s); {done}/{total} done, about {left:.0} s left",
                o.index,
                o.wall
            );
        } else if o.error.is_some() || o.beyond.is_some() {
            self.bar.suspend(|| note!("run {} {status}", o.index));
        }
    }
}
