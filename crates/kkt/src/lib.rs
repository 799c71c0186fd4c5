//! # mstar-kkt — solving the KKT system (eq. 16) fast and safely
//!
//! A KKT *backend* ([`KktBackend`]) factors and solves one sparsity structure
//! many times: its symbolic analysis runs once when it is built, its numeric
//! factorization at every Newton iteration that refreshes the matrix (faer's
//! symbolic/numeric split, diffsol's `LinearSolver`). [`KktSolver`] wraps any
//! backend with the checks every solution must pass: its residual, a lower
//! bound of the condition number, and iterative refinement for a regularized
//! factorization ([`KktSolver::solve_in_place`]).
//!
//! ## Backends
//!
//! Each built-in backend is one file and one line in the registry
//! ([`backends`]); a backend of another crate joins them with [`register`]
//! (docs/extending.md, "Your own KKT backend"). A backend is selected by name
//! ([`Backend`]) and says which KKT structure it reads ([`Structure`]), so
//! that the caller assembles what it needs. The runs of a sweep share one
//! symbolic analysis per structure while a [`SharedAnalyses`] guard lives.
//!
//! - `dense` ([`Backend::DENSE`]): dense LU with partial pivoting, for tiny
//!   systems.
//! - `lu` ([`Backend::SPARSE_LU`]): faer's sparse LU with partial pivoting and
//!   a COLAMD ordering. Needs nothing but a square matrix.
//! - `ldlt` ([`Backend::SPARSE_LDLT`]): faer's sparse LDLᵀ without pivoting,
//!   for KKT matrices `[[S, Bᵀ], [B, 0]]` stored with both triangles and a
//!   symmetric structure, whose first [`KktOptions::n_primal`] unknowns are
//!   primal (`S`) and the rest multipliers. Unknowns are ordered by AMD on the
//!   pattern of `S + BᵀB`, each multiplier right after the last primal unknown
//!   its constraint touches: every pivot then exists when `S` is positive
//!   definite and the constraints are independent; pivots at the rounding
//!   level (redundant constraints) are rejected. When `S` is indefinite the
//!   factorization may still succeed; the checks of the solution decide.
//!   Optionally with signed dynamic regularization and iterative refinement
//!   ([`KktOptions::ldlt_regularization`]).
//! - `schur` ([`Backend::SCHUR`]): the Schur complement on the primal block
//!   `S`, for KKT matrices whose `S` is block-diagonal with blocks of at most
//!   [`MAX_SCHUR_BLOCK`] unknowns (bodies that interact only through
//!   constraints, assembled without the `BᵀB` term): every block of `S` is
//!   inverted densely and `C = B S⁻¹ Bᵀ − D` (pattern of `B Bᵀ`,
//!   block-tridiagonal for a chain) is factored by its envelope in the
//!   constraints' own order when that is narrow, else by faer's sparse LDLᵀ
//!   after AMD. A chain (diagonal `S`, `C` by its envelope) takes one-pass
//!   paths for the factorization and for the residual check. It is the
//!   fastest backend on chains (`docs/performance.md`).
//! - `schur-lu` ([`Backend::SCHUR_LU`]): the same for an `S` whose blocks
//!   are not symmetric (the exact iteration matrix of bodies in Euler
//!   parameters, whose gyroscopic blocks are not): `C` has the symmetric
//!   pattern of `B Bᵀ` and unsymmetric values, and is factored by an LU
//!   without pivoting on its envelope in the constraints' own order (its
//!   symmetric part is positive definite when that of `S` is); a wider
//!   envelope is refused.
//! - [`Backend::AUTO`] (default): when [`KktOptions::n_primal`] is given,
//!   Schur if the structure's `S` is block-diagonal with small blocks, else
//!   LDLᵀ, else sparse LU; up to [`KktOptions::dense_threshold`] unknowns
//!   Schur, else dense; sparse LU without `n_primal`, dense when that small
//!   ([`KktOptions::candidates`]).
//!   `ldlt` and `schur` need a symmetric matrix
//!   ([`Registration::symmetric`]); an unsymmetric one skips to `schur-lu`.
//!
//! A singular or numerically singular matrix is an `Err` naming the unknown that
//! has no pivot, never NaN or a panic. This crate knows nothing of mechanics:
//! the caller maps unknowns to names.
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

mod backend;
#[cfg(test)]
mod chain_tests;
mod csc;
mod dense;
mod envelope;
mod envelope_lu;
mod norm;
mod rcm;
pub(crate) mod schur;
mod solver;
mod sparse_ldlt;
mod sparse_lu;
mod stored;
mod templates;
#[cfg(test)]
mod testing;

pub use backend::{Analyse, Backend, KktBackend, Registration, Structure, backends, register};
pub use csc::{Csc, condition_number};
pub use norm::{Finite, MaxAbs, argmax_abs, max_abs};
pub use schur::MAX_BLOCK as MAX_SCHUR_BLOCK;
pub use solver::KktSolver;
pub use templates::SharedAnalyses;

