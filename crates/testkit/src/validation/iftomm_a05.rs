//! IFToMM A05, the stiff flyball governor, against its equations of motion
//! in four minimal coordinates.
//!
//! The benchmark (library of computational benchmarks of the IFToMM
//! Technical Committee for Multibody Dynamics; González, Dopico, Lugrís &
//! Cuadrado, Multibody Syst. Dyn. 16 (2006) 179–190) asks for the slider's
//! height `s` over 10 s and reports the CPU time of the run. Its reference
//! time history is not available here; the geometry and values are those of
//! its OpenSim port (`models/spatial/iftomm-a05-flyball.toml` says which).
//! The reference is the governor in the coordinates `q = (φ, s, θ₁, θ₂)` —
//! the shaft's angle, the slider's height and each rod's angle from the
//! downward vertical in the plane that turns with the shaft — written here
//! by hand (Lagrange's equations; no mstar code) and integrated by RK4 at
//! [`REFERENCE_STEP`].
//!
//! With `a` the hinges' distance from the shaft, `H` their height, `L` the
//! rods' length, a point at distance `ℓ` along rod `i` is at radius
//! `a + ℓ sin θᵢ` and height `H − ℓ cos θᵢ`, so its speed squared is
//! `ℓ² θ̇ᵢ² + (a + ℓ sin θᵢ)² φ̇²`. The kinetic energy is then diagonal,
//! `T = ½ M_φ(θ) φ̇² + ½ m_s ṡ² + ½ M_θ Σ θ̇ᵢ²`, with
//! `M_φ = J_shaft + J_slider + Σᵢ [m_r (a + (L/2) sin θᵢ)² + I_t sin² θᵢ +
//! I_a cos² θᵢ + m_b (a + L sin θᵢ)²]` and `M_θ = m_r (L/2)² + I_t + m_b L²`
//! (rods of transverse moment `I_t` and axial moment `I_a` about their
//! centres, balls `m_b` at their ends, the rod's angular velocity
//! `φ̇ e_z + θ̇ᵢ n` with `n` normal to the turning plane). The equations:
//! `M_φ φ̈ = −Σᵢ ∂M_φ/∂θᵢ θ̇ᵢ φ̇` (no torque about the shaft),
//! `M_θ θ̈ᵢ = ½ ∂M_φ/∂θᵢ φ̇² − g (m_r L/2 + m_b L) sin θᵢ − Fᵢ ∂ℓᵢ/∂θᵢ`,
//! `m_s s̈ = −m_s g − Σᵢ Fᵢ ∂ℓᵢ/∂s`, where spring `i` joins the slider's
//! point at radius `a`, height `s`, to rod `i`'s centre: length `ℓᵢ` from
//! the differences `Δr = (L/2) sin θᵢ`, `Δz = H − (L/2) cos θᵢ − s` (both
//! points turn with the shaft, so the turning does not stretch it), tension
//! `Fᵢ = k (ℓᵢ − ℓ₀) + c ℓ̇ᵢ`.

use std::path::Path;
use std::time::Instant;

use mstar::file::{Mechanism, MechanismFile};
use mstar::model::{SampleRef, System};

use super::order::order_row;
use super::{Case, Level, Row, worse};

/// `models/spatial/iftomm-a05-flyball.toml`.
pub(super) const CASE: Case = Case {
    model: "spatial/iftomm-a05-flyball.toml",
    run: a05,
};

const MODEL: &str = "spatial/iftomm-a05-flyball.toml";

/// The problem's data (the OpenSim port's `createModel.cpp`): gravity
/// (m/s²), hinges' distance from the shaft and height (m), rods' length (m),
/// rod mass (kg) and moments about its centre (kg m²), ball mass, slider
/// mass (kg) and moment about the shaft, shaft's moment about its axis,
/// spring stiffness (N/m), damping (N s/m) and rest length (m).
const G: f64 = 9.81;
const A: f64 = 0.05;
const H: f64 = 1.0;
const L: f64 = 1.0;
const M_ROD: f64 = 0.3;
const I_T: f64 = 0.0250025;
const I_A: f64 = 5e-6;
const M_BALL: f64 = 5.0;
const M_SLIDER: f64 = 3.0;
const J_SLIDER: f64 = 0.005;
const J_SHAFT: f64 = 5e-6;
const K: f64 = 8e5;
const C: f64 = 4e4;
const REST: f64 = 0.5;

/// The start: `φ = 0`, `s = 0.5` m, both rods 60° from the downward
/// vertical (30° below the horizontal), the shaft at 2π rad/s, everything
/// else at rest relative to it.
const START: [f64; 8] = [
    0.0,
    0.5,
    std::f64::consts::FRAC_PI_3,
    std::f64::consts::FRAC_PI_3,
    std::f64::consts::TAU,
    0.0,
    0.0,
    0.0,
];

