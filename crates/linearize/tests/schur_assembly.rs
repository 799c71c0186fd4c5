//! The KKT matrix assembled in the Schur backend's structure (no `BᵀB` term,
//! no `Bᵀ` block: `assemble` zeroes only the `S` slots and assigns `B`) must
//! equal the fully assembled matrix without `BᵀB` entry by entry, and the full
//! matrix's only other entries must be its `Bᵀ` block, also when assembled
//! again with other coefficients and at another state (nothing stale left in
//! a slot).

use mstar_linearize::{Coefficients, Linearization, Structure};
use mstar_model::planar::bar_chain;
use mstar_model::{StateRef, System};

#[test]
fn the_schur_assembly_equals_the_full_one_outside_the_transpose_block() {
    let sys = bar_chain(7);
    let (n, m) = (sys.n_coords(), sys.n_constraints());
    let plain = Structure {
        augmented: false,
        transpose: true,
    };
    let mut full = Linearization::with_structure(&sys, plain).expect("structure");
    let mut lean = Linearization::with_structure(&sys, Structure::PLAIN).expect("structure");
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
            let x = StateRef {
                t: 0.1,
                u: &u,
                v: &v,
                a: &a,
                lambda: &lambda,
            };
            lin.eval_residual(&sys, &x);
            lin.eval_jacobians(&sys, &x);
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
