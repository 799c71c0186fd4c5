//! The `mstar` command-line program.

/// Report lines for the whole program (see `output::say`): a closed pipe
/// (`mstar chain | head -1`) loses them quietly instead of panicking as the
/// standard `println!` does. Defined before the modules to cover them.
macro_rules! println {
    () => {
        $crate::output::say(format_args!(""))
    };
    ($($arg:tt)*) => {
        $crate::output::say(format_args!($($arg)*))
    };
}

/// `eprintln!` that never panics (see `output::note`).
macro_rules! eprintln {
    ($($arg:tt)*) => {
        $crate::output::note(format_args!($($arg)*))
    };
}

mod animate;
mod limits;
mod model_commands;
mod output;
mod signals;
mod summary;
mod sweep_command;

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use clap::{Parser, Subcommand, ValueEnum};
use mstar::kkt::Backend;
use mstar::model::spatial::{RotationalMass, SpatialSystem, spatial_bar_chain};
use mstar::newmark::Short;
use mstar::pendulum::PendulumRun;
use mstar::{Config, IntegrationError, Newton, Scheme, Start, StepMode, System, csv};

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
    /// Run a model file (TOML or JSON; docs/model-format.md) or a built-in
    /// model, with a progress bar on long runs and a summary at the end.
    /// Exit 0 when it reaches its end within the error tolerance, 3 when it
    /// reaches its end beyond it (a warning says where), 2 when the file
    /// cannot be read, 130/143 after SIGINT/SIGTERM, 1 on other failures.
    Run(model_commands::RunArgs),
    /// Check a model file without integrating it: coordinates, constraints,
    /// degrees of freedom, redundant constraints by name, and how far the
    /// initial state is from the constraints. Exit 0 when it can run as
    /// written, 1 when it cannot, 2 when the file cannot be read or holds a value out of range (an unknown KKT solver too).
    Check(model_commands::CheckArgs),
    /// Run a model file for many values of its keys (--set KEY=V1,V2,… or
    /// KEY=START:STOP:COUNT; every combination, or --zip), on all cores or
    /// --jobs N, one shard of a cluster job with --shard I/N; resumable.
    /// Writes DIR/runs/<index>.csv and DIR/summary.csv (docs/sweeps.md).
    /// Exit 0 when every run reached its end, 10 + n when n runs failed
    /// (110: 100 or more), 2 for a bad model file or command line (nothing
    /// ran), 1 when a file cannot be written.
    Sweep(sweep_command::SweepArgs),
    /// Draw a model moving through the results of `mstar run`: an animated
    /// GIF, a self-contained HTML page (play/pause, time slider) or one frame
    /// as a PNG; a spatial model projected onto the picture (--view). Exit 0
    /// when written, 1 when the results do not fit the model or a file cannot
    /// be written, 2 when the model file cannot be read.
    Animate(animate::AnimateArgs),
    /// The paper's pendulum in u = [x, y, θ] (singular M = diag(m, m, 0)).
    ///
    /// Without a preset: g = 9.81, θ₀ = π/2, h = 0.01, t_end = 10 s,
    /// generalized-α (ρ∞ = 0.9), consistent start. `--preset paper`: g = 10,
    /// λ₀ = (−10, 0), Newmark β = 1/4, γ = 1/2, the paper's M* start. Explicit
    /// options override the preset.
    Pendulum(PendulumArgs),
    /// An N-link chain released horizontally from rest under gravity, with a
    /// timing summary: slender bars (1 kg, 1 m) on revolute joints, or point
    /// masses on rods. Defaults: h = 1e-3 s, t_end = 1 s, generalized-α
    /// (ρ∞ = 0.9), full Newton, consistent start.
    Chain(ChainArgs),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum ChainKind {
    /// Uniform slender bars (1 kg, 1 m, J = m l²/12) on revolute joints.
    Bars,
    /// 1 kg point masses on massless 1 m rods.
    Points,
    /// Solid cylinders (1 kg, 1 m, radius 0.02 m) in Euler parameters on
    /// spherical joints, along +x at rest, gravity −z.
    SpatialBars,
}