/// The benchmark's span (s) and the output interval compared (s).
const SPAN: f64 = 10.0;
const EVERY: f64 = 0.01;

/// RK4's step for the reference: a thousandth of the output interval. The
/// fastest mode (the slider on the two dampers, `λ ≈ −2 c (Δz/ℓ)² / m_s ≈
/// −6.7e3` 1/s) is then at `|λ h| ≈ 0.07`, well inside RK4's stability
/// region, and the smooth motion's error `O(h⁴)` is below 1e-12 m.
const REFERENCE_STEP: f64 = 1e-5;

/// `q̇, q̈` of the state `y = (q, q̇)`, `q = (φ, s, θ₁, θ₂)`.
fn rate(y: &[f64; 8]) -> [f64; 8] {
    let [_, s, t1, t2, dphi, ds, dt1, dt2] = *y;
    let (theta, dtheta) = ([t1, t2], [dt1, dt2]);
    let m_theta = M_ROD * (L / 2.0).powi(2) + I_T + M_BALL * L * L;
    let mut m_phi = J_SHAFT + J_SLIDER;
    let (mut dm_phi, mut q_theta) = ([0.0; 2], [0.0; 2]);
    let mut q_s = -M_SLIDER * G;
    for i in 0..2 {
        let (sn, cs) = theta[i].sin_cos();
        let (r_c, r_b) = (A + L / 2.0 * sn, A + L * sn);
        m_phi += M_ROD * r_c * r_c + I_T * sn * sn + I_A * cs * cs + M_BALL * r_b * r_b;
        dm_phi[i] = 2.0 * M_ROD * r_c * (L / 2.0) * cs
            + 2.0 * (I_T - I_A) * sn * cs
            + 2.0 * M_BALL * r_b * L * cs;
        // Spring i: from the slider's point to the rod's centre.
        let (dr, dz) = (L / 2.0 * sn, H - L / 2.0 * cs - s);
        let length = dr.hypot(dz);
        let (ddr, ddz) = (L / 2.0 * cs * dtheta[i], L / 2.0 * sn * dtheta[i] - ds);
        let stretch_rate = (dr * ddr + dz * ddz) / length;
        let tension = K * (length - REST) + C * stretch_rate;
        let dl_dtheta = (dr * L / 2.0 * cs + dz * L / 2.0 * sn) / length;
        let dl_ds = -dz / length;
        q_theta[i] = -tension * dl_dtheta - G * (M_ROD * L / 2.0 + M_BALL * L) * sn;
        q_s -= tension * dl_ds;
    }
    let ddphi = -(dm_phi[0] * dt1 + dm_phi[1] * dt2) * dphi / m_phi;
    let ddtheta = |i: usize| (q_theta[i] + 0.5 * dm_phi[i] * dphi * dphi) / m_theta;
    [
        dphi,
        ds,
        dt1,
        dt2,
        ddphi,
        q_s / M_SLIDER,
        ddtheta(0),
        ddtheta(1),
    ]
}

/// One RK4 step of `h`.
fn rk4_step(y: &mut [f64; 8], h: f64) {
    let shifted = |y: &[f64; 8], k: &[f64; 8], c: f64| std::array::from_fn(|i| y[i] + c * k[i]);
    let k1 = rate(y);
    let k2 = rate(&shifted(y, &k1, h / 2.0));
    let k3 = rate(&shifted(y, &k2, h / 2.0));
    let k4 = rate(&shifted(y, &k3, h));
    for i in 0..8 {
        y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
    }
}

/// The reference state at `t = 0, EVERY, 2 EVERY, …, t_end`.
fn reference(t_end: f64) -> Vec<[f64; 8]> {
    let per_output = (EVERY / REFERENCE_STEP).round() as usize;
    let outputs = (t_end / EVERY).round() as usize;
    let mut y = START;
    let mut out = vec![y];
    for _ in 0..outputs {
        for _ in 0..per_output {
            rk4_step(&mut y, REFERENCE_STEP);
        }
        out.push(y);
    }
    out
}

/// One run of the file: the largest `|s − s_ref|` at the output times, how
/// many were compared, and the run's CPU time (wall clock, one thread).
struct Run {
    error: f64,
    count: usize,
    cpu: f64,
}

