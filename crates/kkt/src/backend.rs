//! The backend trait, the structure a backend reads, and the registry.
//!
//! A backend is one type implementing [`KktBackend`] (its numeric part:
//! factor, solve, product) and one [`Registration`] (its name, the structure
//! it reads, its symbolic analysis, whether the automatic choice tries it).
//! The built-in backends are listed in [`BUILT_IN`]; a backend of another
//! crate joins them at run time with [`register`]. [`KktSolver`](crate::KktSolver),
//! the integrator and [`KktOptions::candidates`] find both kinds the same way
//! ([`backends`]).

use std::sync::RwLock;

use crate::{Csc, KktError, KktOptions, dense, schur, sparse_ldlt, sparse_lu};

/// The KKT structure a backend reads, `[[S, Bᵀ], [B, D]]`: whether `S`
/// carries the augmentation `c_bb BᵀB` of `M* = M + BᵀB` (eq. 17), and whether
/// the `Bᵀ` block is filled.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Structure {
    /// `S` holds the `BᵀB` term. Backends that factor the whole matrix need it
    /// when `M` is singular (the paper's point, eq. 11); without it `S` is
    /// block-diagonal for bodies that interact only through constraints, and
    /// the multipliers come out without the shift `c_bb Φ`.
    pub augmented: bool,
    /// The backend reads the `Bᵀ` block. Backends that read `S`, `B` and `D`
    /// only (the matrix is symmetric) leave it unassembled.
    pub transpose: bool,
}

impl Structure {
    /// The whole augmented matrix: `S` with `BᵀB`, `Bᵀ` filled (eq. 16-17).
    pub const AUGMENTED: Self = Self {
        augmented: true,
        transpose: true,
    };
    /// `S` without `BᵀB`, and no `Bᵀ` block: what the Schur backend reads.
    pub const PLAIN: Self = Self {
        augmented: false,
        transpose: false,
    };
}

/// The numeric part of a KKT backend: factorizations and solves on the
/// structure its [`Registration::analyse`] analysed.
///
/// Contract: [`factor`](Self::factor) reads the values of the whole
/// structure (or of the part that [`Structure`] says it reads) and keeps what
/// it needs; [`solve_in_place`](Self::solve_in_place) and [`mul`](Self::mul)
/// work on the last successful factorization. [`KktSolver`](crate::KktSolver)
/// checks every factorization's first solution with [`mul`](Self::mul) (or
/// with [`solve_with_residual`](Self::solve_with_residual)) and never calls a
/// solve without a successful factorization.
pub trait KktBackend: Send {
    /// Factors the matrix with these values, one per entry of the analysed
    /// structure; returns `‖A‖∞`, the largest absolute row sum of the matrix
    /// as the backend reads it.
    ///
    /// # Errors
    /// [`KktError::NonFinite`] for NaN or infinite values it reads,
    /// [`KktError::Singular`] naming the unknown without a pivot, when known.
    fn factor(&mut self, values: &[f64]) -> Result<f64, KktError>;

    /// Solves `A x = rhs` in place with the last factorization; returns
    /// `‖x‖∞` as [`max_abs`](crate::max_abs) would (NaN or infinite for a
    /// non-finite `x`).
    fn solve_in_place(&mut self, rhs: &mut [f64]) -> f64;

    /// [`solve_in_place`](Self::solve_in_place) without a refinement step
    /// the backend makes on its own (`schur-lu`'s, `schur/refine.rs`), for a
    /// right-hand side whose solution is a small correction, where the
    /// forward error that step removes is small against the solution it
    /// corrects. The default solves as `solve_in_place`.
    fn solve_in_place_unrefined(&mut self, rhs: &mut [f64]) -> f64 {
        self.solve_in_place(rhs)
    }

    /// `y = A x` for the last factored matrix.
    fn mul(&self, x: &[f64], y: &mut [f64]);

    /// Solves in place and forms `‖A x − rhs‖∞` on the way: `Some((‖x‖∞,
    /// residual))`, or `None` with `rhs` untouched when the backend cannot
    /// (the default; the caller then keeps a copy of `rhs`, solves and
    /// multiplies).
    fn solve_with_residual(&mut self, _rhs: &mut [f64]) -> Option<(f64, f64)> {
        None
    }

