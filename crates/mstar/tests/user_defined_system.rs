//! A model author implements only the required core of `System` — dimensions,
//! `M`, `g`, `Φ`, `B` and their patterns — and gets a working model: the
//! second-order terms (`Φ_t`, the constraint Hessian, the acceleration
//! right-hand side, the force Jacobians) come from the trait's
//! finite-difference defaults.
//!
//! The model: a bead of mass `m` on a straight wire through the origin that
//! turns at the rate `ω` (a rheonomic constraint, `Φ_t ≠ 0`), under gravity.
//! At distance `r` along the wire's direction `e = (cos ωt, sin ωt)`,
//! `m (r̈ − ω² r) = −m g₀ sin ωt`, so `r = A cosh ωt + B sinh ωt + g₀ sin ωt /
//! (2ω²)`; across the wire the constraint force balances the Coriolis and
//! gravity terms, and with `Bᵀλ = λ e⊥` on the left of the equations of
//! motion, `λ = −m g₀ cos ωt − 2 m ω ṙ`. The integrator must reproduce both
//! at second order.

use mstar::{Config, Integrator, Pattern, SampleRef, System};

const G0: f64 = 9.81;

struct Bead {
    m: f64,
    omega: f64,
}

impl System for Bead {
    fn n_coords(&self) -> usize {
        2
    }
    fn n_constraints(&self) -> usize {
        1
    }
    fn mass_pattern(&self) -> Pattern {
        Pattern::diagonal(2)
    }
    fn mass_into(&self, _t: f64, _u: &[f64], mass: &mut [f64]) {
        mass.fill(self.m);
    }
    fn forces_into(&self, _t: f64, _u: &[f64], _v: &[f64], g: &mut [f64]) {
        g.copy_from_slice(&[0.0, -self.m * G0]);
    }
    fn phi_into(&self, t: f64, u: &[f64], phi: &mut [f64]) {
        let (s, c) = (self.omega * t).sin_cos();
        phi[0] = -u[0] * s + u[1] * c;
    }
    fn b_pattern(&self) -> Pattern {
        Pattern::from_entries(1, 2, vec![(0, 0), (0, 1)])
    }
    fn b_into(&self, t: f64, _u: &[f64], b: &mut [f64]) {
        let (s, c) = (self.omega * t).sin_cos();
        b.copy_from_slice(&[-s, c]);
    }
}

/// The closed form: `(x, y, λ)` at `t` from `r(0) = r0`, `ṙ(0) = rdot0`.
fn exact(bead: &Bead, r0: f64, rdot0: f64, t: f64) -> [f64; 3] {
    let w = bead.omega;
    let b = (rdot0 - G0 / (2.0 * w)) / w;
    let r = r0 * (w * t).cosh() + b * (w * t).sinh() + G0 * (w * t).sin() / (2.0 * w * w);
    let rdot = r0 * w * (w * t).sinh() + b * w * (w * t).cosh() + G0 * (w * t).cos() / (2.0 * w);
    let lambda = -bead.m * G0 * (w * t).cos() - 2.0 * bead.m * w * rdot;
    [r * (w * t).cos(), r * (w * t).sin(), lambda]
}

/// Largest errors of position and multiplier over the run at step `h`.
fn errors(bead: &Bead, h: f64) -> (f64, f64) {
    let (r0, rdot0) = (0.4, 0.2);
    let u0 = [r0, 0.0];
    let v0 = [rdot0, r0 * bead.omega];
    let config = Config {
        h,
        h_min: Some(h),
        tol: 1e-12,
        ..Config::default()
    };
    let mut integ = Integrator::new(bead, config, 0.0, &u0, &v0).expect("a consistent start");
    let (mut position, mut multiplier) = (0.0f64, 0.0f64);
    integ
        .run(1.0, &mut |s: &SampleRef<'_>| {
            let [x, y, lambda] = exact(bead, r0, rdot0, s.t);
            position = position.max((s.u[0] - x).hypot(s.u[1] - y));
            multiplier = multiplier.max((s.lambda[0] - lambda).abs());
            assert!(s.u.iter().chain(s.lambda).all(|v| v.is_finite()));
        })
        .expect("integration");
    (position, multiplier)
}

#[test]
fn a_bead_on_a_rotating_wire_follows_the_closed_form_at_second_order() {
    let bead = Bead { m: 0.5, omega: 1.5 };
    let (p_coarse, l_coarse) = errors(&bead, 0.01);
    let (p_fine, l_fine) = errors(&bead, 0.005);
    let (p_order, l_order) = ((p_coarse / p_fine).log2(), (l_coarse / l_fine).log2());
    assert!(
        (p_order - 2.0).abs() <= 0.1,
        "position errors {p_coarse:.3e}, {p_fine:.3e} (order {p_order:.2})"
    );
    assert!(
        (l_order - 2.0).abs() <= 0.2,
        "multiplier errors {l_coarse:.3e}, {l_fine:.3e} (order {l_order:.2})"
    );
    // Small in the problem's own scales: r ≈ 1 m, λ ≈ 5 N.
    assert!(p_fine < 1e-3 && l_fine < 1e-2, "{p_fine:e} m, {l_fine:e} N");
}

#[test]
fn the_defaults_give_the_bead_its_second_order_terms() {
    let bead = Bead { m: 0.5, omega: 1.5 };
    // Names default to u0, u1 and phi0.
    assert_eq!(
        (bead.coord_name(1), bead.constraint_name(0)),
        ("u1".to_string(), "phi0".to_string())
    );
    // Φ_t = −ω (x cos ωt + y sin ωt); c = −2 B_t u̇ − Φ_tt with B_t =
    // −ω (cos ωt, sin ωt) and Φ_tt = ω² (x sin ωt − y cos ωt), by hand.
    let (t, u, v) = (0.7, [0.3, -0.4], [1.1, 0.6]);
    let (s, c) = (bead.omega * t).sin_cos();
    let w = bead.omega;
    let mut phi_t = [0.0];
    bead.phi_t_into(t, &u, &mut phi_t);
    let want = -w * (u[0] * c + u[1] * s);
    assert!((phi_t[0] - want).abs() < 1e-9, "{} vs {want}", phi_t[0]);
    let mut accel = [0.0];
    bead.accel_rhs_into(t, &u, &v, &mut accel);
    let want = 2.0 * w * (c * v[0] + s * v[1]) - w * w * (u[0] * s - u[1] * c);
    assert!((accel[0] - want).abs() < 1e-8, "{} vs {want}", accel[0]);
    // B does not depend on u: the Hessian is zero.
    let mut h = vec![f64::NAN; bead.hessian_pattern().len()];
    bead.hessian_into(t, &u, &[2.0], &mut h);
    assert!(h.iter().all(|&x| x.abs() < 1e-9), "{h:?}");
}