#[derive(clap::Args, Debug)]
struct ChainArgs {
    /// Number of links N.
    #[arg(long, allow_negative_numbers = true)]
    links: usize,
    /// What the links are.
    #[arg(long, value_enum, default_value_t = ChainKind::Bars)]
    kind: ChainKind,
    /// End time, s.
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    t_end: f64,
    #[command(flatten)]
    integ: IntegratorArgs,
    /// Write every step to this CSV file (streamed; complete or not at all).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Write the state every DT seconds instead of every step (interpolated
    /// within the steps: cubic Hermite on u and u̇), and the last state.
    #[arg(long, value_name = "DT", allow_negative_numbers = true)]
    output_every: Option<f64>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum Preset {
    /// The paper's setting (§3 of the paper).
    Paper,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum Integrator {
    /// Newmark(β, γ); the paper's scheme with β = 1/4, γ = 1/2.
    Newmark,
    /// Hilber-Hughes-Taylor α (--alpha in [−1/3, 0]).
    Hht,
    /// Generalized-α (Chung & Hulbert) with spectral radius --rho.
    GeneralizedAlpha,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum Init {
    /// M* ü₀ = g − Bᵀλ₀ with the given λ₀ (the paper's eq. 11).
    Paper,
    /// Consistent accelerations and multipliers from the acceleration-level KKT.
    Consistent,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum NewtonArg {
    /// Refactor at every iteration: one iteration per step on chains, the
    /// fastest there (the default of `mstar chain`).
    Full,
    /// Reuse the factorization while the iteration contracts fast.
    Modified,
}

/// The `--kkt` values: `auto` and every registered backend, with its summary.
fn kkt_values() -> clap::builder::PossibleValuesParser {
    let auto = clap::builder::PossibleValue::new("auto")
        .help("chosen from the size and structure (the default, above)");
    clap::builder::PossibleValuesParser::new(
        std::iter::once(auto).chain(
            mstar::kkt::backends()
                .iter()
                .map(|r| clap::builder::PossibleValue::new(r.backend.name()).help(r.summary)),
        ),
    )
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum Reference {
    /// Classic RK4 on θ̈ = −(g/l) sin θ, reconstructed in [x, y, θ].
    Rk4,
}

/// Integrator options shared by every model command.
#[derive(clap::Args, Debug, Default)]
struct IntegratorArgs {
    /// Step size h, s [default: pendulum 0.01, chain 1e-3].
    #[arg(long, allow_negative_numbers = true)]
    h: Option<f64>,
    /// Smallest step size for step control, s [default: h/1024; with
    /// --adaptive h·1e-6; paper: h, i.e. off].
    #[arg(long, allow_negative_numbers = true)]
    h_min: Option<f64>,
    /// Integrator [default: generalized-alpha; paper: newmark].
    #[arg(long, value_enum)]
    integrator: Option<Integrator>,
    /// Newmark β [paper: 0.25]; implies --integrator newmark.
    #[arg(long, allow_negative_numbers = true)]
    beta: Option<f64>,
    /// Newmark γ [paper: 0.5]; implies --integrator newmark.
    #[arg(long, allow_negative_numbers = true)]
    gamma: Option<f64>,
    /// Generalized-α spectral radius ρ∞ in [0, 1] [default: 0.9].
    #[arg(long, allow_negative_numbers = true)]
    rho: Option<f64>,
    /// HHT α in [−1/3, 0] [default: −0.1].
    #[arg(long, allow_hyphen_values = true)]
    alpha: Option<f64>,
    /// Newton variant [default: modified; chain and paper: full].
    #[arg(long, value_enum)]
    newton: Option<NewtonArg>,
    /// KKT solver [default: auto: dense LU up to 24 unknowns; above, Schur when
    /// the bodies interact only through constraints, have mass and symmetric
    /// force Jacobians, else LDLᵀ, else (unsymmetric) sparse LU].
    #[arg(long, value_parser = kkt_values())]
    kkt: Option<String>,
    /// Relative Newton tolerance on ‖r‖ and ‖Φ‖ [default: 1e-10].
    #[arg(long, allow_negative_numbers = true)]
    tol: Option<f64>,
    /// Newton iterations per step attempt [default: 20].
    #[arg(long, allow_negative_numbers = true)]
    max_iter: Option<usize>,
    /// Relative tolerance of the local error estimate on the positions
    /// [default: 1e-3]: a step is within it when its estimated error is at
    /// most atol + rtol·|u| in every coordinate.
    #[arg(long, allow_negative_numbers = true)]
    rtol: Option<f64>,
    /// Absolute tolerance of the local error estimate, m or rad [default: 1e-6].
    #[arg(long, allow_negative_numbers = true)]
    atol: Option<f64>,
    /// Adapt the step size to the error estimate (--h is the first step;
    /// ρ∞ defaults to 0.5). Without it the step size is fixed and the
    /// estimate only monitored: a warning when it exceeds the tolerance.
    #[arg(long, conflicts_with = "strict")]
    adaptive: bool,
    /// Fixed step size, and an error (exit 1, samples kept) at the first step
    /// whose estimated error exceeds the tolerance.
    #[arg(long)]
    strict: bool,
    /// Largest step size with --adaptive, s [default: none].
    #[arg(long, requires = "adaptive", allow_negative_numbers = true)]
    h_max: Option<f64>,
}

#[derive(clap::Args, Debug)]
struct PendulumArgs {
    /// Start from a preset; explicit options override it.
    #[arg(long, value_enum)]
    preset: Option<Preset>,
    /// Mass m, kg [default: 1].
    #[arg(long, allow_negative_numbers = true)]
    m: Option<f64>,
    /// Rod length l, m [default: 1].
    #[arg(long, allow_negative_numbers = true)]
    l: Option<f64>,
    /// Gravity g₀, m/s² [default: 9.81; paper: 10]; negative values pull up.
    #[arg(long, allow_negative_numbers = true)]
    g: Option<f64>,
    /// Initial angle θ₀ from the downward vertical, rad [default: π/2].
    #[arg(long, allow_hyphen_values = true)]
    theta0: Option<f64>,
    /// Initial angular velocity θ̇₀, rad/s [default: 0].
    #[arg(long, allow_hyphen_values = true)]
    omega0: Option<f64>,
    /// End time, s [default: 10].
    #[arg(long, allow_negative_numbers = true)]
    t_end: Option<f64>,
    #[command(flatten)]
    integ: IntegratorArgs,
    /// Initial acceleration and multipliers [default: consistent; paper: paper].
    #[arg(long, value_enum)]
    init: Option<Init>,
    /// Initial multipliers for --init paper, "L1,L2" [paper: -10,0]; implies --init paper.
    #[arg(long, value_delimiter = ',', num_args = 1, allow_hyphen_values = true)]
    lambda0: Option<Vec<f64>>,
    /// Write a reference solution instead of integrating (same columns).
    #[arg(long, value_enum)]
    reference: Option<Reference>,
    /// Write every step to this CSV file (complete or not at all).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Write the state every DT seconds instead of every step (interpolated
    /// within the steps: cubic Hermite on u and u̇), and the last state.
    #[arg(
        long,
        value_name = "DT",
        conflicts_with = "reference",
        allow_negative_numbers = true
    )]
    output_every: Option<f64>,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match thread_pool() {
        Ok(pool) => pool.install(|| dispatch(cli)),
        Err(e) => {
            eprintln!("error: could not start the thread pool: {e}");
            ExitCode::FAILURE
        }
    }
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
        _ => None,
    };
    if output::is_stdout(out) {
        output::report_on_stderr();
    }
    let result = match cli.command {
        Command::Run(args) => return model_commands::run(&args),
        Command::Check(args) => return model_commands::check(&args),
        Command::Sweep(args) => return sweep_command::sweep(&args),
        Command::Animate(args) => return animate::animate(&args),
        Command::Pendulum(args) => pendulum(&args),
        Command::Chain(args) => chain(&args),
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

/// An error and its causes on one line, `a: b: c` as `{:#}` prints them,
/// but without a cause whose text the line already holds (a library error
/// that quotes its solver's error would otherwise say it twice).
pub(crate) fn report(e: &anyhow::Error) -> String {
    mstar::run::error_message(e.as_ref())
}

/// "the sample" or "the n samples".
pub(crate) fn samples_phrase(n: usize) -> String {
    if n == 1 {
        "the sample".to_string()
    } else {
        format!("the {n} samples")
    }
}

/// The command-line form of a library error's advice: for `mstar run`
/// (`files`), the model file's keys; for the built-in commands, their options.
pub(crate) fn hint(e: &IntegrationError, files: bool) -> Option<&'static str> {
    match (e, files) {
        (IntegrationError::NewtonFailed { .. }, true) => Some(
            "the step size is --h (or [simulation] h), the tolerance --set simulation.tol=…, the scheme --set simulation.integrator=generalized-alpha (with --set simulation.rho=…)",
        ),
        (IntegrationError::NewtonFailed { .. }, false) => Some(
            "generalized-α is --integrator generalized-alpha (--rho sets ρ∞); the step size is --h, the tolerance --tol",
        ),
        (IntegrationError::StepSizeTooSmall { .. }, true) => Some(
            "the step size is --h (or [simulation] h), the smallest step size --set simulation.h_min=…",
        ),
        (IntegrationError::StepSizeTooSmall { .. }, false) => Some(
            "the step size is --h, adaptive steps --adaptive, the smallest step size --h-min, the Newton tolerance --tol, the scheme --integrator",
        ),
        (IntegrationError::ErrorTooLarge { .. }, true) => Some(
            "adaptive steps are --adaptive (or [simulation] error_control = \"adaptive\"), the step size --h, the tolerances --rtol and --atol",
        ),
        (IntegrationError::ErrorTooLarge { .. }, false) => Some(
            "adaptive steps are --adaptive, the step size --h, the tolerances --rtol and --atol, the smallest step size --h-min",
        ),
        _ => None,
    }
}

/// Builds the run from the preset and the explicit options.
fn pendulum_run(args: &PendulumArgs) -> Result<PendulumRun> {
    let mut run = match args.preset {
        Some(Preset::Paper) => PendulumRun::paper(),
        None => PendulumRun::standard(),
    };
    if let Some(m) = args.m {
        run.m = m;
    }
    if let Some(l) = args.l {
        run.l = l;
    }
    if let Some(g) = args.g {
        run.g0 = g;
    }
    if let Some(th) = args.theta0 {
        run.theta0 = th;
    }
    if let Some(w) = args.omega0 {
        run.omega0 = w;
    }
    if let Some(t) = args.t_end {
        run.t_end = t;
    }
    for (name, value) in [("m", run.m), ("l", run.l), ("t-end", run.t_end)] {
        if !(value > 0.0 && value.is_finite()) {
            bail!(
                "--{name} must be a finite positive number (got {})",
                Short(value)
            );
        }
    }
    for (name, value) in [
        ("g", run.g0),
        ("theta0", run.theta0),
        ("omega0", run.omega0),
    ] {
        if !value.is_finite() {
            bail!("--{name} must be a finite number (got {value})");
        }
    }
    apply_integrator(
        &args.integ,
        &mut run.config,
        args.preset == Some(Preset::Paper),
    )?;
    let c = &mut run.config;
    // Start: explicit --init, else implied by --lambda0.
    let init = args.init.or(args.lambda0.as_ref().map(|_| Init::Paper));
    match init {
        Some(Init::Consistent) => {
            if args.lambda0.is_some() {
                bail!("--lambda0 applies to --init paper; a consistent start computes λ₀");
            }
            c.start = Start::Consistent;
        }
        Some(Init::Paper) => {
            let lambda0 = match (&args.lambda0, &c.start) {
                (Some(l), _) => l.clone(),
                (None, Start::Paper { lambda0 }) => lambda0.clone(),
                (None, Start::Consistent) => vec![-10.0, 0.0],
            };
            if lambda0.len() != 2 {
                bail!("--lambda0 takes two values L1,L2 (got {})", lambda0.len());
            }
            c.start = Start::Paper { lambda0 };
        }
        None => {}
    }
    c.validate().context("invalid integrator options")?;
    Ok(run)
}

/// Applies the error-control options to `c`: `--adaptive` without an
/// explicit scheme is generalized-α with ρ∞ = 0.5 (`docs/work-precision.md`).
fn apply_error_control(args: &IntegratorArgs, c: &mut Config) {
    c.error.rtol = args.rtol.unwrap_or(c.error.rtol);
    c.error.atol = args.atol.unwrap_or(c.error.atol);
    c.error.h_max = args.h_max.or(c.error.h_max);
    if args.strict {
        c.error.mode = StepMode::Strict;
    }
    let explicit_scheme = args.integrator.is_some()
        || args.rho.is_some()
        || args.alpha.is_some()
        || args.beta.is_some()
        || args.gamma.is_some();
    if args.adaptive {
        c.error.mode = StepMode::Adaptive;
        if c.scheme == Scheme::default() && !explicit_scheme {
            c.scheme = Scheme::GeneralizedAlpha {
                rho_inf: mstar::run::defaults::RHO_ADAPTIVE,
            };
        }
    }
}

/// Applies the integrator options to `c` (`paper_preset`: an explicit `--h`
/// also fixes `h_min`, keeping step control off as in the paper).
fn apply_integrator(args: &IntegratorArgs, c: &mut Config, paper_preset: bool) -> Result<()> {
    if let Some(h) = args.h {
        c.h = h;
        if paper_preset {
            c.h_min = Some(h);
        }
    }
    if args.h_min.is_some() {
        c.h_min = args.h_min;
    }
    if let Some(tol) = args.tol {
        c.tol = tol;
    }
    if let Some(k) = args.max_iter {
        c.max_iterations = k;
    }
    apply_error_control(args, c);
    if let Some(n) = args.newton {
        c.newton = match n {
            NewtonArg::Full => Newton::Full,
            NewtonArg::Modified => Newton::MODIFIED,
        };
    }
    if let Some(name) = &args.kkt {
        c.kkt.backend =
            Backend::named(name).with_context(|| format!("no KKT solver is called '{name}'"))?;
    }
    // Scheme: explicit --integrator, else implied by --beta/--gamma, --rho, --alpha.
    let newmark_args = args.beta.is_some() || args.gamma.is_some();
    let integrator = args.integrator.or(if newmark_args {
        Some(Integrator::Newmark)
    } else if args.rho.is_some() {
        Some(Integrator::GeneralizedAlpha)
    } else if args.alpha.is_some() {
        Some(Integrator::Hht)
    } else {
        None
    });
    if let Some(integrator) = integrator {
        let misplaced = |opt: &str, needs: &str| -> Result<()> {
            bail!("{opt} applies to --integrator {needs}, not {integrator:?}")
        };
        if newmark_args && integrator != Integrator::Newmark {
            misplaced("--beta/--gamma", "newmark")?;
        }
        if args.rho.is_some() && integrator != Integrator::GeneralizedAlpha {
            misplaced("--rho", "generalized-alpha")?;
        }
        if args.alpha.is_some() && integrator != Integrator::Hht {
            misplaced("--alpha", "hht")?;
        }
        let (beta0, gamma0) = match c.scheme {
            Scheme::Newmark { beta, gamma } => (beta, gamma),
            _ => (0.25, 0.5),
        };
        c.scheme = match integrator {
            Integrator::Newmark => Scheme::Newmark {
                beta: args.beta.unwrap_or(beta0),
                gamma: args.gamma.unwrap_or(gamma0),
            },
            Integrator::Hht => Scheme::Hht {
                alpha: args.alpha.unwrap_or(-0.1),
            },
            Integrator::GeneralizedAlpha => Scheme::GeneralizedAlpha {
                rho_inf: args.rho.unwrap_or(if args.adaptive {
                    mstar::run::defaults::RHO_ADAPTIVE
                } else {
                    mstar::run::defaults::RHO
                }),
            },
        };
    }
    Ok(())
}

fn describe(run: &PendulumRun) -> String {
    let c = &run.config;
    let scheme = match c.scheme {
        Scheme::Newmark { beta, gamma } => {
            format!("Newmark β = {}, γ = {}", Short(beta), Short(gamma))
        }
        Scheme::Hht { alpha } => format!("HHT α = {}", Short(alpha)),
        Scheme::GeneralizedAlpha { rho_inf } => format!("generalized-α ρ∞ = {}", Short(rho_inf)),
    };
    let start = match &c.start {
        Start::Paper { lambda0 } => {
            let values: Vec<String> = lambda0.iter().map(|&x| Short(x).to_string()).collect();
            format!("paper start (M*, λ₀ = [{}])", values.join(", "))
        }
        Start::Consistent => "consistent start".into(),
    };
    let newton = match c.newton {
        Newton::Full => "full Newton".to_string(),
        Newton::Modified { max_rate } => format!("modified Newton (rate ≤ {})", Short(max_rate)),
        Newton::Automatic => "automatic Newton".to_string(),
    };
    format!(
        "pendulum m = {} kg, l = {} m, g = {} m/s², θ₀ = {} rad, θ̇₀ = {} rad/s; {scheme}, {start}, {newton}, h = {} s, t_end = {} s",
        Short(run.m),
        Short(run.l),
        Short(run.g0),
        Short(run.theta0),
        Short(run.omega0),
        Short(c.h),
        Short(run.t_end)
    )
}

/// Refuses an output that would not fit on its file system (`every`: rows
/// every so many steps, `every_time`: rows every Δt seconds).
fn check_output(
    out: Option<&Path>,
    fields: usize,
    (t_end, h): (f64, f64),
    (every, every_time): (Option<usize>, Option<f64>),
) -> Result<()> {
    if let Some(dt) = every_time
        && !(dt > 0.0 && dt.is_finite())
    {
        return Err(output::usage(format!(
            "--output-every must be a finite positive number of seconds (got {})",
            Short(dt)
        )));
    }
    let Some(path) = out else {
        return Ok(());
    };
    let rows = match every_time {
        // The grid's rows and the last state.
        Some(dt) => t_end / dt + 2.0,
        None => t_end / h / every.unwrap_or(1) as f64 + 1.0,
    };
    // Also for devices and standard output, which have no free space to
    // tell: rows at a tiny Δt are not bounded by the steps.
    if let Some(dt) = every_time {
        limits::check_rows(rows, t_end, dt)?;
    }
    let o = limits::Output {
        path,
        rows,
        fields,
        t_end,
        every_time,
    };
    limits::check_output(&o, limits::free_space(path))
}

/// Opens the CSV output, if any, and says which leftovers of killed runs it
/// removed.
pub(crate) fn open_output<S: System + ?Sized>(
    out: Option<&Path>,
    sys: &S,
    extra: &[String],
) -> Result<Option<csv::CsvStream>> {
    let Some(path) = out else {
        return Ok(None);
    };
    let stream = csv::CsvStream::create_with(path, sys, extra)?;
    for leftover in stream.removed_leftovers() {
        eprintln!(
            "note: removed {}, left by an earlier run that was killed",
            leftover.display()
        );
    }
    Ok(Some(stream))
}

fn pendulum(args: &PendulumArgs) -> Result<()> {
    let run = pendulum_run(args)?;
    let sys = run.system();
    limits::check_steps(run.t_end, run.config.h)?;
    let out = args.out.as_deref();
    check_output(
        out,
        csv::header(&sys).len(),
        (run.t_end, run.config.h),
        (None, args.output_every),
    )?;
    if args.reference == Some(Reference::Rk4) {
        return pendulum_reference(args, &run);
    }
    let mut stream = open_output(out, &sys, &[])?;
    println!("{}", describe(&run));
    let u0 = sys.position(&[run.theta0]);
    let v0 = sys.velocity(&[run.theta0], &[run.omega0]);
    let clock = Instant::now();
    let mut integ = mstar::Integrator::new(&sys, run.config.clone(), 0.0, &u0, &v0)?;
    let mut summary = summary::Summary::new();
    let mut grid = output::Grid::new(args.output_every)?;
    let ended = output::drive(&mut integ, run.t_end, &mut |integ| {
        let s = integ.view();
        summary.push(&s);
        if let Some(stream) = stream.as_mut() {
            grid.rows(&s, &mut |row| stream.push(row));
            output::watch(stream);
        }
    });
    if let Some(stream) = stream.as_mut() {
        grid.finish(&mut |row| stream.push(row));
    }
    let wall = clock.elapsed();
    summary.print();
    if ended.is_ok() {
        let stats = integ.stats();
        println!(
            "steps: {} accepted, {} rejected; Newton iterations: {} total, {:.2} per step, {} max; factorizations: {}",
            stats.steps,
            stats.rejected,
            stats.iterations,
            stats.iterations as f64 / stats.steps.max(1) as f64,
            stats.max_iterations,
            stats.factorizations
        );
        println!(
            "wall time: {:.3} s ({:.2} µs per step)",
            wall.as_secs_f64(),
            wall.as_secs_f64() * 1e6 / stats.steps.max(1) as f64
        );
    }
    // Also after a failure: the samples kept are as inaccurate as it says.
    let warned = warn_accuracy(&integ.stats(), &run.config, &sys, false);
    output::conclude(stream, out, ended, integ.time())?;
    Ok(mstar::accuracy::verdict(warned)?)
}

/// Prints the accuracy warning of a run (`mstar::accuracy::warning`), if
/// any; returns whether it did.
pub(crate) fn warn_accuracy<S: System + ?Sized>(
    stats: &mstar::RunStats,
    config: &Config,
    sys: &S,
    files: bool,
) -> bool {
    let warning = mstar::accuracy::warning(stats, config, &|i| sys.coord_name(i), files);
    if let Some(w) = &warning {
        eprintln!("{w}");
    }
    warning.is_some()
}

/// `--reference rk4`: the RK4 solution on the grid `0, h, 2h, …, t_end` (the
/// last step shortened), kept in memory, then written.
fn pendulum_reference(args: &PendulumArgs, run: &PendulumRun) -> Result<()> {
    limits::check_reference(run.t_end, run.config.h, limits::available_memory())?;
    let sys = run.system();
    let samples = run.reference_on_grid();
    let mut stream = open_output(args.out.as_deref(), &sys, &[])?;
    println!("RK4 reference (minimal coordinate θ): {}", describe(run));
    println!("samples: {}", samples.len());
    if let Some(last) = samples.last() {
        println!("θ(t_end) = {:.9} rad at t = {}", last.u[2], Short(last.t));
    }
    let mut ended = Ok(());
    if let Some(stream) = stream.as_mut() {
        for s in &samples {
            if let Some(signal) = signals::received() {
                ended = Err(output::Stop::Signal(signal));
                break;
            }
            stream.push(&s.view());
            if stream.failed() {
                ended = Err(output::Stop::Write);
                break;
            }
        }
    }
    output::conclude(stream, args.out.as_deref(), ended, run.t_end)
}

/// The chain's configuration from the command line.
fn chain_config(args: &ChainArgs) -> Result<Config> {
    if args.links == 0 {
        bail!("--links must be at least 1");
    }
    if !(args.t_end > 0.0 && args.t_end.is_finite()) {
        bail!(
            "--t-end must be a finite positive number (got {})",
            Short(args.t_end)
        );
    }
    // Full Newton: one iteration per step on chains and 1.5 times faster at
    // 10⁵ bars (docs/performance.md); the error estimate reports a whip
    // whichever variant runs it (docs/work-precision.md).
    let mut config = Config {
        h: 1e-3,
        newton: Newton::Full,
        ..Config::default()
    };
    apply_integrator(&args.integ, &mut config, false)?;
    config.validate().context("invalid integrator options")?;
    Ok(config)
}

fn chain(args: &ChainArgs) -> Result<()> {
    let config = chain_config(args)?;
    let n = args.links;
    limits::check_steps(args.t_end, config.h)?;
    let dense = config.kkt.backend == Backend::DENSE;
    let spatial = args.kind == ChainKind::SpatialBars;
    // A spatial link has 7 coordinates and 4 constraints to a planar bar's
    // 3 and 2: about twice the memory per link.
    let weight = if spatial { 2 } else { 1 };
    limits::check_chain(n * weight, dense, limits::available_memory())?;
    let clock = Instant::now();
    match args.kind {
        ChainKind::Bars => run_chain(args, config, &mstar::planar::bar_chain(n), clock),
        ChainKind::Points => run_chain(args, config, &mstar::planar::point_mass_chain(n), clock),
        ChainKind::SpatialBars => {
            // The regularized rotational mass keeps S_T's blocks regular, as
            // the Schur backend needs; the motion is the singular one's.
            let sys = spatial_bar_chain(n, RotationalMass::Regularized);
            // A backend that needs a symmetric matrix (--kkt schur, ldlt) gets
            // the symmetrized tangent: same solution, Newton linear (theory.md).
            let symmetric = config
                .kkt
                .backend
                .registration()
                .is_some_and(|r| r.symmetric);
            let sys = if symmetric {
                sys.with_symmetric_tangent()
            } else {
                sys
            };
            run_chain(args, config, &sys, clock)
        }
    }
}

/// What the chain command reports of a chain model.
trait ChainModel: System {
    /// What the links are.
    fn describe(&self) -> &'static str;
    /// The tip body's name and centre of mass.
    fn tip(&self, u: &[f64]) -> Option<(String, Vec<f64>)>;
    /// The initial state `(u₀, u̇₀)`.
    fn start(&self) -> (Vec<f64>, Vec<f64>);
}

impl ChainModel for mstar::planar::PlanarSystem {
    fn describe(&self) -> &'static str {
        if self.initial_position().len() == 3 * self.n_bodies() {
            "bars on revolute joints"
        } else {
            "point masses on rods"
        }
    }
    fn tip(&self, u: &[f64]) -> Option<(String, Vec<f64>)> {
        let name = format!("link{}", self.n_bodies());
        let x = self.body(&name)?.x;
        Some((name, u[x..x + 2].to_vec()))
    }
    fn start(&self) -> (Vec<f64>, Vec<f64>) {
        (self.initial_position(), self.initial_velocity())
    }
}

impl ChainModel for SpatialSystem {
    fn describe(&self) -> &'static str {
        "solid cylinders on spherical joints (Euler parameters)"
    }
    fn tip(&self, u: &[f64]) -> Option<(String, Vec<f64>)> {
        let name = format!("bar{}", self.n_bodies());
        let (x, _) = self.body(&name)?;
        Some((name, u[x..x + 3].to_vec()))
    }
    fn start(&self) -> (Vec<f64>, Vec<f64>) {
        (self.initial_position(), self.initial_velocity())
    }
}

fn run_chain<S: ChainModel>(
    args: &ChainArgs,
    config: Config,
    sys: &S,
    clock: Instant,
) -> Result<()> {
    let n = args.links;
    let out = args.out.as_deref();
    check_output(
        out,
        csv::header(sys).len(),
        (args.t_end, config.h),
        (None, args.output_every),
    )?;
    let mut stream = open_output(out, sys, &[])?;
    println!(
        "{n}-link chain of {} ({} coordinates, {} constraints); h = {} s, t_end = {} s",
        sys.describe(),
        sys.n_coords(),
        sys.n_constraints(),
        Short(config.h),
        Short(args.t_end)
    );
    let (u0, v0) = sys.start();
    let mut integ = mstar::Integrator::new(sys, config.clone(), 0.0, &u0, &v0)?;
    let setup = clock.elapsed();
    println!(
        "KKT solver: {}; Newton: {}",
        integ.backend(),
        integ.newton()
    );
    let clock = Instant::now();
    let mut progress = Progress::new(args.t_end);
    // Without a file, the samples' energies are not evaluated (see
    // `Observer::reads_energy`): the progress report reads only t.
    let mut grid = output::Grid::new(args.output_every)?;
    let ended = output::drive(&mut integ, args.t_end, &mut |integ| {
        if let Some(stream) = stream.as_mut() {
            grid.rows(&integ.view(), &mut |row| stream.push(row));
            output::watch(stream);
        }
        progress.tick(integ.time());
    });
    if let Some(stream) = stream.as_mut() {
        grid.finish(&mut |row| stream.push(row));
    }
    if ended.is_ok() {
        chain_summary(&integ, sys, n, (setup, clock.elapsed().as_secs_f64()))?;
    }
    let warned = warn_accuracy(&integ.stats(), &config, sys, false);
    output::conclude(stream, out, ended, integ.time())?;
    Ok(mstar::accuracy::verdict(warned)?)
}

/// The chain's timing summary and where its tip ended.
fn chain_summary<S: ChainModel>(
    integ: &mstar::Integrator<'_, S>,
    sys: &S,
    n: usize,
    (setup, wall): (std::time::Duration, f64),
) -> Result<()> {
    let st = integ.stats();
    let steps = st.steps.max(1) as f64;
    println!(
        "wall time: {wall:.3} s (+ {:.3} s setup); steps: {} accepted, {} rejected",
        setup.as_secs_f64(),
        st.steps,
        st.rejected
    );
    println!(
        "Newton iterations: {} ({:.2} per step, {} max); factorizations: {} ({:.3} per step)",
        st.iterations,
        st.iterations as f64 / steps,
        st.max_iterations,
        st.factorizations,
        st.factorizations as f64 / steps
    );
    println!(
        "time per step: {:.2} µs; per body per step: {:.3} µs",
        wall * 1e6 / steps,
        wall * 1e6 / steps / n as f64
    );
    let s = integ.view();
    let (name, tip) = sys.tip(s.u).context("tip body")?;
    let at: Vec<String> = ["x", "y", "z"]
        .iter()
        .zip(&tip)
        .map(|(c, v)| format!("{c} = {v:.9} m"))
        .collect();
    println!(
        "tip ({name}) at t = {}: {}; max ‖Φ‖∞ = {:.3e} m",
        Short(s.t),
        at.join(", "),
        s.constraint
    );
    Ok(())
}

/// Reports the time reached on standard error every two seconds.
struct Progress {
    t_end: f64,
    start: Instant,
    last: Instant,
    steps: usize,
}

impl Progress {
    fn new(t_end: f64) -> Self {
        let now = Instant::now();
        Self {
            t_end,
            start: now,
            last: now,
            steps: 0,
        }
    }

