//! Sparse LDLᵀ (faer) of a quasi-definite KKT matrix `[[S, Bᵀ], [B, 0]]`
//! without pivoting, in an ordering that keeps every pivot away from zero when
//! `S` is positive definite and `B` has full row rank.
//!
//! # Ordering
//!
//! AMD orders the primal unknowns on the pattern of `S + BᵀB` (the primal block
//! with the fill that eliminating the multipliers creates); then every
//! multiplier is placed right after the last primal unknown (in that order)
//! that its constraint row touches. Every leading principal block of the
//! permuted matrix is then itself a KKT matrix `[[S₁₁, B₁ᵀ], [B₁, 0]]` whose
//! constraints only touch the primal unknowns already eliminated, so it is
//! nonsingular whenever `S` is positive definite and the constraints are
//! independent: LDLᵀ exists without pivoting. AMD on the whole KKT pattern
//! gives no such guarantee (it happily eliminates a multiplier first, on its
//! zero diagonal).
//!
//! # Pivot check
//!
//! faer only rejects pivots that are exactly zero. After each factorization,
//! every pivot `d_k = a_kk − Σ_j l_kj² d_j` is compared with the size of the
//! terms it was computed from, `|a_kk| + Σ_j l_kj² |d_j|`; a pivot at the level
//! of the rounding errors of that sum means unknown `k` is numerically
//! dependent on the ones eliminated before it (typically a redundant
//! constraint), and is reported as singular. This also catches singular
//! systems with a consistent right-hand side, whose residual is small.

use std::sync::Arc;

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::ldlt::factor::{LdltError, LdltRegularization};
use faer::perm::PermRef;
use faer::sparse::linalg::amd;
use faer::sparse::linalg::cholesky::supernodal::SupernodalLdltRef;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LdltRef, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};

use crate::backend::{Backend, KktBackend, Registration, Structure};
use crate::stored::Stored;
use crate::{Csc, KktError, KktOptions, max_abs};

/// The `ldlt` backend.
pub(crate) const REGISTRATION: Registration = Registration {
    backend: Backend::SPARSE_LDLT,
    summary: "faer's sparse LDLᵀ without pivoting in a KKT ordering (S positive definite)",
    structure: Structure::AUGMENTED,
    symmetric: true,
    analyse: |a, options| Ok(Box::new(LdltBackend::new(a, options)?)),
    automatic: Some(30),
    needs_n_primal: true,
};

/// The `ldlt` backend: [`SparseLdlt`] of the whole KKT matrix, with a copy of
/// it for the solver's checks.
#[derive(Clone)]
struct LdltBackend {
    stored: Stored,
    ldlt: SparseLdlt,
}

impl LdltBackend {
    fn new(a: &Csc, options: &KktOptions) -> Result<Self, KktError> {
        let np = options.require_n_primal(Backend::SPARSE_LDLT)?;
        let mut ldlt = SparseLdlt::new(a, np)?;
        if let Some(delta) = options.ldlt_regularization {
            if !(delta > 0.0 && delta < 1.0) {
                return Err(KktError::Structure(format!(
                    "the LDLᵀ regularization δ must be in (0, 1), got {delta}"
                )));
            }
            ldlt.set_regularization(np, delta);
        }
        Ok(Self {
            stored: Stored::new(a),
            ldlt,
        })
    }
}

impl KktBackend for LdltBackend {
    fn factor(&mut self, values: &[f64]) -> Result<f64, KktError> {
        let norm = self.stored.load(values)?;
        self.ldlt.factor(self.stored.matrix())?;
        Ok(norm)
    }

    fn solve_in_place(&mut self, rhs: &mut [f64]) -> f64 {
        self.ldlt.solve_in_place(rhs);
        max_abs(rhs)
    }

    fn mul(&self, x: &[f64], y: &mut [f64]) {
        self.stored.mul(x, y);
    }

    fn is_regularized(&self) -> bool {
        self.ldlt.is_regularized()
    }

    fn fork(&self) -> Option<Box<dyn KktBackend>> {
        Some(Box::new(self.clone()))
    }
}

/// A pivot whose magnitude is at most this times the magnitude of the terms it
/// was computed from is taken for zero (≈ 2.2e-12; measured on chains of up to
/// 10⁵ bodies: a repeated constraint leaves a pivot that is exactly zero or
/// below 1e-16 of that scale, regular pivots are above 0.1 of it).
pub(crate) const PIVOT_TOLERANCE: f64 = 1e4 * f64::EPSILON;

