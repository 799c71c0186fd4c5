//! Chains of N bodies released horizontally swing down under gravity. The
//! redundant-coordinate DAE solution (bodies in (x, y, θ), revolute joints or
//! rods, generalized-α) must agree with RK4 on the joint-angle equations of
//! motion, which share no code with it: the tip's position error is small and
//! shrinks by 4 when h is halved (second order).

use mstar::planar::{PlanarSystem, bar_chain, point_mass_chain};
use mstar::rk4::{AngleChain, AngleLink};
use mstar::{Config, Integrator, SampleRef, System};

/// The tip's centre of mass at `t_end` from the DAE path.
fn dae_tip(sys: &PlanarSystem, h: f64, t_end: f64) -> [f64; 2] {
    let u0 = sys.initial_position();
    let v0 = sys.initial_velocity();
    let config = Config {
        h,
        ..Config::default()
    };
    let mut integ = Integrator::new(sys, config, 0.0, &u0, &v0).expect("start");
    let mut last = None;
    integ
        .run(t_end, &mut |s: &SampleRef<'_>| last = Some(s.u.to_vec()))
        .expect("integration");
    let u = last.expect("samples");
    let tip = sys
        .body(&format!("link{}", sys.n_bodies()))
        .map(|b| b.x)
        .expect("tip body");
    [u[tip], u[tip + 1]]
}

fn oracle_tip(links: Vec<AngleLink>, t_end: f64) -> [f64; 2] {
    let n = links.len();
    let chain = AngleChain::new(links, 9.81);
    let (phi, _) = chain
        .solve(&vec![0.0; n], &vec![0.0; n], &[t_end])
        .remove(0);
    *chain.centres(&phi).last().expect("links")
}

fn check(name: &str, sys: &PlanarSystem, reference: [f64; 2]) {
    let t_end = 1.0;
    let err = |h: f64| {
        let tip = dae_tip(sys, h, t_end);
        (tip[0] - reference[0]).hypot(tip[1] - reference[1])
    };
    let (coarse, fine) = (err(2e-3), err(1e-3));
    let order = (coarse / fine).log2();
    assert!(
        (order - 2.0).abs() <= 0.25,
        "{name}: tip error {coarse:.3e} at h = 2e-3, {fine:.3e} at h = 1e-3 (order {order:.2})"
    );
    // A loose sanity bound in the chain's own scales, (ωh)² · L · 10 with
    // ω = √(g/l), L the chain's length: the order check above is the real test.
    let length = sys.n_bodies() as f64;
    assert!(
        fine <= 9.81 * 1e-6 * length * 10.0,
        "{name}: tip error {fine:.3e} m"
    );
}

#[test]
fn bar_chains_match_joint_angle_rk4() {
    for n in [2, 5, 10] {
        let bar = AngleLink {
            m: 1.0,
            j: 1.0 / 12.0,
            l: 1.0,
            c: 0.5,
        };
        check(
            &format!("bar chain N = {n}"),
            &bar_chain(n),
            oracle_tip(vec![bar; n], 1.0),
        );
    }
}

#[test]
fn point_mass_chains_match_joint_angle_rk4() {
    for n in [2, 5, 10] {
        let point = AngleLink {
            m: 1.0,
            j: 0.0,
            l: 1.0,
            c: 1.0,
        };
        let sys = point_mass_chain(n);
        assert_eq!(sys.n_coords(), 2 * n);
        check(
            &format!("point-mass chain N = {n}"),
            &sys,
            oracle_tip(vec![point; n], 1.0),
        );
    }
}

/// The KKT backends and Newton variants solve the same discrete equations, so
/// their trajectories agree to the level of the Newton tolerance (1e-10
/// relative, here with a margin of 100 for 300 steps of accumulation).
#[test]
fn every_kkt_backend_and_newton_variant_gives_the_same_motion() {
    use mstar::Newton;
    use mstar::kkt::{Backend, KktOptions};
    let sys = bar_chain(10);
    let (u0, v0) = (sys.initial_position(), sys.initial_velocity());
    let tip = sys.body("link10").map(|b| b.x).expect("tip body");
    let run = |backend: Backend, newton: Newton| {
        let config = Config {
            h: 1e-3,
            newton,
            kkt: KktOptions {
                backend,
                ..KktOptions::default()
            },
            ..Config::default()
        };
        let mut integ = Integrator::new(&sys, config, 0.0, &u0, &v0).expect("start");
        let resolved = (integ.backend(), integ.newton());
        let mut last = None;
        integ
            .run(0.3, &mut |s: &SampleRef<'_>| last = Some(s.u.to_vec()))
            .expect("integration");
        let u = last.expect("samples");
        (resolved, [u[tip], u[tip + 1]])
    };
    let (resolved, reference) = run(Backend::AUTO, Newton::default());
    // The automatic Newton variant is once per step with `schur`, as with
    // `schur-lu` (crates/cli/tests/model_files_spatial.rs).
    assert_eq!(resolved, (Backend::SCHUR, Newton::PER_STEP));
    for (backend, newton) in [
        (Backend::SCHUR, Newton::Full),
        (Backend::SCHUR, Newton::MODIFIED),
        (Backend::SPARSE_LDLT, Newton::Automatic),
        (Backend::SPARSE_LDLT, Newton::MODIFIED),
        (Backend::SPARSE_LDLT, Newton::Full),
        (Backend::SPARSE_LU, Newton::MODIFIED),
        (Backend::DENSE, Newton::Full),
    ] {
        let ((b, nw), got) = run(backend, newton);
        // Automatic resolves to modified Newton with the other backends.
        assert_eq!((b, nw), (backend, newton.resolve(backend, true)));
        assert_ne!(nw, Newton::Automatic);
        let diff = (got[0] - reference[0]).hypot(got[1] - reference[1]);
        assert!(
            diff <= 100.0 * 1e-10 * 10.0,
            "{backend:?}/{newton:?}: tip differs by {diff:.3e} m"
        );
    }
}
