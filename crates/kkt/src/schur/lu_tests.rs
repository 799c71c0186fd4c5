//! The `schur-lu` backend against dense LU on random KKT matrices
//! `[[S, Bᵀ], [B, 0]]` whose `S` is block-diagonal with unsymmetric blocks of
//! 1 and 4 unknowns (a body in Euler parameters: `x`, `y`, `z`, `p`), and
//! whose `B` joins consecutive bodies (a chain: `C` has a narrow envelope),
//! with or without a row of each body's own (a normalization `pᵀp = 1`,
//! eliminated with the body's 4 × 4 block).

use crate::testing::{Lcg, csc_of_entries, relative_difference, relative_residual, vector};
use crate::{Backend, Csc, KktError, KktOptions, KktSolver};

/// Unknowns per body and constraint rows per body.
const K: usize = 7;
const ROWS: usize = 4;

/// Entries `(row, column, value)` of the chain: `S` (unsymmetric, its
/// symmetric part positive definite), then `B` (rows after `K n` unknowns),
/// and with `transpose` the `Bᵀ` block. `singular_block`: body whose 4 × 4
/// block is made singular (two equal rows); `duplicate`: a constraint row
/// repeated (a redundant constraint), appended last; `own_row`: each body
/// has a fifth row touching only its 4 × 4 block, after its other rows (with
/// `Some(k)`, body `k`'s is all zeros: no pivot); `symmetric`: `S` symmetric.
#[derive(Default)]
struct Chain {
    n_bodies: usize,
    seed: u64,
    singular_block: Option<usize>,
    duplicate: Option<usize>,
    own_row: Option<Option<usize>>,
    symmetric: bool,
}

impl Chain {
    fn n_primal(&self) -> usize {
        K * self.n_bodies
    }

    fn entries(&self, transpose: bool) -> (usize, Vec<(usize, usize, f64)>) {
        let mut rng = Lcg::new(self.seed);
        let np = self.n_primal();
        let mut e = Vec::new();
        for k in 0..self.n_bodies {
            let x = K * k;
            for i in 0..3 {
                e.push((x + i, x + i, rng.range(0.5, 2.0)));
            }
            let mut s = [[0.0; 4]; 4];
            for (i, row) in s.iter_mut().enumerate() {
                for (j, v) in row.iter_mut().enumerate() {
                    *v = rng.range(-0.3, 0.3) + if i == j { rng.range(1.0, 3.0) } else { 0.0 };
                }
            }
            if self.singular_block == Some(k) {
                s[3] = s[2];
            }
            if self.symmetric {
                for i in 0..4 {
                    for j in 0..i {
                        s[i][j] = s[j][i];
                    }
                }
            }
            for (i, row) in s.iter().enumerate() {
                for (j, &v) in row.iter().enumerate() {
                    e.push((x + 3 + i, x + 3 + j, v));
                }
            }
        }
        // Body k's rows touch it and (but for the first) body k − 1.
        let mut rows: Vec<Vec<(usize, f64)>> = Vec::new();
        for k in 0..self.n_bodies {
            for _ in 0..ROWS {
                let mut row: Vec<(usize, f64)> =
                    (0..K).map(|i| (K * k + i, rng.range(-1.0, 1.0))).collect();
                if k > 0 {
                    row.extend((0..K).map(|i| (K * (k - 1) + i, rng.range(-1.0, 1.0))));
                }
                rows.push(row);
            }
            if let Some(zero) = self.own_row {
                let scale = if zero == Some(k) { 0.0 } else { 1.0 };
                rows.push(
                    (3..K)
                        .map(|i| (K * k + i, scale * rng.range(0.5, 1.5)))
                        .collect(),
                );
            }
        }
        if let Some(r) = self.duplicate {
            rows.push(rows[r].clone());
        }
        for (r, row) in rows.iter().enumerate() {
            for &(j, v) in row {
                e.push((np + r, j, v));
                if transpose {
                    e.push((j, np + r, v));
                }
            }
        }
        (np + rows.len(), e)
    }

    /// The matrix as the Schur backends read it (no `Bᵀ`), or whole.
    fn csc(&self, transpose: bool) -> Csc {
        let (n, e) = self.entries(transpose);
        csc_of_entries(n, e)
    }
}

/// The chain's matrix (as `backend` reads it) analysed and factored.
fn factored(chain: &Chain, backend: Backend) -> Result<KktSolver, KktError> {
    let a = chain.csc(backend != Backend::SCHUR_LU);
    let options = KktOptions {
        backend,
        n_primal: Some(chain.n_primal()),
        ..KktOptions::default()
    };
    let mut s = KktSolver::new(&a, &options)?;
    s.factor(&a.values)?;
    Ok(s)
}

fn solve(chain: &Chain, backend: Backend, b: &[f64]) -> Result<Vec<f64>, KktError> {
    let mut s = factored(chain, backend)?;
    let mut x = b.to_vec();
    s.solve_in_place(&mut x)?;
    Ok(x)
}

#[test]
fn schur_lu_solves_unsymmetric_block_diagonal_s_as_dense_lu_does() {
    for (n_bodies, seed) in [(1, 1), (3, 2), (8, 3), (8, 4)] {
        let chain = Chain {
            n_bodies,
            seed,
            ..Chain::default()
        };
        let whole = chain.csc(true);
        // S is not symmetric: the symmetric Schur backend would be wrong.
        let s01 = whole.position(3, 4).map(|p| whole.values[p]);
        let s10 = whole.position(4, 3).map(|p| whole.values[p]);
        assert_ne!(s01, s10);
        let b = vector(whole.n, seed);
        let dense = solve(&chain, Backend::DENSE, &b).expect("dense LU");
        let lu = solve(&chain, Backend::SCHUR_LU, &b).expect("schur-lu");
        let (diff, res) = (
            relative_difference(&lu, &dense),
            relative_residual(&whole, &lu, &b),
        );
        assert!(
            diff <= 1e-12,
            "N = {n_bodies}: ‖x − x_dense‖/‖x‖ = {diff:e}"
        );
        assert!(res <= 1e-14, "N = {n_bodies}: relative residual {res:e}");
    }
}