/// Symbolic LDLᵀ analysis and reused numeric buffers.
pub(crate) struct SparseLdlt {
    /// Shared by the copies (`Clone`): the analysis does not change.
    symbolic: Arc<SymbolicCholesky<usize>>,
    /// Values of the factor `L` (unit diagonal replaced by `D`).
    l_values: Vec<f64>,
    /// `fwd[k]` = original unknown eliminated `k`-th.
    fwd: Vec<usize>,
    /// Position of the diagonal entry of each original column in the values of
    /// the matrix, `usize::MAX` if not stored.
    diag_pos: Vec<usize>,
    /// `Σ_j l_kj² |d_j|` per (permuted) unknown, for the pivot check.
    scale: Vec<f64>,
    mem: MemBuffer,
    /// The triangle faer reads (the matrix stores both).
    side: Side,
    /// Signed dynamic regularization: the expected pivot signs (original
    /// order: `+1` primal, `−1` multiplier) and `δ` relative to `max |a_ij|`.
    regularization: Option<(Vec<i8>, f64)>,
}

impl Clone for SparseLdlt {
    /// The same analysis (shared) with copies of the numeric buffers and new
    /// scratch (faer's `MemBuffer` is not `Clone`; like a `Vec`'s copy it
    /// aborts when memory runs out).
    fn clone(&self) -> Self {
        let req = StackReq::any_of(&[
            self.symbolic
                .factorize_numeric_ldlt_scratch::<f64>(Par::Seq, Default::default()),
            self.symbolic.solve_in_place_scratch::<f64>(1, Par::Seq),
        ]);
        Self {
            symbolic: Arc::clone(&self.symbolic),
            l_values: self.l_values.clone(),
            fwd: self.fwd.clone(),
            diag_pos: self.diag_pos.clone(),
            scale: self.scale.clone(),
            mem: MemBuffer::new(req),
            side: self.side,
            regularization: self.regularization.clone(),
        }
    }
}

impl SparseLdlt {
    /// Orders and analyses `a`, whose first `n_primal` unknowns are primal.
    pub(crate) fn new(a: &Csc, n_primal: usize) -> Result<Self, KktError> {
        Self::with_params(a, n_primal, CholeskySymbolicParams::default())
    }

    pub(crate) fn with_params(
        a: &Csc,
        n_primal: usize,
        params: CholeskySymbolicParams<'_>,
    ) -> Result<Self, KktError> {
        let n = a.n;
        check_symmetric_structure(a)?;
        let (fwd, inv) = kkt_ordering(a, n_primal, params.amd_params)?;
        let sym = SymbolicSparseColMatRef::new_checked(n, n, &a.col_ptr, None, &a.row_idx);
        let perm = PermRef::new_checked(&fwd, &inv, n);
        let symbolic =
            factorize_symbolic_cholesky(sym, Side::Lower, SymmetricOrdering::Custom(perm), params)
                .map_err(faer_error)?;
        Self::with_symbolic(a, symbolic, fwd, Side::Lower)
    }

    /// The buffers around a symbolic factorization of `a` in the order `fwd`,
    /// factoring the triangle `side`.
    fn with_symbolic(
        a: &Csc,
        symbolic: SymbolicCholesky<usize>,
        fwd: Vec<usize>,
        side: Side,
    ) -> Result<Self, KktError> {
        let n = a.n;
        let req = StackReq::any_of(&[
            symbolic.factorize_numeric_ldlt_scratch::<f64>(Par::Seq, Default::default()),
            symbolic.solve_in_place_scratch::<f64>(1, Par::Seq),
        ]);
        let mem = MemBuffer::try_new(req).map_err(|_| KktError::OutOfMemory)?;
        let diag_pos = (0..n)
            .map(|j| {
                let col = &a.row_idx[a.col_ptr[j]..a.col_ptr[j + 1]];
                col.binary_search(&j)
                    .map_or(usize::MAX, |k| a.col_ptr[j] + k)
            })
            .collect();
        Ok(Self {
            l_values: vec![0.0; symbolic.len_val()],
            symbolic: Arc::new(symbolic),
            fwd,
            diag_pos,
            scale: vec![0.0; n],
            mem,
            side,
            regularization: None,
        })
    }

