//! The start of an integration decides whether `ü` and `λ` are right from the
//! first step (`algorithm.md` §6): consistent accelerations satisfy both the
//! equations of motion and the second derivative of the constraints; a rough
//! initial state is projected onto Φ = 0, B u̇ + Φ_t = 0 by minimum-norm
//! corrections and the corrections are reported; and every kind of bad input
//! is an error that says where, never a panic or NaN.

use mstar_model::{Link, Pattern, PendulumChain, System};
use mstar_newmark::{Config, IntegrationError, Integrator, Trajectory};

fn three_links() -> PendulumChain {
    PendulumChain::new(
        vec![
            Link { m: 1.0, l: 1.0 },
            Link { m: 2.0, l: 0.5 },
            Link { m: 0.5, l: 0.8 },
        ],
        9.81,
    )
}

#[test]
fn consistent_start_satisfies_the_dae_at_acceleration_level() {
    let sys = three_links();
    let theta = [0.3, -0.7, 1.2];
    let omega = [0.5, -1.0, 2.0];
    let (u, v) = (sys.position(&theta), sys.velocity(&theta, &omega));
    // Without the O(h²) start correction of u̇ (tested below), the state is
    // exactly the given one.
    let config = Config {
        corrected_start: false,
        ..Config::default()
    };
    let integ = Integrator::new(&sys, config, 0.0, &u, &v).expect("consistent start");
    let s = integ.sample();
    let (n, m) = (sys.n_coords(), sys.n_constraints());
    let (mp, bp) = (sys.mass_pattern(), sys.b_pattern());
    let mut mass = vec![0.0; mp.len()];
    let mut b = vec![0.0; bp.len()];
    sys.mass_into(0.0, &s.u, &mut mass);
    sys.b_into(0.0, &s.u, &mut b);
    // B ü = c = −(B u̇)_u u̇ − 2 B_t u̇ − Φ_tt, to round-off.
    let mut ba = vec![0.0; m];
    bp.mul_add(&b, &s.a, &mut ba);
    let mut c = vec![0.0; m];
    sys.accel_rhs_into(0.0, &s.u, &s.v, &mut c);
    for i in 0..m {
        assert!(
            (ba[i] - c[i]).abs() <= 1e-12 * c[i].abs().max(1.0),
            "constraint {i}: {} vs {}",
            ba[i],
            c[i]
        );
    }
    // M ü + Bᵀλ = g, to round-off.
    let mut lhs = vec![0.0; n];
    mp.mul_add(&mass, &s.a, &mut lhs);
    bp.mul_transpose_add(&b, &s.lambda, &mut lhs);
    let mut g = vec![0.0; n];
    sys.forces_into(0.0, &s.u, &s.v, &mut g);
    for i in 0..n {
        assert!(
            (lhs[i] - g[i]).abs() <= 1e-12 * g[i].abs().max(10.0),
            "equation {i}"
        );
    }
}

#[test]
fn paper_start_solves_m_star() {
    // θ₀ = π/2 at rest, λ₀ = (−10, 0), m = l = 1, g₀ = 10: M* ü₀ = g − Bᵀλ₀ with
    // M* = [[2,0,0],[0,2,−1],[0,−1,1]] and g − Bᵀλ₀ = (10, −10, 0) gives
    // ü₀ = (5, −10, −10) by hand.
    let sys = PendulumChain::paper(1.0, 1.0, 10.0);
    let u = sys.position(&[std::f64::consts::FRAC_PI_2]);
    let integ = Integrator::new(
        &sys,
        Config::paper(0.01, vec![-10.0, 0.0]),
        0.0,
        &u,
        &[0.0; 3],
    )
    .expect("start");
    let a = integ.sample().a;
    for (got, want) in a.iter().zip([5.0, -10.0, -10.0]) {
        assert!((got - want).abs() < 1e-12, "{a:?}");
    }
}

