//! `cargo xtask <command>`: the project's studies and reports.
//!
//! Each command lives in its own file and writes its results under
//! `target/studies/<study>/`, printing a summary table. The program first
//! changes to the workspace root, so it behaves the same from any directory.
//!
//! - `cargo xtask paper`: the paper's pendulum example, Figs. 4-13, against
//!   the RK4 oracle ([`paper`]).
//! - `cargo xtask stability`: the period-2h mode over 100 s, the start
//!   correction and the conditioning ([`stability`]).
//! - `cargo xtask convergence`: fitted orders in u, u̇, ü, λ ([`convergence`]).
//! - `cargo xtask energy`: energy error over 1000 s ([`energy`]).
//! - `cargo xtask bench`: the chain benchmark as a table and a plot ([`bench`](mod@bench)).
//! - `cargo xtask validate`: the models of `models/` against independent
//!   references; writes docs/validation.md ([`validate`]).
//! - `cargo xtask work-precision`: error against CPU time, fixed and
//!   adaptive steps; writes docs/work-precision.md ([`work_precision`]).
//! - `cargo xtask setup`: the time from the command line to the first step
//!   on the N-four-bar at 10³, 10⁴, 10⁵ bodies; `cargo xtask n-four-bar-file`
//!   writes one such file ([`setup`]).
//! - `cargo xtask chain-scaling`: `mstar chain` at 10⁵ bodies against 10⁴
//!   per body, in interleaved cycles ([`chain_scaling`]).
//! - `cargo xtask hanging-chain-file`: a planar bar chain hanging at its
//!   equilibrium as a model file, for `mstar modes` ([`setup`]).
//! - `cargo xtask animate-check`: `mstar animate`'s page in headless Chromium,
//!   a screenshot and a check that its script plays ([`animate_check`]).

mod animate_check;
mod bench;
mod bench_files;
mod chain_scaling;
mod common;
mod convergence;
mod energy;
mod paper;
mod plot;
mod setup;
mod stability;
mod validate;
mod work_precision;

use std::path::{Path, PathBuf};

use anyhow::{Context as _, Result};
use clap::{Parser, Subcommand};

/// mstar studies: paper figures, convergence, stability, energy drift.
#[derive(Debug, Parser)]
#[command(name = "cargo xtask", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// The studies.
#[derive(Debug, Subcommand)]
enum Command {
    /// Reproduce the paper's pendulum example (Figs. 4-13) against the RK4
    /// oracle; writes CSVs and PNGs to target/studies/paper/ and copies the
    /// PNGs to docs/figures/paper/.
    Paper,
    /// The period-2h mode of ü and λ over 100 s (pendulum, double pendulum),
    /// the start correction and the KKT conditioning; writes to
    /// target/studies/stability/ and docs/figures/stability/.
    Stability,
    /// Fitted convergence orders in u, u̇, ü and λ at t = 1 s against the
    /// oracle; writes to target/studies/convergence/ and docs/figures/convergence/.
    Convergence,
    /// Energy error over 1000 s (RK4, trapezoidal, generalized-α); writes to
    /// target/studies/energy/ and docs/figures/energy/.
    Energy,
    /// Every model of models/ against its independent reference (closed
    /// forms, RK4 on minimal coordinates, published values); prints the
    /// table and writes docs/validation.md.
    Validate,
    /// The chain benchmark (criterion, release build) for N = 10 … max-n:
    /// µs per step and per body per step, Newton iterations and factorizations
    /// per step, phase times, peak memory; writes to target/studies/bench/.
    Bench {
        /// Largest chain (10, 100, 1000, 10000 or 100000).
        #[arg(long, default_value_t = 100_000)]
        max_n: usize,
        /// Only print and plot the results of the last run (no benchmark).
        #[arg(long)]
        report_only: bool,
        /// Only the model files through `mstar run` (set-up and step cost
        /// of the spatial chain and N-four-bar files at 10³ … max-n bodies,
        /// Exudyn beside them): target/studies/bench/files.csv.
        #[arg(long, conflicts_with = "report_only")]
        files_only: bool,
    },
    /// `mstar chain` at 10⁵ links against 10⁴, per body per step, as a user
    /// runs it (the command's defaults, rayon's pool as the environment sets
    /// it): cycles of three runs at 10⁴ and one at 10⁵, a cycle's ratio
    /// being its 10⁵ run over the median of its 10⁴ runs; writes
    /// target/studies/chain-scaling/cycles.csv.
    ChainScaling {
        /// Number of cycles.
        #[arg(long, default_value_t = 5)]
        cycles: usize,
        /// The chain's kind (`mstar chain --kind`; the command's default
        /// when not given).
        #[arg(long)]
        kind: Option<String>,
        /// End time of every run (the command's default, 1 s, when not
        /// given).
        #[arg(long)]
        t_end: Option<f64>,
    },
    /// `mstar animate` in a real browser: the four-bar's HTML page in
    /// headless Chromium (`apt-get install -y chromium`), a screenshot to
    /// docs/figures/animate-four-bar.png and a check that the script plays;
    /// a slider-crank frame to docs/figures/animate-slider-crank.png.
    AnimateCheck,
    /// Error against CPU time on the pendulum, a 10-link chain and Andrews'
    /// mechanism, fixed steps against error-controlled ones; writes
    /// docs/work-precision.md and docs/figures/work-precision.png.
    WorkPrecision,
    /// Set-up time (read, check, start) of `mstar check` and `mstar run` on
    /// the N-four-bar at 10³, 10⁴ and 10⁵ bodies (release build); writes
    /// the files and setup.csv to target/studies/setup/.
    Setup {
        /// Largest model, in bodies.
        #[arg(long, default_value_t = 100_001)]
        max_bodies: usize,
    },
    /// Writes the IFToMM N-four-bar (models/n-four-bar.toml) for any N:
    /// 2N + 1 bodies.
    NFourBarFile {
        /// N, the number of couplers.
        #[arg(long)]
        bars: usize,
        /// The file to write.
        #[arg(long)]
        out: PathBuf,
        /// Add a second copy of one coupler joint (a redundant joint).
        #[arg(long)]
        duplicate: bool,
    },
    /// Writes the spatial bar chain of `mstar chain --kind spatial-bars` as
    /// a model file (docs/performance.md, "Model files at the chain
    /// command's speed").
    SpatialChainFile {
        /// The number of bars.
        #[arg(long)]
        links: usize,
        /// The file to write.
        #[arg(long)]
        out: PathBuf,
    },
    /// Writes a planar bar chain hanging straight down (its equilibrium) as
    /// a model file, for `mstar modes` (docs/performance.md, "Vibration
    /// modes").
    HangingChainFile {
        /// The number of bars.
        #[arg(long)]
        links: usize,
        /// The file to write.
        #[arg(long)]
        out: PathBuf,
    },
}