    /// Analyses `a`, stored with both triangles and already in elimination
    /// order (no permutation: faer then factors the values in place, without
    /// the permuted copy of [`new`](Self::new)).
    pub(crate) fn preordered(a: &Csc) -> Result<Self, KktError> {
        check_symmetric_structure(a)?;
        Self::preordered_side(a, Side::Upper)
    }

    /// As [`preordered`](Self::preordered) for a matrix that stores only its
    /// upper (`upper`) or lower triangle; `None` when faer's choice of kernel
    /// reads the other one (then store both).
    pub(crate) fn preordered_triangle(a: &Csc, upper: bool) -> Result<Option<Self>, KktError> {
        let side = if upper { Side::Upper } else { Side::Lower };
        let this = Self::preordered_side(a, side)?;
        Ok((this.side == side).then_some(this))
    }

    fn preordered_side(a: &Csc, stored: Side) -> Result<Self, KktError> {
        let n = a.n;
        let sym = SymbolicSparseColMatRef::new_checked(n, n, &a.col_ptr, None, &a.row_idx);
        let symbolic = factorize_symbolic_cholesky(
            sym,
            stored,
            SymmetricOrdering::Identity,
            CholeskySymbolicParams::default(),
        )
        .map_err(faer_error)?;
        // faer's simplicial kernel reads the upper triangle, its supernodal
        // one the lower: give it the one it reads, so it copies nothing.
        let side = match symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(_) => Side::Upper,
            SymbolicCholeskyRaw::Supernodal(_) => Side::Lower,
        };
        Self::with_symbolic(a, symbolic, (0..n).collect(), side)
    }

    /// Number of stored values of the factor.
    pub(crate) fn factor_len(&self) -> usize {
        self.l_values.len()
    }

    /// Whether factorizations read only the upper triangle (else the lower).
    pub(crate) fn reads_upper(&self) -> bool {
        self.side == Side::Upper
    }

    /// Whether faer chose its supernodal (blocked) factorization.
    #[cfg(test)]
    pub(crate) fn is_supernodal(&self) -> bool {
        matches!(self.symbolic.raw(), SymbolicCholeskyRaw::Supernodal(_))
    }

    /// The elimination order: `order()[k]` is the unknown eliminated `k`-th.
    #[cfg(test)]
    pub(crate) fn order(&self) -> &[usize] {
        &self.fwd
    }

    /// Whether [`set_regularization`](Self::set_regularization) was called.
    pub(crate) fn is_regularized(&self) -> bool {
        self.regularization.is_some()
    }

    /// Turns on signed dynamic regularization: a pivot of the wrong sign or of
    /// magnitude at most `delta · max |a_ij|` becomes `±delta · max |a_ij|`
    /// (`+` for the first `n_primal` unknowns, `−` for the multipliers). The
    /// pivot check is then off; the caller refines the solutions.
    pub(crate) fn set_regularization(&mut self, n_primal: usize, delta: f64) {
        let n = self.diag_pos.len();
        let signs = (0..n).map(|i| if i < n_primal { 1 } else { -1 }).collect();
        self.regularization = Some((signs, delta));
    }

    pub(crate) fn factor(&mut self, a: &Csc) -> Result<(), KktError> {
        let sym = SymbolicSparseColMatRef::new_checked(a.n, a.n, &a.col_ptr, None, &a.row_idx);
        let mat = SparseColMatRef::new(sym, &a.values);
        let stack = MemStack::new(&mut self.mem);
        // By default no regularization: with this ordering the pivots of a
        // regular quasi-definite matrix are bounded away from zero, and a
        // perturbed pivot would only hide a singular matrix from the check
        // below.
        let regularization = match &self.regularization {
            Some((signs, delta)) => {
                let size = max_abs(&a.values);
                LdltRegularization {
                    dynamic_regularization_signs: Some(signs),
                    dynamic_regularization_delta: delta * size,
                    dynamic_regularization_epsilon: delta * size,
                }
            }
            None => LdltRegularization::default(),
        };
        let result = self.symbolic.factorize_numeric_ldlt(
            &mut self.l_values,
            mat,
            self.side,
            regularization,
            Par::Seq,
            stack,
            Default::default(),
        );
        match result {
            // Regularized: no pivot is zero, the caller's refinement and
            // residual check judge the solution.
            Ok(_) if self.regularization.is_some() => return Ok(()),
            Ok(_) => {}
            Err(LdltError::ZeroPivot { index }) => {
                // faer's simplicial kernel reports the pivot 1-based, its dense
                // (supernodal) kernel 0-based.
                let k = match self.symbolic.raw() {
                    SymbolicCholeskyRaw::Simplicial(_) => index.checked_sub(1),
                    SymbolicCholeskyRaw::Supernodal(_) => Some(index),
                };
                return Err(KktError::Singular {
                    unknown: k.and_then(|k| self.fwd.get(k).copied()),
                });
            }
        }
        self.check_pivots(a)
    }

    /// Rejects pivots at the rounding level of the sums they come from (see
    /// the module documentation).
    fn check_pivots(&mut self, a: &Csc) -> Result<(), KktError> {
        let scale = &mut self.scale;
        scale.fill(0.0);
        let fwd = &self.fwd;
        let diag_pos = &self.diag_pos;
        let is_zero = |k: usize, d: f64, s: f64| -> bool {
            let p = diag_pos[fwd[k]];
            let akk = if p == usize::MAX {
                0.0
            } else {
                a.values[p].abs()
            };
            d.is_nan() || d.abs() <= PIVOT_TOLERANCE * (akk + s)
        };
        match self.symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => {
                let (col_ptr, row_idx) = (s.col_ptr(), s.row_idx());
                for k in 0..a.n {
                    let (start, end) = (col_ptr[k], col_ptr[k + 1]);
                    let d = self.l_values[start];
                    if is_zero(k, d, scale[k]) {
                        return Err(KktError::Singular {
                            unknown: Some(fwd[k]),
                        });
                    }
                    let d = d.abs();
                    for p in start + 1..end {
                        let l = self.l_values[p];
                        scale[row_idx[p]] += l * l * d;
                    }
                }
            }
            SymbolicCholeskyRaw::Supernodal(s) => {
                let ldlt = SupernodalLdltRef::new(s, &self.l_values);
                for sn in 0..s.n_supernodes() {
                    let node = ldlt.supernode(sn);
                    let (start, pattern, val) = (node.start(), node.pattern(), node.val());
                    let ncols = val.ncols();
                    for j in 0..ncols {
                        let k = start + j;
                        let d = val[(j, j)];
                        if is_zero(k, d, scale[k]) {
                            return Err(KktError::Singular {
                                unknown: Some(fwd[k]),
                            });
                        }
                        let d = d.abs();
                        for i in j + 1..ncols {
                            let l = val[(i, j)];
                            scale[start + i] += l * l * d;
                        }
                        for (r, &row) in pattern.iter().enumerate() {
                            let l = val[(ncols + r, j)];
                            scale[row] += l * l * d;
                        }
                    }
                }
            }
        }
        Ok(())
    }

    pub(crate) fn solve_in_place(&mut self, rhs: &mut [f64]) {
        let n = rhs.len();
        let ldlt = LdltRef::new(&self.symbolic, &self.l_values);
        let stack = MemStack::new(&mut self.mem);
        let x = MatMut::from_column_major_slice_mut(rhs, n, 1);
        ldlt.solve_in_place_with_conj(Conj::No, x, Par::Seq, stack);
    }
}

