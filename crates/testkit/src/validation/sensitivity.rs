//! Forward sensitivities of the discrete solution (`mstar run
//! --sensitivity`, [`mstar::newmark::Sensitivities`]) against central
//! differences of whole runs at `p ± δ` and `p ± 2δ`, extrapolated
//! (Richardson): `D₁`, `D₂` have errors `c δ²` and `4 c δ²`, `R = (4 D₁ −
//! D₂)/3` removes them, and `|D₁ − D₂|/3` (the estimate of `D₁`'s error)
//! bounds `R`'s. The runs' own errors `η` reach `R` as at most `1.5 η/δ`.

use std::path::{Path, PathBuf};

use mstar::file::{Mechanism, MechanismFile};
use mstar::model::System;
use mstar::newmark::{Integrator, Parameterized, Variant};

use super::{Case, Level, Row};

/// `models/pendulum.toml`: the angle w.r.t. the rod's length.
pub(super) const PENDULUM: Case = Case {
    model: "pendulum.toml",
    run: pendulum,
};

/// `models/slider-crank.toml`: the motor torque w.r.t. the coupler's mass.
pub(super) const SLIDER_CRANK: Case = Case {
    model: "slider-crank.toml",
    run: slider_crank,
};

/// Newton tolerance of every run.
const TOL: f64 = 1e-12;

/// A parameter of a model file given by the overrides it makes at a value.
struct Overrides {
    path: PathBuf,
    name: &'static str,
    value: f64,
    /// The `--set` assignments of the model at a value, and the run's own.
    set: fn(f64) -> Vec<String>,
    common: Vec<String>,
}

/// A model file read at one value.
struct FileModel {
    mechanism: Mechanism,
    u0: Vec<f64>,
    v0: Vec<f64>,
    simulation: mstar::file::Simulation,
}

impl Variant for FileModel {
    fn system(&self) -> &dyn System {
        self.mechanism.system()
    }
    fn initial_position(&self) -> &[f64] {
        &self.u0
    }
    fn initial_velocity(&self) -> &[f64] {
        &self.v0
    }
}

impl Overrides {
    fn model(&self, value: f64) -> Result<FileModel, String> {
        let mut set = self.common.clone();
        set.extend((self.set)(value));
        let file = MechanismFile::load_with(&self.path, &set).map_err(|e| e.to_string())?;
        let sys = mstar::run::lookup(&file.mechanism);
        let (u0, v0) = (sys.initial_position(), sys.initial_velocity());
        Ok(FileModel {
            mechanism: file.mechanism,
            u0,
            v0,
            simulation: file.simulation,
        })
    }

    /// The final `(u, λ)` of a run at `value`, and with `sensitivity` the
    /// final `(∂u/∂p, ∂λ/∂p)` too.
    fn run(&self, value: f64, sensitivity: bool) -> Result<[Vec<f64>; 4], String> {
        let model = self.model(value)?;
        let (config, t_end) = mstar::run::config(&model.simulation).map_err(|e| e.to_string())?;
        let sys = model.system();
        let mut integ =
            Integrator::new(sys, config, 0.0, &model.u0, &model.v0).map_err(|e| e.to_string())?;
        let mut sens = if sensitivity {
            Some(integ.sensitivities(&[self]).map_err(|e| e.to_string())?)
        } else {
            None
        };
        while !integ.reached(t_end) {
            match &mut sens {
                Some(s) => integ.step_with(t_end, s),
                None => integ.step(t_end),
            }
            .map_err(|e| e.to_string())?;
        }
        let s = integ.view();
        let (du, dl) = sens.map_or((Vec::new(), Vec::new()), |s| {
            (s.u(0).to_vec(), s.lambda(0).to_vec())
        });
        Ok([s.u.to_vec(), s.lambda.to_vec(), du, dl])
    }

    /// The sensitivity of `f(u, λ)` (its derivative `df(∂u/∂p, ∂λ/∂p)`,
    /// `f` being linear here) against the extrapolated differences with step `delta`; `eta`
    /// the runs' error in `f`. Returns (ours, reference, tolerance).
    fn check(
        &self,
        delta: f64,
        eta: f64,
        f: &dyn Fn(&[f64], &[f64]) -> f64,
        df: &dyn Fn(&[f64], &[f64]) -> f64,
    ) -> Result<(f64, f64, f64), String> {
        let [_, _, du, dl] = self.run(self.value, true)?;
        let ours = df(&du, &dl);
        let at = |k: f64| -> Result<f64, String> {
            let [u, l, _, _] = self.run(self.value + k * delta, false)?;
            Ok(f(&u, &l))
        };
        let d1 = (at(1.0)? - at(-1.0)?) / (2.0 * delta);
        let d2 = (at(2.0)? - at(-2.0)?) / (4.0 * delta);
        let reference = (4.0 * d1 - d2) / 3.0;
        Ok((ours, reference, (d1 - d2).abs() / 3.0 + 1.5 * eta / delta))
    }
}

