//! Reactions and driver efforts by name (`PlanarSystem::reaction`) against
//! closed forms: the sign of `λ` (eq. 1: `M ü + Bᵀλ = g`, constraint force
//! `−Bᵀλ`) must come out as the force the joint really applies.

use mstar::file::ModelFile;
use mstar::planar::{At, Coordinate, PlanarBuilder, PlanarSystem, RigidBody, TimeFunction};
use mstar::{Config, Integrator, SampleRef, Scheme, System};

const G: f64 = 9.81;

/// A uniform bar (mass `m`, length `l`) hinged to the ground at its left
/// end, horizontal, optionally driven at constant angular rate `omega`.
fn bar(m: f64, l: f64, omega: Option<f64>) -> PlanarSystem {
    let mut b = PlanarBuilder::new();
    let bar = b.rigid_body(
        "bar",
        RigidBody {
            mass: m,
            inertia: m * l * l / 12.0,
            pose: [l / 2.0, 0.0, 0.0],
            velocity: [0.0, omega.unwrap_or(0.0) * l / 2.0, omega.unwrap_or(0.0)],
        },
    );
    b.revolute(
        "hinge",
        At::Ground([0.0, 0.0]),
        At::Body(bar, [-l / 2.0, 0.0]),
    );
    if let Some(rate) = omega {
        let f = TimeFunction::Linear { value: 0.0, rate };
        b.driver("motor", bar, Coordinate::Theta, f);
    }
    b.build().expect("valid bar")
}

/// Every sample's `(t, u, λ)` of a run to `t_end` with step `h`.
fn run(sys: &PlanarSystem, h: f64, t_end: f64) -> Vec<(f64, Vec<f64>, Vec<f64>)> {
    let config = Config {
        h,
        tol: 1e-12,
        ..Config::default()
    };
    let (u0, v0) = (sys.initial_position(), sys.initial_velocity());
    let mut integ = Integrator::new(sys, config, 0.0, &u0, &v0).expect("start");
    let mut out = Vec::new();
    integ
        .run(t_end, &mut |s: &SampleRef<'_>| {
            out.push((s.t, s.u.to_vec(), s.lambda.to_vec()));
        })
        .expect("run");
    out
}

#[test]
fn a_bar_released_horizontally_hangs_on_a_quarter_of_its_weight() {
    // α = 3g/(2l) clockwise, the centre falls at 3g/4: the pin carries
    // N = m g − m·3g/4 = m g/4 upward, at the left end, whose moment about
    // the centre is −(l/2)(m g/4) = −m g l/8 (= I α, I = m l²/12).
    let (m, l) = (2.0, 0.8);
    let sys = bar(m, l, None);
    let (t, u, lambda) = &run(&sys, 1e-3, 1e-3)[0];
    assert_eq!(*t, 0.0);
    let r = sys.reaction("hinge", *t, u, lambda).expect("hinge");
    assert_eq!(r.body, "bar");
    let tol = 1e-9 * m * G;
    assert!(r.force[0].abs() < tol, "{r:?}");
    assert!((r.force[1] - m * G / 4.0).abs() < tol, "{r:?}");
    assert!((r.moment + m * G * l / 8.0).abs() < tol * l, "{r:?}");
}

/// The torque a motor needs to turn the bar at constant rate: about the
/// pivot `τ = m g (l/2) cos θ` (inverse dynamics, `θ̈ = 0`).
fn motor_torque_error(h: f64) -> f64 {
    let (m, l, omega) = (1.5, 0.6, 4.0);
    let sys = bar(m, l, Some(omega));
    let mut worst = 0.0f64;
    for (t, u, lambda) in run(&sys, h, 1.0) {
        let effort = sys.reaction("motor", t, &u, &lambda).expect("motor").moment;
        let rows = sys.joint_rows("motor").expect("rows");
        assert_eq!(effort, -lambda[rows.start], "effort is −λ");
        let exact = m * G * l / 2.0 * (omega * t).cos();
        worst = worst.max((effort - exact).abs());
    }
    worst
}

