//! IFToMM benchmark A02, the N-four-bar (N = 40), against its one-coordinate
//! minimal form integrated by RK4.
//!
//! Every vertical bar turns by the same angle `φ` (from `+x`) and every
//! coupler translates with the tops, so with `m = 1 kg`, `l = 1 m`:
//! `T = ½ ((N + 1)/3 + N) φ̇²`, `V = g ((N + 1)/2 + N) sin φ`, and
//! `((N + 1)/3 + N) φ̈ = −g ((N + 1)/2 + N) cos φ`; B₀ = (cos φ, sin φ).

use std::path::Path;

use mstar::rk4::rk4_at;

use super::{Case, Level, Row, samples, worse};

/// `models/n-four-bar.toml`.
pub(super) const CASE: Case = Case {
    model: "n-four-bar.toml",
    run: n_four_bar,
};

const N: f64 = 40.0;
const G: f64 = 9.81;

fn n_four_bar(models: &Path, level: Level) -> Result<Vec<Row>, String> {
    let t_end = if level == Level::Tight { 20.0 } else { 5.0 };
    let set = [format!("simulation.t_end={t_end:e}")];
    let model = super::load(models, "n-four-bar.toml", &[])?;
    let v0 = model.system.body("V0").ok_or("no body 'V0'")?;
    let theta = v0.theta.ok_or("V0 is not a rigid body")?;
    let run = samples(models, "n-four-bar.toml", &set)?;
    let (inertia, lever) = ((N + 1.0) / 3.0 + N, G * ((N + 1.0) / 2.0 + N));
    let times: Vec<f64> = run.iter().map(|s| s.t).collect();
    let f = |y: &[f64]| vec![y[1], -lever / inertia * y[0].cos()];
    let reference = rk4_at(f, vec![std::f64::consts::FRAC_PI_2, -1.0], &times, 1e-4);
    let (mut position, mut energy) = (0.0f64, 0.0f64);
    let e0 = run.first().map_or(f64::NAN, |s| s.energy);
    for (s, y) in run.iter().zip(&reference) {
        // B₀, the top of V0: its centre plus half a bar along its angle.
        let (sn, cs) = s.u[theta].sin_cos();
        let b0 = [s.u[v0.x] + 0.5 * cs, s.u[v0.y] + 0.5 * sn];
        position = worse(position, (b0[0] - y[0].cos()).hypot(b0[1] - y[0].sin()));
        energy = worse(energy, ((s.energy - e0) / e0).abs());
    }
    let turns = reference
        .last()
        .map_or(0.0, |y| (y[0] - std::f64::consts::FRAC_PI_2).abs())
        / std::f64::consts::TAU;
    Ok(vec![
        Row {
            model: "n-four-bar.toml".to_string(),
            quantity: format!("max |Δ B₀| over {t_end} s ({turns:.1} turns, h = 1e-3)"),
            reference: "minimal form, RK4 (h = 1e-4)".to_string(),
            ours: format!("{position:.2e} m"),
            error: position,
            tolerance: 1e-3,
        },
        Row {
            model: "n-four-bar.toml".to_string(),
            quantity: format!("max |E − E₀|/E₀ over {t_end} s"),
            reference: "0 (conservative)".to_string(),
            ours: format!("{energy:.2e}"),
            error: energy,
            tolerance: 1e-3,
        },
    ])
}
