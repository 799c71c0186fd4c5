//! The driven mechanisms: a slider-crank against its closed form and the
//! crank torque of inverse dynamics, a four-bar against its loop-closure
//! equations.

use std::path::Path;

use super::order::order_at_least_row;
use super::{Case, Level, Row, samples, worse};

/// `models/slider-crank.toml`.
pub(super) const CASE: Case = Case {
    model: "slider-crank.toml",
    run: slider_crank,
};

/// `models/four-bar.toml`.
pub(super) const FOUR_BAR: Case = Case {
    model: "four-bar.toml",
    run: four_bar,
};

/// The slider-crank of the model file: crank `r` (0.5 kg, inertia
/// 4.1667e-4 kg m², centre at `r/2`), rod `l` (0.8 kg, 0.006 kg m², centre
/// at `l/2`), slider 1 kg on the x axis, `θ = 0.3 + 10 t`, g = 9.81 m/s².
const R: f64 = 0.1;
const L: f64 = 0.3;
const OMEGA: f64 = 10.0;
const G: f64 = 9.81;
const MASSES: [f64; 3] = [0.5, 0.8, 1.0];
const INERTIAS: [f64; 2] = [4.1666666666667e-4, 0.006];

/// The slider's `x`: `r cos θ + √(l² − r² sin² θ)`.
fn slider_x(theta: f64) -> f64 {
    R * theta.cos() + (L * L - (R * theta.sin()).powi(2)).sqrt()
}

/// The kinetic energy per `θ̇²/2`, `J(θ)`, and the potential energy `V(θ)`:
/// the crank's, the rod's (angle `ψ`, `l sin ψ = −r sin θ`) and the slider's
/// centres and their derivatives in `θ`, by hand.
fn energies(theta: f64) -> (f64, f64) {
    let (s, c) = theta.sin_cos();
    let psi = (-R * s / L).asin();
    let dpsi = -R * c / (L * psi.cos());
    let crank = [-R / 2.0 * s, R / 2.0 * c];
    let rod = [
        -R * s - L / 2.0 * psi.sin() * dpsi,
        R * c + L / 2.0 * psi.cos() * dpsi,
    ];
    let slider = -R * s - L * psi.sin() * dpsi;
    let j = MASSES[0] * (crank[0].powi(2) + crank[1].powi(2))
        + INERTIAS[0]
        + MASSES[1] * (rod[0].powi(2) + rod[1].powi(2))
        + INERTIAS[1] * dpsi * dpsi
        + MASSES[2] * slider * slider;
    let v = G * (MASSES[0] * R / 2.0 * s + MASSES[1] * (R * s + L / 2.0 * psi.sin()));
    (j, v)
}

/// The motor torque at constant `θ̇ = ω` from Lagrange's equation in `θ`:
/// `τ = ½ J'(θ) ω² + V'(θ)` (`θ̈ = 0`), `J'` and `V'` by fourth-order central
/// differences (step 1e-3: truncation ~1e-12 relative).
fn torque(theta: f64) -> f64 {
    let d = 1e-3;
    let at = |k: f64| energies(theta + k * d);
    let (m2, m1, p1, p2) = (at(-2.0), at(-1.0), at(1.0), at(2.0));
    let diff =
        |f: fn(&(f64, f64)) -> f64| (f(&m2) - 8.0 * f(&m1) + 8.0 * f(&p1) - f(&p2)) / (12.0 * d);
    0.5 * diff(|e| e.0) * OMEGA * OMEGA + diff(|e| e.1)
}

