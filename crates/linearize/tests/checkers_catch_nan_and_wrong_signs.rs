//! A derivative checker is only worth its errors if it can fail. Each
//! derivative a `System` provides — `B`, the constraint Hessian, `∂g/∂u`,
//! `∂(M w)/∂u`, `∂g/∂u̇`, `Φ_t`, the acceleration right-hand side and the fused
//! `Φ`/`B` evaluation — is corrupted in turn, once with a NaN and once with
//! the wrong sign, and `check_derivatives` must report it in the matching
//! error and in `max()`. (A checker folding with `f64::max` would score a NaN
//! as zero error.)

use mstar_linearize::{DerivativeErrors, check_derivatives};
use mstar_model::planar::{At, Coordinate, PlanarBuilder, RigidBody, SpringDamper, TimeFunction};
use mstar_model::{FnSystem, Pattern, StateRef, System};

/// A correct system's errors are below this (central differences: see
/// `derivatives_match_finite_differences.rs`).
const FD_TOL: f64 = 1e-6;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Target {
    B,
    Hessian,
    ForcesDu,
    MassDu,
    ForcesDv,
    PhiT,
    AccelRhs,
    Fused,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum How {
    Nan,
    WrongSign,
}

/// `inner` with one derivative corrupted.
struct Corrupt<'a> {
    inner: &'a dyn System,
    target: Target,
    how: How,
}

impl Corrupt<'_> {
    fn spoil(&self, target: Target, out: &mut [f64]) {
        if target != self.target {
            return;
        }
        match self.how {
            How::Nan => out[0] = f64::NAN,
            How::WrongSign => out.iter_mut().for_each(|x| *x = -*x),
        }
    }
}

impl System for Corrupt<'_> {
    fn n_coords(&self) -> usize {
        self.inner.n_coords()
    }
    fn n_constraints(&self) -> usize {
        self.inner.n_constraints()
    }
    fn mass_pattern(&self) -> Pattern {
        self.inner.mass_pattern()
    }
    fn mass_into(&self, t: f64, u: &[f64], m: &mut [f64]) {
        self.inner.mass_into(t, u, m);
    }
    fn forces_into(&self, t: f64, u: &[f64], v: &[f64], g: &mut [f64]) {
        self.inner.forces_into(t, u, v, g);
    }
    fn phi_into(&self, t: f64, u: &[f64], phi: &mut [f64]) {
        self.inner.phi_into(t, u, phi);
    }
    fn b_pattern(&self) -> Pattern {
        self.inner.b_pattern()
    }
    fn b_into(&self, t: f64, u: &[f64], b: &mut [f64]) {
        self.inner.b_into(t, u, b);
        self.spoil(Target::B, b);
    }
    fn workspace_len(&self) -> usize {
        self.inner.workspace_len()
    }
    fn phi_b_into(&self, t: f64, u: &[f64], phi: &mut [f64], b: &mut [f64], w: &mut [f64]) {
        self.inner.phi_b_into(t, u, phi, b, w);
        self.spoil(Target::Fused, b);
    }
    fn phi_t_into(&self, t: f64, u: &[f64], phi_t: &mut [f64]) {
        self.inner.phi_t_into(t, u, phi_t);
        self.spoil(Target::PhiT, phi_t);
    }
    fn hessian_pattern(&self) -> Pattern {
        self.inner.hessian_pattern()
    }
    fn hessian_into(&self, t: f64, u: &[f64], mu: &[f64], out: &mut [f64]) {
        self.inner.hessian_into(t, u, mu, out);
        self.spoil(Target::Hessian, out);
    }
    fn accel_rhs_into(&self, t: f64, u: &[f64], v: &[f64], c: &mut [f64]) {
        self.inner.accel_rhs_into(t, u, v, c);
        self.spoil(Target::AccelRhs, c);
    }
    fn forces_du_pattern(&self) -> Pattern {
        self.inner.forces_du_pattern()
    }
    fn forces_du_into(&self, t: f64, u: &[f64], v: &[f64], out: &mut [f64]) {
        self.inner.forces_du_into(t, u, v, out);
        self.spoil(Target::ForcesDu, out);
    }
    fn forces_dv_pattern(&self) -> Pattern {
        self.inner.forces_dv_pattern()
    }
    fn forces_dv_into(&self, t: f64, u: &[f64], v: &[f64], out: &mut [f64]) {
        self.inner.forces_dv_into(t, u, v, out);
        self.spoil(Target::ForcesDv, out);
    }
    fn mass_du_pattern(&self) -> Pattern {
        self.inner.mass_du_pattern()
    }
    fn mass_du_into(&self, t: f64, u: &[f64], w: &[f64], out: &mut [f64]) {
        self.inner.mass_du_into(t, u, w, out);
        self.spoil(Target::MassDu, out);
    }
}

