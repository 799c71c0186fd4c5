//! The same chain hinged at the origin and at `x = 10⁶ m` must move the same:
//! physics does not depend on where the ground point is. Far from the origin
//! every coordinate rounds to one ulp, ε·10⁶ ≈ 1.2e-10 m, and `Φ` is the
//! difference of such numbers; Newton must still converge (to the same
//! tolerance, relative to the forces) without iterating on that noise.

use mstar::planar::{At, PlanarBuilder, PlanarSystem, RigidBody};
use mstar::{Config, Integrator, SampleRef};

/// A 10-bar chain (1 kg, 1 m), horizontal at rest, hinged at `(x0, 0)`.
fn chain(x0: f64) -> PlanarSystem {
    let mut b = PlanarBuilder::new();
    let mut previous = At::Ground([x0, 0.0]);
    for k in 1..=10 {
        let body = b.rigid_body(
            &format!("link{k}"),
            RigidBody {
                mass: 1.0,
                inertia: 1.0 / 12.0,
                pose: [x0 + k as f64 - 0.5, 0.0, 0.0],
                velocity: [0.0; 3],
            },
        );
        b.revolute(&format!("joint{k}"), previous, At::Body(body, [-0.5, 0.0]));
        previous = At::Body(body, [0.5, 0.0]);
    }
    b.build().expect("valid chain")
}

/// The tip's centre of mass relative to the hinge at `t_end`, and the run's
/// Newton iterations.
fn tip(x0: f64, t_end: f64) -> ([f64; 2], usize) {
    let sys = chain(x0);
    let config = Config {
        tol: 1e-8,
        h: 1e-3,
        ..Config::default()
    };
    let (u0, v0) = (sys.initial_position(), sys.initial_velocity());
    let mut integ = Integrator::new(&sys, config, 0.0, &u0, &v0).expect("start");
    let mut last = None;
    integ
        .run(t_end, &mut |s: &SampleRef<'_>| last = Some(s.u.to_vec()))
        .unwrap_or_else(|e| panic!("hinge at x = {x0}: {e}"));
    let u = last.expect("samples");
    let i = sys.body("link10").map(|b| b.x).expect("tip");
    ([u[i] - x0, u[i + 1]], integ.stats().iterations)
}

#[test]
fn a_chain_far_from_the_origin_moves_like_one_at_it() {
    let t_end = 0.5;
    let (near, near_iterations) = tip(0.0, t_end);
    let (far, far_iterations) = tip(1e6, t_end);
    // The far run's positions carry one rounding of 1.2e-10 m per step: over
    // 500 steps at most 500 of them, 6e-8 m, if none cancelled.
    let diff = (far[0] - near[0]).hypot(far[1] - near[1]);
    assert!(
        diff <= 500.0 * f64::EPSILON * 1e6,
        "tip relative to the hinge: {near:?} at the origin, {far:?} at 1e6 m ({diff:.3e} apart)"
    );
    // Iterating on noise would show as many more iterations than the same
    // motion at the origin needs.
    assert!(
        far_iterations as f64 <= 1.5 * near_iterations as f64,
        "{far_iterations} Newton iterations far from the origin, {near_iterations} at it"
    );
}
