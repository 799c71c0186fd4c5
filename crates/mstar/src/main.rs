//! The `mstar` command-line program.

mod animate;
mod model_commands;

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use clap::{Parser, Subcommand, ValueEnum};
use mstar::kkt::Backend;
use mstar::newmark::Short;
use mstar::pendulum::PendulumRun;
use mstar::{
    Config, IntegrationError, Newton, Observer, Sample, SampleRef, Scheme, Start, System, csv,
};

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
    Run(model_commands::RunArgs),
    /// Check a model file without integrating it: coordinates, constraints,
    /// degrees of freedom, redundant constraints by name, and how far the
    /// initial state is from the constraints. Exit 0 when it can run as
    /// written, 1 when it cannot, 2 when the file cannot be read.
    Check(model_commands::CheckArgs),
    /// Draw a model moving through the results of `mstar run`: an animated
    /// GIF, a self-contained HTML page (play/pause, time slider) or one frame
    /// as a PNG. Exit 0 when written, 1 when the results do not fit the model
    /// or a file cannot be written, 2 when the model file cannot be read.
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
    /// (ρ∞ = 0.9), consistent start.
    Chain(ChainArgs),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum ChainKind {
    /// Uniform slender bars (1 kg, 1 m, J = m l²/12) on revolute joints.
    Bars,
    /// 1 kg point masses on massless 1 m rods.
    Points,
}

#[derive(clap::Args, Debug)]
struct ChainArgs {
    /// Number of links N.
    #[arg(long)]
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
    /// fastest there; but step control has no error estimate, and cheap
    /// converged steps let h regrow into fast motion it does not resolve.
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
    /// Smallest step size for step control, s [default: h/1024; paper: h, i.e. off].
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
    /// Newton variant [default: modified; paper: full].
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
    #[arg(long)]
    max_iter: Option<usize>,
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
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run(args) => return model_commands::run(&args),
        Command::Check(args) => return model_commands::check(&args),
        Command::Animate(args) => return animate::animate(&args),
        Command::Pendulum(args) => pendulum(&args),
        Command::Chain(args) => chain(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", report(&e));
            if let Some(hint) = e
                .downcast_ref::<IntegrationError>()
                .and_then(|e| hint(e, false))
            {
                eprintln!("hint: {hint}");
            }
            ExitCode::FAILURE
        }
    }
}