/// Runs the file to `t_end` at step `h` as `mstar run` does, comparing the
/// slider's height with `reference` at every multiple of [`EVERY`].
fn run(models: &Path, t_end: f64, h: f64, reference: &[[f64; 8]]) -> Result<Run, String> {
    let set = [
        format!("simulation.t_end={t_end:e}"),
        format!("simulation.h={h:e}"),
    ];
    let file = MechanismFile::load_with(&models.join(MODEL), &set).map_err(|e| e.to_string())?;
    let Mechanism::Spatial(sys) = &file.mechanism else {
        return Err(format!("{MODEL}: not a spatial model"));
    };
    let s_index = (0..sys.n_coords())
        .find(|&i| sys.coord_name(i) == "slider.z")
        .ok_or(format!("{MODEL}: no coordinate 'slider.z'"))?;
    let (mut error, mut count) = (0.0f64, 0usize);
    let clock = Instant::now();
    mstar::run::simulate(
        mstar::run::lookup(&file.mechanism),
        &file.simulation,
        &mut |x: &SampleRef<'_>| {
            let k = (x.t / EVERY).round();
            if (x.t - k * EVERY).abs() <= 0.25 * h {
                let want = reference.get(k as usize).map_or(f64::NAN, |y| y[1]);
                error = worse(error, (x.u[s_index] - want).abs());
                count += 1;
            }
        },
    )
    .map_err(|e| format!("{MODEL}: {e}"))?;
    let cpu = clock.elapsed().as_secs_f64();
    if count != reference.len() {
        return Err(format!(
            "{MODEL}: {count} samples on output times, not {}",
            reference.len()
        ));
    }
    Ok(Run { error, count, cpu })
}

/// The rows: `s` against the reference at the file's step with the run's
/// CPU time, and the observed order from half that step. `Quick` runs the
/// first 2 s (the test), `Tight` the benchmark's 10 s.
///
/// The error's tolerance is that of the other spatial rows: the
/// trapezoidal rule's phase error `(ω h)²/12` a radian at the fastest
/// rotation rate `ω` (the shaft's largest rate), allowed twelve times, over
/// the span `T`, on a motion of amplitude `A_s` (the largest `|s − s₀|` of
/// the reference): `A_s ω T (ω h)²`.
fn a05(models: &Path, level: Level) -> Result<Vec<Row>, String> {
    let t_end = if level == Level::Tight { SPAN } else { 2.0 };
    let reference = reference(t_end);
    let h = 1e-3;
    let coarse = run(models, t_end, h, &reference)?;
    let fine = run(models, t_end, h / 2.0, &reference)?;
    let amplitude = reference
        .iter()
        .fold(0.0f64, |m, y| worse(m, (y[1] - START[1]).abs()));
    let omega = reference.iter().fold(0.0f64, |m, y| worse(m, y[4].abs()));
    let tolerance = amplitude * omega * t_end * (omega * h).powi(2);
    Ok(vec![
        Row {
            model: MODEL.to_string(),
            quantity: format!(
                "IFToMM A05: max |Δs| (slider height) at the {} output times (every {EVERY} s) over {t_end} s (h = {h:e})",
                coarse.count
            ),
            reference: format!(
                "RK4 (h = {REFERENCE_STEP:e}) on Lagrange's equations in (φ, s, θ₁, θ₂); A_s ω T (ω h)²"
            ),
            ours: format!("{:.2e} m; CPU time {:.3} s", coarse.error, coarse.cpu),
            error: coarse.error,
            tolerance,
        },
        order_row(
            MODEL,
            &format!("max |Δs| over {t_end} s"),
            "RK4 on the minimal coordinates",
            h,
            coarse.error,
            fine.error,
        ),
    ])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The reference conserves the shaft's angular momentum `M_φ φ̇` (no
    /// torque about it) to RK4's error, and the slider moves.
    #[test]
    fn the_reference_conserves_the_shaft_s_momentum() {
        let momentum = |y: &[f64; 8]| {
            let mut m_phi = J_SHAFT + J_SLIDER;
            for theta in [y[2], y[3]] {
                let (sn, cs) = theta.sin_cos();
                let (r_c, r_b) = (A + L / 2.0 * sn, A + L * sn);
                m_phi += M_ROD * r_c * r_c + I_T * sn * sn + I_A * cs * cs + M_BALL * r_b * r_b;
            }
            m_phi * y[4]
        };
        let run = reference(1.0);
        let first = momentum(&run[0]);
        for y in &run {
            assert!(
                (momentum(y) - first).abs() <= 1e-10 * first.abs(),
                "{} vs {first}",
                momentum(y)
            );
        }
        // The motion is not trivial: the slider rises by centimetres.
        let rise = run.iter().fold(0.0f64, |m, y| m.max(y[1] - START[1]));
        assert!(rise > 0.1, "{rise}");
    }

    #[test]
    fn the_model_follows_the_reference_over_its_first_2_s() {
        let models = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models");
        let rows = a05(&models, Level::Quick).unwrap_or_else(|e| panic!("{e}"));
        assert!(rows.iter().all(Row::pass), "{rows:#?}");
    }
}
