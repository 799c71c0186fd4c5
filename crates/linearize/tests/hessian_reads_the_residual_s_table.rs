//! The constraint Hessian at the state of the last residual reads the table
//! of `sin θ, cos θ` that the residual's `phi_b_into` left
//! (`System::hessian_after_phi_b`); at any other state it computes its own.
//! Either way the values are those of `hessian_into` on a fresh
//! evaluation, bit for bit, also after the table was overwritten at another
//! state.

use mstar_linearize::Linearization;
use mstar_model::planar::{At, PlanarBuilder, PlanarSystem, RigidBody};
use mstar_model::{StateRef, System};

/// Three bars on revolute joints, two of them closing a loop to the ground
/// (several joints per body: the table is read from more than one kernel).
fn model() -> PlanarSystem {
    let mut b = PlanarBuilder::new();
    b.gravity(0.0, -9.81);
    let bar = |b: &mut PlanarBuilder, name: &str, pose: [f64; 3]| {
        b.rigid_body(
            name,
            RigidBody {
                mass: 1.0,
                inertia: 0.1,
                pose,
                velocity: [0.0; 3],
            },
        )
    };
    let crank = bar(&mut b, "crank", [0.0, 0.5, std::f64::consts::FRAC_PI_2]);
    let coupler = bar(&mut b, "coupler", [1.0, 1.0, 0.0]);
    let rocker = bar(&mut b, "rocker", [2.0, 0.5, std::f64::consts::FRAC_PI_2]);
    b.revolute("a", At::Ground([0.0, 0.0]), At::Body(crank, [-0.5, 0.0]));
    b.revolute(
        "b",
        At::Body(crank, [0.5, 0.0]),
        At::Body(coupler, [-1.0, 0.0]),
    );
    b.revolute(
        "c",
        At::Body(coupler, [1.0, 0.0]),
        At::Body(rocker, [0.5, 0.0]),
    );
    b.revolute("d", At::Body(rocker, [-0.5, 0.0]), At::Ground([2.0, 0.0]));
    b.build().expect("a valid model")
}

/// The Hessian's values at `u` with multipliers `lambda`, from nothing.
fn fresh(sys: &PlanarSystem, u: &[f64], lambda: &[f64]) -> Vec<f64> {
    let mut out = vec![0.0; sys.hessian_pattern().len()];
    sys.hessian_into(0.0, u, lambda, &mut out);
    out
}

fn bits(x: &[f64]) -> Vec<u64> {
    x.iter().map(|x| x.to_bits()).collect()
}

#[test]
fn the_table_is_read_only_at_the_residual_s_state() {
    let sys = model();
    let (n, m) = (sys.n_coords(), sys.n_constraints());
    let mut lin = Linearization::new(&sys).expect("a linearization");
    let u1: Vec<f64> = sys.initial_position().to_vec();
    let u2: Vec<f64> = u1.iter().map(|x| x + 0.37).collect();
    let zero = vec![0.0; n];
    let lambda: Vec<f64> = (0..m).map(|i| 1.5 - 0.7 * i as f64).collect();
    let state = |u: &[f64]| (u.to_vec(), zero.clone(), zero.clone(), lambda.clone());
    let (h1, h2) = (fresh(&sys, &u1, &lambda), fresh(&sys, &u2, &lambda));
    assert_ne!(bits(&h1), bits(&h2), "the two states must differ");
    let hessian = |lin: &Linearization| lin.jacobians()[0].to_vec();
    let eval = |lin: &mut Linearization, u: &[f64], residual: bool| {
        let (u, v, a, l) = state(u);
        let x = StateRef {
            t: 0.0,
            u: &u,
            v: &v,
            a: &a,
            lambda: &l,
        };
        if residual {
            lin.eval_residual(&sys, &x);
        }
        lin.eval_jacobians(&sys, &x);
    };
    // At the residual's state: the table it left.
    eval(&mut lin, &u1, true);
    assert_eq!(bits(&hessian(&lin)), bits(&h1));
    // At another state: its own table, which overwrites the residual's.
    eval(&mut lin, &u2, false);
    assert_eq!(bits(&hessian(&lin)), bits(&h2));
    // Back at the residual's state, whose table is gone: computed again.
    eval(&mut lin, &u1, false);
    assert_eq!(bits(&hessian(&lin)), bits(&h1));
}