/// An error and its causes on one line, `a: b: c` as `{:#}` prints them,
/// but without a cause whose text the line already holds (a library error
/// that quotes its solver's error would otherwise say it twice).
pub(crate) fn report(e: &anyhow::Error) -> String {
    let mut line = String::new();
    for cause in e.chain() {
        let text = cause.to_string();
        if line.contains(&text) {
            continue;
        }
        if !line.is_empty() {
            line.push_str(": ");
        }
        line.push_str(&text);
    }
    line
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
        (IntegrationError::StepSizeTooSmall { .. }, false) => {
            Some("the step size is --h, the smallest step size --h-min")
        }
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
                rho_inf: args.rho.unwrap_or(0.9),
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

fn partial_path(out: &Path) -> PathBuf {
    let stem = out
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    out.with_file_name(format!("{stem}.partial.csv"))
}

fn pendulum(args: &PendulumArgs) -> Result<()> {
    let run = pendulum_run(args)?;
    let sys = run.system();
    if args.reference == Some(Reference::Rk4) {
        let samples = run.reference_on_grid();
        println!("RK4 reference (minimal coordinate θ): {}", describe(&run));
        println!("samples: {}", samples.len());
        if let Some(last) = samples.last() {
            println!("θ(t_end) = {:.9} rad at t = {}", last.u[2], last.t);
        }
        if let Some(out) = &args.out {
            csv::write_csv(out, &sys, &samples)?;
            println!("wrote {}", out.display());
        }
        return Ok(());
    }
    println!("{}", describe(&run));
    let clock = Instant::now();
    let (samples, result) = run.run();
    let wall = clock.elapsed();
    summary(&samples);
    match result {
        Ok(stats) => {
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
            if let Some(out) = &args.out {
                csv::write_csv(out, &sys, &samples)?;
                println!("wrote {} ({} rows)", out.display(), samples.len());
            }
            Ok(())
        }
        Err(e) => {
            if let Some(out) = &args.out {
                let partial = partial_path(out);
                csv::write_csv(&partial, &sys, &samples)?;
                eprintln!(
                    "note: {} was not written; {} up to the failure {} in {}",
                    out.display(),
                    samples_phrase(samples.len()),
                    if samples.len() == 1 { "is" } else { "are" },
                    partial.display()
                );
            }
            Err(e.into())
        }
    }
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
    let mut config = Config {
        h: 1e-3,
        ..Config::default()
    };
    apply_integrator(&args.integ, &mut config, false)?;
    config.validate().context("invalid integrator options")?;
    Ok(config)
}

fn chain(args: &ChainArgs) -> Result<()> {
    let config = chain_config(args)?;
    let n = args.links;
    let clock = Instant::now();
    let sys = match args.kind {
        ChainKind::Bars => mstar::planar::bar_chain(n),
        ChainKind::Points => mstar::planar::point_mass_chain(n),
    };
    println!(
        "{n}-link chain of {} ({} coordinates, {} constraints); h = {} s, t_end = {} s",
        match args.kind {
            ChainKind::Bars => "bars on revolute joints",
            ChainKind::Points => "point masses on rods",
        },
        sys.n_coords(),
        sys.n_constraints(),
        Short(config.h),
        Short(args.t_end)
    );
    let (u0, v0) = (sys.initial_position(), sys.initial_velocity());
    let mut integ = mstar::Integrator::new(&sys, config, 0.0, &u0, &v0)?;
    let setup = clock.elapsed();
    println!(
        "KKT solver: {}; Newton: {}",
        integ.backend(),
        match integ.newton() {
            Newton::Modified { max_rate } => format!("modified (rate ≤ {max_rate})"),
            Newton::Full => "full (a fresh Jacobian at every iteration)".to_string(),
        }
    );
    let stream = args
        .out
        .as_deref()
        .map(|p| csv::CsvStream::create(p, &sys))
        .transpose()?;
    let clock = Instant::now();
    let mut output = ChainOutput {
        stream,
        progress: Progress::new(args.t_end),
    };
    integ.run(args.t_end, &mut output)?;
    let wall = clock.elapsed().as_secs_f64();
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
    let s = integ.sample();
    let tip = sys
        .body(&format!("link{n}"))
        .map(|b| b.x)
        .context("tip body")?;
    println!(
        "tip (link{n}) at t = {}: x = {:.9} m, y = {:.9} m; max ‖Φ‖∞ = {:.3e} m",
        s.t,
        s.u[tip],
        s.u[tip + 1],
        s.constraint
    );
    if let (Some(stream), Some(out)) = (output.stream, &args.out) {
        stream.finish()?;
        println!("wrote {}", out.display());
    }
    Ok(())
}

/// The chain's output: the CSV stream, if any, and the progress report.
struct ChainOutput {
    stream: Option<csv::CsvStream>,
    progress: Progress,
}

impl Observer for ChainOutput {
    fn observe(&mut self, s: &SampleRef<'_>) {
        if let Some(stream) = self.stream.as_mut() {
            stream.observe(s);
        }
        self.progress.observe(s);
    }

    /// Only the CSV file has an energy column.
    fn reads_energy(&self) -> bool {
        self.stream.is_some()
    }
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
}

impl Observer for Progress {
    fn reads_energy(&self) -> bool {
        false
    }

    fn observe(&mut self, s: &SampleRef<'_>) {
        self.steps += 1;
        if self.last.elapsed().as_secs_f64() > 2.0 {
            self.last = Instant::now();
            eprintln!(
                "  t = {:.4} s of {} ({:.0} %), {} steps, {:.1} s elapsed",
                s.t,
                Short(self.t_end),
                100.0 * s.t / self.t_end,
                self.steps.saturating_sub(1),
                self.start.elapsed().as_secs_f64()
            );
        }
    }
}

/// `max |x|`, NaN-aware: a summary never reports a NaN as small.
fn largest(values: impl Iterator<Item = f64>) -> f64 {
    let mut m = mstar::kkt::MaxAbs::new();
    values.for_each(|x| m.push(x));
    m.value()
}

fn summary(samples: &[Sample]) {
    let (Some(first), Some(last)) = (samples.first(), samples.last()) else {
        return;
    };
    let e0 = first.energy();
    let drift = largest(samples.iter().map(|s| s.energy() - e0));
    let phi = largest(samples.iter().map(|s| s.constraint));
    println!(
        "t reached: {} s; θ = {:.9} rad, θ̇ = {:.9} rad/s, λ = [{:.6}, {:.6}]",
        last.t, last.u[2], last.v[2], last.lambda[0], last.lambda[1]
    );
    println!("energy: E₀ = {e0:.6} J, max |E − E₀| = {drift:.3e} J; max ‖Φ‖∞ = {phi:.3e} m");
    // The trapezoidal rule's period-2h mode of λ grows silently: warn when the
    // last second's amplitude is far above the first second's.
    let per_second = samples
        .iter()
        .position(|s| s.t >= first.t + 1.0)
        .unwrap_or(samples.len());
    if samples.len() >= 2 * per_second && per_second >= 3 {
        let amplitude = |part: &[Sample]| {
            (0..first.lambda.len())
                .map(|i| {
                    let x: Vec<f64> = part.iter().map(|s| s.lambda[i]).collect();
                    mstar::analysis::nyquist_amplitude(&x)
                })
                .fold(0.0, f64::max)
        };
        // (The amplitudes of finite samples: a NaN would have stopped the run.)
        let (early, late) = (
            amplitude(&samples[..per_second]),
            amplitude(&samples[samples.len() - per_second..]),
        );
        let scale = largest(samples.iter().flat_map(|s| s.lambda.iter().copied()));
        if late > 10.0 * early && late > 1e-3 * scale {
            println!(
                "warning: the period-2h oscillation of λ grew from {early:.3e} in the first second to {late:.3e} in the last: \
                 the multipliers are not trustworthy (trapezoidal rule on an index-3 system); use generalized-α"
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
        assert_eq!(c.h, 1e-3);
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