/// A faer error as ours.
fn faer_error(e: faer::sparse::FaerError) -> KktError {
    match e {
        faer::sparse::FaerError::OutOfMemory => KktError::OutOfMemory,
        e => KktError::Backend(format!("{e:?}")),
    }
}

/// Whether `a`'s pattern is structurally symmetric (what
/// [`check_symmetric_structure`] checks, without its message).
pub(crate) fn is_symmetric_structure(a: &Csc) -> bool {
    check_symmetric_structure(a).is_ok()
}

/// Checks that entry `(i, j)` is stored whenever `(j, i)` is.
fn check_symmetric_structure(a: &Csc) -> Result<(), KktError> {
    for j in 0..a.n {
        for &i in &a.row_idx[a.col_ptr[j]..a.col_ptr[j + 1]] {
            if a.row_idx[a.col_ptr[i]..a.col_ptr[i + 1]]
                .binary_search(&j)
                .is_err()
            {
                return Err(KktError::Structure(format!(
                    "LDLᵀ needs a structurally symmetric matrix: ({i}, {j}) is stored but ({j}, {i}) is not"
                )));
            }
        }
    }
    Ok(())
}

/// The elimination order of the KKT matrix `a` whose first `n_primal` unknowns
/// are primal: AMD on the pattern of `S + BᵀB` for the primal unknowns, each
/// multiplier right after the last primal unknown its row touches. Returns the
/// forward (`fwd[k]` = unknown eliminated `k`-th) and inverse permutations.
///
/// A constraint row touching more than a dense threshold of primal unknowns
/// does not contribute its clique to the AMD pattern (it would be quadratic in
/// size; AMD would postpone such a row anyway): this only affects fill.
pub(crate) fn kkt_ordering(
    a: &Csc,
    n_primal: usize,
    control: amd::Control,
) -> Result<(Vec<usize>, Vec<usize>), KktError> {
    let n = a.n;
    if n_primal > n {
        return Err(KktError::Structure(format!(
            "n_primal = {n_primal} exceeds the dimension {n}"
        )));
    }
    for c in n_primal..n {
        if primal_rows(a, n_primal, c).is_empty() {
            return Err(KktError::Structure(format!(
                "constraint {} (unknown {c}) touches no primal unknown",
                c - n_primal
            )));
        }
    }
    let (p_fwd, p_inv) = primal_order(a, n_primal, control)?;
    let fwd = with_multipliers(a, n_primal, &p_fwd, &p_inv);
    let mut inv = vec![0usize; n];
    for (k, &u) in fwd.iter().enumerate() {
        inv[u] = k;
    }
    Ok((fwd, inv))
}

