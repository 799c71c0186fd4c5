//! # mstar-kkt — solving the KKT system (eq. 16) fast and safely
//!
//! [`KktSolver`] analyses a sparsity pattern once ([`KktSolver::new`]), then
//! [`factor`](KktSolver::factor)s new values and
//! [`solve`](KktSolver::solve_in_place)s right-hand sides as often as needed,
//! reusing every buffer.
//!
//! ## Backends
//!
//! - [`Backend::Dense`]: dense LU with partial pivoting, for tiny systems.
//! - [`Backend::SparseLu`]: faer's sparse LU with partial pivoting and a
//!   COLAMD ordering. Needs nothing but a square matrix.
//! - [`Backend::SparseLdlt`]: faer's sparse LDLᵀ without pivoting, for KKT
//!   matrices `[[S, Bᵀ], [B, 0]]` stored with both triangles and a symmetric
//!   structure, whose first [`KktOptions::n_primal`] unknowns are primal (`S`)
//!   and the rest multipliers. Unknowns are ordered by AMD on the pattern of
//!   `S + BᵀB`, each multiplier right after the last primal unknown its
//!   constraint touches: every pivot then exists when `S` is positive definite
//!   and the constraints are independent. Its numeric factorization is about
//!   3× faster than the LU's on chain-shaped systems, to the same accuracy;
//!   pivots at the rounding level (redundant constraints) are rejected. When
//!   `S` is indefinite the factorization may still succeed; the checks of the
//!   solution below decide. Optionally with signed dynamic regularization
//!   and iterative refinement ([`KktOptions::ldlt_regularization`]).
//! - [`Backend::Schur`]: the Schur complement on the primal block `S`, for
//!   KKT matrices whose `S` is block-diagonal with blocks of at most
//!   [`MAX_SCHUR_BLOCK`] unknowns (bodies that interact only through
//!   constraints, assembled without the `BᵀB` term): every block of `S` is
//!   inverted densely and `C = B S⁻¹ Bᵀ` (pattern of `B Bᵀ`, block-tridiagonal
//!   for a chain) is factored by its envelope in the constraints' own order
//!   when that is narrow, else by faer's sparse LDLᵀ after AMD. On the
//!   10⁴-bar chain it factors 7.5× and solves 2.4× faster than LDLᵀ of the
//!   whole KKT matrix (`cargo xtask bench`, docs/performance.md).
//! - [`Backend::Auto`] (default): dense up to [`KktOptions::dense_threshold`]
//!   unknowns; above it, when [`KktOptions::n_primal`] is given, Schur if `S`'s
//!   pattern is block-diagonal with small blocks, else LDLᵀ; sparse LU without
//!   `n_primal`.
//!
//! A singular or numerically singular matrix is an `Err` naming the unknown that
//! has no pivot, never NaN or a panic; every solution is checked by its residual
//! and by a lower bound of the condition number
//! ([`solve_in_place`](KktSolver::solve_in_place)).
//! This crate knows nothing of mechanics: the caller maps unknowns to names.
//!
//! ```
//! use mstar_kkt::{Csc, KktOptions, KktSolver};
//!
//! // [[2, 1], [1, 0]] in compressed sparse column form.
//! let a = Csc { n: 2, col_ptr: vec![0, 2, 3], row_idx: vec![0, 1, 0], values: vec![2.0, 1.0, 1.0] };
//! let mut solver = KktSolver::new(&a, &KktOptions::default())?;
//! solver.factor(&a.values)?;
//! let mut x = [4.0, 1.0];
//! solver.solve_in_place(&mut x)?;
//! assert!((x[0] - 1.0).abs() < 1e-14 && (x[1] - 2.0).abs() < 1e-14);
//! # Ok::<(), mstar_kkt::KktError>(())
//! ```
#![deny(missing_docs)]

#[cfg(test)]
mod chain_tests;
mod dense;
mod envelope;
mod schur;
mod sparse_ldlt;
mod sparse_lu;
#[cfg(test)]
mod testing;

