//! The `mstar` command-line program as a library: [`main_from`] is the
//! whole program (the binary's `main`, and the `mstar` command the Python
//! package installs, `python/src/cli.rs`).

/// A report line (`output::say`): on standard output, or on standard error
/// when standard output carries the CSV; a closed pipe (`mstar chain | head
/// -1`) loses it quietly instead of panicking as `println!` does. Defined
/// before the modules to cover them.
macro_rules! say {
    () => {
        $crate::output::say(format_args!(""))
    };
    ($($arg:tt)*) => {
        $crate::output::say(format_args!($($arg)*))
    };
}

/// A line on standard error that never panics (`output::note`), where
/// `eprintln!` would.
macro_rules! note {
    ($($arg:tt)*) => {
        $crate::output::note(format_args!($($arg)*))
    };
}

mod animate;
mod commands;
mod limits;
mod messages;
mod output;
mod signals;
mod summary;

use std::ffi::OsString;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// mstar: time integration of constrained multibody systems (index-3 DAEs
/// M ü + Bᵀλ = g, Φ(u, t) = 0) with Newmark / HHT-α / generalized-α and
/// Newton-Raphson on the KKT system.
#[derive(Parser, Debug)]
#[command(version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Run a model file (TOML, JSON or URDF; docs/model-format.md) or a built-in
    /// model, with a progress bar on long runs and a summary at the end.
    /// Exit 0 when it reaches its end within the error tolerance, 3 when it
    /// reaches its end beyond it (a warning says where), 2 when the file
    /// cannot be read, 130/143 after SIGINT/SIGTERM, 1 on other failures.
    Run(commands::run::RunArgs),
    /// Check a model file without integrating it: coordinates, constraints,
    /// degrees of freedom, redundant constraints by name, and how far the
    /// initial state is from the constraints. Exit 0 when it can run as
    /// written, 1 when it cannot, 2 when the file cannot be read or holds a value out of range (an unknown KKT solver too).
    Check(commands::check::CheckArgs),
    /// Find the static equilibrium of a model file (velocities zero, drivers
    /// held at t = 0) by damped Newton on the KKT system of statics, from
    /// its initial pose; --out writes it as one CSV row, --write-model as a
    /// model file starting there (docs/analysis.md). Exit 0 when found, 1
    /// when none is found or it is neutral, 2 when the file cannot be read.
    Equilibrium(commands::equilibrium::EquilibriumArgs),
    /// The constrained vibration modes of a model file about its static
    /// equilibrium (or --about initial: its initial pose at rest): one line
    /// a mode, `mode K: f = … Hz, ζ = …` (f = |s|/2π, ζ = −Re(s)/|s|);
    /// --out writes the frequencies, damping ratios and shapes (unit modal
    /// mass) as CSV (docs/analysis.md). Exit 0 when found, 1 when there is
    /// no equilibrium or the eigenproblem fails, 2 when the file cannot be
    /// read.
    Modes(commands::modes::ModesArgs),
    /// Write a linear state-space model ẋ = A x + B p + xdot0,
    /// y = y0 + C x + D p of a model file about its equilibrium (or --about
    /// initial: its initial pose at rest) in a minimal set of coordinates,
    /// as JSON: inputs (optional) are force or torque values of the file,
    /// outputs (optional) columns of `mstar run` (docs/analysis.md). Exit 0 when written, 1 when no model can be
    /// formed or written, 2 when the file, a key or a column is wrong.
    Linearize(commands::linearize::LinearizeArgs),
    /// Write a URDF robot (`.urdf`) as the mstar.spatial/1 model file it
    /// means (docs/model-format.md, "URDF robots"); `run`, `check` and
    /// `animate` also read a `.urdf` directly. Exit 0 when written, 2 when
    /// the URDF cannot be read or converted, 1 when the output cannot be
    /// written.
    Convert(commands::convert::ConvertArgs),
    /// Run a model file for many values of its keys (--set KEY=V1,V2,… or
    /// KEY=START:STOP:COUNT; every combination, or --zip), on all cores or
    /// --jobs N, one shard of a cluster job with --shard I/N; resumable.
    /// Writes DIR/runs/<index>.csv and DIR/summary.csv (docs/sweeps.md).
    /// Exit 0 when every run reached its end within the error tolerance, 3
    /// when none failed and some ended beyond it, 10 + n when n runs failed
    /// (110: 100 or more), 2 for a bad model file or command line (nothing
    /// ran), 1 when a file cannot be read or written or the runs would not
    /// fit, 130/143 after SIGINT/SIGTERM (the summary so far written).
    Sweep(commands::sweep::SweepArgs),
    /// Draw a model moving through the results of `mstar run`, or one of its
    /// vibration modes (--mode K): an animated
    /// GIF, a self-contained HTML page (play/pause, time slider) or one frame
    /// as a PNG; a spatial model projected onto the picture (--view). Exit 0
    /// when written, 1 when the results do not fit the model or a file cannot
    /// be written, 2 when the model file cannot be read.
    Animate(commands::animate::AnimateArgs),
    /// The paper's pendulum in u = [x, y, θ] (singular M = diag(m, m, 0)).
    ///
    /// Without a preset: g = 9.81, θ₀ = π/2, h = 0.01, t_end = 10 s,
    /// generalized-α (ρ∞ = 0.9), consistent start. `--preset paper`: g = 10,
    /// λ₀ = (−10, 0), Newmark β = 1/4, γ = 1/2, the paper's M* start. Explicit
    /// options override the preset.
    Pendulum(commands::pendulum::PendulumArgs),
    /// An N-link chain released horizontally from rest under gravity, with a
    /// timing summary: slender bars (1 kg, 1 m) on revolute joints, or point
    /// masses on rods. Defaults: h = 1e-3 s, t_end = 1 s, generalized-α
    /// (ρ∞ = 0.9), full Newton, consistent start.
    Chain(commands::chain::ChainArgs),
}

