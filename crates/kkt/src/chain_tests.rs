//! The backends on KKT matrices of planar chains (see [`crate::testing`]).

use crate::schur::Schur;
use crate::testing::{chain, chain_with, relative_difference, relative_residual, vector};
use crate::{Backend, Csc, KktBackend, KktError, KktOptions, KktSolver, max_abs};
use proptest::prelude::*;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

fn options(backend: Backend, n_bodies: usize) -> KktOptions {
    KktOptions {
        backend,
        n_primal: Some(3 * n_bodies),
        ..KktOptions::default()
    }
}

fn solve(backend: Backend, n_bodies: usize, a: &Csc, b: &[f64]) -> Result<Vec<f64>, KktError> {
    let mut s = KktSolver::new(a, &options(backend, n_bodies))?;
    assert_eq!(s.backend(), backend);
    s.factor(&a.values)?;
    let mut x = b.to_vec();
    s.solve_in_place(&mut x)?;
    Ok(x)
}

#[test]
fn backends_agree_on_chains() {
    for n_bodies in [1, 10, 1000] {
        let a = chain(n_bodies, 7, None);
        let mut b = vec![0.0; a.n];
        a.mul(&vector(a.n, 3), &mut b);
        let ldlt =
            solve(Backend::SPARSE_LDLT, n_bodies, &a, &b).expect("LDLᵀ solves a regular chain");
        let lu = solve(Backend::SPARSE_LU, n_bodies, &a, &b).expect("LU solves a regular chain");
        let (r_ldlt, r_lu) = (
            relative_residual(&a, &ldlt, &b),
            relative_residual(&a, &lu, &b),
        );
        let diff = relative_difference(&ldlt, &lu);
        eprintln!(
            "N = {n_bodies}: residual LDLᵀ {r_ldlt:.1e}, LU {r_lu:.1e}; ‖x_LDLᵀ − x_LU‖/‖x‖ {diff:.1e}"
        );
        assert!(
            r_ldlt <= 1e-12 && r_lu <= 1e-12,
            "N = {n_bodies}: {r_ldlt:e} {r_lu:e}"
        );
        assert!(diff <= 1e-10, "N = {n_bodies}: {diff:e}");
        if n_bodies <= 10 {
            let dense =
                solve(Backend::DENSE, n_bodies, &a, &b).expect("dense LU solves a regular chain");
            let diff = relative_difference(&ldlt, &dense);
            eprintln!("N = {n_bodies}: ‖x_LDLᵀ − x_dense‖/‖x‖ {diff:.1e}");
            assert!(diff <= 1e-10, "N = {n_bodies}: {diff:e}");
        }
    }
}

#[test]
fn auto_picks_schur_then_ldlt_when_the_primal_count_is_given() {
    let a = chain(10, 1, None);
    let auto = |n_primal| KktOptions {
        n_primal,
        ..KktOptions::default()
    };
    let pick = |o: KktOptions| KktSolver::new(&a, &o).expect("regular structure").backend();
    // S + BᵀB couples every body: not block-diagonal.
    assert_eq!(pick(auto(Some(30))), Backend::SPARSE_LDLT);
    let plain = chain_with(10, 1, None, false);
    let s = KktSolver::new(&plain, &auto(Some(30))).expect("regular structure");
    assert_eq!(s.backend(), Backend::SCHUR);
    assert_eq!(pick(auto(None)), Backend::SPARSE_LU);
    // Small: the Schur backends before the dense LU (one body's `S` is one
    // block), the dense LU without the primal count.
    let small = chain(1, 1, None);
    let s = KktSolver::new(&small, &auto(Some(3))).expect("regular structure");
    assert_eq!(s.backend(), Backend::SCHUR);
    let s = KktSolver::new(&small, &auto(None)).expect("regular structure");
    assert_eq!(s.backend(), Backend::DENSE);
}

