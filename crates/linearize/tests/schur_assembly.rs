//! The KKT matrix assembled in the Schur backend's structure (no `BᵀB` term,
//! no `Bᵀ` block: `assemble` zeroes only the `S` slots and assigns `B`) must
//! equal the fully assembled matrix without `BᵀB` entry by entry, and the full
//! matrix's only other entries must be its `Bᵀ` block, also when assembled
//! again with other coefficients and at another state (nothing stale left in
//! a slot). The spatial chain takes the lean structure's shortcuts for
//! bodies in Euler parameters (`M` assigned to the `S` slots, the velocity
//! terms added in one pass).

use mstar_linearize::{Coefficients, Linearization, Structure};
use mstar_model::planar::bar_chain;
use mstar_model::spatial::{RotationalMass, spatial_bar_chain};
use mstar_model::{StateRef, System};

#[test]
fn the_schur_assembly_equals_the_full_one_outside_the_transpose_block() {
    let planar = bar_chain(7);
    equal_outside_the_transpose_block(&planar, &planar.initial_position());
    let spatial = spatial_bar_chain(5, RotationalMass::Regularized);
    equal_outside_the_transpose_block(&spatial, &spatial.initial_position());
}

/// `(u, u̇, ü, λ)` of a bent chain with nonzero multipliers (the Hessian
/// term of `S`) from the pose `u0`, `m` multipliers; `k` varies it.
/// The state `[u, u̇, ü, λ]` of [`bent_state`] at t = 0.1.
fn at(state: &[Vec<f64>; 4]) -> StateRef<'_> {
    let [u, v, a, lambda] = state;
    StateRef {
        t: 0.1,
        u,
        v,
        a,
        lambda,
    }
}

fn bent_state(u0: &[f64], m: usize, k: usize) -> [Vec<f64>; 4] {
    let n = u0.len();
    let u = u0
        .iter()
        .enumerate()
        .map(|(i, &x)| x + 0.1 * ((i + k) as f64 * 0.7).sin())
        .collect();
    let v = (0..n).map(|i| (i as f64 * 0.3).cos()).collect();
    let a = (0..n).map(|i| 0.5 + (i as f64 * 1.1).sin()).collect();
    let lambda = (0..m).map(|i| 3.0 + (i + k) as f64).collect();
    [u, v, a, lambda]
}

fn equal_outside_the_transpose_block<S: System>(sys: &S, u0: &[f64]) {
    let (n, m) = (sys.n_coords(), sys.n_constraints());
    let plain = Structure {
        augmented: false,
        transpose: true,
    };
    let mut full = Linearization::with_structure(sys, plain).expect("structure");
    let mut lean = Linearization::with_structure(sys, Structure::PLAIN).expect("structure");
    for (k, c) in [
        Coefficients {
            c_u: 1.0,
            c_v: 250.0,
            c_a: 4e6,
            c_bb: 4e6,
            c_identity: 0.0,
            scale: 2.5e-7,
        },
        Coefficients::acceleration(),
        Coefficients::projection(),
    ]
    .into_iter()
    .enumerate()
    {
        let state = bent_state(u0, m, k);
        for lin in [&mut full, &mut lean] {
            let x = at(&state);
            lin.eval_residual(sys, &x);
            lin.eval_jacobians(sys, &x);
            lin.assemble(&c);
        }
        let (f, l) = (full.kkt(), lean.kkt());
        let mut transpose_entries = 0;
        for j in 0..n + m {
            for p in f.col_ptr[j]..f.col_ptr[j + 1] {
                let i = f.row_idx[p];
                match l.position(i, j) {
                    Some(q) => {
                        assert!(!(j >= n && i < n), "the lean structure has Bᵀ ({i}, {j})");
                        assert_eq!(l.values[q], f.values[p], "coefficients {k}: ({i}, {j})");
                    }
                    None => {
                        assert!(j >= n && i < n, "coefficients {k}: ({i}, {j}) missing");
                        transpose_entries += usize::from(f.values[p] != 0.0);
                    }
                }
            }
        }
        assert_eq!(
            f.nnz() - l.nnz(),
            sys.b_pattern().len(),
            "one Bᵀ entry per entry of B"
        );
        assert!(transpose_entries > 0, "the full matrix has a Bᵀ block");
    }
}

/// The `S` block the Schur structure assembles for bodies in Euler
/// parameters (`M` assigned to its slots, the velocity terms added in one
/// pass) against its terms summed densely from the Jacobians' values:
/// `scale (c_a M + c_u (H − ∂g/∂u + ∂(M ü)/∂u) − c_v ∂g/∂u̇)`, to the
/// rounding of the terms.
#[test]
fn the_spatial_schur_block_is_its_terms_summed() {
    let sys = spatial_bar_chain(4, RotationalMass::Regularized);
    let (n, m) = (sys.n_coords(), sys.n_constraints());
    let mut lin = Linearization::with_structure(&sys, Structure::PLAIN).expect("structure");
    let state = bent_state(&sys.initial_position(), m, 0);
    let x = at(&state);
    lin.eval_residual(&sys, &x);
    lin.eval_jacobians(&sys, &x);
    let c = Coefficients {
        c_u: 1.0,
        c_v: 250.0,
        c_a: 4e6,
        c_bb: 0.0,
        c_identity: 0.0,
        scale: 2.5e-7,
    };
    lin.assemble(&c);
    let [hessian, g_u, g_v, mass_du] = lin.jacobians();
    let terms = [
        (sys.mass_pattern(), lin.mass(), c.c_a),
        (sys.hessian_pattern(), hessian, c.c_u),
        (sys.forces_du_pattern(), g_u, -c.c_u),
        (sys.mass_du_pattern(), mass_du, c.c_u),
        (sys.forces_dv_pattern(), g_v, -c.c_v),
    ];
    let (mut want, mut size) = (vec![vec![0.0; n]; n], vec![vec![0.0f64; n]; n]);
    for (pattern, values, coef) in terms {
        assert!(values.iter().any(|&x| x != 0.0), "a term without values");
        for (&(i, j), &x) in pattern.entries.iter().zip(values) {
            want[i][j] += c.scale * coef * x;
            size[i][j] += (c.scale * coef * x).abs();
        }
    }
    let kkt = lin.kkt();
    let mut compared = 0;
    for j in 0..n {
        for p in kkt.col_ptr[j]..kkt.col_ptr[j + 1] {
            let i = kkt.row_idx[p];
            if i < n {
                let got = kkt.values[p];
                let bound = 8.0 * f64::EPSILON * size[i][j];
                assert!(
                    (got - want[i][j]).abs() <= bound,
                    "({i}, {j}): {got} against {}",
                    want[i][j]
                );
                compared += 1;
            }
        }
    }
    assert_eq!(
        compared,
        19 * 4,
        "three translations and a 4 × 4 block a bar"
    );
}
