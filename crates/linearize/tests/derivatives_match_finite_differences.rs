//! The Newton iteration converges quadratically only if `B = ∂Φ/∂u`,
//! `K_T = −∂r/∂u` (eq. 6, with the constraint Hessian `Σλᵢ∂²Φᵢ/∂u²`) and
//! `C_T = −∂r/∂u̇` (eq. 7) are the true derivatives. Every analytic derivative
//! of the pendulum chains is compared with central finite differences at random
//! states, and the assembled KKT matrix with the dense formula of eqs. (16)-(17).

use mstar_linearize::{Coefficients, Linearization, Structure, check_derivatives};
use mstar_model::{Link, PendulumChain, StateRef, System};
use proptest::prelude::*;
use proptest::test_runner::FileFailurePersistence;

/// Central differences with step 1e-6 have truncation error ~1e-12·f‴ and
/// round-off ~1e-16/1e-6 = 1e-10 relative; 1e-6 leaves a wide margin while a
/// wrong sign or a missing term gives errors of order 1.
const FD_TOL: f64 = 1e-6;

fn chain(masses: &[f64], lengths: &[f64], g0: f64) -> PendulumChain {
    let links = masses
        .iter()
        .zip(lengths)
        .map(|(&m, &l)| Link { m, l })
        .collect();
    PendulumChain::new(links, g0)
}

proptest! {
    #![proptest_config(ProptestConfig {
        failure_persistence: Some(Box::new(FileFailurePersistence::WithSource("regressions"))),
        ..ProptestConfig::default()
    })]
    #[test]
    fn pendulum_chain_derivatives(
        n in 1usize..5,
        seed in prop::collection::vec(-3.0f64..3.0, 48),
        masses in prop::collection::vec(0.1f64..5.0, 4),
        lengths in prop::collection::vec(0.2f64..2.0, 4),
    ) {
        let sys = chain(&masses[..n], &lengths[..n], 9.81);
        let (nc, m) = (sys.n_coords(), sys.n_constraints());
        // An arbitrary (not necessarily consistent) state.
        let u = &seed[..nc];
        let v = &seed[nc..2 * nc];
        let a = &seed[2 * nc..3 * nc];
        let lambda = &seed[3 * nc..3 * nc + m];
        let e = check_derivatives(&sys, &StateRef { t: 0.3, u, v, a, lambda });
        prop_assert!(e.max() < FD_TOL, "{e:?}");
    }
}

#[test]
fn wrong_hessian_sign_is_caught() {
    // The checker must be able to fail: flip the Hessian of a correct system.
    struct Flipped(PendulumChain);
    impl System for Flipped {
        fn n_coords(&self) -> usize {
            self.0.n_coords()
        }
        fn n_constraints(&self) -> usize {
            self.0.n_constraints()
        }
        fn coord_name(&self, i: usize) -> String {
            self.0.coord_name(i)
        }
        fn constraint_name(&self, i: usize) -> String {
            self.0.constraint_name(i)
        }
        fn mass_pattern(&self) -> mstar_model::Pattern {
            self.0.mass_pattern()
        }
        fn mass_into(&self, t: f64, u: &[f64], m: &mut [f64]) {
            self.0.mass_into(t, u, m)
        }
        fn forces_into(&self, t: f64, u: &[f64], v: &[f64], g: &mut [f64]) {
            self.0.forces_into(t, u, v, g)
        }
        fn phi_into(&self, t: f64, u: &[f64], phi: &mut [f64]) {
            self.0.phi_into(t, u, phi)
        }
        fn b_pattern(&self) -> mstar_model::Pattern {
            self.0.b_pattern()
        }
        fn b_into(&self, t: f64, u: &[f64], b: &mut [f64]) {
            self.0.b_into(t, u, b)
        }
        fn hessian_pattern(&self) -> mstar_model::Pattern {
            self.0.hessian_pattern()
        }
        fn hessian_into(&self, t: f64, u: &[f64], mu: &[f64], out: &mut [f64]) {
            self.0.hessian_into(t, u, mu, out);
            out.iter_mut().for_each(|x| *x = -*x);
        }
        fn accel_rhs_into(&self, t: f64, u: &[f64], v: &[f64], c: &mut [f64]) {
            self.0.accel_rhs_into(t, u, v, c)
        }
    }
    let sys = Flipped(PendulumChain::paper(1.0, 1.0, 10.0));
    let e = check_derivatives(
        &sys,
        &StateRef {
            t: 0.0,
            u: &[0.7, -0.7, 0.8],
            v: &[0.1; 3],
            a: &[0.0; 3],
            lambda: &[3.0, -4.0],
        },
    );
    assert!(e.k_t > 0.1, "{e:?}");
}