#[test]
fn refactorization_reuses_the_analysis() {
    let n_bodies = 100;
    let a0 = chain(n_bodies, 0, None);
    let mut s =
        KktSolver::new(&a0, &options(Backend::SPARSE_LDLT, n_bodies)).expect("regular structure");
    for seed in 1..6 {
        let a = chain(n_bodies, seed, None);
        assert_eq!(
            (&a.col_ptr, &a.row_idx),
            (&a0.col_ptr, &a0.row_idx),
            "same structure"
        );
        let b = vector(a.n, seed);
        s.factor(&a.values).expect("regular values");
        let mut x = b.clone();
        s.solve_in_place(&mut x).expect("accurate");
        let fresh = solve(Backend::SPARSE_LU, n_bodies, &a, &b).expect("LU");
        assert!(relative_difference(&x, &fresh) <= 1e-10, "seed {seed}");
        // A second right-hand side with the same factors.
        let mut y = vector(a.n, seed + 100);
        let b2 = y.clone();
        s.solve_in_place(&mut y).expect("accurate");
        assert!(relative_residual(&a, &y, &b2) <= 1e-12);
    }
}

/// The chain with constraint `r` repeated (times `f`), and a right-hand side
/// that is consistent (`A x` for some `x`) or not.
fn redundant(n_bodies: usize, r: usize, f: f64, consistent: bool) -> (Csc, Vec<f64>) {
    let a = chain(n_bodies, 11, Some((r, f)));
    let b = if consistent {
        let mut b = vec![0.0; a.n];
        a.mul(&vector(a.n, 5), &mut b);
        b
    } else {
        vector(a.n, 5)
    };
    (a, b)
}