    /// [`solve_with_residual`](Self::solve_with_residual) without the
    /// backend's own refinement step (as
    /// [`solve_in_place_unrefined`](Self::solve_in_place_unrefined)), the
    /// residual being that of the unrefined solution. The default: as
    /// `solve_with_residual`.
    fn solve_unrefined_with_residual(&mut self, rhs: &mut [f64]) -> Option<(f64, f64)> {
        self.solve_with_residual(rhs)
    }

    /// Whether the factorization is perturbed (regularized), so that every
    /// solution must be refined iteratively against [`mul`](Self::mul)
    /// (default: no).
    fn is_regularized(&self) -> bool {
        false
    }

    /// A backend with this one's symbolic analysis and fresh numeric
    /// buffers, as [`Registration::analyse`] would build it for the same
    /// structure and options, or `None` when it cannot share its analysis
    /// (the default). Called on backends that have not factored yet:
    /// [`KktSolver::new`](crate::KktSolver::new) keeps one such template per
    /// recent structure, so that the runs of a sweep analyse an identical
    /// pattern once.
    fn fork(&self) -> Option<Box<dyn KktBackend>> {
        None
    }
}

/// A backend's symbolic analysis of a structure (values ignored).
pub type Analyse = fn(&Csc, &KktOptions) -> Result<Box<dyn KktBackend>, KktError>;

/// How a backend is found and built.
#[derive(Clone, Copy)]
pub struct Registration {
    /// Its name (`--kkt <name>` on the command line).
    pub backend: Backend,
    /// One line for help texts.
    pub summary: &'static str,
    /// The KKT structure it reads.
    pub structure: Structure,
    /// Whether it needs a symmetric matrix: it reads one triangle of `S`
    /// (or factors `C = B S⁻¹ Bᵀ` as symmetric). An unsymmetric iteration
    /// matrix (velocity-dependent or non-conservative forces, a
    /// configuration-dependent `M`) then gets a wrong factorization, which
    /// the solver's residual check rejects.
    pub symmetric: bool,
    /// The symbolic analysis of a structure (values ignored).
    pub analyse: Analyse,
    /// Whether and when [`Backend::AUTO`] tries it above the dense
    /// threshold ([`KktOptions::candidates`]): `None` never (it must be
    /// named), `Some(rank)` in ascending rank (the built-ins: `schur` 10,
    /// `schur-lu` 20, `ldlt` 30, `lu` 100; ties in registration order).
    pub automatic: Option<u16>,
    /// Whether it needs [`KktOptions::n_primal`]: the automatic choice skips
    /// it without.
    pub needs_n_primal: bool,
}

impl std::fmt::Debug for Registration {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Registration")
            .field("backend", &self.backend)
            .field("structure", &self.structure)
            .finish_non_exhaustive()
    }
}

/// The built-in backends, in the order help texts list them.
const BUILT_IN: &[Registration] = &[
    dense::REGISTRATION,
    sparse_lu::REGISTRATION,
    sparse_ldlt::REGISTRATION,
    schur::REGISTRATION,
    schur::REGISTRATION_LU,
];

/// The backends of other crates, in the order they were registered.
static REGISTERED: RwLock<Vec<Registration>> = RwLock::new(Vec::new());

/// The backends registered with [`register`] (none if the lock was
/// poisoned by a panic while registering).
fn registered() -> Vec<Registration> {
    REGISTERED.read().map(|r| r.clone()).unwrap_or_default()
}

/// Every backend: the built-in ones, then those added with [`register`].
#[must_use]
pub fn backends() -> Vec<Registration> {
    let mut all = BUILT_IN.to_vec();
    all.extend(registered());
    all
}