use dense::DenseLu;
pub use schur::MAX_BLOCK as MAX_SCHUR_BLOCK;
use schur::Schur;
use sparse_ldlt::SparseLdlt;
use sparse_lu::SparseLu;

/// A square sparse matrix in compressed sparse column form with sorted row
/// indices and no duplicates.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Csc {
    /// Dimension.
    pub n: usize,
    /// Column pointers, length `n + 1`.
    pub col_ptr: Vec<usize>,
    /// Row indices, length `nnz`.
    pub row_idx: Vec<usize>,
    /// Values, length `nnz`.
    pub values: Vec<f64>,
}

impl Csc {
    /// Number of stored values.
    #[must_use]
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    /// `y = A x`.
    ///
    /// # Panics
    /// If `x` or `y` is not of length `n`.
    pub fn mul(&self, x: &[f64], y: &mut [f64]) {
        assert_eq!(x.len(), self.n);
        assert_eq!(y.len(), self.n);
        y.fill(0.0);
        for (j, &xj) in x.iter().enumerate() {
            for k in self.col_ptr[j]..self.col_ptr[j + 1] {
                y[self.row_idx[k]] += self.values[k] * xj;
            }
        }
    }

    /// The dense row-major matrix (for tests, diagnostics and small systems).
    #[must_use]
    pub fn to_dense(&self) -> Vec<Vec<f64>> {
        let mut a = vec![vec![0.0; self.n]; self.n];
        for j in 0..self.n {
            for k in self.col_ptr[j]..self.col_ptr[j + 1] {
                a[self.row_idx[k]][j] += self.values[k];
            }
        }
        a
    }

    /// Checks the structure: lengths, bounds, sorted unique row indices.
    fn validate(&self) -> Result<(), KktError> {
        let bad = |why: &str| Err(KktError::Structure(why.to_string()));
        if self.col_ptr.len() != self.n + 1 || self.col_ptr[0] != 0 {
            return bad("col_ptr must have n + 1 entries starting at 0");
        }
        if self.col_ptr.windows(2).any(|w| w[0] > w[1]) {
            return bad("col_ptr must be non-decreasing");
        }
        if self.col_ptr[self.n] != self.row_idx.len() || self.values.len() != self.row_idx.len() {
            return bad("row_idx and values must have col_ptr[n] entries");
        }
        for j in 0..self.n {
            let col = &self.row_idx[self.col_ptr[j]..self.col_ptr[j + 1]];
            if col.windows(2).any(|w| w[0] >= w[1]) || col.iter().any(|&i| i >= self.n) {
                return bad("row indices must be sorted, unique and below n");
            }
        }
        Ok(())
    }
}

/// Which factorization to use.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub enum Backend {
    /// Dense LU up to [`KktOptions::dense_threshold`] unknowns; above it
    /// [`SparseLdlt`](Self::SparseLdlt) if [`KktOptions::n_primal`] is given,
    /// else [`SparseLu`](Self::SparseLu) (default).
    #[default]
    Auto,
    /// Dense LU with partial pivoting.
    Dense,
    /// faer's sparse LU with partial pivoting and a COLAMD column ordering.
    SparseLu,
    /// faer's sparse LDLᵀ without pivoting, in a KKT-aware ordering (AMD on
    /// `S + BᵀB`, each multiplier after the last primal unknown it touches).
    /// Requires [`KktOptions::n_primal`] and a structurally symmetric matrix
    /// stored with both triangles; reads its lower triangle.
    SparseLdlt,
    /// Schur complement on the primal block: `S` must be block-diagonal
    /// (blocks of at most [`MAX_SCHUR_BLOCK`] unknowns, the connected
    /// components of its pattern); each block is inverted densely and
    /// `C = B S⁻¹ Bᵀ − D` factored by sparse LDLᵀ. Requires
    /// [`KktOptions::n_primal`]. Reads `S`, `B` (rows after `n_primal`,
    /// columns before) and `D` only: the matrix must be symmetric, as KKT
    /// matrices are; it keeps compact copies of them instead of the whole
    /// matrix, for its residual check too.
    Schur,
}