#[test]
fn a_redundant_constraint_is_an_error_for_every_backend() {
    for (n_bodies, r) in [(1, 0), (1, 1), (10, 7), (1000, 0), (1000, 1999)] {
        for f in [1.0, 1.0 / 3.0] {
            for consistent in [true, false] {
                let (a, b) = redundant(n_bodies, r, f, consistent);
                let mut backends = vec![Backend::SPARSE_LDLT, Backend::SPARSE_LU];
                if n_bodies <= 10 {
                    backends.push(Backend::DENSE);
                }
                for backend in backends {
                    let result = solve(backend, n_bodies, &a, &b);
                    if backend == Backend::SPARSE_LU && f != 1.0 && consistent {
                        // Known gap: faer's LU finds a tiny nonzero pivot and
                        // may return a moderate solution, one of many, of the
                        // singular but consistent system; its factors are not
                        // public for a pivot check like LDLᵀ's.
                        continue;
                    }
                    let case = format!(
                        "N = {n_bodies}, row {r} × {f}, consistent {consistent}, {backend:?}: {result:?}"
                    );
                    assert!(
                        matches!(
                            result,
                            Err(KktError::Singular { .. } | KktError::Inaccurate { .. })
                        ),
                        "{case}"
                    );
                    if backend == Backend::SPARSE_LDLT {
                        // The later of the two copies in elimination order.
                        let pair = [3 * n_bodies + r, a.n - 1];
                        assert!(
                            matches!(result, Err(KktError::Singular { unknown: Some(k) }) if pair.contains(&k)),
                            "{case}"
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn factor_recovers_after_a_singular_matrix() {
    let n_bodies = 10;
    let (a, _) = redundant(n_bodies, 4, 1.0, true);
    let mut s = KktSolver::new(&a, &options(Backend::SPARSE_LDLT, n_bodies)).expect("structure");
    assert!(matches!(
        s.factor(&a.values),
        Err(KktError::Singular { .. })
    ));
    let mut x = vector(a.n, 1);
    assert_eq!(s.solve_in_place(&mut x), Err(KktError::NotFactored));
    // Make the repeated row independent: change its first entry (and the
    // symmetric one), which S does not see.
    let mut values = a.values.clone();
    let last = a.n - 1;
    let first = a.row_idx[a.col_ptr[last]];
    values[a.col_ptr[last]] += 0.5;
    let k = a.col_ptr[first]
        + a.row_idx[a.col_ptr[first]..a.col_ptr[first + 1]]
            .binary_search(&last)
            .expect("symmetric structure");
    values[k] += 0.5;
    let independent = Csc {
        values,
        ..a.clone()
    };
    s.factor(&independent.values)
        .expect("independent constraints");
    let b = x.clone();
    s.solve_in_place(&mut x).expect("accurate");
    assert!(relative_residual(&independent, &x, &b) <= 1e-12);
}

#[test]
fn ldlt_rejects_what_it_cannot_factor() {
    let a = chain(10, 1, None);
    let with = |n_primal| KktOptions {
        backend: Backend::SPARSE_LDLT,
        n_primal,
        ..KktOptions::default()
    };
    let structure = |r: Result<KktSolver, KktError>| matches!(r, Err(KktError::Structure(_)));
    assert!(structure(KktSolver::new(&a, &with(None))), "needs n_primal");
    assert!(
        structure(KktSolver::new(&a, &with(Some(a.n + 1)))),
        "n_primal > n"
    );
    // Copies `a` without the entries for which `drop(i, j)` holds.
    let without = |drop: &dyn Fn(usize, usize) -> bool| {
        let mut m = Csc {
            n: a.n,
            col_ptr: vec![0],
            ..Csc::default()
        };
        for j in 0..a.n {
            for k in a.col_ptr[j]..a.col_ptr[j + 1] {
                if !drop(a.row_idx[k], j) {
                    m.row_idx.push(a.row_idx[k]);
                    m.values.push(a.values[k]);
                }
            }
            m.col_ptr.push(m.row_idx.len());
        }
        m
    };
    let last = a.n - 1;
    let empty_row = without(&|i, j| (i == last || j == last) && i != j);
    assert!(
        structure(KktSolver::new(&empty_row, &with(Some(30)))),
        "empty constraint row"
    );
    let unsym = without(&|i, j| (i, j) == (30, 0));
    assert!(
        structure(KktSolver::new(&unsym, &with(Some(30)))),
        "unsymmetric structure"
    );
    // The LU backends ignore n_primal, except for its bound.
    let lu = KktOptions {
        backend: Backend::SPARSE_LU,
        ..with(Some(30))
    };
    assert!(KktSolver::new(&unsym, &lu).is_ok());
    assert!(structure(KktSolver::new(
        &a,
        &KktOptions {
            n_primal: Some(a.n + 1),
            ..lu
        }
    )));
}

#[test]
fn ldlt_solves_a_system_without_constraints() {
    // n_primal = n: an SPD matrix.
    let a = chain(20, 2, None);
    let np = 60;
    let mut s = Csc {
        n: np,
        col_ptr: vec![0],
        ..Csc::default()
    };
    for j in 0..np {
        for k in a.col_ptr[j]..a.col_ptr[j + 1] {
            if a.row_idx[k] < np {
                s.row_idx.push(a.row_idx[k]);
                s.values.push(a.values[k]);
            }
        }
        s.col_ptr.push(s.row_idx.len());
    }
    let b = vector(np, 9);
    let opts = KktOptions {
        backend: Backend::SPARSE_LDLT,
        n_primal: Some(np),
        ..KktOptions::default()
    };
    let mut solver = KktSolver::new(&s, &opts).expect("SPD structure");
    solver.factor(&s.values).expect("SPD");
    let mut x = b.clone();
    solver.solve_in_place(&mut x).expect("accurate");
    assert!(relative_residual(&s, &x, &b) <= 1e-13);
}

#[test]
fn empty_system() {
    let a = Csc {
        n: 0,
        col_ptr: vec![0],
        ..Csc::default()
    };
    for backend in [
        Backend::SPARSE_LDLT,
        Backend::SPARSE_LU,
        Backend::DENSE,
        Backend::SCHUR,
    ] {
        let opts = KktOptions {
            backend,
            n_primal: Some(0),
            ..KktOptions::default()
        };
        let mut s = KktSolver::new(&a, &opts).expect("empty structure");
        s.factor(&[]).expect("nothing to factor");
        s.solve_in_place(&mut []).expect("nothing to solve");
    }
}

#[test]
fn regularized_ldlt_solves_regular_chains_and_rejects_redundant_ones() {
    let regularized = |n_bodies: usize| KktOptions {
        ldlt_regularization: Some(1e-10),
        ..options(Backend::SPARSE_LDLT, n_bodies)
    };
    let solve_reg = |n_bodies: usize, a: &Csc, b: &[f64]| {
        let mut s = KktSolver::new(a, &regularized(n_bodies))?;
        s.factor(&a.values)?;
        let mut x = b.to_vec();
        s.solve_in_place(&mut x).map(|()| x)
    };
    for n_bodies in [1, 10, 1000] {
        let a = chain(n_bodies, 7, None);
        let mut b = vec![0.0; a.n];
        a.mul(&vector(a.n, 3), &mut b);
        let plain = solve(Backend::SPARSE_LDLT, n_bodies, &a, &b).expect("regular chain");
        let reg = solve_reg(n_bodies, &a, &b).expect("regular chain");
        let diff = relative_difference(&plain, &reg);
        assert!(diff <= 1e-12, "N = {n_bodies}: {diff:e}");
    }
    // A redundant constraint with an inconsistent right-hand side: the
    // regularized pivot hides the zero one, and the answer is either an error
    // or multipliers of order 1/δ that pass the backward-error checks (why
    // regularization is off by default: unregularized, this is an error
    // naming the multiplier, see above).
    let (a, b) = redundant(10, 7, 1.0 / 3.0, false);
    match solve_reg(10, &a, &b) {
        Err(KktError::Singular { .. } | KktError::Inaccurate { .. }) => {}
        Ok(x) => {
            let largest = crate::max_abs(&x[30..]);
            assert!(largest > 1e6, "multipliers up to {largest:e}");
        }
        Err(e) => panic!("{e:?}"),
    }
    let bad = KktOptions {
        ldlt_regularization: Some(0.0),
        ..options(Backend::SPARSE_LDLT, 10)
    };
    assert!(matches!(
        KktSolver::new(&chain(10, 1, None), &bad),
        Err(KktError::Structure(_))
    ));
}

#[test]
fn schur_matches_ldlt_and_lu_on_chains() {
    for n_bodies in [1, 10, 1000] {
        let a = chain_with(n_bodies, 7, None, false);
        let mut b = vec![0.0; a.n];
        a.mul(&vector(a.n, 3), &mut b);
        let schur = solve(Backend::SCHUR, n_bodies, &a, &b).expect("Schur solves a regular chain");
        let ldlt = solve(Backend::SPARSE_LDLT, n_bodies, &a, &b).expect("LDLᵀ");
        let lu = solve(Backend::SPARSE_LU, n_bodies, &a, &b).expect("LU");
        let r = relative_residual(&a, &schur, &b);
        let (d_ldlt, d_lu) = (
            relative_difference(&schur, &ldlt),
            relative_difference(&schur, &lu),
        );
        eprintln!("N = {n_bodies}: Schur residual {r:.1e}; vs LDLᵀ {d_ldlt:.1e}, vs LU {d_lu:.1e}");
        assert!(r <= 1e-12, "N = {n_bodies}: {r:e}");
        assert!(d_ldlt <= 1e-10 && d_lu <= 1e-10, "N = {n_bodies}");
    }
}

#[test]
fn schur_names_a_redundant_constraint_or_a_singular_block() {
    for (n_bodies, r) in [(1, 0), (10, 7), (1000, 1999)] {
        for consistent in [true, false] {
            let a = chain_with(n_bodies, 11, Some((r, 1.0 / 3.0)), false);
            let mut b = vector(a.n, 5);
            if consistent {
                a.mul(&vector(a.n, 5), &mut b);
            }
            let result = solve(Backend::SCHUR, n_bodies, &a, &b);
            let pair = [3 * n_bodies + r, a.n - 1];
            assert!(
                matches!(result, Err(KktError::Singular { unknown: Some(k) }) if pair.contains(&k)),
                "N = {n_bodies}, row {r}: {result:?}"
            );
        }
    }
    // A body without mass: its block of S is zero.
    let mut a = chain_with(10, 3, None, false);
    let body = 4;
    for j in 3 * body..3 * body + 3 {
        for k in a.col_ptr[j]..a.col_ptr[j + 1] {
            if a.row_idx[k] == j {
                a.values[k] = 0.0;
            }
        }
    }
    let result = solve(Backend::SCHUR, 10, &a, &vector(a.n, 1));
    assert!(
        matches!(result, Err(KktError::Singular { unknown: Some(k) }) if (12..15).contains(&k)),
        "{result:?}"
    );
}

/// `a` with its multipliers (unknowns from `np` on) in the reversed-halves
/// order `m/2 .. m, 0 .. m/2` interleaved: far from the chain's band.
fn scrambled_multipliers(a: &Csc, np: usize) -> Csc {
    let m = a.n - np;
    let order: Vec<usize> = (0..m)
        .map(|k| if k % 2 == 0 { k / 2 } else { m - 1 - k / 2 })
        .collect();
    let mut new_of = (0..a.n).collect::<Vec<_>>();
    for (k, &old) in order.iter().enumerate() {
        new_of[np + old] = np + k;
    }
    let mut cols: Vec<Vec<(usize, f64)>> = vec![Vec::new(); a.n];
    for j in 0..a.n {
        for k in a.col_ptr[j]..a.col_ptr[j + 1] {
            cols[new_of[j]].push((new_of[a.row_idx[k]], a.values[k]));
        }
    }
    let mut out = Csc {
        n: a.n,
        col_ptr: vec![0],
        ..Csc::default()
    };
    for col in &mut cols {
        col.sort_by_key(|&(i, _)| i);
        for &(i, v) in col.iter() {
            out.row_idx.push(i);
            out.values.push(v);
        }
        out.col_ptr.push(out.row_idx.len());
    }
    out
}

#[test]
fn schur_solves_constraints_in_any_order() {
    // Scrambled, the constraints' own order has a wide envelope: C is
    // factored by its envelope in the reverse Cuthill–McKee order, which
    // brings a chain's rows back together.
    for n_bodies in [10, 1000] {
        let a = scrambled_multipliers(&chain_with(n_bodies, 5, None, false), 3 * n_bodies);
        let mut b = vec![0.0; a.n];
        a.mul(&vector(a.n, 2), &mut b);
        let schur = solve(Backend::SCHUR, n_bodies, &a, &b).expect("regular chain");
        let lu = solve(Backend::SPARSE_LU, n_bodies, &a, &b).expect("regular chain");
        assert!(relative_difference(&schur, &lu) <= 1e-10, "N = {n_bodies}");
        // (envelope, own order, the one-pass factorization)
        let envelope = |a: &Csc| {
            let s = Schur::new(a, 3 * n_bodies).expect("structure");
            (s.uses_envelope(), s.natural_order(), s.is_banded())
        };
        assert_eq!(
            envelope(&a),
            (true, false, true),
            "N = {n_bodies}: scrambled, RCM"
        );
        assert_eq!(
            envelope(&chain_with(n_bodies, 5, None, false)),
            (true, true, true),
            "in order, envelope"
        );
        assert!(relative_residual(&a, &schur, &b) <= 1e-12, "N = {n_bodies}");
    }
}

/// The KKT matrix (both triangles) of `k × k` planar bodies on a grid, each
/// joined to its right and upper neighbour by one random row (a distance,
/// say; 2k(k − 1) rows on 3k² coordinates, of full rank): `C`'s graph
/// is a grid, whose envelope in any order holds about `k` times the values
/// of its factor after AMD.
fn grid(k: usize, seed: u64) -> Csc {
    let mut rng = crate::testing::Lcg::new(seed);
    let (n_bodies, body) = (k * k, |i: usize, j: usize| 3 * (i * k + j));
    let mut rows: Vec<Vec<(usize, f64)>> = Vec::new();
    for i in 0..k {
        for j in 0..k {
            for (di, dj) in [(0, 1), (1, 0)] {
                if i + di < k && j + dj < k {
                    let (p, q) = (body(i, j), body(i + di, j + dj));
                    let mut row: Vec<(usize, f64)> =
                        (0..3).map(|c| (p + c, rng.range(-1.0, 1.0))).collect();
                    row.extend((0..3).map(|c| (q + c, rng.range(-1.0, 1.0))));
                    rows.push(row);
                }
            }
        }
    }
    let np = 3 * n_bodies;
    let mut pairs = Vec::new();
    for i in 0..np {
        pairs.push((i, i, rng.range(0.5, 2.0)));
    }
    for (r, row) in rows.iter().enumerate() {
        pairs.push((np + r, np + r, 0.0));
        for &(p, v) in row {
            pairs.extend([(p, np + r, v), (np + r, p, v)]);
        }
    }
    crate::testing::csc_of_entries(np + rows.len(), pairs)
}

#[test]
fn schur_lu_refuses_a_grid_and_its_advice_works() {
    // schur-lu has no AMD fallback: a grid's C is refused with advice to
    // use lu, which solves it.
    let k = 20;
    let np = 3 * k * k;
    let a = grid(k, 3);
    // schur-lu reads the matrix without the Bᵀ block.
    let entries = (0..a.n)
        .flat_map(|j| (a.col_ptr[j]..a.col_ptr[j + 1]).map(move |p| (p, j)))
        .filter(|&(p, j)| !(a.row_idx[p] < np && j >= np))
        .map(|(p, j)| (a.row_idx[p], j, a.values[p]))
        .collect();
    let without_bt = crate::testing::csc_of_entries(a.n, entries);
    match KktSolver::new(&without_bt, &options(Backend::SCHUR_LU, k * k)) {
        Err(KktError::Structure(why)) => assert!(why.contains("(use lu)"), "{why}"),
        other => panic!("schur-lu should refuse the grid: {other:?}"),
    }
    let mut b = vec![0.0; a.n];
    a.mul(&vector(a.n, 4), &mut b);
    let lu = solve(Backend::SPARSE_LU, k * k, &a, &b).expect("lu solves the grid");
    assert!(relative_residual(&a, &lu, &b) <= 1e-12);
}

#[test]
fn schur_factors_a_grid_after_amd() {
    // No order gives a grid's C a narrow envelope: faer's sparse LDLᵀ
    // after AMD, against sparse LU.
    let k = 20;
    let a = grid(k, 3);
    let mut b = vec![0.0; a.n];
    a.mul(&vector(a.n, 4), &mut b);
    assert!(
        !Schur::new(&a, 3 * k * k)
            .expect("structure")
            .uses_envelope()
    );
    let schur = solve(Backend::SCHUR, k * k, &a, &b).expect("regular grid");
    let lu = solve(Backend::SPARSE_LU, k * k, &a, &b).expect("regular grid");
    assert!(relative_difference(&schur, &lu) <= 1e-10);
    assert!(relative_residual(&a, &schur, &b) <= 1e-12);
}

#[test]
fn schur_rejects_non_finite_values_anywhere_it_reads() {
    let a = chain_with(10, 3, None, false);
    for k in [0, a.col_ptr[5] + 1, a.nnz() - 1] {
        let mut bad = a.clone();
        bad.values[k] = f64::NAN;
        let mut s = KktSolver::new(&a, &options(Backend::SCHUR, 10)).expect("structure");
        assert_eq!(s.factor(&bad.values), Err(KktError::NonFinite), "entry {k}");
        s.factor(&a.values).expect("recovers");
    }
}

#[test]
fn schur_needs_a_block_diagonal_primal_block() {
    let a = chain(10, 1, None);
    let result = KktSolver::new(&a, &options(Backend::SCHUR, 10));
    assert!(matches!(result, Err(KktError::Structure(_))), "{result:?}");
    let missing = KktOptions {
        backend: Backend::SCHUR,
        ..KktOptions::default()
    };
    assert!(matches!(
        KktSolver::new(&chain_with(10, 1, None, false), &missing),
        Err(KktError::Structure(_))
    ));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    #[test]
    fn ldlt_matches_dense_lu_on_random_chains(n_bodies in 1usize..12, seed in any::<u64>(), rhs_seed in any::<u64>()) {
        let a = chain(n_bodies, seed, None);
        let b = vector(a.n, rhs_seed);
        let ldlt = solve(Backend::SPARSE_LDLT, n_bodies, &a, &b).expect("regular chain");
        let dense = solve(Backend::DENSE, n_bodies, &a, &b).expect("regular chain");
        prop_assert!(relative_difference(&ldlt, &dense) <= 1e-10);
        prop_assert!(relative_residual(&a, &ldlt, &b) <= 1e-12);
    }

    #[test]
    fn schur_matches_dense_lu_on_random_chains(n_bodies in 1usize..12, seed in any::<u64>(), rhs_seed in any::<u64>()) {
        let a = chain_with(n_bodies, seed, None, false);
        let b = vector(a.n, rhs_seed);
        let schur = solve(Backend::SCHUR, n_bodies, &a, &b).expect("regular chain");
        let dense = solve(Backend::DENSE, n_bodies, &a, &b).expect("regular chain");
        prop_assert!(relative_difference(&schur, &dense) <= 1e-10);
        prop_assert!(relative_residual(&a, &schur, &b) <= 1e-12);
    }
}

/// `a` with the multiplier block's diagonal set to `d` (C = B S⁻¹ Bᵀ − D
/// stays positive definite for d ≤ 0).
fn with_multiplier_diagonal(a: &Csc, np: usize, d: f64) -> Csc {
    let mut a = a.clone();
    for j in np..a.n {
        for k in a.col_ptr[j]..a.col_ptr[j + 1] {
            if a.row_idx[k] == j {
                a.values[k] = d;
            }
        }
    }
    a
}

#[test]
fn the_residual_check_inside_the_schur_solve_is_the_residual() {
    // A chain in order, and scrambled (C in the reverse Cuthill–McKee order).
    let cases = [(1, 0.0), (10, 0.0), (1000, 0.0), (10, -0.3), (1000, -0.3)];
    for ((n_bodies, d), scrambled) in cases.into_iter().flat_map(|c| [(c, false), (c, true)]) {
        let np = 3 * n_bodies;
        let a = with_multiplier_diagonal(&chain_with(n_bodies, 8, None, false), np, d);
        let a = if scrambled {
            scrambled_multipliers(&a, np)
        } else {
            a
        };
        let b = vector(a.n, 5);
        let mut schur = Schur::new(&a, np).expect("structure");
        let a_norm = schur.factor(&a.values).expect("regular");
        assert!(
            schur.is_banded() && schur.checks_in_solve(),
            "N = {n_bodies}, scrambled: {scrambled}"
        );
        let mut x = b.clone();
        let (x_norm, fused) = schur.solve_checked(&mut x);
        let mut ax = vec![0.0; a.n];
        a.mul(&x, &mut ax);
        let explicit = ax
            .iter()
            .zip(&b)
            .fold(0.0f64, |m, (p, q)| m.max((p - q).abs()));
        let scale = a_norm * x_norm + b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        // Both are rounding-level residuals of the same solution; they may
        // differ only by rounding in how they are summed.
        assert!(fused <= 1e-14 * scale, "N = {n_bodies}, d = {d}: {fused:e}");
        assert!(
            (fused - explicit).abs() <= 1e-14 * scale,
            "N = {n_bodies}, d = {d}: {fused:e} vs {explicit:e}"
        );
        // The one-pass factorization's ‖A‖∞ is the largest absolute row sum.
        let mut row_sums = vec![0.0f64; a.n];
        for j in 0..a.n {
            for k in a.col_ptr[j]..a.col_ptr[j + 1] {
                row_sums[a.row_idx[k]] += a.values[k].abs();
            }
        }
        let norm = row_sums.iter().fold(0.0f64, |m, &v| m.max(v));
        assert!(
            (a_norm - norm).abs() <= 1e-14 * norm,
            "{} vs {norm}",
            a_norm
        );
    }
}

/// The Schur backend with its factorizations spoiled afterwards while
/// `spoiled` is set, with its residual formed in the solve (`fused`) or
/// left to the caller's product.
struct Spoilable {
    schur: Schur,
    spoiled: Arc<AtomicBool>,
    fused: bool,
}

impl Spoilable {
    fn new(a: &Csc, n_primal: usize, spoiled: bool, fused: bool) -> Self {
        Self {
            schur: Schur::new(a, n_primal).expect("structure"),
            spoiled: Arc::new(AtomicBool::new(spoiled)),
            fused,
        }
    }
}

impl KktBackend for Spoilable {
    fn factor(&mut self, values: &[f64]) -> Result<f64, KktError> {
        let norm = self.schur.factor(values)?;
        if self.spoiled.load(Ordering::Relaxed) {
            self.schur.spoil(7, 1.5);
        }
        Ok(norm)
    }
    fn solve_in_place(&mut self, rhs: &mut [f64]) -> f64 {
        self.schur.solve_in_place(rhs)
    }
    fn mul(&self, x: &[f64], y: &mut [f64]) {
        self.schur.mul(x, y);
    }
    fn solve_with_residual(&mut self, rhs: &mut [f64]) -> Option<(f64, f64)> {
        if self.fused {
            self.schur.solve_with_residual(rhs)
        } else {
            None
        }
    }
}

#[test]
fn a_spoiled_factorization_fails_the_check_inside_the_schur_solve() {
    let n_bodies = 50;
    let a = chain_with(n_bodies, 4, None, false);
    let b = vector(a.n, 6);
    let schur = Spoilable::new(&a, 3 * n_bodies, true, true);
    let opts = options(Backend::SCHUR, n_bodies);
    let mut s = KktSolver::with_backend(Box::new(schur), Backend::SCHUR, a.n, &opts);
    s.factor(&a.values).expect("regular");
    let mut x = b.clone();
    let result = s.solve_in_place(&mut x);
    assert!(
        matches!(result, Err(KktError::Inaccurate { relative_residual }) if relative_residual > 1e-6),
        "{result:?}"
    );
    // Unspoiled, the same solver passes.
    let schur = Spoilable::new(&a, 3 * n_bodies, false, true);
    let mut s = KktSolver::with_backend(Box::new(schur), Backend::SCHUR, a.n, &opts);
    s.factor(&a.values).expect("regular");
    let mut x = b.clone();
    s.solve_in_place(&mut x).expect("accurate");
    assert!(relative_residual(&a, &x, &b) <= 1e-12);
}

/// Newton's corrections leave the residual check of a backend without a
/// fused residual to [`KktSolver::verify`], once the first factorization
/// they meet has passed it on the spot: a spoiled first factorization
/// fails at once; a later spoiled one passes `solve_unverified_correction`
/// (its solution is wrong) and `verify` finds it; a sound one verifies.
#[test]
fn newton_corrections_leave_the_check_to_verify() {
    let n_bodies = 50;
    let a = chain_with(n_bodies, 4, None, false);
    let b = vector(a.n, 6);
    let opts = options(Backend::SCHUR, n_bodies);
    let solver = |spoiled: &Arc<AtomicBool>| {
        let schur = Spoilable {
            schur: Schur::new(&a, 3 * n_bodies).expect("structure"),
            spoiled: spoiled.clone(),
            fused: false,
        };
        KktSolver::with_backend(Box::new(schur), Backend::SCHUR, a.n, &opts)
    };
    let inaccurate = |r: &Result<(), KktError>| matches!(r, Err(KktError::Inaccurate { relative_residual }) if *relative_residual > 1e-6);
    // A spoiled first factorization fails on the spot.
    let spoiled = Arc::new(AtomicBool::new(true));
    let mut s = solver(&spoiled);
    s.factor(&a.values).expect("regular");
    let mut x = b.clone();
    let first = s.solve_unverified_correction(&mut x, max_abs(&b));
    assert!(inaccurate(&first), "{first:?}");
    // A sound first factorization passes; a later spoiled one is left to
    // `verify`, which finds it; a sound one verifies.
    let spoiled = Arc::new(AtomicBool::new(false));
    let mut s = solver(&spoiled);
    for spoil in [false, true, false] {
        spoiled.store(spoil, Ordering::Relaxed);
        s.factor(&a.values).expect("regular");
        let mut x = b.clone();
        s.solve_unverified_correction(&mut x, max_abs(&b))
            .expect("not checked on the spot after the first factorization");
        let residual = relative_residual(&a, &x, &b);
        let mut probe = b.clone();
        let verified = s.verify(&mut probe);
        if spoil {
            assert!(residual > 1e-6, "a spoiled solution: {residual:e}");
            assert!(inaccurate(&verified), "{verified:?}");
        } else {
            assert!(residual <= 1e-12, "{residual:e}");
            verified.expect("a sound factorization verifies");
        }
    }
}