#[test]
fn rough_initial_state_is_projected_and_reported() {
    let sys = three_links();
    let theta = [0.3, -0.7, 1.2];
    let mut u = sys.position(&theta);
    let mut v = sys.velocity(&theta, &[0.5, -1.0, 2.0]);
    u[0] += 0.05;
    u[4] -= 0.03;
    v[1] += 0.2;
    let integ = Integrator::new(&sys, Config::default(), 0.0, &u, &v).expect("projected");
    let report = integ.start_report();
    assert!(report.position_violation > 0.02);
    assert!(report.velocity_violation > 0.1);
    let s = integ.sample();
    let mut phi = vec![0.0; sys.n_constraints()];
    sys.phi_into(0.0, &s.u, &mut phi);
    assert!(phi.iter().all(|p| p.abs() < 1e-12), "{phi:?}");
    // The state also carries the O(h²) start correction of the velocity.
    let start = &report.velocity_start_correction;
    assert_eq!(start.len(), u.len());
    for i in 0..u.len() {
        assert!((s.u[i] - u[i] - report.position_correction[i]).abs() < 1e-15);
        assert!((s.v[i] - v[i] - report.velocity_correction[i] - start[i]).abs() < 1e-15);
        assert!(
            start[i].abs()
                < 1e-2
                    * report
                        .velocity_correction
                        .iter()
                        .fold(0.0f64, |m, x| m.max(x.abs()))
        );
    }
    // The velocity correction is the minimum-norm one: it lies in the range of Bᵀ,
    // so it is orthogonal to every admissible velocity, e.g. the chain's own.
    let admissible = sys.velocity(&[s.u[2], s.u[5], s.u[8]], &[1.0, -0.3, 0.7]);
    let dot: f64 = admissible
        .iter()
        .zip(&report.velocity_correction)
        .map(|(a, b)| a * b)
        .sum();
    assert!(dot.abs() < 1e-10, "{dot}");
}

#[test]
fn inconsistent_state_without_projection_names_the_constraint() {
    let sys = three_links();
    let mut u = sys.position(&[0.3, -0.7, 1.2]);
    u[7] += 0.01; // link3.y
    let config = Config {
        project: false,
        ..Config::default()
    };
    match Integrator::new(&sys, config, 0.0, &u, &[0.0; 9]) {
        Err(IntegrationError::InconsistentInitialState {
            level, constraint, ..
        }) => {
            assert_eq!(level, "position");
            assert_eq!(constraint, "rod3.y");
        }
        other => panic!("expected an inconsistent-state error, got {other:?}"),
    }
}

/// The paper's pendulum with its second constraint declared twice.
struct Redundant(PendulumChain);

impl System for Redundant {
    fn n_coords(&self) -> usize {
        3
    }
    fn n_constraints(&self) -> usize {
        3
    }
    fn coord_name(&self, i: usize) -> String {
        self.0.coord_name(i)
    }
    fn constraint_name(&self, i: usize) -> String {
        if i < 2 {
            self.0.constraint_name(i)
        } else {
            "rod.y (again)".into()
        }
    }
    fn mass_pattern(&self) -> Pattern {
        self.0.mass_pattern()
    }
    fn mass_into(&self, t: f64, u: &[f64], m: &mut [f64]) {
        self.0.mass_into(t, u, m);
    }
    fn forces_into(&self, t: f64, u: &[f64], v: &[f64], g: &mut [f64]) {
        self.0.forces_into(t, u, v, g);
    }
    fn phi_into(&self, t: f64, u: &[f64], phi: &mut [f64]) {
        self.0.phi_into(t, u, &mut phi[..2]);
        phi[2] = phi[1];
    }
    fn b_pattern(&self) -> Pattern {
        let mut p = self.0.b_pattern();
        p.nrows = 3;
        p.push(2, 1);
        p.push(2, 2);
        p
    }
    fn b_into(&self, t: f64, u: &[f64], b: &mut [f64]) {
        self.0.b_into(t, u, &mut b[..4]);
        b[4] = b[2];
        b[5] = b[3];
    }
    fn hessian_pattern(&self) -> Pattern {
        self.0.hessian_pattern()
    }
    fn hessian_into(&self, t: f64, u: &[f64], mu: &[f64], out: &mut [f64]) {
        self.0.hessian_into(t, u, &[mu[0], mu[1] + mu[2]], out);
    }
    fn accel_rhs_into(&self, t: f64, u: &[f64], v: &[f64], c: &mut [f64]) {
        self.0.accel_rhs_into(t, u, v, &mut c[..2]);
        c[2] = c[1];
    }
}

#[test]
fn redundant_constraint_is_named() {
    let sys = Redundant(PendulumChain::paper(1.0, 1.0, 10.0));
    let u = sys.0.position(&[0.4]);
    match Integrator::new(&sys, Config::default(), 0.0, &u, &[0.0; 3]) {
        Err(e @ IntegrationError::StartFailed { .. }) => {
            let text = e.to_string();
            assert!(text.contains("rod.y (again)"), "{text}");
            // A consistent start: no initial violation to blame, no step size.
            assert!(text.starts_with("at start-up (t = 0), "), "{text}");
            assert!(
                !text.contains("violates") && !text.contains("h ="),
                "{text}"
            );
        }
        other => panic!("expected a start-up error, got {other:?}"),
    }
}