#[test]
fn kkt_matrix_is_eq_16_with_m_star() {
    // The paper's pendulum at θ: S_T = K_T + γ/(βh) C_T + M*/(βh²) (17) with
    // M* of eq. (19), K_T = diag(0, 0, l(λ₁ sin θ − λ₂ cos θ)), C_T = 0.
    let (m, l, th) = (1.0, 1.0, 0.6f64);
    let sys = PendulumChain::paper(m, l, 10.0);
    let u = sys.position(&[th]);
    let lambda = [2.0, -3.0];
    let mut lin = Linearization::new(&sys).expect("valid");
    let x = StateRef {
        t: 0.0,
        u: &u,
        v: &[0.0; 3],
        a: &[0.0; 3],
        lambda: &lambda,
    };
    lin.eval_residual(&sys, &x);
    lin.eval_jacobians(&sys, &x);
    let (beta, gamma, h) = (0.25, 0.5, 0.01);
    let ca = 1.0 / (beta * h * h);
    lin.assemble(&Coefficients {
        c_u: 1.0,
        c_v: gamma / (beta * h),
        c_a: ca,
        c_bb: ca,
        c_identity: 0.0,
        scale: 1.0,
    });
    let (c, s) = (th.cos(), th.sin());
    let m_star = [
        [m + 1.0, 0.0, -l * c],
        [0.0, m + 1.0, -l * s],
        [-l * c, -l * s, l * l],
    ];
    let b = [[1.0, 0.0, -l * c], [0.0, 1.0, -l * s]];
    let k33 = l * (lambda[0] * s - lambda[1] * c);
    let dense = lin.kkt().to_dense();
    for i in 0..5 {
        for j in 0..5 {
            let expected = match (i < 3, j < 3) {
                (true, true) => ca * m_star[i][j] + if i == 2 && j == 2 { k33 } else { 0.0 },
                (true, false) => b[j - 3][i],
                (false, true) => b[i - 3][j],
                (false, false) => 0.0,
            };
            assert!(
                (dense[i][j] - expected).abs() <= 1e-9 * expected.abs().max(1.0),
                "({i},{j}): {} vs {expected}",
                dense[i][j]
            );
        }
    }
}

#[test]
fn m_star_is_eq_19_in_every_structure() {
    // M* = M + BᵀB of the paper's pendulum at θ (eq. 19), whether the KKT
    // structure carries BᵀB (augmented: its pairs built with the layout) or
    // not (plain: M*'s structure and BᵀB's pairs built on first use).
    let (m, l, th) = (1.0, 1.0, 0.6f64);
    let sys = PendulumChain::paper(m, l, 10.0);
    let u = sys.position(&[th]);
    let (c, s) = (th.cos(), th.sin());
    let want = [
        [m + 1.0, 0.0, -l * c],
        [0.0, m + 1.0, -l * s],
        [-l * c, -l * s, l * l],
    ];
    let x = StateRef {
        t: 0.0,
        u: &u,
        v: &[0.0; 3],
        a: &[0.0; 3],
        lambda: &[2.0, -3.0],
    };
    for structure in [Structure::AUGMENTED, Structure::PLAIN] {
        let mut lin = Linearization::with_structure(&sys, structure).expect("valid");
        lin.eval_residual(&sys, &x);
        // Twice: the second call refills the structure built by the first.
        for _ in 0..2 {
            let dense = lin.m_star().to_dense();
            for i in 0..3 {
                for j in 0..3 {
                    // Each entry is a sum of at most three rounded products
                    // of numbers of size ≤ 1 (cos²θ + sin²θ at (2,2)):
                    // within 4 ulps of 1.
                    assert!(
                        (dense[i][j] - want[i][j]).abs() <= 4.0 * f64::EPSILON,
                        "{structure:?} ({i},{j}): {} vs {}",
                        dense[i][j],
                        want[i][j]
                    );
                }
            }
        }
    }
}

/// A model with every planar element, at random parameters: all of them in
/// one system, so that their rows and entries must not overlap.
fn every_element(p: &[f64]) -> mstar_model::planar::PlanarSystem {
    use mstar_model::planar::{At, PlanarBuilder, PointMass, RigidBody};
    let rigid = |mass, inertia, pose| RigidBody {
        mass,
        inertia,
        pose,
        velocity: [0.0; 3],
    };
    let mut b = PlanarBuilder::new();
    b.gravity(p[0], p[1]);
    let r1 = b.rigid_body(
        "r1",
        rigid(1.0 + p[2].abs(), 0.1 + p[3].abs(), [p[4], p[5], p[6]]),
    );
    let r2 = b.rigid_body("r2", rigid(2.0, 0.3, [p[7], p[8], p[9]]));
    let r3 = b.rigid_body("r3", rigid(0.5, 0.05, [p[10], p[11], p[12]]));
    let pm = b.point_mass(
        "pm",
        PointMass {
            mass: 0.7,
            position: [p[13], p[14]],
            velocity: [0.0; 2],
        },
    );
    b.revolute(
        "hinge",
        At::Ground([p[15], p[16]]),
        At::Body(r1, [p[17], p[18]]),
    );
    b.revolute(
        "pin",
        At::Body(r1, [p[19], p[20]]),
        At::Body(r2, [p[21], p[22]]),
    );
    b.distance(
        "rod",
        At::Body(r2, [p[23], p[24]]),
        At::Body(pm, [0.0, 0.0]),
        1.0 + p[25].abs(),
    );
    b.prismatic(
        "slider",
        At::Body(r2, [p[26], p[27]]),
        [p[28], 1.0],
        At::Body(r3, [p[29], p[30]]),
    );
    b.prismatic(
        "rail",
        At::Ground([p[31], 0.0]),
        [1.0, p[32]],
        At::Body(pm, [0.0, 0.0]),
    );
    b.weld(
        "glue",
        At::Body(r3, [p[33], p[34]]),
        At::Body(r1, [p[35], p[36]]),
    );
    b.distance(
        "tether",
        At::Ground([0.0, 1.0]),
        At::Body(r3, [p[37], p[38]]),
        2.0,
    );
    loads(&mut b, p, [r1, r2, r3], pm);
    b.build().expect("valid model")
}