#[test]
fn schur_lu_names_a_singular_block_and_a_redundant_constraint() {
    let chain = |singular_block, duplicate| Chain {
        n_bodies: 6,
        seed: 5,
        singular_block,
        duplicate,
        ..Chain::default()
    };
    let block = chain(Some(2), None);
    let b = vector(block.csc(true).n, 1);
    // Rows 3 and 4 of body 2's rotational block are equal: no pivot for
    // its last unknown.
    assert_eq!(
        solve(&block, Backend::SCHUR_LU, &b),
        Err(KktError::Singular {
            unknown: Some(K * 2 + 6)
        })
    );
    let redundant = chain(None, Some(9));
    let m_dup = redundant.n_primal() + ROWS * 6;
    let b = vector(redundant.csc(true).n, 2);
    assert_eq!(
        solve(&redundant, Backend::SCHUR_LU, &b),
        Err(KktError::Singular {
            unknown: Some(m_dup)
        })
    );
}

/// Each body's own row is eliminated with its block (`C` keeps the joining
/// rows only), and the solution is dense LU's: with `schur-lu` on unsymmetric
/// blocks and with `schur` on symmetric ones. The bounds are those of the
/// test above (a well-conditioned chain: round-off times a small growth).
#[test]
fn a_row_of_one_body_is_eliminated_with_its_block() {
    for (n_bodies, seed) in [(1, 6), (3, 7), (8, 8)] {
        for (backend, symmetric) in [(Backend::SCHUR_LU, false), (Backend::SCHUR, true)] {
            let chain = Chain {
                n_bodies,
                seed,
                own_row: Some(None),
                symmetric,
                ..Chain::default()
            };
            let whole = chain.csc(true);
            let np = chain.n_primal();
            let schur = super::Schur::with_symmetry(
                &chain.csc(false),
                np,
                if symmetric {
                    super::Symmetry::Symmetric
                } else {
                    super::Symmetry::General
                },
            )
            .expect("analysed");
            // 4 joining rows a body stay in C; the fifth is local.
            assert_eq!(schur.m_c, ROWS * n_bodies, "N = {n_bodies}");
            let b = vector(whole.n, seed);
            let dense = solve(&chain, Backend::DENSE, &b).expect("dense LU");
            let x = solve(&chain, backend, &b).expect("schur");
            let (diff, res) = (
                relative_difference(&x, &dense),
                relative_residual(&whole, &x, &b),
            );
            assert!(diff <= 1e-12, "{backend:?}, N = {n_bodies}: {diff:e}");
            assert!(res <= 1e-14, "{backend:?}, N = {n_bodies}: {res:e}");
        }
    }
}

/// A body's own row of zeros leaves its block without a pivot for that
/// row's multiplier, which the error names.
#[test]
fn a_zero_row_of_one_body_is_named() {
    let chain = Chain {
        n_bodies: 4,
        seed: 9,
        own_row: Some(Some(2)),
        ..Chain::default()
    };
    let b = vector(chain.csc(true).n, 3);
    // Body 2's own row is the fifth of its rows.
    let row = (ROWS + 1) * 2 + ROWS;
    assert_eq!(
        solve(&chain, Backend::SCHUR_LU, &b),
        Err(KktError::Singular {
            unknown: Some(chain.n_primal() + row)
        })
    );
}

/// `KktSolver::solve_correction` (a Newton iteration's solve): `schur-lu`
/// solves without its refinement step, the first solve after the
/// factorization included (checked by the unrefined solution's residual),
/// still to a backward-stable residual and close to dense LU; the other
/// Schur backend, which does not refine, solves as before to the bit.
#[test]
fn a_correction_solves_without_the_refinement_step() {
    let chain = Chain {
        n_bodies: 8,
        seed: 3,
        ..Chain::default()
    };
    let whole = chain.csc(true);
    let b = vector(whole.n, 7);
    let dense = solve(&chain, Backend::DENSE, &b).expect("dense LU");
    let mut s = factored(&chain, Backend::SCHUR_LU).expect("analysis and factorization");
    let norm = crate::max_abs(&b);
    let mut first = b.clone();
    s.solve_correction(&mut first, norm)
        .expect("the first solve checks it");
    let mut refined = b.clone();
    s.solve_in_place(&mut refined).expect("solve");
    let mut correction = b.clone();
    s.solve_correction(&mut correction, norm).expect("solve");
    assert_eq!(first, correction, "checked or not, the same solve");
    assert_ne!(correction, refined, "the refinement step was skipped");
    let (diff, res) = (
        relative_difference(&correction, &dense),
        relative_residual(&whole, &correction, &b),
    );
    assert!(diff <= 1e-10, "‖x − x_dense‖/‖x‖ = {diff:e}");
    assert!(res <= 1e-14, "relative residual {res:e}");

    let sym = Chain {
        symmetric: true,
        ..chain
    };
    let mut s = factored(&sym, Backend::SCHUR).expect("analysis and factorization");
    let mut x = b.clone();
    s.solve_in_place(&mut x).expect("solve");
    let mut y = b.clone();
    s.solve_correction(&mut y, norm).expect("solve");
    assert_eq!(x, y, "schur has no refinement to skip");
}