fn main() -> Result<()> {
    let cli = Cli::parse();
    // A file named on the command line is the caller's: resolved against
    // the directory the command was run from, before the studies move to
    // the workspace root.
    let caller = std::env::current_dir().unwrap_or_default();
    let root = project_root();
    std::env::set_current_dir(&root)
        .with_context(|| format!("could not change to {}", root.display()))?;
    match cli.command {
        Command::Paper => paper::run(),
        Command::Stability => stability::run(),
        Command::Convergence => convergence::run(),
        Command::Energy => energy::run(),
        Command::Validate => validate::run(),
        Command::Bench {
            max_n,
            report_only,
            files_only,
        } => bench::run(max_n, report_only, files_only),
        Command::ChainScaling {
            cycles,
            kind,
            t_end,
        } => chain_scaling::run(&chain_scaling::Options {
            cycles,
            kind,
            t_end,
        }),
        Command::AnimateCheck => animate_check::run(),
        Command::WorkPrecision => work_precision::run(),
        Command::Setup { max_bodies } => setup::run(max_bodies),
        Command::NFourBarFile {
            bars,
            out,
            duplicate,
        } => setup::write_file(bars, duplicate, &caller.join(out)),
        Command::SpatialChainFile { links, out } => {
            setup::write_spatial_chain(links, &caller.join(out))
        }
        Command::HangingChainFile { links, out } => {
            setup::write_hanging_chain(links, &caller.join(out))
        }
    }
}

/// The checkout the studies run in and write to: the nearest directory at or
/// above the current one that holds this workspace (`Cargo.toml` and
/// `xtask/Cargo.toml`), else the one `cargo run` names at run time
/// (`CARGO_MANIFEST_DIR`), else the one that compiled this binary. The
/// compile-time path alone would send a copied checkout's studies into the
/// original.
fn project_root() -> PathBuf {
    let from_cwd = std::env::current_dir()
        .ok()
        .and_then(|d| workspace_at_or_above(&d));
    let from_cargo = std::env::var_os("CARGO_MANIFEST_DIR")
        .map(PathBuf::from)
        .and_then(|d| workspace_at_or_above(&d));
    from_cwd.or(from_cargo).unwrap_or_else(|| {
        let manifest = Path::new(env!("CARGO_MANIFEST_DIR"));
        manifest.parent().unwrap_or(manifest).to_path_buf()
    })
}

/// The nearest directory at or above `dir` with `Cargo.toml` and
/// `xtask/Cargo.toml`.
fn workspace_at_or_above(dir: &Path) -> Option<PathBuf> {
    dir.ancestors()
        .find(|d| d.join("Cargo.toml").is_file() && d.join("xtask/Cargo.toml").is_file())
        .map(Path::to_path_buf)
}

/// `target/studies/<study>/`, created if missing (relative to the root).
///
/// # Errors
/// If the directory cannot be created.
fn study_dir(study: &str) -> Result<PathBuf> {
    let dir = Path::new("target").join("studies").join(study);
    std::fs::create_dir_all(&dir).with_context(|| format!("could not create {}", dir.display()))?;
    Ok(dir)
}

#[cfg(test)]
mod tests {
    use super::workspace_at_or_above;

    /// A copied checkout finds itself, from its root or any folder in it,
    /// not the checkout that compiled the binary.
    #[test]
    fn the_workspace_is_found_from_where_the_studies_run() {
        let copy = std::env::temp_dir().join(format!("mstar-xtask-root-{}", std::process::id()));
        let deep = copy.join("crates/mstar/src");
        std::fs::create_dir_all(&deep).expect("scratch tree");
        std::fs::create_dir_all(copy.join("xtask")).expect("xtask dir");
        std::fs::write(copy.join("Cargo.toml"), "[workspace]\n").expect("write");
        std::fs::write(copy.join("xtask/Cargo.toml"), "[package]\n").expect("write");
        assert_eq!(
            workspace_at_or_above(&deep).as_deref(),
            Some(copy.as_path())
        );
        assert_eq!(
            workspace_at_or_above(&copy).as_deref(),
            Some(copy.as_path())
        );
        let outside = std::env::temp_dir().join(format!("mstar-xtask-none-{}", std::process::id()));
        std::fs::create_dir_all(&outside).expect("scratch dir");
        assert_ne!(
            workspace_at_or_above(&outside).as_deref(),
            Some(copy.as_path())
        );
        std::fs::remove_dir_all(&copy).ok();
        std::fs::remove_dir_all(&outside).ok();
    }
}
