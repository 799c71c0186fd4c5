//! Spatial mechanisms of `models/spatial/` against the index-1 reference
//! (`mstar::rk4::Index1Rk4`: RK4 on the acceleration-level KKT system with
//! projection, no code shared with the linearize / kkt / newmark path), a
//! one-angle pendulum, the torque-free closed form and energy conservation.

use std::path::Path;

use mstar::model::System;
use mstar::rk4::rigid::torque_free_period;
use mstar::rk4::{AngleChain, AngleLink, Index1Rk4};

use super::kinematics::{dot, omega_body};

use super::order::{order_at_least_row, order_row};
use super::{Case, Level, Row, Sample, load_spatial, samples, worse};

/// The largest `|x − y|` over the entries `keep` admits.
fn max_diff(x: &[f64], y: &[f64], keep: impl Fn(usize) -> bool) -> f64 {
    x.iter()
        .zip(y)
        .enumerate()
        .filter(|(i, _)| keep(*i))
        .fold(0.0, |acc, (_, (a, b))| worse(acc, (a - b).abs()))
}

/// The errors in `u`, `u̇` and `λ` (rows `keep`) of `run` against the
/// reference at the times of `at` (every `stride`-th sample of `run`).
fn errors(
    run: &[Sample],
    stride: usize,
    at: &[(Vec<f64>, Vec<f64>, Vec<f64>)],
    keep: &dyn Fn(usize) -> bool,
) -> [f64; 3] {
    let mut e = [0.0f64; 3];
    for (s, (u, v, lambda)) in run.iter().step_by(stride).zip(at) {
        e[0] = worse(e[0], max_diff(&s.u, u, |_| true));
        e[1] = worse(e[1], max_diff(&s.v, v, |_| true));
        e[2] = worse(e[2], max_diff(&s.lambda, lambda, keep));
    }
    e
}

/// Order rows (2 ± 0.1, the target for spatial models) of the
/// largest errors in positions, velocities and joint multipliers over
/// `t_end` against `Index1Rk4` at `h` and `h/2`, tolerance 1e-12 on Newton.
pub(super) fn against_index1(
    models: &Path,
    name: &str,
    t_end: f64,
    h: f64,
) -> Result<Vec<Row>, String> {
    let sys = load_spatial(models, name, &[])?;
    let run = |h: f64| samples(models, name, &settings(h, t_end));
    let (coarse, fine) = (run(h)?, run(0.5 * h)?);
    let times: Vec<f64> = coarse.iter().map(|s| s.t).collect();
    let oracle = Index1Rk4::new(&sys);
    let states = oracle
        .solve(&sys.initial_position(), &sys.initial_velocity(), &times)
        .map_err(|e| e.to_string())?;
    let mut reference = Vec::with_capacity(states.len());
    for (&t, (u, v)) in times.iter().zip(states) {
        let lambda = oracle.multipliers(t, &u, &v).map_err(|e| e.to_string())?;
        reference.push((u, v, lambda));
    }
    // The normalization rows' multipliers depend on how the singular
    // direction of M is filled (docs/theory.md): joint rows only.
    let keep = |i: usize| !sys.constraint_name(i).ends_with(".norm");
    let (ec, ef) = (
        errors(&coarse, 1, &reference, &keep),
        errors(&fine, 2, &reference, &keep),
    );
    let what = ["positions u", "velocities u̇", "joint multipliers λ"];
    Ok((0..3)
        .map(|k| {
            let mut row = order_row(
                name,
                &format!("max |Δ {}| over {t_end} s", what[k]),
                "Index1Rk4",
                h,
                ec[k],
                ef[k],
            );
            row.tolerance = 0.1;
            row
        })
        .collect())
}

/// `models/spatial/double-pendulum.toml` against the index-1 reference.
pub(super) const DOUBLE_PENDULUM: Case = Case {
    model: "spatial/double-pendulum.toml",
    run: |models, level| against_index1(models, "spatial/double-pendulum.toml", span(level), 1e-3),
};