/// Two bars — one hinged to the ground and driven harmonically, one hanging
/// from it on a rod — and a damped spring from the second to the ground:
/// every planar derivative is non-zero.
fn linkage() -> impl System {
    let mut b = PlanarBuilder::new();
    let crank = b.rigid_body(
        "crank",
        RigidBody {
            mass: 1.0,
            inertia: 0.1,
            pose: [0.3, 0.1, 0.4],
            velocity: [0.0; 3],
        },
    );
    let rocker = b.rigid_body(
        "rocker",
        RigidBody {
            mass: 2.0,
            inertia: 0.3,
            pose: [0.9, -0.4, -0.7],
            velocity: [0.0; 3],
        },
    );
    b.revolute(
        "pivot",
        At::Ground([0.0, 0.0]),
        At::Body(crank, [-0.3, -0.1]),
    );
    b.distance(
        "rod",
        At::Body(crank, [0.2, 0.0]),
        At::Body(rocker, [-0.4, 0.1]),
        0.8,
    );
    b.spring(
        "spring",
        At::Body(rocker, [0.3, 0.0]),
        At::Ground([1.5, 0.5]),
        SpringDamper {
            stiffness: 50.0,
            damping: 3.0,
            rest_length: 0.4,
        },
    );
    let motor = TimeFunction::Sine {
        offset: 0.5,
        amplitude: 0.3,
        omega: 2.0,
        phase: 0.1,
    };
    b.driver("motor", crank, Coordinate::Theta, motor);
    b.build().expect("a valid linkage")
}

/// A point mass in polar coordinates `u = [r, θ]` on a circle `r = 1`:
/// `M = diag(m, m r²)` depends on `u`, the inertia forces on `u̇`.
fn polar() -> FnSystem {
    let m = 2.0;
    FnSystem::new(
        vec![m, m],
        1,
        |_t, u, phi| phi[0] = u[0] - 1.0,
        |_t, _u, b| b.copy_from_slice(&[1.0, 0.0]),
    )
    .with_mass(move |_t, u, mass| mass.copy_from_slice(&[m, 0.0, 0.0, m * u[0] * u[0]]))
    .with_forces(move |_t, u, v, g| {
        g[0] = m * u[0] * v[1] * v[1] - 9.81 * m * u[1].sin();
        g[1] = -2.0 * m * u[0] * v[0] * v[1] - 9.81 * m * u[0] * u[1].cos();
    })
}

/// What a test of a correct system asserts, `error < FD_TOL`, is false.
fn fails(error: f64) -> bool {
    error.is_nan() || error >= FD_TOL
}

/// The error of `e` that checks `target`.
fn field(e: &DerivativeErrors, target: Target) -> f64 {
    match target {
        Target::B => e.b,
        Target::Hessian | Target::ForcesDu | Target::MassDu => e.k_t,
        Target::ForcesDv => e.c_t,
        Target::PhiT => e.phi_t,
        Target::AccelRhs => e.accel_rhs,
        Target::Fused => e.fused,
    }
}

/// Corrupts each of `targets` of `inner` both ways and checks that it is
/// caught; the uncorrupted system passes.
fn each_corruption_is_caught(inner: &dyn System, u: &[f64], targets: &[Target]) {
    let (n, m) = (inner.n_coords(), inner.n_constraints());
    let v: Vec<f64> = (0..n).map(|i| 0.8 + 0.3 * (i as f64).sin()).collect();
    let a: Vec<f64> = (0..n).map(|i| 1.0 - 0.5 * (i as f64).cos()).collect();
    let lambda: Vec<f64> = (0..m).map(|i| 3.0 + i as f64).collect();
    let clean = check_derivatives(
        inner,
        &StateRef {
            t: 0.3,
            u,
            v: &v,
            a: &a,
            lambda: &lambda,
        },
    );
    assert!(clean.max() < FD_TOL, "the uncorrupted system: {clean:?}");
    for &target in targets {
        for how in [How::Nan, How::WrongSign] {
            let sys = Corrupt { inner, target, how };
            let e = check_derivatives(
                &sys,
                &StateRef {
                    t: 0.3,
                    u,
                    v: &v,
                    a: &a,
                    lambda: &lambda,
                },
            );
            assert!(fails(field(&e, target)), "{target:?} {how:?} passed: {e:?}");
            assert!(fails(e.max()), "{target:?} {how:?} passed max(): {e:?}");
        }
    }
}

#[test]
fn every_planar_derivative_check_can_fail() {
    let sys = linkage();
    let targets = [
        Target::B,
        Target::Hessian,
        Target::ForcesDu,
        Target::ForcesDv,
        Target::PhiT,
        Target::AccelRhs,
        Target::Fused,
    ];
    let u: Vec<f64> = [0.3, 0.1, 0.4, 0.9, -0.4, -0.7].to_vec();
    each_corruption_is_caught(&sys, &u, &targets);
}

#[test]
fn the_mass_derivative_check_can_fail() {
    let sys = polar();
    each_corruption_is_caught(
        &sys,
        &[1.2, 0.5],
        &[Target::MassDu, Target::ForcesDu, Target::ForcesDv],
    );
}