/// The primal rows of column `c` (sorted): for a multiplier, its
/// constraint row.
fn primal_rows(a: &Csc, n_primal: usize, c: usize) -> &[usize] {
    let col = a.column(c);
    &col[..col.partition_point(|&i| i < n_primal)]
}

/// AMD on the pattern of `S + BᵀB`; returns the forward and inverse
/// permutations of the primal unknowns.
fn primal_order(
    a: &Csc,
    np: usize,
    control: amd::Control,
) -> Result<(Vec<usize>, Vec<usize>), KktError> {
    let dense = (control.dense * (np as f64).sqrt()).max(16.0);
    // Pattern of S + BᵀB, sorted columns.
    let mut col_ptr = Vec::with_capacity(np + 1);
    let mut row_idx = Vec::new();
    let mut mark = vec![usize::MAX; np];
    col_ptr.push(0);
    for j in 0..np {
        let start = row_idx.len();
        let mut push = |i: usize, row_idx: &mut Vec<usize>| {
            if mark[i] != j {
                mark[i] = j;
                row_idx.push(i);
            }
        };
        for &i in a.column(j) {
            if i < np {
                push(i, &mut row_idx);
            } else {
                let rows = primal_rows(a, np, i);
                if (rows.len() as f64) <= dense {
                    for &r in rows {
                        push(r, &mut row_idx);
                    }
                }
            }
        }
        row_idx[start..].sort_unstable();
        col_ptr.push(row_idx.len());
    }
    let mut p_fwd = vec![0usize; np];
    let mut p_inv = vec![0usize; np];
    if np > 0 {
        let g = SymbolicSparseColMatRef::new_checked(np, np, &col_ptr, None, &row_idx);
        let mut mem = MemBuffer::try_new(amd::order_scratch::<usize>(np, row_idx.len()))
            .map_err(|_| KktError::OutOfMemory)?;
        amd::order(&mut p_fwd, &mut p_inv, g, control, MemStack::new(&mut mem))
            .map_err(|e| KktError::Backend(format!("AMD ordering failed: {e:?}")))?;
    }
    Ok((p_fwd, p_inv))
}

