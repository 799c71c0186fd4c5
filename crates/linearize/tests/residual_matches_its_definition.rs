//! `Linearization::eval_residual` forms `r = g − Bᵀλ − M ü` (eq. 3) in one
//! pass, with `Bᵀλ` gathered by column, `M ü` not stored for a diagonal `M`,
//! and constant `M` and `g` evaluated once. Compared here, at random states and
//! twice in a row, with the definition built from the system's own dense `M`,
//! `B` and `g`; and `kkt_rhs` must return exactly `‖[scale·r; −Φ]‖∞`, and
//! `eval_kkt_rhs` the same right-hand side and norms bit for bit.

use mstar_linearize::{Linearization, max_abs};
use mstar_model::planar::{At, PlanarBuilder, PlanarSystem, RigidBody, SpringDamper, bar_chain};
use mstar_model::{Link, PendulumChain, StateRef, System};
use proptest::prelude::*;

/// `g − Bᵀλ − M ü` at `t` from the dense matrices, for the state
/// `s = [u, u̇, ü, λ]`.
fn definition<S: System>(sys: &S, t: f64, s: &[f64]) -> Vec<f64> {
    let (n, m) = (sys.n_coords(), sys.n_constraints());
    let (u, v, a, lambda) = (&s[..n], &s[n..2 * n], &s[2 * n..3 * n], &s[3 * n..]);
    let dense = |pattern: mstar_model::Pattern, eval: &dyn Fn(&mut [f64])| {
        let mut values = vec![0.0; pattern.len()];
        eval(&mut values);
        pattern.to_dense(&values)
    };
    let md = dense(sys.mass_pattern(), &|x| sys.mass_into(t, u, x));
    let bd = dense(sys.b_pattern(), &|x| sys.b_into(t, u, x));
    let mut g = vec![0.0; n];
    sys.forces_into(t, u, v, &mut g);
    (0..n)
        .map(|i| {
            let bl: f64 = (0..m).map(|k| bd[k][i] * lambda[k]).sum();
            let ma: f64 = (0..n).map(|j| md[i][j] * a[j]).sum();
            g[i] - bl - ma
        })
        .collect()
}

/// Two bars on revolute joints with a spring between them: forces that
/// depend on `u` and `u̇` (not constant).
fn sprung() -> PlanarSystem {
    let mut b = PlanarBuilder::new();
    let l1 = b.rigid_body(
        "l1",
        RigidBody {
            mass: 1.0,
            inertia: 0.1,
            pose: [0.5, 0.0, 0.0],
            velocity: [0.0; 3],
        },
    );
    let l2 = b.rigid_body(
        "l2",
        RigidBody {
            mass: 2.0,
            inertia: 0.3,
            pose: [1.5, 0.0, 0.0],
            velocity: [0.0; 3],
        },
    );
    b.revolute("j1", At::Ground([0.0, 0.0]), At::Body(l1, [-0.5, 0.0]));
    b.revolute("j2", At::Body(l1, [0.5, 0.0]), At::Body(l2, [-0.5, 0.0]));
    b.spring(
        "s",
        At::Ground([0.0, 1.0]),
        At::Body(l2, [0.5, 0.0]),
        SpringDamper {
            stiffness: 30.0,
            damping: 2.0,
            rest_length: 0.5,
        },
    );
    b.build().expect("valid")
}