/// Options of a [`KktSolver`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KktOptions {
    /// Factorization (default: [`Backend::Auto`]).
    pub backend: Backend,
    /// Largest dimension that [`Backend::Auto`] solves densely (default: 24).
    pub dense_threshold: usize,
    /// Largest accepted relative residual `‖A x − b‖∞ / (‖A‖∞ ‖x‖∞ + ‖b‖∞)` of a
    /// solution; above it the matrix is reported as numerically singular
    /// (default: 1e-8).
    pub residual_tolerance: f64,
    /// Number of leading primal unknowns (`Δu`); the remaining unknowns are
    /// multipliers (`Δλ`), one per constraint row. Required by
    /// [`Backend::SparseLdlt`] and makes [`Backend::Auto`] choose it; ignored
    /// by the LU backends (default: `None`).
    pub n_primal: Option<usize>,
    /// Signed dynamic regularization of [`Backend::SparseLdlt`] (default:
    /// `None`, off): a pivot of the wrong sign (primal unknowns must give
    /// positive pivots, multipliers negative ones: the matrix is
    /// quasi-definite) or of magnitude at most `δ · max |a_ij|` is replaced by
    /// `±δ · max |a_ij|`, and every solution is refined iteratively (up to
    /// [`REFINEMENT_STEPS`] steps) against the unregularized matrix. It turns
    /// zero pivots into a perturbed factorization instead of an error; the
    /// residual check still rejects what refinement cannot repair. Ignored by
    /// the other backends.
    pub ldlt_regularization: Option<f64>,
}

/// Most iterative-refinement steps per solve with a regularized LDLᵀ.
pub const REFINEMENT_STEPS: usize = 3;

impl Default for KktOptions {
    fn default() -> Self {
        Self {
            backend: Backend::Auto,
            dense_threshold: 24,
            residual_tolerance: 1e-8,
            n_primal: None,
            ldlt_regularization: None,
        }
    }
}

/// Errors of the KKT solver.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum KktError {
    /// The matrix is (numerically) singular; `unknown` is the column that found
    /// no pivot, when the factorization could tell.
    #[error("the KKT matrix is singular{}", match .unknown { Some(k) => format!(" (no pivot for unknown {k})"), None => String::new() })]
    Singular {
        /// Index of the unknown without a pivot.
        unknown: Option<usize>,
    },
    /// The matrix or the right-hand side contains NaN or infinity.
    #[error("the KKT matrix or right-hand side contains NaN or infinity")]
    NonFinite,
    /// The solution's residual is too large: the matrix is numerically singular.
    #[error(
        "the KKT solution is inaccurate (relative residual {relative_residual:.2e}): the matrix is numerically singular"
    )]
    Inaccurate {
        /// `‖A x − b‖∞ / (‖A‖∞ ‖x‖∞ + ‖b‖∞)`.
        relative_residual: f64,
    },
    /// The sparsity structure is malformed.
    #[error("malformed sparse structure: {0}")]
    Structure(String),
    /// `solve_in_place` was called before a successful `factor`.
    #[error("solve called without a successful factorization")]
    NotFactored,
    /// Memory for the factorization could not be allocated.
    #[error("out of memory for the factorization")]
    OutOfMemory,
    /// An error reported by faer.
    #[error("sparse factorization failed: {0}")]
    Backend(String),
}

enum Inner {
    Dense(DenseLu),
    SparseLu(Box<SparseLu>),
    SparseLdlt(Box<SparseLdlt>),
    Schur(Box<Schur>),
}

/// Factors and solves one sparse square system many times: symbolic analysis
/// once, numeric factorization per call to [`factor`](Self::factor), no
/// allocation after [`new`](Self::new).
pub struct KktSolver {
    a: Csc,
    inner: Inner,
    backend: Backend,
    factored: bool,
    /// Whether a solve has checked the current factorization's residual.
    verified: bool,
    tol: f64,
    rhs: Vec<f64>,
    ax: Vec<f64>,
    a_norm: f64,
}