#[test]
fn a_driver_applies_the_torque_of_inverse_dynamics_to_second_order() {
    // Generalized-α is (at least) second order in λ with the start of
    // theory.md: the error is within τ_max (ω h)², the torque's scale times
    // the square of the step in radians, and falls at least as h² (here the
    // motion is prescribed exactly and it falls faster).
    let (e1, e2) = (motor_torque_error(4e-3), motor_torque_error(2e-3));
    let tau_max = 1.5 * G * 0.3;
    for (e, h) in [(e1, 4e-3), (e2, 2e-3)] {
        assert!(e <= tau_max * (4.0 * h) * (4.0 * h), "{e:e} at h = {h}");
    }
    let order = (e1 / e2).log2();
    assert!(order > 1.8, "order {order}: {e1:e} → {e2:e}");
}

#[test]
fn look_ups_by_name() {
    let sys = bar(1.0, 1.0, Some(1.0));
    let b = sys.body("bar").expect("bar");
    assert_eq!((b.x, b.y, b.theta), (0, 1, Some(2)));
    assert!(sys.body("ground").is_none());
    assert_eq!(sys.joint_rows("hinge"), Some(0..2));
    assert_eq!(sys.joint_rows("motor"), Some(2..3));
    assert_eq!(sys.is_driver("motor"), Some(true));
    assert_eq!(sys.is_driver("hinge"), Some(false));
    assert_eq!(sys.joint_names().collect::<Vec<_>>(), ["hinge", "motor"]);
    assert!(sys.reaction("nothing", 0.0, &[0.0; 3], &[0.0; 3]).is_none());
    assert!(
        sys.reaction("hinge", 0.0, &[0.0; 3], &[0.0; 1]).is_none(),
        "λ too short"
    );
}

/// The period-2h part of a uniformly sampled signal:
/// `max |x_{k+2} − 4x_{k+1} + 6x_k − 4x_{k−1} + x_{k−2}| / 16`, which is `A`
/// for `A(−1)^k` and `O((ω h)⁴)` of a smooth part of frequency ω.
fn period_2h(x: &[f64]) -> f64 {
    x.windows(5)
        .map(|w| (w[4] - 4.0 * w[3] + 6.0 * w[2] - 4.0 * w[1] + w[0]).abs() / 16.0)
        .fold(0.0, f64::max)
}

/// `Σ |ü_k| h²` after a position error of 1 at one step (every other
/// position exact), from the scheme's own relations (Arnold & Brüls 2007)
/// run over 2000 steps: the most that errors `|δ_k| ≤ δ` in the positions
/// can put into the accelerations is this gain × `δ/h²`.
fn kick_gain(rho_inf: f64) -> f64 {
    let p = Scheme::GeneralizedAlpha { rho_inf }.params().expect("ρ∞");
    let (am, af, b, g) = (p.alpha_m, p.alpha_f, p.beta, p.gamma);
    // h = 1: (u, u̇, a, ü) of the error.
    let (mut u, mut v, mut a, mut acc, mut sum) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for k in 1..2000 {
        let u1 = if k == 1 { 1.0 } else { 0.0 };
        let a1 = (u1 - u - v - (0.5 - b) * a) / b;
        v += (1.0 - g) * a + g * a1;
        acc = ((1.0 - am) * a1 + am * a - af * acc) / (1.0 - af);
        (u, a) = (u1, a1);
        sum += acc.abs();
    }
    sum
}

/// The motor's effort over [0.1 s, 1 s] of the driven bar (the start's
/// transient, which decays as `ρ∞ⁿ`, left out).
fn motor_efforts(h: f64, rho_inf: f64) -> Vec<f64> {
    let (m, l, omega) = (1.5, 0.6, 4.0);
    let sys = bar(m, l, Some(omega));
    let config = Config {
        h,
        scheme: Scheme::GeneralizedAlpha { rho_inf },
        ..Config::default()
    };
    let (u0, v0) = (sys.initial_position(), sys.initial_velocity());
    let mut integ = Integrator::new(&sys, config, 0.0, &u0, &v0).expect("start");
    let mut efforts = Vec::new();
    integ
        .run(1.0, &mut |s: &SampleRef<'_>| {
            if s.t >= 0.1 {
                let r = sys.reaction("motor", s.t, s.u, s.lambda).expect("motor");
                efforts.push(r.moment);
            }
        })
        .expect("run");
    efforts
}

