//! [`KktSolver`]: any backend, with the checks every solution must pass.

use crate::{
    Backend, Csc, KktBackend, KktError, KktOptions, MaxAbs, REFINEMENT_STEPS, max_abs, templates,
};

/// Factors and solves one sparse square system many times: symbolic analysis
/// once, numeric factorization per call to [`factor`](Self::factor), no
/// allocation after [`new`](Self::new). Wraps a [`KktBackend`] with the
/// residual check, the condition bound and iterative refinement.
pub struct KktSolver {
    inner: Box<dyn KktBackend>,
    backend: Backend,
    n: usize,
    factored: bool,
    /// Whether a solve has checked the current factorization's residual.
    verified: bool,
    /// Whether a solve of
    /// [`solve_unverified_correction`](Self::solve_unverified_correction)
    /// has checked a factorization: the first one it meets is checked on
    /// the spot (a backend unfit for the iteration matrix fails there, not
    /// as a slow Newton iteration).
    corrections_verified: bool,
    /// Whether the solve under way skips the backend's own refinement
    /// ([`solve_correction`](Self::solve_correction)).
    unrefined: bool,
    /// Whether the solve under way leaves an unverified factorization's
    /// check to [`verify`](Self::verify) when it would cost a product
    /// ([`solve_unverified_correction`](Self::solve_unverified_correction)).
    deferred: bool,
    tol: f64,
    /// `‖A‖∞` of the last factorization.
    a_norm: f64,
    /// The right-hand side of a solve being checked, and `A x` (scratch).
    rhs: Vec<f64>,
    ax: Vec<f64>,
    /// Whether the backend is a fork of an analysis made before
    /// ([`SharedAnalyses`](crate::SharedAnalyses)).
    shared: bool,
}

impl std::fmt::Debug for KktSolver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("KktSolver")
            .field("n", &self.n)
            .field("backend", &self.backend)
            .finish_non_exhaustive()
    }
}