    /// One more sample, at `t`.
    fn tick(&mut self, t: f64) {
        self.steps += 1;
        if self.last.elapsed().as_secs_f64() > 2.0 {
            self.last = Instant::now();
            eprintln!(
                "  t = {:.4} s of {} ({:.0} %), {} steps, {:.1} s elapsed",
                t,
                Short(self.t_end),
                100.0 * t / self.t_end,
                self.steps.saturating_sub(1),
                self.start.elapsed().as_secs_f64()
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(args: &[&str]) -> Result<PendulumRun> {
        let cli = Cli::try_parse_from(std::iter::once("mstar").chain(args.iter().copied()))?;
        match cli.command {
            Command::Pendulum(a) => pendulum_run(&a),
            _ => bail!("not a pendulum command"),
        }
    }

    fn parse_chain(args: &[&str]) -> Result<Config> {
        let cli = Cli::try_parse_from(std::iter::once("mstar").chain(args.iter().copied()))?;
        match cli.command {
            Command::Chain(a) => chain_config(&a),
            _ => bail!("not a chain command"),
        }
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

    #[test]
    fn chain_defaults_and_options() -> Result<()> {
        let c = parse_chain(&["chain", "--links", "10"])?;
        assert_eq!((c.h, c.newton), (1e-3, Newton::Full));
        let c = parse_chain(&["chain", "--links", "10", "--newton", "modified"])?;
        assert_eq!(c.newton, Newton::MODIFIED);
        assert_eq!(c.scheme, Scheme::GeneralizedAlpha { rho_inf: 0.9 });
        let c = parse_chain(&[
            "chain", "--links", "3", "--rho", "0.8", "--h", "0.002", "--newton", "full",
        ])?;
        assert_eq!((c.h, c.newton), (0.002, Newton::Full));
        assert_eq!(c.kkt.backend, Backend::AUTO);
        assert_eq!(c.scheme, Scheme::GeneralizedAlpha { rho_inf: 0.8 });
        let c = parse_chain(&["chain", "--links", "3", "--kkt", "ldlt"])?;
        assert_eq!(c.kkt.backend, Backend::SPARSE_LDLT);
        for r in mstar::kkt::backends() {
            let name = r.backend.name();
            let c = parse_chain(&["chain", "--links", "3", "--kkt", name])?;
            assert_eq!(c.kkt.backend, r.backend, "--kkt {name}");
        }
        assert!(parse_chain(&["chain", "--links", "3", "--kkt", "qr"]).is_err());
        assert!(parse_chain(&["chain", "--links", "0"]).is_err());
        assert!(parse_chain(&["chain", "--links", "5", "--t-end", "-1"]).is_err());
        Ok(())
    }

    #[test]
    fn paper_preset_and_overrides() -> Result<()> {
        let run = parse(&["pendulum", "--preset", "paper"])?;
        assert_eq!(run, PendulumRun::paper());
        let run = parse(&[
            "pendulum",
            "--preset",
            "paper",
            "--h",
            "0.005",
            "--lambda0",
            "-5,1",
        ])?;
        assert_eq!(run.config.h, 0.005);
        assert_eq!(run.config.h_min, Some(0.005));
        assert_eq!(
            run.config.start,
            Start::Paper {
                lambda0: vec![-5.0, 1.0]
            }
        );
        let run = parse(&[
            "pendulum",
            "--preset",
            "paper",
            "--integrator",
            "generalized-alpha",
            "--init",
            "consistent",
        ])?;
        assert_eq!(run.config.scheme, Scheme::GeneralizedAlpha { rho_inf: 0.9 });
        assert_eq!(run.config.start, Start::Consistent);
        Ok(())
    }

    #[test]
    fn default_is_generalized_alpha_with_a_consistent_start() -> Result<()> {
        let run = parse(&["pendulum"])?;
        assert_eq!(run, PendulumRun::standard());
        assert_eq!(run.g0, 9.81);
        let run = parse(&["pendulum", "--beta", "0.3", "--gamma", "0.6"])?;
        assert_eq!(
            run.config.scheme,
            Scheme::Newmark {
                beta: 0.3,
                gamma: 0.6
            }
        );
        Ok(())
    }

    /// A library error that quotes its cause is printed once, with the
    /// context before it.
    #[test]
    fn a_quoted_cause_is_not_repeated() {
        let e = IntegrationError::Kkt {
            context: "solving with the iteration matrix",
            t: 1.0,
            h: 0.01,
            unknown: None,
            source: mstar::kkt::KktError::Singular { unknown: Some(3) },
        };
        let full = anyhow::Error::from(e).context("the run");
        assert_eq!(
            format!("{full:#}")
                .matches("no pivot for unknown 3")
                .count(),
            2
        );
        let line = report(&full);
        assert_eq!(line.matches("no pivot for unknown 3").count(), 1, "{line}");
        assert!(
            line.starts_with("the run: solving with the iteration matrix at t = 1"),
            "{line}"
        );
    }

    #[test]
    fn contradictory_or_invalid_options_are_errors() {
        assert!(parse(&["pendulum", "--integrator", "hht", "--rho", "0.5"]).is_err());
        assert!(parse(&["pendulum", "--init", "consistent", "--lambda0", "1,2"]).is_err());
        assert!(parse(&["pendulum", "--lambda0", "1,2,3"]).is_err());
        assert!(parse(&["pendulum", "--rho", "2"]).is_err());
        assert!(parse(&["pendulum", "--h", "-0.1"]).is_err());
        assert!(parse(&["pendulum", "--t-end", "0"]).is_err());
    }
}