fn slider_crank(models: &Path, level: Level) -> Result<Vec<Row>, String> {
    let t_end = if level == Level::Tight { 1.0 } else { 0.2 };
    let model = super::load(models, "slider-crank.toml", &[])?;
    let sys = &model.system;
    let slider = sys.body("slider").ok_or("no body 'slider'")?.x;
    let motor = sys.joint_rows("motor").ok_or("no driver 'motor'")?.start;
    let run = |h: f64| {
        let set = [
            format!("simulation.h={h:e}"),
            format!("simulation.t_end={t_end:e}"),
            "simulation.tol=1e-12".to_string(),
        ];
        samples(models, "slider-crank.toml", &set)
    };
    let (mut position, mut errors) = (0.0f64, [0.0f64; 2]);
    for (k, h) in [1e-3, 5e-4].into_iter().enumerate() {
        for s in run(h)? {
            let theta = 0.3 + OMEGA * s.t;
            position = worse(position, (s.u[slider] - slider_x(theta)).abs());
            // The effort of the driver is −λ (docs/model-format.md, Output).
            errors[k] = worse(errors[k], (-s.lambda[motor] - torque(theta)).abs());
        }
    }
    let tau_max = (0..=200)
        .map(|i| torque(0.3 + f64::from(i) * std::f64::consts::TAU / 200.0).abs())
        .fold(0.0, f64::max);
    Ok(vec![
        Row {
            model: "slider-crank.toml".to_string(),
            quantity: format!("max |Δx| of the slider over {t_end} s (h = 1e-3, 5e-4)"),
            reference: "r cos θ + √(l² − r² sin² θ)".to_string(),
            ours: format!("{position:.2e} m"),
            error: position,
            tolerance: 1e-10,
        },
        Row {
            model: "slider-crank.toml".to_string(),
            quantity: "max |Δτ| of the motor (effort = −λ) at h = 5e-4".to_string(),
            reference: "inverse dynamics ½ J′(θ) ω² + V′(θ)".to_string(),
            ours: format!("{:.2e} N m (|τ| ≤ {tau_max:.3} N m)", errors[1]),
            error: errors[1],
            // Second order: within τ_max (ω h)².
            tolerance: tau_max * (OMEGA * 5e-4).powi(2),
        },
        order_at_least_row(
            "slider-crank.toml",
            "max |Δτ| of the motor",
            "inverse dynamics",
            1e-3,
            errors[0],
            errors[1],
        ),
    ])
}

fn four_bar(models: &Path, level: Level) -> Result<Vec<Row>, String> {
    let t_end = if level == Level::Tight { 2.0 } else { 0.5 };
    let set = [
        format!("simulation.t_end={t_end:e}"),
        "simulation.tol=1e-12".to_string(),
    ];
    let model = super::load(models, "four-bar.toml", &[])?;
    let angle = |name: &str| {
        model
            .system
            .body(name)
            .and_then(|b| b.theta)
            .ok_or(format!("no rigid body '{name}'"))
    };
    let (coupler, rocker) = (angle("coupler")?, angle("rocker")?);
    let mut angles = (0.7381223365325295, 1.5320736152650125);
    let mut worst = 0.0f64;
    for s in samples(models, "four-bar.toml", &set)? {
        angles = loop_closure(0.5 + 2.0 * s.t, angles);
        worst = worse(worst, (s.u[coupler] - angles.0).abs());
        worst = worse(worst, (s.u[rocker] - angles.1).abs());
    }
    Ok(vec![Row {
        model: "four-bar.toml".to_string(),
        quantity: format!("max |Δ| of the coupler and rocker angles over {t_end} s"),
        reference: "loop closure O₂A + AB = O₂O₄ + O₄B (Newton)".to_string(),
        ours: format!("{worst:.2e} rad"),
        error: worst,
        tolerance: 1e-10,
    }])
}

/// The coupler and rocker angles `(α, β)` at crank angle `θ`: Newton on
/// `0.2 e(θ) + 0.6 e(α) − (0.6, 0) − 0.5 e(β) = 0` from `guess`.
fn loop_closure(theta: f64, guess: (f64, f64)) -> (f64, f64) {
    let (mut a, mut b) = guess;
    for _ in 0..50 {
        let f = [
            0.2 * theta.cos() + 0.6 * a.cos() - 0.6 - 0.5 * b.cos(),
            0.2 * theta.sin() + 0.6 * a.sin() - 0.5 * b.sin(),
        ];
        let j = [
            [-0.6 * a.sin(), 0.5 * b.sin()],
            [0.6 * a.cos(), -0.5 * b.cos()],
        ];
        let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
        let da = (f[0] * j[1][1] - f[1] * j[0][1]) / det;
        let db = (j[0][0] * f[1] - j[1][0] * f[0]) / det;
        (a, b) = (a - da, b - db);
        if da.abs().max(db.abs()) < 1e-15 {
            break;
        }
    }
    (a, b)
}