/// The drivers and loads of [`every_element`].
fn loads(
    b: &mut mstar_model::planar::PlanarBuilder,
    p: &[f64],
    [r1, r2, r3]: [mstar_model::planar::BodyId; 3],
    pm: mstar_model::planar::BodyId,
) {
    use mstar_model::planar::{At, Coordinate, RotationalSpringDamper, SpringDamper, TimeFunction};
    let sine = TimeFunction::Sine {
        offset: p[39],
        amplitude: 0.5,
        omega: 2.0,
        phase: p[40],
    };
    b.driver("motor", r2, Coordinate::Theta, sine.clone());
    b.driver(
        "lift",
        pm,
        Coordinate::Y,
        TimeFunction::Linear {
            value: 0.1,
            rate: p[41],
        },
    );
    b.force(
        "push",
        At::Body(r1, [p[42], p[43]]),
        sine.clone(),
        TimeFunction::Constant(p[44]),
    );
    b.torque("twist", r3, sine);
    b.spring(
        "spring",
        At::Body(r1, [p[45], 0.2]),
        At::Body(pm, [0.0, 0.0]),
        SpringDamper {
            stiffness: 50.0,
            damping: 3.0,
            rest_length: 0.5,
        },
    );
    b.spring(
        "anchor",
        At::Ground([1.0, 1.0]),
        At::Body(r2, [0.1, p[46]]),
        SpringDamper {
            stiffness: 20.0,
            damping: 1.0,
            rest_length: 0.0,
        },
    );
    b.rotational_spring(
        "torsion",
        Some(r1),
        r2,
        RotationalSpringDamper {
            stiffness: 10.0,
            damping: 0.5,
        },
    );
    b.rotational_spring(
        "ground torsion",
        None,
        r3,
        RotationalSpringDamper {
            stiffness: 4.0,
            damping: 0.2,
        },
    );
}

proptest! {
    #![proptest_config(ProptestConfig {
        failure_persistence: Some(Box::new(FileFailurePersistence::WithSource("regressions"))),
        ..ProptestConfig::default()
    })]
    #[test]
    fn planar_element_derivatives(
        params in prop::collection::vec(-1.0f64..1.0, 47),
        state in prop::collection::vec(-2.0f64..2.0, 60),
        t in 0.0f64..2.0,
    ) {
        let sys = every_element(&params);
        let (n, m) = (sys.n_coords(), sys.n_constraints());
        prop_assert_eq!((n, m), (11, 14));
        let u = &state[..n];
        let v = &state[n..2 * n];
        let a = &state[2 * n..3 * n];
        let lambda = &state[3 * n..3 * n + m];
        let e = check_derivatives(&sys, &StateRef { t, u, v, a, lambda });
        prop_assert!(e.max() < FD_TOL, "{e:?}");
    }
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 64,
        failure_persistence: Some(Box::new(FileFailurePersistence::WithSource("regressions"))),
        ..ProptestConfig::default()
    })]
    /// Every registered joint, driver and load, between every pair of
    /// anchors it accepts (the model crate's registry, no hand-kept list).
    #[test]
    fn every_registered_element_derivatives(
        params in prop::collection::vec(-1.0f64..1.0, 24),
        state in prop::collection::vec(-2.0f64..2.0, 21),
        t in 0.0f64..2.0,
    ) {
        for (what, sys) in mstar_model::planar::element_examples(&params) {
            let (n, m) = (sys.n_coords(), sys.n_constraints());
            let (u, v, a) = (&state[..n], &state[6..6 + n], &state[12..12 + n]);
            let lambda = &state[18..18 + m];
            let e = check_derivatives(&sys, &StateRef { t, u, v, a, lambda });
            prop_assert!(e.max() < FD_TOL, "{what}: {e:?}");
        }
    }
}

#[test]
fn chain_generators_start_assembled() {
    use mstar_model::planar::{bar_chain, point_mass_chain};
    for sys in [bar_chain(7), point_mass_chain(7)] {
        let u = sys.initial_position();
        let mut phi = vec![0.0; sys.n_constraints()];
        sys.phi_into(0.0, &u, &mut phi);
        assert!(phi.iter().all(|p| p.abs() < 1e-14), "{phi:?}");
        assert_eq!(sys.coord_name(0), "link1.x");
    }
    assert_eq!(bar_chain(3).coord_name(8), "link3.theta");
}