#[test]
fn bad_input_is_an_error_not_a_panic() {
    let sys = PendulumChain::paper(1.0, 1.0, 10.0);
    let u = sys.position(&[0.4]);
    let nan = [f64::NAN, 0.0, 0.0];
    let e = Integrator::new(&sys, Config::default(), 0.0, &u, &nan).expect_err("NaN velocity");
    assert!(e.to_string().contains("coordinate 'x'"), "{e}");
    let e =
        Integrator::new(&sys, Config::default(), 0.0, &u[..2], &[0.0; 3]).expect_err("short u0");
    assert!(
        matches!(e, IntegrationError::Dimension { what: "u0", .. }),
        "{e}"
    );
    let e = Integrator::new(&sys, Config::paper(0.01, vec![1.0]), 0.0, &u, &[0.0; 3])
        .expect_err("short λ₀");
    assert!(
        matches!(
            e,
            IntegrationError::Dimension {
                what: "lambda0",
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn newton_failure_names_time_and_both_norms() {
    // One Newton iteration cannot converge from the paper's predictor ü⁰ = 0.
    let sys = PendulumChain::paper(1.0, 1.0, 10.0);
    let u = sys.position(&[1.0]);
    let config = Config {
        max_iterations: 1,
        ..Config::paper(0.01, vec![-10.0, 0.0])
    };
    let mut integ = Integrator::new(&sys, config, 0.0, &u, &[0.0; 3]).expect("start");
    let e = integ
        .run(1.0, &mut Trajectory::default())
        .expect_err("must fail");
    match e {
        IntegrationError::NewtonFailed {
            t,
            h,
            residual,
            residual_tol,
            ..
        } => {
            assert!((t - 0.01).abs() < 1e-15 && h == 0.01);
            assert!(residual > residual_tol);
        }
        other => panic!("expected NewtonFailed, got {other}"),
    }
}

#[test]
fn step_control_rescues_a_too_large_step() {
    // A 4-iteration budget fails at h = 0.2 from rest at θ = 2.5 rad; step
    // control halves h until Newton converges and still reaches t_end.
    let sys = PendulumChain::paper(1.0, 1.0, 10.0);
    let u = sys.position(&[2.5]);
    let config = Config {
        h: 0.2,
        max_iterations: 4,
        ..Config::default()
    };
    let mut integ = Integrator::new(&sys, config, 0.0, &u, &[0.0; 3]).expect("start");
    let stats = integ
        .run(2.0, &mut Trajectory::default())
        .expect("step control");
    assert!(stats.rejected > 0, "{stats:?}");
    assert!(stats.h_min_used < 0.2);
    assert!((stats.t - 2.0).abs() < 1e-12);
}

#[test]
fn non_finite_times_are_errors_not_hangs() {
    let sys = PendulumChain::paper(1.0, 1.0, 10.0);
    let u = sys.position(&[0.4]);
    for t0 in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let e = Integrator::new(&sys, Config::default(), t0, &u, &[0.0; 3]).err();
        assert!(
            matches!(e, Some(IntegrationError::Time { what: "t0", .. })),
            "t0 = {t0}: {e:?}"
        );
    }
    let mut integ =
        Integrator::new(&sys, Config::default(), 0.0, &u, &[0.0; 3]).expect("a consistent start");
    for t_end in [f64::NAN, f64::INFINITY] {
        let e = integ.run(t_end, &mut Trajectory::default()).err();
        let text = e.as_ref().map(ToString::to_string).unwrap_or_default();
        assert!(
            matches!(e, Some(IntegrationError::Time { what: "t_end", .. })),
            "run({t_end}): {e:?}"
        );
        assert!(text.contains("finite") && text.contains("t = 0)"), "{text}");
    }
    // Nothing was integrated: the next finite run starts from t = 0.
    assert_eq!(integ.time(), 0.0);
    let stats = integ.run(0.05, &mut Trajectory::default());
    assert_eq!(stats.map(|s| s.steps).ok(), Some(5));
}

#[test]
fn a_step_to_a_time_not_ahead_is_an_error() {
    let sys = PendulumChain::paper(1.0, 1.0, 10.0);
    let u = sys.position(&[0.4]);
    let mut integ =
        Integrator::new(&sys, Config::default(), 0.0, &u, &[0.0; 3]).expect("a consistent start");
    assert!(integ.step(0.1).is_ok());
    let t = integ.time();
    assert!((t - 0.01).abs() < 1e-15, "one step of h = 0.01: {t}");
    for t_end in [t, t - 0.5, f64::NAN] {
        let e = integ.step(t_end).err();
        assert!(
            matches!(e, Some(IntegrationError::Time { what: "t_end", .. })),
            "step({t_end}) at t = {t}: {e:?}"
        );
        assert_eq!(integ.time(), t, "no step was taken");
    }
    // A run to a time already passed has nothing to do.
    assert_eq!(
        integ
            .run(0.0, &mut Trajectory::default())
            .map(|s| s.steps)
            .ok(),
        Some(1)
    );
}
