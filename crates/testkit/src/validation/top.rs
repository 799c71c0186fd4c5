//! The heavy symmetric top (`models/spatial/top.toml`,
//! `models/spatial/top-steady.toml`): its three invariants, and its
//! precession and nutation rates against the closed forms of
//! `mstar::rk4::rigid` (Goldstein §5.7).

use std::path::Path;

use mstar::rk4::rigid::top_slow_rates;

use super::kinematics::{apply, cross, dot, omega_body, rotation};
use super::order::{order_at_least_row, order_row};
use super::{Case, Level, Row, Sample, samples};

/// `models/spatial/top.toml`: the invariants, and the order against the
/// index-1 reference.
pub(super) const TOP: Case = Case {
    model: "spatial/top.toml",
    run: top,
};

/// `models/spatial/top-steady.toml`: precession and nutation.
pub(super) const TOP_STEADY: Case = Case {
    model: "spatial/top-steady.toml",
    run: top_steady,
};

/// The tops of the model files: 2 kg, principal moments 0.05, 0.05, 0.08
/// kg m² about the centre of mass, which is 0.25 m up the symmetry axis
/// from the tip (fixed at the origin); g = 9.81 m/s² along −z.
const MASS: f64 = 2.0;
const J: [f64; 3] = [0.05, 0.05, 0.08];
const L: f64 = 0.25;
const G: f64 = 9.81;

/// Energy, angular momentum about the vertical through the tip, and spin
/// about the symmetry axis of the state `(u, u̇)` (one body, `x, y, z, e₀…e₃`).
fn invariants(u: &[f64], v: &[f64]) -> [f64; 3] {
    let (r, rd) = ([u[0], u[1], u[2]], [v[0], v[1], v[2]]);
    let w = omega_body(&u[3..7], &v[3..7]);
    let jw = [J[0] * w[0], J[1] * w[1], J[2] * w[2]];
    let energy = 0.5 * MASS * dot(rd, rd) + 0.5 * dot(w, jw) + MASS * G * r[2];
    let spin_momentum = apply(&rotation(&u[3..7]), jw);
    let orbital = cross(r, rd);
    let l_z = MASS * orbital[2] + spin_momentum[2];
    [energy, l_z, w[2]]
}

/// The largest `|I(t) − I(0)| / |I(0)|` of each invariant over a run.
fn drifts(run: &[Sample]) -> [f64; 3] {
    let first = invariants(&run[0].u, &run[0].v);
    let mut worst = [0.0f64; 3];
    for s in run {
        let now = invariants(&s.u, &s.v);
        for k in 0..3 {
            worst[k] = super::worse(worst[k], ((now[k] - first[k]) / first[k]).abs());
        }
    }
    worst
}

fn top(models: &Path, level: Level) -> Result<Vec<Row>, String> {
    let name = "spatial/top.toml";
    let t_end = if level == Level::Tight { 10.0 } else { 1.0 };
    let run = |h: f64| {
        let set = [
            format!("simulation.h={h:e}"),
            format!("simulation.t_end={t_end:e}"),
            "simulation.tol=1e-12".to_string(),
        ];
        samples(models, name, &set)
    };
    let (coarse, fine) = (drifts(&run(1e-3)?), drifts(&run(5e-4)?));
    let mut rows = Vec::new();
    let what = ["energy", "vertical angular momentum", "spin ω₃"];
    for k in 0..3 {
        rows.push(Row {
            model: name.to_string(),
            quantity: format!(
                "max relative drift of the {} over {t_end} s (h = 1e-3)",
                what[k]
            ),
            reference: "invariant: 0".to_string(),
            ours: format!("{:.2e}", coarse[k]),
            error: coarse[k],
            tolerance: 1e-6,
        });
        rows.push(order_at_least_row(
            name,
            &format!("the {} drift", what[k]),
            "invariant",
            1e-3,
            coarse[k],
            fine[k],
        ));
    }
    let span = if level == Level::Tight { 1.0 } else { 0.2 };
    rows.extend(super::spatial::against_index1(models, name, span, 1e-3)?);
    Ok(rows)
}