impl Parameterized for Overrides {
    fn name(&self) -> String {
        self.name.to_string()
    }
    fn value(&self) -> f64 {
        self.value
    }
    fn at(&self, value: f64) -> Result<Box<dyn Variant>, String> {
        Ok(Box::new(self.model(value)?))
    }
}

/// The paper's pendulum with its rod's length `l` (the hinge's point on the
/// bob and the bob's initial position), released horizontally: `θ` at
/// `t_end` w.r.t. `l`.
fn pendulum(models: &Path, level: Level) -> Result<Vec<Row>, String> {
    let t_end = if level == Level::Tight { 1.0 } else { 0.3 };
    let param = Overrides {
        path: models.join("pendulum.toml"),
        name: "rod length",
        value: 1.0,
        set: |l| {
            vec![
                format!("joint.hinge.points=[[0.0, 0.0], [0.0, {l:?}]]"),
                format!("body.bob.pose=[{l:?}, 0.0, 1.5707963267948966]"),
            ]
        },
        common: vec![
            format!("simulation.t_end={t_end:?}"),
            format!("simulation.tol={TOL:e}"),
        ],
    };
    let delta = 1e-3;
    // θ is u[2]; the positions converge to ‖Φ‖∞ ≤ TOL max(1, ‖u‖∞).
    let (ours, reference, tolerance) =
        param.check(delta, TOL * 2.0, &|u, _| u[2], &|du, _| du[2])?;
    Ok(vec![Row {
        model: "pendulum.toml".to_string(),
        quantity: format!("∂θ/∂l at t = {t_end} s (h = 1e-2), l = 1 m"),
        reference: "central differences of runs at l ± δ, ± 2δ (δ = 1e-3), Richardson".to_string(),
        ours: format!("{ours:.10} rad/m (differences {reference:.10})"),
        error: (ours - reference).abs(),
        tolerance,
    }])
}

/// The slider-crank's motor torque `τ = −λ_motor` at `t_end` w.r.t. the
/// coupler's mass (`body.rod.mass`, 0.8 kg). The mechanism has no degree of
/// freedom: `λ` is affine in the mass, and `δ` can be large (1e-2) against
/// the runs' errors: Newton's residual floor `4 β' ε` (`newton.rs`; β' =
/// 3.97e6 s⁻² at h = 1e-3, ρ∞ = 0.9) over the shortest lever arm, 0.05 m.
fn slider_crank(models: &Path, level: Level) -> Result<Vec<Row>, String> {
    let t_end = if level == Level::Tight { 1.0 } else { 0.2 };
    let path = models.join("slider-crank.toml");
    let motor = {
        let file = MechanismFile::load(&path).map_err(|e| e.to_string())?;
        let sys = file.mechanism.system();
        (0..sys.n_constraints())
            .find(|&i| sys.constraint_name(i) == "motor")
            .ok_or("no driver 'motor'")?
    };
    let param = Overrides {
        path,
        name: "body.rod.mass",
        value: 0.8,
        set: |m| vec![format!("body.rod.mass={m:?}")],
        common: vec![
            format!("simulation.t_end={t_end:?}"),
            format!("simulation.tol={TOL:e}"),
        ],
    };
    let (rho, h) = (0.9f64, 1e-3f64);
    let (alpha_m, alpha_f) = ((2.0 * rho - 1.0) / (rho + 1.0), rho / (rho + 1.0));
    let beta = (1.0 - alpha_m + alpha_f).powi(2) / 4.0;
    let beta_p = (1.0 - alpha_m) / ((1.0 - alpha_f) * beta * h * h);
    let eta = (TOL * 20.0).max(4.0 * beta_p * f64::EPSILON) / 0.05;
    let (ours, reference, tolerance) =
        param.check(1e-2, eta, &|_, l| -l[motor], &|_, dl| -dl[motor])?;
    Ok(vec![Row {
        model: "slider-crank.toml".to_string(),
        quantity: format!("∂τ/∂m of the motor w.r.t. the coupler's mass at t = {t_end} s"),
        reference: "central differences of runs at m ± δ, ± 2δ (δ = 1e-2), Richardson".to_string(),
        ours: format!("{ours:.10} N m/kg (differences {reference:.10})"),
        error: (ours - reference).abs(),
        tolerance,
    }])
}