/// The whole elimination order: the primal unknowns in the order `p_fwd`,
/// each multiplier right after the last primal unknown its row touches.
fn with_multipliers(a: &Csc, np: usize, p_fwd: &[usize], p_inv: &[usize]) -> Vec<usize> {
    let n = a.n;
    // Bucket the multipliers by the position of the last primal they touch.
    let mut count = vec![0usize; np + 1];
    let mut last = vec![0usize; n - np];
    for c in np..n {
        let l = primal_rows(a, np, c)
            .iter()
            .map(|&r| p_inv[r])
            .max()
            .unwrap_or(0);
        last[c - np] = l;
        count[l + 1] += 1;
    }
    for k in 0..np {
        count[k + 1] += count[k];
    }
    // count[k] = number of multipliers placed before primal position k + 1's
    // bucket; fill buckets in multiplier order.
    let mut bucket = vec![0usize; n - np];
    let mut next = count.clone();
    for (i, &l) in last.iter().enumerate() {
        bucket[next[l]] = np + i;
        next[l] += 1;
    }
    let mut fwd = Vec::with_capacity(n);
    for k in 0..np {
        fwd.push(p_fwd[k]);
        fwd.extend_from_slice(&bucket[count[k]..count[k + 1]]);
    }
    fwd
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::{chain, relative_residual, vector};
    use faer::sparse::linalg::SupernodalThreshold;

    fn forced(a: &Csc, n_primal: usize, supernodal: bool) -> SparseLdlt {
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: if supernodal {
                SupernodalThreshold::FORCE_SUPERNODAL
            } else {
                SupernodalThreshold::FORCE_SIMPLICIAL
            },
            ..CholeskySymbolicParams::default()
        };
        let s = SparseLdlt::with_params(a, n_primal, params).expect("regular structure");
        assert_eq!(s.is_supernodal(), supernodal);
        s
    }

    #[test]
    fn each_multiplier_follows_the_last_primal_it_touches() {
        let (n_bodies, dup) = (50, Some((17, 1.0)));
        let a = chain(n_bodies, 3, dup);
        let np = 3 * n_bodies;
        let s = SparseLdlt::new(&a, np).expect("regular structure");
        let order = s.order();
        let mut position = vec![0; a.n];
        for (k, &u) in order.iter().enumerate() {
            position[u] = k;
        }
        let mut seen = order.to_vec();
        seen.sort_unstable();
        assert_eq!(seen, (0..a.n).collect::<Vec<_>>(), "a permutation");
        for c in np..a.n {
            let col = &a.row_idx[a.col_ptr[c]..a.col_ptr[c + 1]];
            let last = col
                .iter()
                .filter(|&&i| i < np)
                .map(|&i| position[i])
                .max()
                .expect("rows touch primal unknowns");
            // Only multipliers between the last primal and this one.
            assert!(position[c] > last);
            assert!(
                order[last + 1..position[c]].iter().all(|&u| u >= np),
                "multiplier {c}"
            );
        }
    }

    #[test]
    fn simplicial_and_supernodal_factors_agree() {
        let a = chain(30, 5, None);
        let b = vector(a.n, 1);
        let mut xs = Vec::new();
        for supernodal in [false, true] {
            let mut s = forced(&a, 90, supernodal);
            s.factor(&a).expect("regular");
            let mut x = b.clone();
            s.solve_in_place(&mut x);
            assert!(relative_residual(&a, &x, &b) <= 1e-13);
            xs.push(x);
        }
        assert!(crate::testing::relative_difference(&xs[0], &xs[1]) <= 1e-12);
    }

    /// Factors a chain with a repeated constraint both ways; faer's own zero
    /// pivot or the pivot check must name one of the two copies (original
    /// indices, whichever kernel found it).
    #[test]
    fn a_redundant_constraint_names_one_of_its_copies() {
        let mut checked_by_us = 0;
        for (n_bodies, r) in [(1, 0), (1, 1), (10, 7), (200, 0), (200, 399)] {
            for f in [1.0, 1.0 / 3.0, -2.5] {
                let a = chain(n_bodies, 13, Some((r, f)));
                let pair = [3 * n_bodies + r, a.n - 1];
                for supernodal in [false, true] {
                    let mut s = forced(&a, 3 * n_bodies, supernodal);
                    let result = s.factor(&a);
                    assert!(
                        matches!(result, Err(KktError::Singular { unknown: Some(k) }) if pair.contains(&k)),
                        "N = {n_bodies}, row {r} × {f}, supernodal {supernodal}: {result:?}"
                    );
                    // Which check caught it?
                    let sym = SymbolicSparseColMatRef::new_checked(
                        a.n, a.n, &a.col_ptr, None, &a.row_idx,
                    );
                    let faer_ok = s
                        .symbolic
                        .factorize_numeric_ldlt(
                            &mut s.l_values,
                            SparseColMatRef::new(sym, &a.values),
                            Side::Lower,
                            LdltRegularization::default(),
                            Par::Seq,
                            MemStack::new(&mut s.mem),
                            Default::default(),
                        )
                        .is_ok();
                    checked_by_us += usize::from(faer_ok);
                }
            }
        }
        assert!(checked_by_us > 0, "the pivot check itself was exercised");
    }
}