impl std::fmt::Debug for KktSolver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("KktSolver")
            .field("n", &self.a.n)
            .field("nnz", &self.a.row_idx.len())
            .field("backend", &self.backend)
            .finish()
    }
}

impl KktSolver {
    /// Analyses the structure of `a` (its values are ignored).
    ///
    /// # Errors
    /// [`KktError::Structure`] for a malformed structure, an
    /// [`n_primal`](KktOptions::n_primal) above the dimension, and for
    /// [`Backend::SparseLdlt`]: a missing `n_primal`, an unsymmetric structure
    /// or a constraint row without primal entries. [`KktError::Backend`] or
    /// [`KktError::OutOfMemory`] when the symbolic analysis fails.
    pub fn new(a: &Csc, options: &KktOptions) -> Result<Self, KktError> {
        a.validate()?;
        if let Some(np) = options.n_primal
            && np > a.n
        {
            return Err(KktError::Structure(format!(
                "n_primal = {np} exceeds the dimension {}",
                a.n
            )));
        }
        let mut backend = match options.backend {
            Backend::Auto if a.n <= options.dense_threshold => Backend::Dense,
            Backend::Auto if options.n_primal.is_some() => Backend::Schur,
            Backend::Auto => Backend::SparseLu,
            b => b,
        };
        let need_primal = |what: &str| {
            options.n_primal.ok_or_else(|| {
                KktError::Structure(format!("the {what} backend needs KktOptions::n_primal"))
            })
        };
        let mut schur = None;
        if backend == Backend::Schur {
            let np = need_primal("Schur")?;
            match Schur::new(a, np) {
                Ok(s) => schur = Some(s),
                // Auto: S is not block-diagonal with small blocks.
                Err(KktError::Structure(_)) if options.backend == Backend::Auto => {
                    backend = Backend::SparseLdlt;
                }
                Err(e) => return Err(e),
            }
        }
        let inner = match backend {
            Backend::Schur => match schur {
                Some(s) => Inner::Schur(Box::new(s)),
                None => return Err(KktError::Structure("Schur analysis missing".to_string())),
            },
            Backend::Dense => Inner::Dense(DenseLu::new(a.n, &a.col_ptr, &a.row_idx)),
            Backend::SparseLdlt => {
                let np = need_primal("LDLᵀ")?;
                let mut ldlt = SparseLdlt::new(a, np)?;
                if let Some(delta) = options.ldlt_regularization {
                    if !(0.0..1.0).contains(&delta) || delta == 0.0 {
                        return Err(KktError::Structure(format!(
                            "the LDLᵀ regularization δ must be in (0, 1), got {delta}"
                        )));
                    }
                    ldlt.set_regularization(np, delta);
                }
                Inner::SparseLdlt(Box::new(ldlt))
            }
            Backend::SparseLu | Backend::Auto => Inner::SparseLu(Box::new(SparseLu::new(a)?)),
        };
        Ok(Self {
            a: Csc {
                values: vec![0.0; a.row_idx.len()],
                ..a.clone()
            },
            inner,
            backend,
            factored: false,
            verified: false,
            tol: options.residual_tolerance,
            rhs: vec![0.0; a.n],
            ax: vec![0.0; a.n],
            a_norm: 0.0,
        })
    }

    /// The backend in use ([`Backend::Auto`] resolved).
    #[must_use]
    pub fn backend(&self) -> Backend {
        self.backend
    }

    /// Dimension of the system.
    #[must_use]
    pub fn dim(&self) -> usize {
        self.a.n
    }