/// `models/spatial/slider-crank.toml` against the index-1 reference.
pub(super) const SLIDER_CRANK: Case = Case {
    model: "spatial/slider-crank.toml",
    run: |models, level| against_index1(models, "spatial/slider-crank.toml", span(level), 1e-3),
};

/// `models/spatial/tilted-hinge.toml` against a one-angle pendulum.
pub(super) const TILTED_HINGE: Case = Case {
    model: "spatial/tilted-hinge.toml",
    run: tilted_hinge,
};

/// `models/spatial/dzhanibekov.toml`: the flip interval.
pub(super) const DZHANIBEKOV: Case = Case {
    model: "spatial/dzhanibekov.toml",
    run: dzhanibekov,
};

/// `models/spatial/bricard.toml`: energy.
pub(super) const BRICARD: Case = Case {
    model: "spatial/bricard.toml",
    run: bricard,
};

/// The span of the comparisons with the index-1 reference, s.
fn span(level: Level) -> f64 {
    if level == Level::Tight { 1.0 } else { 0.5 }
}

/// `simulation.h`, `t_end` and a Newton tolerance of 1e-12.
fn settings(h: f64, t_end: f64) -> [String; 3] {
    [
        format!("simulation.h={h:e}"),
        format!("simulation.t_end={t_end:e}"),
        "simulation.tol=1e-12".to_string(),
    ]
}

/// The bar of the tilted hinge (1 kg, 1 m, its centre 0.5 m from the hinge
/// along +y, moment 0.0833667 kg m² about the axis through its centre
/// parallel to the hinge axis `n = (cos 30°, 0, sin 30°)`) turns in the plane
/// spanned by `e₁ = (0, 1, 0)` and `e₂ = n × e₁ = (−sin 30°, 0, cos 30°)`,
/// where gravity has the component `g cos 30°` along `−e₂`: a pendulum of one
/// angle from `e₁`, `(J + m c²) φ̈ = −m g cos 30° c cos φ`, started at rest at
/// `φ = 0`.
fn tilted_hinge(models: &Path, level: Level) -> Result<Vec<Row>, String> {
    let name = "spatial/tilted-hinge.toml";
    let t_end = if level == Level::Tight { 5.0 } else { 1.0 };
    let (s30, c30) = (0.5f64, 0.75f64.sqrt());
    let link = AngleLink {
        m: 1.0,
        j: 0.0833667,
        l: 1.0,
        c: 0.5,
    };
    let chain = AngleChain::new(vec![link], 9.81 * c30);
    let (e1, e2) = ([0.0, 1.0, 0.0], [-s30, 0.0, c30]);
    let h = 1e-3;
    let mut worst = [0.0f64; 2];
    for (k, step) in [h, 0.5 * h].into_iter().enumerate() {
        let run = samples(models, name, &settings(step, t_end))?;
        let times: Vec<f64> = run.iter().map(|s| s.t).collect();
        let reference = chain.solve(&[0.0], &[0.0], &times);
        for (s, (phi, _)) in run.iter().zip(&reference) {
            let [x, y] = chain.centres(phi)[0];
            let d: f64 = (0..3)
                .map(|i| (s.u[i] - x * e1[i] - y * e2[i]).powi(2))
                .sum();
            worst[k] = worse(worst[k], d.sqrt());
        }
    }
    Ok(vec![order_row(
        name,
        &format!("max |Δ bar's centre| over {t_end} s"),
        "RK4 on the one-angle pendulum, g cos 30°",
        h,
        worst[0],
        worst[1],
    )])
}

/// The free body of `dzhanibekov.toml`: principal moments, kg m².
const DZHANIBEKOV_INERTIA: [f64; 3] = [0.1, 0.2, 0.3];

/// The times at which the body-axis angular velocity about the intermediate
/// axis changes sign (the flips), interpolated linearly, with the index of
/// the sample after each.
fn flips(run: &[Sample]) -> Vec<(f64, usize)> {
    let w2: Vec<f64> = run
        .iter()
        .map(|s| omega_body(&s.u[3..7], &s.v[3..7])[1])
        .collect();
    (1..run.len())
        .filter(|&i| (w2[i - 1] > 0.0) != (w2[i] > 0.0))
        .map(|i| {
            let f = w2[i - 1] / (w2[i - 1] - w2[i]);
            (run[i - 1].t + f * (run[i].t - run[i - 1].t), i)
        })
        .collect()
}

