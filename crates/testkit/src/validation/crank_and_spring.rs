//! The example of docs/model-format.md: a crank driven at 10 rad/s against
//! a constant torque, and a point mass on a damped spring to the ground
//! (not linked to the crank). References: the slider's two equations of
//! motion integrated by RK4, and the motor torque of the crank's moment
//! balance about its pivot.

use std::path::Path;

use mstar::rk4::rk4_at;

use super::order::order_row;
use super::{Case, Level, Row, samples, worse};

/// `models/crank-and-spring.toml`.
pub(super) const CASE: Case = Case {
    model: "crank-and-spring.toml",
    run: crank_and_spring,
};

const G: f64 = 9.81;

/// The slider (1 kg) on the spring-damper to (0.6, 0): `k` 200 N/m, `c`
/// 2 N s/m, rest length 0.25 m; tension `k (ℓ − ℓ₀) + c ℓ̇` along the
/// spring, gravity along −y. State `(x, y, ẋ, ẏ)`.
fn slider(y: &[f64]) -> Vec<f64> {
    let d = [y[0] - 0.6, y[1]];
    let l = d[0].hypot(d[1]);
    let rate = (d[0] * y[2] + d[1] * y[3]) / l;
    let tension = 200.0 * (l - 0.25) + 2.0 * rate;
    vec![y[2], y[3], -tension * d[0] / l, -tension * d[1] / l - G]
}

/// The motor torque that keeps `θ̈ = 0`: about the pivot, gravity's moment
/// on the crank (0.5 kg, centre 0.05 m out) is `−0.05 m g cos θ` and the
/// drive adds 0.2 N m, so `τ = 0.05 m g cos θ − 0.2`.
fn motor(t: f64) -> f64 {
    0.05 * 0.5 * G * (10.0 * t).cos() - 0.2
}

fn crank_and_spring(models: &Path, level: Level) -> Result<Vec<Row>, String> {
    let file = "crank-and-spring.toml";
    let t_end = if level == Level::Tight { 1.0 } else { 0.5 };
    let model = super::load(models, file, &[])?;
    let p = model
        .system
        .body("slider")
        .ok_or("no point mass 'slider'")?;
    let row = model
        .system
        .joint_rows("motor")
        .ok_or("no driver 'motor'")?
        .start;
    let (mut position, mut torque) = ([0.0f64; 2], [0.0f64; 2]);
    for (k, h) in [1e-3, 5e-4].into_iter().enumerate() {
        let set = [
            format!("simulation.h={h:e}"),
            format!("simulation.t_end={t_end:e}"),
        ];
        let run = samples(models, file, &set)?;
        let times: Vec<f64> = run.iter().map(|s| s.t).collect();
        let reference = rk4_at(slider, vec![0.4, 0.0, 0.0, 0.0], &times, 1e-5);
        for (s, y) in run.iter().zip(&reference) {
            position[k] = worse(position[k], (s.u[p.x] - y[0]).hypot(s.u[p.y] - y[1]));
            torque[k] = worse(torque[k], (-s.lambda[row] - motor(s.t)).abs());
        }
    }
    let tau_max = 0.05 * 0.5 * G + 0.2;
    Ok(vec![
        order_row(
            file,
            &format!("max |Δ slider| over {t_end} s"),
            "RK4 on the slider's equations",
            1e-3,
            position[0],
            position[1],
        ),
        Row {
            model: file.to_string(),
            quantity: format!("max |Δτ| of the motor over {t_end} s at h = 5e-4"),
            reference: "0.05 m g cos θ − 0.2 N m".to_string(),
            ours: format!("{:.2e} N m", torque[1]),
            error: torque[1],
            // Second order: within τ_max (ω h)².
            tolerance: tau_max * (10.0 * 5e-4f64).powi(2),
        },
    ])
}