/// Options of a [`KktSolver`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KktOptions {
    /// Factorization (default: [`Backend::AUTO`]).
    pub backend: Backend,
    /// Largest dimension that [`Backend::AUTO`] solves densely when no
    /// Schur backend takes it ([`candidates`](Self::candidates); default: 24).
    pub dense_threshold: usize,
    /// Largest accepted relative residual `‖A x − b‖∞ / (‖A‖∞ ‖x‖∞ + ‖b‖∞)` of a
    /// solution; above it the matrix is reported as numerically singular
    /// (default: 1e-8).
    pub residual_tolerance: f64,
    /// Number of leading primal unknowns (`Δu`); the remaining unknowns are
    /// multipliers (`Δλ`), one per constraint row. Required by the `ldlt` and
    /// `schur` backends and makes [`Backend::AUTO`] choose them; ignored by
    /// the LU backends (default: `None`).
    pub n_primal: Option<usize>,
    /// Signed dynamic regularization of the `ldlt` backend (default: `None`,
    /// off): a pivot of the wrong sign (primal unknowns must give positive
    /// pivots, multipliers negative ones: the matrix is quasi-definite) or of
    /// magnitude at most `δ · max |a_ij|` is replaced by `±δ · max |a_ij|`, and
    /// every solution is refined iteratively (up to [`REFINEMENT_STEPS`]
    /// steps) against the unregularized matrix. It turns zero pivots into a
    /// perturbed factorization instead of an error; the residual check still
    /// rejects what refinement cannot repair. Ignored by the other backends.
    pub ldlt_regularization: Option<f64>,
}

/// Most iterative-refinement steps per solve with a regularized factorization.
pub const REFINEMENT_STEPS: usize = 3;

impl Default for KktOptions {
    fn default() -> Self {
        Self {
            backend: Backend::AUTO,
            dense_threshold: 24,
            residual_tolerance: 1e-8,
            n_primal: None,
            ldlt_regularization: None,
        }
    }
}

impl KktOptions {
    /// The backends [`KktSolver::new`] tries, in order, for a matrix of
    /// dimension `dim`: the chosen one alone, or for [`Backend::AUTO`] the
    /// backends whose [`Registration::automatic`] has a rank, in ascending
    /// rank, leaving out those that [`need n_primal`](Registration::needs_n_primal)
    /// when it is not given. Up to [`dense_threshold`](Self::dense_threshold)
    /// unknowns only those that read `S` without `BᵀB`
    /// ([`Structure::augmented`] false: they eliminate `S`'s small blocks)
    /// are tried, then the dense LU: where they take the structure they are
    /// as fast as the dense LU or faster on the systems of `models/` that
    /// small (docs/performance.md, "Backends compared"), and a general
    /// sparse factorization is not. For the built-in backends: with
    /// [`n_primal`](Self::n_primal) Schur, Schur with LU, LDLᵀ, then sparse
    /// LU (both Schur backends refuse a structure whose `S` is not
    /// block-diagonal with small blocks, `schur-lu` also one whose `C` has a
    /// wide envelope, LDLᵀ one that is not symmetric; a caller that knows its
    /// matrix is not symmetric skips `schur` and `ldlt`, and so takes
    /// `schur-lu` for an unsymmetric block-diagonal `S`), else sparse LU;
    /// small, Schur, Schur with LU, then dense.
    ///
    /// ```
    /// use mstar_kkt::{Backend, KktOptions};
    ///
    /// let auto = KktOptions::default();
    /// assert_eq!(auto.candidates(20), [Backend::DENSE]);
    /// assert_eq!(auto.candidates(50), [Backend::SPARSE_LU]);
    /// let kkt = KktOptions { n_primal: Some(30), ..auto };
    /// assert_eq!(
    ///     kkt.candidates(50),
    ///     [Backend::SCHUR, Backend::SCHUR_LU, Backend::SPARSE_LDLT, Backend::SPARSE_LU]
    /// );
    /// let small = KktOptions { n_primal: Some(12), ..auto };
    /// assert_eq!(
    ///     small.candidates(20),
    ///     [Backend::SCHUR, Backend::SCHUR_LU, Backend::DENSE]
    /// );
    /// let chosen = KktOptions { backend: Backend::SPARSE_LDLT, ..kkt };
    /// assert_eq!(chosen.candidates(50), [Backend::SPARSE_LDLT]);
    /// ```
    #[must_use]
    pub fn candidates(&self, dim: usize) -> Vec<Backend> {
        if self.backend != Backend::AUTO {
            return vec![self.backend];
        }
        let small = dim <= self.dense_threshold;
        let mut ranked: Vec<(u16, Backend)> = backends()
            .iter()
            .filter(|r| self.n_primal.is_some() || !r.needs_n_primal)
            .filter(|r| !small || !r.structure.augmented)
            .filter_map(|r| r.automatic.map(|rank| (rank, r.backend)))
            .collect();
        // Stable: equal ranks keep the registration order.
        ranked.sort_by_key(|&(rank, _)| rank);
        let mut candidates: Vec<Backend> = ranked.into_iter().map(|(_, b)| b).collect();
        if small {
            candidates.push(Backend::DENSE);
        }
        candidates
    }

    /// The number of primal unknowns, required by `backend`.
    ///
    /// # Errors
    /// [`KktError::Structure`] when [`n_primal`](Self::n_primal) is not given.
    pub fn require_n_primal(&self, backend: Backend) -> Result<usize, KktError> {
        self.n_primal.ok_or_else(|| {
            KktError::Structure(format!(
                "the {backend} backend needs KktOptions::n_primal (the number of primal unknowns)"
            ))
        })
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
    /// The sparsity structure is malformed, or a backend cannot take it.
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
    /// [`register`]: the name is `auto`, empty, or already a backend's.
    #[error("a KKT backend cannot be registered as '{name}': the name is taken or reserved")]
    NameTaken {
        /// The name asked for.
        name: &'static str,
    },
}
