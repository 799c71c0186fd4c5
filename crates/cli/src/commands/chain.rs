//! `mstar chain`: an N-link chain released from rest, with a timing summary.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use clap::ValueEnum;
use mstar::kkt::Backend;
use mstar::model::spatial::{RotationalMass, SpatialSystem, spatial_bar_chain};
use mstar::newmark::Short;
use mstar::{Config, Newton, System, csv};

use super::options::{IntegratorArgs, apply_integrator};
use super::{check_output, open_output, warn_accuracy};
use crate::{limits, output};

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
pub struct ChainArgs {
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
    pub out: Option<PathBuf>,
    /// Write the state every DT seconds instead of every step (interpolated
    /// within the steps: cubic Hermite on u and u̇), and the last state.
    #[arg(long, value_name = "DT", allow_negative_numbers = true)]
    output_every: Option<f64>,
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
    // A fresh Jacobian once per step: one iteration per step on chains up to
    // 10⁴ bars, and the second one at 10⁵ without a second factorization
    // (docs/performance.md, "The second Newton iteration at 10⁵ bodies");
    // the error estimate reports a whip whichever variant runs it
    // (docs/work-precision.md).
    let mut config = Config {
        h: 1e-3,
        newton: Newton::PER_STEP,
        ..Config::default()
    };
    apply_integrator(&args.integ, &mut config, false)?;
    config.validate().context("invalid integrator options")?;
    Ok(config)
}

pub fn chain(args: &ChainArgs) -> Result<()> {
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
    let mut stream = open_output(out, sys, &[], None)?;
    say!(
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
    say!(
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
    say!(
        "wall time: {wall:.3} s (+ {:.3} s setup); steps: {} accepted, {} rejected",
        setup.as_secs_f64(),
        st.steps,
        st.rejected
    );
    say!(
        "Newton iterations: {} ({:.2} per step, {} max); factorizations: {} ({:.3} per step)",
        st.iterations,
        st.iterations as f64 / steps,
        st.max_iterations,
        st.factorizations,
        st.factorizations as f64 / steps
    );
    say!(
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
    say!(
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
            note!(
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
    use clap::Parser;
    use mstar::Scheme;

    use super::*;

    /// The options of `mstar chain` alone (the first argument names the
    /// program).
    #[derive(Parser)]
    struct Chain {
        #[command(flatten)]
        args: ChainArgs,
    }

    fn parse_chain(args: &[&str]) -> Result<Config> {
        chain_config(&Chain::try_parse_from(args.iter().copied())?.args)
    }

    #[test]
    fn chain_defaults_and_options() -> Result<()> {
        let c = parse_chain(&["chain", "--links", "10"])?;
        assert_eq!((c.h, c.newton), (1e-3, Newton::PER_STEP));
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
}