/// The tilt `θ` of the symmetry axis from the vertical and its azimuth
/// `φ` (the precession angle, not unwrapped) at `u`.
fn tilt_and_azimuth(u: &[f64]) -> (f64, f64) {
    let k = apply(&rotation(&u[3..7]), [0.0, 0.0, 1.0]);
    (k[2].clamp(-1.0, 1.0).acos(), k[1].atan2(k[0]))
}

/// The nutation frequency and mean precession rate of a run: between the
/// first and the last upward crossing of the tilt through its mean (a whole
/// number of nutation periods), `2π periods / span` and `Δφ / span`, the
/// crossings interpolated linearly.
fn rates(run: &[Sample]) -> Result<(f64, f64), String> {
    let mut phi = Vec::with_capacity(run.len());
    let mut theta = Vec::with_capacity(run.len());
    for s in run {
        let (th, az) = tilt_and_azimuth(&s.u);
        // Unwrap the azimuth: successive samples differ by far less than π.
        let last = phi.last().copied().unwrap_or(az);
        let turn = std::f64::consts::TAU;
        phi.push(last + (az - last + 0.5 * turn).rem_euclid(turn) - 0.5 * turn);
        theta.push(th);
    }
    let mean = theta.iter().sum::<f64>() / theta.len() as f64;
    let mut crossings = Vec::new();
    for i in 1..run.len() {
        let (a, b) = (theta[i - 1] - mean, theta[i] - mean);
        if a < 0.0 && b >= 0.0 {
            let f = a / (a - b);
            let t = run[i - 1].t + f * (run[i].t - run[i - 1].t);
            crossings.push((t, phi[i - 1] + f * (phi[i] - phi[i - 1])));
        }
    }
    match (crossings.first(), crossings.last()) {
        (Some(&(t0, phi0)), Some(&(t1, phi1))) if crossings.len() >= 3 => {
            let periods = (crossings.len() - 1) as f64;
            Ok((
                std::f64::consts::TAU * periods / (t1 - t0),
                (phi1 - phi0) / (t1 - t0),
            ))
        }
        _ => Err(format!(
            "{} nutation periods: too few to measure",
            crossings.len()
        )),
    }
}

fn top_steady(models: &Path, level: Level) -> Result<Vec<Row>, String> {
    let name = "spatial/top-steady.toml";
    let t_end = if level == Level::Tight { 10.0 } else { 3.0 };
    let sys = super::load_spatial(models, name, &[])?;
    let (u0, v0) = (sys.initial_position(), sys.initial_velocity());
    let (theta0, _) = tilt_and_azimuth(&u0);
    let omega3 = omega_body(&u0[3..7], &v0[3..7])[2];
    let a = J[0] + MASS * L * L;
    let closed = top_slow_rates(MASS, G, L, a, J[2], omega3, theta0);
    let mut measured = Vec::new();
    for h in [1e-3, 5e-4] {
        let set = [
            format!("simulation.h={h:e}"),
            format!("simulation.t_end={t_end:e}"),
            "simulation.tol=1e-12".to_string(),
        ];
        measured.push(rates(&samples(models, name, &set)?)?);
    }
    // The trapezoidal rule's relative phase error on a rotation at rate ω is
    // (ω h)²/12; the fastest here is the spin ω₃: allowed 12 times that.
    let tolerance = (omega3.abs().max(closed.nutation) * 1e-3).powi(2);
    let mut rows = Vec::new();
    for (k, (what, reference)) in [
        ("nutation frequency Ω", closed.nutation),
        ("mean precession rate φ̇", closed.precession),
    ]
    .into_iter()
    .enumerate()
    {
        let pick = |m: &(f64, f64)| if k == 0 { m.0 } else { m.1 };
        let error = |m: &(f64, f64)| ((pick(m) - reference) / reference).abs();
        let closed_form = "small nutation, Goldstein §5.7";
        rows.push(Row {
            model: name.to_string(),
            quantity: format!("{what} over {t_end} s, relative error (h = 1e-3)"),
            reference: format!("{reference:.6} rad/s ({closed_form})"),
            ours: format!("{:.6} rad/s", pick(&measured[0])),
            error: error(&measured[0]),
            tolerance,
        });
        let (coarse, fine) = (error(&measured[0]), error(&measured[1]));
        rows.push(order_row(name, what, closed_form, 1e-3, coarse, fine));
    }
    Ok(rows)
}
