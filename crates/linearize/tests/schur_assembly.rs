//! The KKT matrix assembled for the Schur backend (no `BᵀB` term, `Bᵀ` block
//! not filled: `assemble` zeroes only the `S` slots and assigns `B`) must
//! equal the fully assembled matrix outside the `Bᵀ` block, which stays zero,
//! also when assembled again with other coefficients and at another state
//! (nothing stale left in a slot).

use mstar_linearize::{Coefficients, Linearization};
use mstar_model::System;
use mstar_model::planar::bar_chain;

#[test]
fn the_schur_assembly_equals_the_full_one_outside_the_transpose_block() {
    let sys = bar_chain(7);
    let (n, m) = (sys.n_coords(), sys.n_constraints());
    let mut full = Linearization::with_augmentation(&sys, false).expect("structure");
    let mut lean = Linearization::with_augmentation(&sys, false).expect("structure");
    lean.set_fill_transpose(false);
    let u0 = sys.initial_position();
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
        // A bent chain with nonzero multipliers (the Hessian term of S).
        let u: Vec<f64> = u0
            .iter()
            .enumerate()
            .map(|(i, &x)| x + 0.1 * ((i + k) as f64 * 0.7).sin())
            .collect();
        let v: Vec<f64> = (0..n).map(|i| (i as f64 * 0.3).cos()).collect();
        let a = vec![0.5; n];
        let lambda: Vec<f64> = (0..m).map(|i| 3.0 + (i + k) as f64).collect();
        for lin in [&mut full, &mut lean] {
            lin.eval_residual(&sys, 0.1, &u, &v, &a, &lambda);
            lin.eval_jacobians(&sys, 0.1, &u, &v, &a, &lambda);
            lin.assemble(&c);
        }
        let (f, l) = (full.kkt(), lean.kkt());
        assert_eq!(f.col_ptr, l.col_ptr);
        assert_eq!(f.row_idx, l.row_idx);
        let mut transpose_entries = 0;
        for j in 0..n + m {
            for p in f.col_ptr[j]..f.col_ptr[j + 1] {
                let i = f.row_idx[p];
                if j >= n && i < n {
                    // The Bᵀ block: filled in one, zero in the other.
                    assert_eq!(l.values[p], 0.0, "coefficients {k}: Bᵀ ({i}, {j})");
                    transpose_entries += usize::from(f.values[p] != 0.0);
                } else {
                    assert_eq!(l.values[p], f.values[p], "coefficients {k}: ({i}, {j})");
                }
            }
        }
        assert!(transpose_entries > 0, "the full matrix has a Bᵀ block");
    }
}