impl KktSolver {
    /// Analyses the structure of `a` (its values are ignored) with the first
    /// backend of [`KktOptions::candidates`] that takes it.
    ///
    /// # Errors
    /// [`KktError::Structure`] for a malformed structure, an
    /// [`n_primal`](KktOptions::n_primal) above the dimension, and when the
    /// backend cannot take the structure (e.g. `ldlt` and `schur` without
    /// `n_primal`; `schur` with an `S` that is not block-diagonal);
    /// [`KktError::Backend`] or [`KktError::OutOfMemory`] when the symbolic
    /// analysis fails.
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
        let candidates = options.candidates(a.n);
        let mut last = KktError::Structure("no backend to try".to_string());
        for (k, backend) in candidates.iter().enumerate() {
            let Some(registration) = backend.registration() else {
                return Err(KktError::Structure(format!(
                    "no KKT backend is called '{backend}'"
                )));
            };
            if let Some(inner) = templates::fork(*backend, a, options) {
                let mut solver = Self::with_backend(inner, *backend, a.n, options);
                solver.shared = true;
                return Ok(solver);
            }
            match (registration.analyse)(a, options) {
                Ok(inner) => {
                    templates::keep(*backend, a, options, inner.as_ref());
                    return Ok(Self::with_backend(inner, *backend, a.n, options));
                }
                // The next candidate may take what this one refuses.
                Err(e @ KktError::Structure(_)) if k + 1 < candidates.len() => last = e,
                Err(e) => return Err(e),
            }
        }
        Err(last)
    }

    /// Wraps a backend already analysed for matrices of dimension `n` (e.g.
    /// one of the caller's own).
    #[must_use]
    pub fn with_backend(
        inner: Box<dyn KktBackend>,
        backend: Backend,
        n: usize,
        options: &KktOptions,
    ) -> Self {
        Self {
            inner,
            backend,
            n,
            factored: false,
            verified: false,
            corrections_verified: false,
            unrefined: false,
            deferred: false,
            tol: options.residual_tolerance,
            a_norm: 0.0,
            rhs: vec![0.0; n],
            ax: vec![0.0; n],
            shared: false,
        }
    }

    /// Whether [`new`](Self::new) reused an analysis of the same structure
    /// made before, while a [`SharedAnalyses`](crate::SharedAnalyses) guard
    /// lived, instead of analysing.
    #[must_use]
    pub fn reused_analysis(&self) -> bool {
        self.shared
    }

    /// The backend in use ([`Backend::AUTO`] resolved).
    #[must_use]
    pub fn backend(&self) -> Backend {
        self.backend
    }

    /// Dimension of the system.
    #[must_use]
    pub fn dim(&self) -> usize {
        self.n
    }

    /// `‖A‖∞` of the last successful factorization.
    #[must_use]
    pub fn norm(&self) -> f64 {
        self.a_norm
    }

    /// Factors the matrix with these values (same structure as at construction).
    ///
    /// # Errors
    /// [`KktError::NonFinite`] for NaN or infinite values, [`KktError::Singular`]
    /// when a pivot is missing (for the `ldlt` and `schur` backends also when it
    /// is at the rounding level of the terms it was computed from); `unknown` is
    /// then the original index of the unknown without a pivot, e.g. the
    /// multiplier of a redundant constraint.
    ///
    /// # Panics
    /// If `values` does not have one value per structural entry.
    pub fn factor(&mut self, values: &[f64]) -> Result<(), KktError> {
        self.factored = false;
        self.a_norm = self.inner.factor(values)?;
        self.factored = true;
        self.verified = false;
        Ok(())
    }

    /// Solves `A x = rhs` in place with the last factorization and checks the
    /// solution: its relative residual `‖A x − rhs‖∞ / (‖A‖∞ ‖x‖∞ + ‖rhs‖∞)`
    /// must not exceed [`KktOptions::residual_tolerance`], and `‖A‖∞ ‖x‖∞ /
    /// ‖rhs‖∞`, a lower bound of the condition number, must stay below
    /// `1 / (16 ε)` ≈ 2.8e14. The residual check verifies the factorization:
    /// backward stability then holds for every further right-hand side, so it
    /// runs on the first solve after each [`factor`](Self::factor).
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

    /// [`solve_in_place_with_norm`](Self::solve_in_place_with_norm) without
    /// the backend's own refinement step
    /// ([`KktBackend::solve_in_place_unrefined`]), for a solve whose error
    /// the caller corrects (a Newton iteration, whose residual is checked
    /// again; a refinement against another matrix). The first solve after a
    /// factorization checks it by the residual of the unrefined solution.
    ///
    /// # Errors
    /// As [`solve_in_place`](Self::solve_in_place).
    ///
    /// # Panics
    /// If `rhs.len()` differs from the dimension.
    pub fn solve_correction(&mut self, rhs: &mut [f64], rhs_norm: f64) -> Result<(), KktError> {
        self.unrefined = true;
        let solved = self.solve_in_place_with_norm(rhs, rhs_norm);
        self.unrefined = false;
        solved
    }

    /// [`solve_correction`](Self::solve_correction) for a solve inside an
    /// iteration whose own residual certifies where it leads (a Newton
    /// iteration; a refinement against another matrix): the residual
    /// check of an unverified factorization is made here only when the
    /// backend forms it in the solve's own sweeps, or for the first
    /// factorization such a solve meets (a backend unfit for the iteration
    /// matrix fails at once);
    /// otherwise (a product with
    /// the whole matrix: 6 % of a spatial chain's step,
    /// docs/performance.md, "Newton's checks when Newton fails") it is left
    /// to [`verify`](Self::verify), which the caller runs when the iteration
    /// fails. The bound on `‖A‖∞ ‖x‖∞ / ‖rhs‖∞` (a singular matrix) is
    /// checked at every solve, as always.
    ///
    /// # Errors
    /// As [`solve_in_place`](Self::solve_in_place).
    ///
    /// # Panics
    /// If `rhs.len()` differs from the dimension.
    pub fn solve_unverified_correction(
        &mut self,
        rhs: &mut [f64],
        rhs_norm: f64,
    ) -> Result<(), KktError> {
        self.deferred = true;
        let solved = self.solve_correction(rhs, rhs_norm);
        self.deferred = false;
        solved
    }

    /// Checks the current factorization by the residual of a solve of `rhs`
    /// (any right-hand side: Newton's last residual when an iteration
    /// failed after
    /// [`solve_unverified_correction`](Self::solve_unverified_correction));
    /// `rhs` is overwritten. Nothing to do when a solve has verified the
    /// factorization already, when there is none, or for a zero or
    /// non-finite `rhs`, which cannot test it.
    ///
    /// # Errors
    /// [`KktError::Inaccurate`] or [`KktError::Singular`], as
    /// [`solve_in_place`](Self::solve_in_place).
    ///
    /// # Panics
    /// If `rhs.len()` differs from the dimension.
    pub fn verify(&mut self, rhs: &mut [f64]) -> Result<(), KktError> {
        let rhs_norm = max_abs(rhs);
        if self.verified || !self.factored || !rhs_norm.is_finite() || rhs_norm == 0.0 {
            return Ok(());
        }
        self.solve_correction(rhs, rhs_norm)
    }

    /// [`solve_in_place`](Self::solve_in_place) for a caller that knows
    /// `rhs_norm = ‖rhs‖∞` already (NaN or infinite if `rhs` has a NaN or an
    /// infinity), which saves a pass over `rhs`.
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
        assert_eq!(rhs.len(), self.n, "right-hand side of the wrong length");
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
        let (xn, residual) = self.solve(rhs, bn);
        if !xn.is_finite() {
            return Err(KktError::Singular { unknown: None });
        }
        if let Some(res) = residual {
            let denom = self.a_norm * xn + bn;
            let relative_residual = if denom > 0.0 { res / denom } else { 0.0 };
            // (A NaN residual fails too.)
            if relative_residual.is_nan() || relative_residual > self.tol {
                return Err(KktError::Inaccurate { relative_residual });
            }
            self.verified = true;
            self.corrections_verified |= self.deferred;
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

    /// Solves in place; returns `‖x‖∞` and, when the factorization is not
    /// verified yet, `‖A x − b‖∞`.
    fn solve(&mut self, rhs: &mut [f64], bn: f64) -> (f64, Option<f64>) {
        let refine = self.inner.is_regularized();
        if !self.verified && !refine {
            let checked = if self.unrefined {
                self.inner.solve_unrefined_with_residual(rhs)
            } else {
                self.inner.solve_with_residual(rhs)
            };
            if let Some((xn, res)) = checked {
                return (xn, Some(res));
            }
        }
        // With `solve_unverified_correction` the product is left to `verify`.
        let check = !self.verified && (refine || !(self.deferred && self.corrections_verified));
        if check || refine {
            self.rhs.copy_from_slice(rhs);
        }
        let mut xn = if self.unrefined {
            self.inner.solve_in_place_unrefined(rhs)
        } else {
            self.inner.solve_in_place(rhs)
        };
        if refine {
            self.refine(rhs, bn);
            xn = max_abs(rhs);
        }
        let residual = check.then(|| {
            self.inner.mul(rhs, &mut self.ax);
            let mut res = MaxAbs::new();
            for (ax, b) in self.ax.iter().zip(&self.rhs) {
                res.push(ax - b);
            }
            res.value()
        });
        (xn, residual)
    }

    /// Iterative refinement of `x` against the backend's (unregularized)
    /// matrix: `x += A_reg⁻¹ (b − A x)` until the relative residual is at the
    /// rounding level or [`REFINEMENT_STEPS`] steps are done.
    fn refine(&mut self, x: &mut [f64], bn: f64) {
        for _ in 0..REFINEMENT_STEPS {
            self.inner.mul(x, &mut self.ax);
            let mut res = MaxAbs::new();
            for (r, &b) in self.ax.iter_mut().zip(&self.rhs) {
                *r = b - *r;
                res.push(*r);
            }
            let scale = self.a_norm * max_abs(x) + bn;
            if !res.is_finite() || res.value() <= 4.0 * f64::EPSILON * scale {
                return;
            }
            self.inner.solve_in_place(&mut self.ax);
            for (xi, d) in x.iter_mut().zip(&self.ax) {
                *xi += d;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::condition_number;

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
            Backend::DENSE,
            Backend::SPARSE_LU,
            Backend::SPARSE_LDLT,
            Backend::SCHUR,
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
        let x = solve_with(Backend::SCHUR, 5, &a, &b).expect("nonsingular");
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
            solve_with(Backend::SCHUR, 5, &singular, &b),
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
            solve_with(Backend::DENSE, 2, &a, &b),
            Err(KktError::Singular { unknown: Some(3) })
        );
        assert_eq!(
            solve_with(Backend::SPARSE_LDLT, 2, &a, &b),
            Err(KktError::Singular { unknown: Some(3) })
        );
        // The Schur complement's AMD may keep either copy last.
        assert!(matches!(
            solve_with(Backend::SCHUR, 2, &a, &b),
            Err(KktError::Singular {
                unknown: Some(2 | 3)
            })
        ));
        let sparse = solve_with(Backend::SPARSE_LU, 2, &a, &b);
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