    /// Factors the matrix with these values (same structure as at construction).
    ///
    /// # Errors
    /// [`KktError::NonFinite`] for NaN or infinite values, [`KktError::Singular`]
    /// when a pivot is missing (for [`Backend::SparseLdlt`] also when it is at
    /// the rounding level of the terms it was computed from); `unknown` is then
    /// the original index of the unknown without a pivot, e.g. the multiplier
    /// of a redundant constraint.
    ///
    /// # Panics
    /// If `values` does not have one value per structural entry.
    pub fn factor(&mut self, values: &[f64]) -> Result<(), KktError> {
        assert_eq!(values.len(), self.a.values.len(), "one value per entry");
        self.factored = false;
        if let Inner::Schur(schur) = &mut self.inner {
            // The Schur backend keeps compact copies of S, B and D itself: no
            // copy of the whole matrix, and its own products and norm.
            schur.factor(values)?;
            self.a_norm = schur.norm_inf();
            self.factored = true;
            self.verified = false;
            return Ok(());
        }
        // One pass: copy, ‖A‖∞ (largest absolute row sum; NaN or infinite
        // for non-finite values).
        self.ax.fill(0.0);
        for ((&i, v), &x) in self.a.row_idx.iter().zip(&mut self.a.values).zip(values) {
            *v = x;
            self.ax[i] += x.abs();
        }
        if self.ax.iter().any(|v| !v.is_finite()) {
            return Err(KktError::NonFinite);
        }
        self.a_norm = self.ax.iter().fold(0.0, |m: f64, &x| m.max(x));
        match &mut self.inner {
            Inner::Dense(lu) => lu.factor(values)?,
            Inner::SparseLu(lu) => lu.factor(&self.a)?,
            Inner::SparseLdlt(ldlt) => ldlt.factor(&self.a)?,
            Inner::Schur(_) => {}
        }
        self.factored = true;
        self.verified = false;
        Ok(())
    }

    /// Solves `A x = rhs` in place with the last factorization and checks the
    /// solution: its relative residual `‖A x − rhs‖∞ / (‖A‖∞ ‖x‖∞ + ‖rhs‖∞)`
    /// must not exceed [`KktOptions::residual_tolerance`], and `‖A‖∞ ‖x‖∞ /
    /// ‖rhs‖∞`, a lower bound of the condition number, must stay below
    /// `1 / (16 ε)` ≈ 2.8e14.
    ///
    /// # Errors
    /// [`KktError::NotFactored`] without a successful factorization;
    /// [`KktError::NonFinite`] for a non-finite right-hand side;
    /// [`KktError::Singular`] (with `unknown: None`) when the solution is not
    /// finite or the condition bound is exceeded, [`KktError::Inaccurate`] when
    /// the residual is too large: both mean the matrix is numerically singular.
    /// On error `rhs` holds the rejected solution.
    ///
    /// # Panics
    /// If `rhs.len()` differs from the dimension.
    pub fn solve_in_place(&mut self, rhs: &mut [f64]) -> Result<(), KktError> {
        let rhs_norm = max_abs(rhs);
        self.solve_in_place_with_norm(rhs, rhs_norm)
    }