/// The worst relative deviation from the closed-form period `period` of the
/// time between every flip and the next but one (a whole period: the two
/// halves of a period differ when the numerical solution is slightly
/// asymmetric).
fn flip_error(run: &[Sample], period: f64) -> Result<f64, String> {
    let times = flips(run);
    if times.len() < 3 {
        return Err(format!("{} flips: too few to measure", times.len()));
    }
    Ok(times.windows(3).fold(0.0, |acc, w| {
        worse(acc, ((w[2].0 - w[0].0) - period).abs() / period)
    }))
}

fn dzhanibekov(models: &Path, level: Level) -> Result<Vec<Row>, String> {
    let name = "spatial/dzhanibekov.toml";
    let sys = load_spatial(models, name, &[])?;
    let (u0, v0) = (sys.initial_position(), sys.initial_velocity());
    let omega0 = omega_body(&u0[3..7], &v0[3..7]);
    let period = torque_free_period(DZHANIBEKOV_INERTIA, omega0);
    let t_end = period * if level == Level::Tight { 4.0 } else { 1.9 };
    let h = 1e-3;
    let run = |h: f64| samples(models, name, &settings(h, t_end));
    let (coarse, fine) = (
        flip_error(&run(h)?, period)?,
        flip_error(&run(0.5 * h)?, period)?,
    );
    let rate = dot(omega0, omega0).sqrt();
    let reference = "torque-free polhode period (Landau & Lifshitz §37)";
    Ok(vec![
        Row {
            model: name.to_string(),
            quantity: format!("max relative |Δ period| between flips over {t_end:.2} s (h = 1e-3)"),
            reference: format!("T = {period:.6} s ({reference})"),
            ours: format!("{coarse:.2e}"),
            error: coarse,
            // The trapezoidal rule's relative phase error at rate |ω| is
            // (|ω| h)²/12: allowed 12 times that.
            tolerance: (rate * h).powi(2),
        },
        order_row(name, "the period between flips", reference, h, coarse, fine),
    ])
}

fn bricard(models: &Path, level: Level) -> Result<Vec<Row>, String> {
    let name = "spatial/bricard.toml";
    let t_end = if level == Level::Tight { 2.0 } else { 0.5 };
    let h = 1e-3;
    let drift = |step: f64| -> Result<(f64, f64, f64), String> {
        let run = samples(models, name, &settings(step, t_end))?;
        let e0 = run.first().ok_or("no samples")?.energy;
        let scale = run.iter().fold(0.0, |acc, s| worse(acc, s.kinetic));
        let worst = run
            .iter()
            .fold(0.0, |acc, s| worse(acc, (s.energy - e0).abs()));
        let rate = run
            .iter()
            .fold(0.0, |acc, s| worse(acc, fastest_rotation(s)));
        Ok((worst / scale, scale, rate))
    };
    let ((coarse, scale, rate), (fine, _, _)) = (drift(h)?, drift(0.5 * h)?);
    Ok(vec![
        Row {
            model: name.to_string(),
            quantity: format!(
                "max |ΔE| over {t_end} s / max kinetic energy (h = 1e-3, minimum-norm λ)"
            ),
            reference: "conserved: 0".to_string(),
            ours: format!("{coarse:.2e} (of {scale:.3} J)"),
            error: coarse,
            // Second order: (ω h)² for the fastest rotation ω in the run.
            tolerance: (rate * h).powi(2),
        },
        order_at_least_row(name, "the energy drift", "conserved", h, coarse, fine),
    ])
}

/// The largest angular speed of the bodies of a sample (coordinates in
/// blocks of seven, `x, y, z, e₀…e₃`).
fn fastest_rotation(s: &Sample) -> f64 {
    (0..s.u.len() / 7)
        .map(|b| {
            let w = omega_body(&s.u[7 * b + 3..7 * b + 7], &s.v[7 * b + 3..7 * b + 7]);
            dot(w, w).sqrt()
        })
        .fold(0.0, worse)
}