#[test]
fn a_motor_torque_alternates_only_by_the_round_off_of_the_positions() {
    // The driven angle θ = ω t is a double: its error δ ≤ ε|θ| per step, and
    // the other positions' are alike. The scheme turns position errors into
    // accelerations through 1/(βh²) (eq. 15) and its double root −ρ∞, at
    // most kick_gain · δ/h², and the torque is I θ̈ plus the hinge's share,
    // within I_pivot = m l²/3 times that. Two roundings a step (the
    // corrector's sums), |θ| ≤ 4: δ = 8ε. Newton stopping at ‖Φ‖∞ ≤ tol ‖u‖∞
    // alone swings it by 4.1e-5 N m at ρ∞ = 0.9, h = 2.5e-4, twice the bound
    // (docs/theory.md, "Round-off in the multipliers").
    let (m, l) = (1.5, 0.6);
    let inertia = m * l * l / 3.0;
    let mut amplitude = Vec::new();
    for rho_inf in [0.9, 0.5] {
        for h in [1e-3, 5e-4, 2.5e-4] {
            let got = period_2h(&motor_efforts(h, rho_inf));
            let bound = inertia * kick_gain(rho_inf) * 8.0 * f64::EPSILON / (h * h);
            assert!(
                got <= bound,
                "ρ∞ = {rho_inf}, h = {h}: {got:e} N m > {bound:e}"
            );
            amplitude.push(got);
        }
    }
    // The remedy docs/model-format.md gives: ρ∞ = 0.5 damps the ringing
    // (kick_gain 16× smaller) while staying second order.
    for k in 0..3 {
        assert!(amplitude[k + 3] < amplitude[k] / 4.0, "{amplitude:?}");
    }
}

#[test]
fn every_step_leaves_its_constraints_at_round_off() {
    // Modified Newton stopping at ‖Φ‖∞ ≤ tol ‖u‖∞ alone accepts a step of
    // this run (ρ∞ = 0.5, h = 2.5e-4) with 51 ε‖u‖∞ left, and the next
    // step's correction rings the reactions at 1e-6 N, twenty times their
    // round-off (docs/theory.md, "Round-off in the multipliers").
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/driven-arm-with-collar.toml");
    let model = ModelFile::load(&path).unwrap_or_else(|e| panic!("{e}"));
    let sys = &model.system;
    let mut phi = vec![0.0; sys.n_constraints()];
    let (mut worst, mut slot) = (0.0f64, Vec::new());
    mstar::run::simulate(sys, &model.simulation, &mut |s: &SampleRef<'_>| {
        sys.phi_into(s.t, s.u, &mut phi);
        let u_max = s.u.iter().fold(1.0f64, |m, x| m.max(x.abs()));
        worst = worst.max(mstar::kkt::max_abs(&phi) / (f64::EPSILON * u_max));
        if s.t >= 0.1 {
            let r = sys.reaction("slot", s.t, s.u, s.lambda).expect("slot");
            slot.push(r.force[0]);
        }
    })
    .expect("run");
    assert!(worst <= 4.0, "‖Φ‖∞ reached {worst:.1} ε‖u‖∞");
    let swing = period_2h(&slot);
    // ρ∞ = 0.5, h = 2.5e-4, m = 0.3 kg, |u| ≤ 2.6 m: 0.3·kick_gain·8ε·2.6/h².
    let bound = 0.3 * kick_gain(0.5) * 8.0 * f64::EPSILON * 2.6 / (2.5e-4f64 * 2.5e-4);
    assert!(swing <= bound, "{swing:e} N > {bound:e} N");
}
