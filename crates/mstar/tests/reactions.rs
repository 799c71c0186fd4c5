//! Reactions and driver efforts by name (`PlanarSystem::reaction`) against
//! closed forms: the sign of `λ` (eq. 1: `M ü + Bᵀλ = g`, constraint force
//! `−Bᵀλ`) must come out as the force the joint really applies.

use mstar::planar::{At, Coordinate, PlanarBuilder, PlanarSystem, RigidBody, TimeFunction};
use mstar::{Config, Integrator, SampleRef};

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
