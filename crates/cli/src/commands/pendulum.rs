//! `mstar pendulum`: the paper's pendulum, its presets, and the RK4 reference.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use clap::ValueEnum;
use mstar::newmark::Short;
use mstar::pendulum::PendulumRun;
use mstar::{Newton, Scheme, Start, csv};

use super::options::{IntegratorArgs, apply_integrator};
use super::{check_output, open_output, warn_accuracy};
use crate::{limits, output, signals, summary};

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum Preset {
    /// The paper's setting (§3 of the paper).
    Paper,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum Init {
    /// M* ü₀ = g − Bᵀλ₀ with the given λ₀ (the paper's eq. 11).
    Paper,
    /// Consistent accelerations and multipliers from the acceleration-level KKT.
    Consistent,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum Reference {
    /// Classic RK4 on θ̈ = −(g/l) sin θ, reconstructed in [x, y, θ].
    Rk4,
}

#[derive(clap::Args, Debug)]
pub struct PendulumArgs {
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
    pub out: Option<PathBuf>,
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
        Newton::PerStep { max_rate } => {
            format!("Newton once per step (rate ≤ {})", Short(max_rate))
        }
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

pub fn pendulum(args: &PendulumArgs) -> Result<()> {
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
    let mut stream = open_output(out, &sys, &[], None)?;
    say!("{}", describe(&run));
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
    summary.print(
        run.config
            .scheme
            .params()
            .is_ok_and(|p| p.gamma > 0.5 + 1e-12),
    );
    if ended.is_ok() {
        let stats = integ.stats();
        say!(
            "steps: {} accepted, {} rejected; Newton iterations: {} total, {:.2} per step, {} max; factorizations: {}",
            stats.steps,
            stats.rejected,
            stats.iterations,
            stats.iterations as f64 / stats.steps.max(1) as f64,
            stats.max_iterations,
            stats.factorizations
        );
        say!(
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

/// `--reference rk4`: the RK4 solution on the grid `0, h, 2h, …, t_end` (the
/// last step shortened), kept in memory, then written.
fn pendulum_reference(args: &PendulumArgs, run: &PendulumRun) -> Result<()> {
    limits::check_reference(run.t_end, run.config.h, limits::available_memory())?;
    let sys = run.system();
    let samples = run.reference_on_grid();
    let mut stream = open_output(args.out.as_deref(), &sys, &[], None)?;
    say!("RK4 reference (minimal coordinate θ): {}", describe(run));
    say!("samples: {}", samples.len());
    if let Some(last) = samples.last() {
        say!("θ(t_end) = {:.9} rad at t = {}", last.u[2], Short(last.t));
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

#[cfg(test)]
mod tests {
    use clap::Parser;
    use mstar::Scheme;

    use super::*;

    /// The options of `mstar pendulum` alone (the first argument names the
    /// program).
    #[derive(Parser)]
    struct Pendulum {
        #[command(flatten)]
        args: PendulumArgs,
    }

    fn parse(args: &[&str]) -> Result<PendulumRun> {
        pendulum_run(&Pendulum::try_parse_from(args.iter().copied())?.args)
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
