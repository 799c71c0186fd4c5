//! `Linearization::tangent_mul_transpose_add` against the transpose of the
//! matrices `tangent_mul_add` applies, read column by column from unit
//! vectors, on a model whose tangent is not symmetric (a damped spring
//! stretching, a rotational damper turning).

use mstar_linearize::Linearization;
use mstar_model::StateRef;
use mstar_model::System;
use mstar_model::planar::{
    At, PlanarBuilder, PointMass, RigidBody, RotationalSpringDamper, SpringDamper,
};

/// A bar on a hinge and a point mass on a damped spring to the bar's tip.
fn model() -> mstar_model::planar::PlanarSystem {
    let mut b = PlanarBuilder::new();
    b.gravity(0.0, -9.81);
    let bar = b.rigid_body(
        "bar",
        RigidBody {
            mass: 2.0,
            inertia: 0.2,
            pose: [0.4, 0.3, 0.6435],
            velocity: [0.0; 3],
        },
    );
    let bob = b.point_mass(
        "bob",
        PointMass {
            mass: 0.7,
            position: [1.5, -0.2],
            velocity: [0.0; 2],
        },
    );
    b.revolute("hinge", At::Ground([0.0, 0.0]), At::Body(bar, [-0.5, 0.0]));
    b.spring(
        "spring",
        At::Body(bar, [0.5, 0.0]),
        At::Body(bob, [0.0, 0.0]),
        SpringDamper {
            stiffness: 40.0,
            damping: 3.0,
            rest_length: 0.3,
        },
    );
    b.rotational_spring(
        "bearing",
        None,
        bar,
        RotationalSpringDamper {
            stiffness: 5.0,
            damping: 0.7,
        },
    );
    b.build().expect("a valid model")
}

/// Row `i` of `(K_T, C_T)` by the transposed product of `e_i`, and column
/// `j` by the product of `e_j`: entry `(i, j)` both ways, within the
/// rounding of the pattern's sums (a few ε of the largest entry).
#[test]
fn transposed_products_are_the_transposes() {
    let sys = model();
    let (n, m) = (sys.n_coords(), sys.n_constraints());
    let mut lin = Linearization::new(&sys).expect("a linearization");
    let u = sys.initial_position();
    let v: Vec<f64> = (0..n).map(|i| 0.3 + 0.4 * i as f64).collect();
    let a: Vec<f64> = (0..n).map(|i| 1.0 - 0.2 * i as f64).collect();
    let lambda: Vec<f64> = (0..m).map(|i| 2.0 + i as f64).collect();
    let x = StateRef {
        t: 0.0,
        u: &u,
        v: &v,
        a: &a,
        lambda: &lambda,
    };
    lin.eval_residual(&sys, &x);
    lin.eval_jacobians(&sys, &x);
    let unit = |j: usize| -> Vec<f64> { (0..n).map(|i| f64::from(u8::from(i == j))).collect() };
    let zero = vec![0.0; n];
    // k[j], c[j]: column j of K_T, C_T.
    let (mut k, mut c) = (Vec::new(), Vec::new());
    for j in 0..n {
        let (mut kj, mut cj) = (vec![0.0; n], vec![0.0; n]);
        lin.tangent_mul_add(&unit(j), &zero, &mut kj);
        lin.tangent_mul_add(&zero, &unit(j), &mut cj);
        k.push(kj);
        c.push(cj);
    }
    let largest = k
        .iter()
        .chain(&c)
        .flatten()
        .fold(0.0_f64, |s, x| s.max(x.abs()));
    let asymmetry = (0..n)
        .flat_map(|i| (0..n).map(move |j| (i, j)))
        .map(|(i, j)| (k[j][i] - k[i][j]).abs())
        .fold(0.0, f64::max);
    assert!(
        asymmetry > 1e-3 * largest,
        "K_T is symmetric here: the test would not tell"
    );
    let tolerance = 8.0 * f64::EPSILON * largest;
    for i in 0..n {
        let (mut k_row, mut c_row) = (vec![0.0; n], vec![0.0; n]);
        lin.tangent_mul_transpose_add(&unit(i), &mut k_row, &mut c_row);
        for j in 0..n {
            assert!((k_row[j] - k[j][i]).abs() <= tolerance, "K_T[{i}][{j}]");
            assert!((c_row[j] - c[j][i]).abs() <= tolerance, "C_T[{i}][{j}]");
        }
    }
}