fn check<S: System>(sys: &S, seed: &[f64], scale: f64) -> Result<(), TestCaseError> {
    let (n, m) = (sys.n_coords(), sys.n_constraints());
    let mut lin = Linearization::new(sys).expect("structure");
    // The same evaluations through eval_kkt_rhs (r formed into the rhs).
    let mut fused = Linearization::new(sys).expect("structure");
    // Two different states in a row: a cached constant M or g must not go stale.
    for (pass, s) in [&seed[..3 * n + m], &seed[3 * n + m..2 * (3 * n + m)]]
        .into_iter()
        .enumerate()
    {
        let (u, v, a, lambda) = (&s[..n], &s[n..2 * n], &s[2 * n..3 * n], &s[3 * n..]);
        lin.eval_residual(
            sys,
            &StateRef {
                t: 0.2,
                u,
                v,
                a,
                lambda,
            },
        );
        let want = definition(sys, 0.2, s);
        for (i, (&r, &w)) in lin.r().iter().zip(&want).enumerate() {
            // Sums of a few terms of size ≤ 10·max(|λ|, |ü|) in another order.
            prop_assert!(
                (r - w).abs() <= 1e-13 * (1.0 + w.abs()) * 100.0,
                "pass {pass}, r[{i}] = {r} vs {w}"
            );
        }
        prop_assert_eq!(lin.residual_norm(), max_abs(lin.r()));
        prop_assert_eq!(lin.constraint_norm(), max_abs(lin.phi()));
        let mut rhs = vec![0.0; n + m];
        let norm = lin.kkt_rhs(scale, &mut rhs);
        prop_assert_eq!(norm, max_abs(&rhs));
        let mut fused_rhs = vec![f64::NAN; n + m];
        let fused_norm = fused.eval_kkt_rhs(
            sys,
            &StateRef {
                t: 0.2,
                u,
                v,
                a,
                lambda,
            },
            scale,
            &mut fused_rhs,
        );
        prop_assert_eq!(&fused_rhs, &rhs, "pass {}: eval_kkt_rhs", pass);
        prop_assert_eq!(fused_norm, norm);
        prop_assert_eq!(fused.residual_norm(), lin.residual_norm());
        prop_assert_eq!(fused.constraint_norm(), lin.constraint_norm());
        prop_assert_eq!(fused.force_scale(), lin.force_scale());
    }
    Ok(())
}

proptest! {
    #[test]
    fn residual_and_rhs_norm_match_their_definitions(
        seed in prop::collection::vec(-3.0f64..3.0, 2 * (3 * 15 + 10)),
        scale in prop_oneof![Just(1.0), Just(0.0), 1e-9f64..1e3, -1e3f64..-1e-9],
    ) {
        check(&sprung(), &seed, scale)?;
        check(&bar_chain(5), &seed, scale)?;
        let links = (0..3).map(|k| Link { m: 1.0 + k as f64, l: 0.5 + k as f64 }).collect();
        check(&PendulumChain::new(links, 9.81), &seed, scale)?;
    }
}

/// A NaN anywhere in `r` makes `‖r‖∞` NaN, also when finite entries follow it
/// (a running `f64::max` would drop it); the same for the right-hand side's
/// norm.
#[test]
fn a_nan_in_the_residual_is_not_lost() {
    let sys = bar_chain(20);
    let (n, m) = (sys.n_coords(), sys.n_constraints());
    let mut lin = Linearization::new(&sys).expect("structure");
    let u = sys.initial_position();
    for at in [0, m / 2, m - 1] {
        let mut lambda = vec![1.0; m];
        lambda[at] = f64::NAN;
        lin.eval_residual(
            &sys,
            &StateRef {
                t: 0.0,
                u: &u,
                v: &vec![0.0; n],
                a: &vec![0.0; n],
                lambda: &lambda,
            },
        );
        assert!(lin.residual_norm().is_nan(), "NaN in λ[{at}]");
        let mut rhs = vec![0.0; n + m];
        assert!(lin.kkt_rhs(0.5, &mut rhs).is_nan(), "NaN in λ[{at}]");
        let mut fused = Linearization::new(&sys).expect("structure");
        let zeros = vec![0.0; n];
        let norm = fused.eval_kkt_rhs(
            &sys,
            &StateRef {
                t: 0.0,
                u: &u,
                v: &zeros,
                a: &zeros,
                lambda: &lambda,
            },
            0.5,
            &mut rhs,
        );
        assert!(norm.is_nan(), "eval_kkt_rhs, NaN in λ[{at}]");
    }
}