    /// [`solve_in_place`](Self::solve_in_place) for a caller that knows
    /// `rhs_norm = ‖rhs‖∞` already (NaN or infinite if `rhs` has a NaN or an
    /// infinity), which saves a pass over `rhs` (at 10⁵ bodies, one through
    /// memory).
    ///
    /// # Errors
    /// As [`solve_in_place`](Self::solve_in_place).
    ///
    /// # Panics
    /// If `rhs.len()` differs from the dimension.
    pub fn solve_in_place_with_norm(
        &mut self,
        rhs: &mut [f64],
        rhs_norm: f64,
    ) -> Result<(), KktError> {
        assert_eq!(rhs.len(), self.a.n, "right-hand side of the wrong length");
        if !self.factored {
            return Err(KktError::NotFactored);
        }
        let bn = rhs_norm;
        debug_assert!(
            !bn.is_finite() || bn == max_abs(rhs),
            "rhs_norm {bn} is not ‖rhs‖∞ {}",
            max_abs(rhs)
        );
        if !bn.is_finite() {
            return Err(KktError::NonFinite);
        }
        let refine = matches!(&self.inner, Inner::SparseLdlt(l) if l.is_regularized());
        // The Schur backend of a chain forms the check's residual inside its
        // solve (no copy of rhs, no product with the matrix afterwards).
        let check_in_solve =
            !self.verified && matches!(&self.inner, Inner::Schur(s) if s.checks_in_solve());
        if (!self.verified && !check_in_solve) || refine {
            self.rhs.copy_from_slice(rhs);
        }
        let mut residual_in_solve = None;
        let xn = match &mut self.inner {
            Inner::Dense(lu) => {
                lu.solve_in_place(rhs);
                max_abs(rhs)
            }
            Inner::SparseLu(lu) => {
                lu.solve_in_place(rhs);
                max_abs(rhs)
            }
            Inner::SparseLdlt(ldlt) => {
                ldlt.solve_in_place(rhs);
                if refine {
                    self.refine(rhs, bn);
                }
                max_abs(rhs)
            }
            Inner::Schur(schur) if check_in_solve => {
                let (xn, residual) = schur.solve_checked(rhs);
                residual_in_solve = Some(residual);
                xn
            }
            Inner::Schur(schur) => schur.solve_in_place(rhs),
        };
        if !xn.is_finite() {
            return Err(KktError::Singular { unknown: None });
        }
        // The residual check verifies the factorization: backward stability
        // then holds for every further right-hand side, so it runs on the first
        // solve after each `factor` (modified Newton reuses factors often).
        if !self.verified {
            let res = match residual_in_solve {
                Some(res) => res,
                None => {
                    match &self.inner {
                        Inner::Schur(schur) => schur.mul(rhs, &mut self.ax),
                        _ => self.a.mul(rhs, &mut self.ax),
                    }
                    self.ax
                        .iter()
                        .zip(&self.rhs)
                        .fold(0.0f64, |m, (ax, b)| m.max((ax - b).abs()))
                }
            };
            let denom = self.a_norm * xn + bn;
            let relative_residual = if denom > 0.0 { res / denom } else { 0.0 };
            if relative_residual > self.tol {
                return Err(KktError::Inaccurate { relative_residual });
            }
            self.verified = true;
        }
        // A small relative residual is a small backward error, which a nearly
        // singular matrix also gives, with a huge x (e.g. multipliers of 1e18
        // for a redundant constraint that a pivot of 1e-17 did not reveal).
        // ‖A‖ ‖x‖ / ‖b‖ is a lower bound of the condition number ‖A‖ ‖A⁻¹‖:
        // beyond 1/(16 ε) ≈ 2.8e14 the matrix is singular to working precision.
        if self.a_norm * xn * (16.0 * f64::EPSILON) > bn {
            return Err(KktError::Singular { unknown: None });
        }
        Ok(())
    }
}

impl KktSolver {
    /// Iterative refinement of `x` against the stored (unregularized) matrix:
    /// `x += A_reg⁻¹ (b − A x)` until the relative residual is at the rounding
    /// level or [`REFINEMENT_STEPS`] steps are done.
    fn refine(&mut self, x: &mut [f64], bn: f64) {
        let Inner::SparseLdlt(ldlt) = &mut self.inner else {
            return;
        };
        for _ in 0..REFINEMENT_STEPS {
            self.a.mul(x, &mut self.ax);
            let mut res = 0.0f64;
            for (r, &b) in self.ax.iter_mut().zip(&self.rhs) {
                *r = b - *r;
                res = res.max(r.abs());
            }
            let scale = self.a_norm * max_abs(x) + bn;
            if res <= 4.0 * f64::EPSILON * scale {
                return;
            }
            ldlt.solve_in_place(&mut self.ax);
            for (xi, d) in x.iter_mut().zip(&self.ax) {
                *xi += d;
            }
        }
    }
}