/// The program run with the command line `args` (the first: the program's
/// name, as `--help` shows it): what it prints, and its exit code. A command
/// line clap refuses prints clap's message and gives its code (2; 0 for
/// `--help` and `--version`), as `Cli::parse` would before exiting.
pub fn main_from<I, T>(args: I) -> u8
where
    I: IntoIterator<Item = T>,
    T: Into<OsString> + Clone,
{
    let cli = match Cli::try_parse_from(args) {
        Ok(cli) => cli,
        Err(e) => {
            // A closed standard output or error loses the message quietly.
            let _ = e.print();
            return u8::try_from(e.exit_code()).unwrap_or(2);
        }
    };
    match thread_pool() {
        Ok(pool) => code_of(pool.install(|| dispatch(cli))),
        Err(e) => {
            note!("error: could not start the thread pool: {e}");
            1
        }
    }
}

/// The number of an exit code (`ExitCode` keeps it private; the program's
/// codes are those of `ExitCode::from(u8)`, told apart by comparison).
fn code_of(code: ExitCode) -> u8 {
    (0..=u8::MAX)
        .find(|&k| ExitCode::from(k) == code)
        .unwrap_or(1)
}

/// Runs the command.
fn dispatch(cli: Cli) -> ExitCode {
    let integrates = matches!(
        cli.command,
        Command::Run(_)
            | Command::Pendulum(_)
            | Command::Chain(_)
            | Command::Animate(_)
            | Command::Sweep(_)
    );
    signals::install(integrates);
    let out = match &cli.command {
        Command::Run(args) => args.out.as_deref(),
        Command::Pendulum(args) => args.out.as_deref(),
        Command::Chain(args) => args.out.as_deref(),
        Command::Equilibrium(args) => args.out(),
        Command::Modes(args) => args.out(),
        Command::Linearize(args) => args.out(),
        _ => None,
    };
    if output::is_stdout(out) {
        output::report_on_stderr();
    }
    let result = match cli.command {
        Command::Run(args) => return commands::run::run(&args),
        Command::Check(args) => return commands::check::check(&args),
        Command::Equilibrium(args) => return commands::equilibrium::equilibrium(&args),
        Command::Modes(args) => return commands::modes::modes(&args),
        Command::Linearize(args) => return commands::linearize::linearize(&args),
        Command::Convert(args) => return commands::convert::convert(&args),
        Command::Sweep(args) => return commands::sweep::sweep(&args),
        Command::Animate(args) => return commands::animate::animate(&args),
        Command::Pendulum(args) => commands::pendulum::pendulum(&args),
        Command::Chain(args) => commands::chain::chain(&args),
    };
    ExitCode::from(output::exit_code(result, false, 1))
}

/// The thread pool the program runs in: one thread a core, or as many as
/// start under a limit on processes (`ulimit -u`) or on the address space
/// (`ulimit -v`), else the main thread alone. (rayon's global pool would
/// panic on first use when its threads cannot start.)
///
/// # Errors
/// When not even the main thread can serve as the pool.
fn thread_pool() -> Result<rayon::ThreadPool, rayon::ThreadPoolBuildError> {
    // The main thread's stack: the program runs on a worker.
    const STACK: usize = 8 << 20;
    let cores = std::thread::available_parallelism().map_or(1, usize::from);
    let builder = || rayon::ThreadPoolBuilder::new().stack_size(STACK);
    builder()
        .num_threads(cores)
        .build()
        .or_else(|_| builder().num_threads(1).build())
        .or_else(|_| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(1)
                .use_current_thread()
                .build()
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every exit code the program can give reads back as its number.
    #[test]
    fn exit_codes_read_back() {
        for k in [0, 1, 2, 3, 10, 110, 130, 143, 255] {
            assert_eq!(code_of(ExitCode::from(k)), k);
        }
        assert_eq!(code_of(ExitCode::SUCCESS), 0);
        assert_eq!(code_of(ExitCode::FAILURE), 1);
    }

    /// The help describes the program's options, not library items, and
    /// offers every registered KKT backend with its summary.
    #[test]
    fn help_speaks_of_options_and_lists_every_backend() {
        use clap::CommandFactory;
        let mut cli = Cli::command();
        for sub in ["pendulum", "chain"] {
            let help = cli
                .find_subcommand_mut(sub)
                .map(|c| c.render_long_help().to_string())
                .unwrap_or_default();
            assert!(help.contains("--kkt"), "{sub}: {help}");
            assert!(
                !help.contains("library") && !help.contains("Newton::"),
                "{sub}: {help}"
            );
            for r in mstar::kkt::backends() {
                assert!(help.contains(r.summary), "{sub}: {}", r.backend);
            }
        }
    }
}