/// Adds a backend of your own: from then on [`Backend::named`],
/// [`KktSolver::new`](crate::KktSolver::new), the integrator and, with
/// [`Registration::automatic`], the automatic choice find it like a built-in
/// one (docs/extending.md, "Your own KKT backend").
///
/// # Errors
/// [`KktError::NameTaken`] when its name is `auto`, empty, or already a
/// backend's.
pub fn register(registration: Registration) -> Result<Backend, KktError> {
    let name = registration.backend.0;
    let taken = name.is_empty() || name == Backend::AUTO.0 || Backend::named(name).is_some();
    if taken {
        return Err(KktError::NameTaken { name });
    }
    let mut list = REGISTERED
        .write()
        .map_err(|_| KktError::NameTaken { name })?;
    // Checked again under the write lock: two threads may register one name.
    if list.iter().any(|r| r.backend.0 == name) {
        return Err(KktError::NameTaken { name });
    }
    list.push(registration);
    Ok(registration.backend)
}

/// A KKT backend by name: [`Backend::AUTO`] or a registered backend
/// ([`backends`]). Displays as its name.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct Backend(&'static str);

impl Backend {
    /// Chosen from the dimension and structure ([`KktOptions::candidates`]).
    pub const AUTO: Self = Self("auto");
    /// Dense LU with partial pivoting (`crates/kkt/src/dense.rs`).
    pub const DENSE: Self = Self("dense");
    /// faer's sparse LU (`crates/kkt/src/sparse_lu.rs`).
    pub const SPARSE_LU: Self = Self("lu");
    /// faer's sparse LDLᵀ in a KKT ordering (`crates/kkt/src/sparse_ldlt.rs`).
    pub const SPARSE_LDLT: Self = Self("ldlt");
    /// The Schur complement on a block-diagonal `S` (`crates/kkt/src/schur/`).
    pub const SCHUR: Self = Self("schur");
    /// The Schur complement on a block-diagonal `S` that need not be
    /// symmetric, `C` by an envelope LU (`crates/kkt/src/schur/`).
    pub const SCHUR_LU: Self = Self("schur-lu");

    /// The name of a backend of your own, for its [`Registration`]; it
    /// refers to a backend once [`register`]ed.
    #[must_use]
    pub const fn new(name: &'static str) -> Self {
        Self(name)
    }

    /// The backend called `name` (`"auto"` or a registered name).
    #[must_use]
    pub fn named(name: &str) -> Option<Self> {
        if name == Self::AUTO.0 {
            return Some(Self::AUTO);
        }
        Self::find(|r| r.backend.0 == name).map(|r| r.backend)
    }

    /// The first registration that `matches`, built-in ones first.
    fn find(matches: impl Fn(&Registration) -> bool) -> Option<Registration> {
        if let Some(r) = BUILT_IN.iter().find(|r| matches(r)) {
            return Some(*r);
        }
        registered().into_iter().find(|r| matches(r))
    }

    /// Its name.
    #[must_use]
    pub fn name(self) -> &'static str {
        self.0
    }

    /// Its registration (`None` for [`Backend::AUTO`] and for a name not
    /// registered).
    #[must_use]
    pub fn registration(self) -> Option<Registration> {
        Self::find(|r| r.backend == self)
    }

    /// The structure it reads (`None` for [`Backend::AUTO`], which depends on
    /// the candidate chosen).
    #[must_use]
    pub fn structure(self) -> Option<Structure> {
        self.registration().map(|r| r.structure)
    }
}

impl Default for Backend {
    fn default() -> Self {
        Self::AUTO
    }
}

impl std::fmt::Debug for Backend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.0)
    }
}

impl std::fmt::Display for Backend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_named_backend_is_registered_once() {
        for b in [
            Backend::DENSE,
            Backend::SPARSE_LU,
            Backend::SPARSE_LDLT,
            Backend::SCHUR,
            Backend::SCHUR_LU,
        ] {
            assert_eq!(Backend::named(b.name()), Some(b));
            assert!(b.structure().is_some(), "{b}");
        }
        let mut names: Vec<_> = backends().iter().map(|r| r.backend.name()).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), backends().len(), "unique names");
        assert!(!names.contains(&"auto"));
        assert_eq!(Backend::named("auto"), Some(Backend::AUTO));
        assert_eq!(Backend::named("qr"), None);
        assert_eq!(Backend::AUTO.structure(), None);
    }
}