/// `‖x‖∞` (NaN if any entry is NaN, else infinite if any entry is).
#[must_use]
pub fn max_abs(x: &[f64]) -> f64 {
    // Four independent lanes the compiler can vectorize; NaN and ±inf turn
    // `0 · v` into NaN, which the lane sums carry to the end.
    let (mut m, mut z) = ([0.0f64; 4], [0.0f64; 4]);
    let chunks = x.chunks_exact(4);
    let tail = chunks.remainder();
    for c in chunks {
        for k in 0..4 {
            let a = c[k].abs();
            m[k] = if a > m[k] { a } else { m[k] };
            z[k] += 0.0 * c[k];
        }
    }
    for (k, &v) in tail.iter().enumerate() {
        let a = v.abs();
        m[k] = if a > m[k] { a } else { m[k] };
        z[k] += 0.0 * v;
    }
    let max = m[0].max(m[1]).max(m[2].max(m[3]));
    if (z[0] + z[1] + z[2] + z[3]).is_nan() && max.is_finite() {
        f64::NAN
    } else {
        max
    }
}

/// The 2-norm condition number `σ_max / σ_min` of a (small) sparse matrix,
/// computed from the singular values of its dense form; `inf` when singular.
/// For diagnostics and conditioning studies, not for large systems.
#[must_use]
pub fn condition_number(a: &Csc) -> f64 {
    let mut d = nalgebra::DMatrix::<f64>::zeros(a.n, a.n);
    for j in 0..a.n {
        for k in a.col_ptr[j]..a.col_ptr[j + 1] {
            d[(a.row_idx[k], j)] += a.values[k];
        }
    }
    let s = d.singular_values();
    let max = s.iter().fold(0.0f64, |m, &x| m.max(x));
    let min = s.iter().fold(f64::INFINITY, |m, &x| m.min(x));
    if min == 0.0 { f64::INFINITY } else { max / min }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A dense matrix (row-major) as [`Csc`].
    fn csc(a: &[&[f64]]) -> Csc {
        let n = a.len();
        let mut m = Csc {
            n,
            col_ptr: vec![0],
            ..Csc::default()
        };
        for j in 0..n {
            for (i, row) in a.iter().enumerate() {
                if row[j] != 0.0 || i == j {
                    m.row_idx.push(i);
                    m.values.push(row[j]);
                }
            }
            m.col_ptr.push(m.row_idx.len());
        }
        m
    }

    fn kkt_example() -> Csc {
        // [S Bᵀ; B 0] with S = diag(2, 3, 4), B = [1 1 0; 0 1 1].
        csc(&[
            &[2.0, 0.0, 0.0, 1.0, 0.0],
            &[0.0, 3.0, 0.0, 1.0, 1.0],
            &[0.0, 0.0, 4.0, 0.0, 1.0],
            &[1.0, 1.0, 0.0, 0.0, 0.0],
            &[0.0, 1.0, 1.0, 0.0, 0.0],
        ])
    }

    fn solve_with(
        backend: Backend,
        n_primal: usize,
        a: &Csc,
        b: &[f64],
    ) -> Result<Vec<f64>, KktError> {
        let opts = KktOptions {
            backend,
            n_primal: Some(n_primal),
            ..KktOptions::default()
        };
        let mut s = KktSolver::new(a, &opts)?;
        s.factor(&a.values)?;
        let mut x = b.to_vec();
        s.solve_in_place(&mut x)?;
        Ok(x)
    }

    #[test]
    fn dense_and_sparse_solve_a_kkt_system() {
        let a = kkt_example();
        let x_true = [1.0, -2.0, 0.5, 3.0, -1.0];
        let mut b = vec![0.0; 5];
        a.mul(&x_true, &mut b);
        for backend in [
            Backend::Dense,
            Backend::SparseLu,
            Backend::SparseLdlt,
            Backend::Schur,
        ] {
            let x = solve_with(backend, 3, &a, &b).expect("nonsingular");
            for (xi, ti) in x.iter().zip(&x_true) {
                assert!((xi - ti).abs() < 1e-13, "{backend:?}: {x:?}");
            }
        }
    }

    #[test]
    fn schur_with_dense_blocks_matches_dense_lu() {
        // S = blocks {0, 1, 2} (3 × 3) and {3, 4} (2 × 2), coupled by B only.
        let a = csc(&[
            &[4.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0],
            &[1.0, 3.0, 0.5, 0.0, 0.0, 0.0, 2.0],
            &[0.0, 0.5, 2.0, 0.0, 0.0, -1.0, 0.0],
            &[0.0, 0.0, 0.0, 2.0, 0.3, 0.5, 1.0],
            &[0.0, 0.0, 0.0, 0.3, 1.0, 0.0, -1.0],
            &[1.0, 0.0, -1.0, 0.5, 0.0, 0.0, 0.0],
            &[0.0, 2.0, 0.0, 1.0, -1.0, 0.0, 0.0],
        ]);
        let x_true = [1.0, -2.0, 0.5, 3.0, -1.0, 0.25, 2.0];
        let mut b = vec![0.0; 7];
        a.mul(&x_true, &mut b);
        let x = solve_with(Backend::Schur, 5, &a, &b).expect("nonsingular");
        for (xi, ti) in x.iter().zip(&x_true) {
            assert!((xi - ti).abs() < 1e-13, "{x:?}");
        }
        // A singular block is named by one of its unknowns.
        let mut singular = a.clone();
        for j in 3..5 {
            for k in singular.col_ptr[j]..singular.col_ptr[j + 1] {
                if singular.row_idx[k] < 5 {
                    singular.values[k] = 1.0;
                }
            }
        }
        assert!(matches!(
            solve_with(Backend::Schur, 5, &singular, &b),
            Err(KktError::Singular {
                unknown: Some(3 | 4)
            })
        ));
    }

    #[test]
    fn redundant_constraint_is_an_error_naming_its_multiplier() {
        // Two identical constraint rows: the second multiplier is undetermined.
        let a = csc(&[
            &[2.0, 0.0, 1.0, 1.0],
            &[0.0, 3.0, 1.0, 1.0],
            &[1.0, 1.0, 0.0, 0.0],
            &[1.0, 1.0, 0.0, 0.0],
        ]);
        let b = [1.0, 1.0, 1.0, 1.0];
        assert_eq!(
            solve_with(Backend::Dense, 2, &a, &b),
            Err(KktError::Singular { unknown: Some(3) })
        );
        assert_eq!(
            solve_with(Backend::SparseLdlt, 2, &a, &b),
            Err(KktError::Singular { unknown: Some(3) })
        );
        // The Schur complement's AMD may keep either copy last.
        assert!(matches!(
            solve_with(Backend::Schur, 2, &a, &b),
            Err(KktError::Singular {
                unknown: Some(2 | 3)
            })
        ));
        let sparse = solve_with(Backend::SparseLu, 2, &a, &b);
        assert!(
            matches!(
                sparse,
                Err(KktError::Singular { .. } | KktError::Inaccurate { .. })
            ),
            "{sparse:?}"
        );
    }

    #[test]
    fn nan_is_an_error() {
        let mut a = kkt_example();
        a.values[0] = f64::NAN;
        let mut s = KktSolver::new(&a, &KktOptions::default()).expect("structure");
        assert_eq!(s.factor(&a.values), Err(KktError::NonFinite));
        let mut x = [0.0; 5];
        assert_eq!(s.solve_in_place(&mut x), Err(KktError::NotFactored));
    }

    #[test]
    fn malformed_structure_is_an_error() {
        let a = Csc {
            n: 2,
            col_ptr: vec![0, 2, 3],
            row_idx: vec![1, 0, 0],
            values: vec![1.0; 3],
        };
        assert!(matches!(
            KktSolver::new(&a, &KktOptions::default()),
            Err(KktError::Structure(_))
        ));
    }

    #[test]
    fn condition_number_of_a_diagonal_matrix() {
        let a = csc(&[&[4.0, 0.0], &[0.0, -0.5]]);
        assert!((condition_number(&a) - 8.0).abs() < 1e-12);
    }
}
