//! Constrained vibration modes: the linearized motion about a state at rest.
//!
//! About a state `(u, u̇ = 0, λ)` the equations of motion (paper eqs. 3-4,
//! `M ü + Bᵀλ = g`, `Φ = 0`) linearize to
//!
//! ```text
//! M δü + C δu̇ + K δu + Bᵀ δλ = 0,     B δu = 0,
//! K = Σ λᵢ ∂²Φᵢ/∂u² − ∂g/∂u,    C = −∂g/∂u̇
//! ```
//!
//! (`K_T` and `C_T` of `algorithm.md` eqs. 6-7 at `ü = 0`; the constraint
//! Hessian contracted with `λ` is the geometric stiffness that makes a
//! hanging pendulum stable). Modes `δu = φ e^{st}` live in the tangent space
//! `B φ = 0`. Two numerical paths:
//!
//! - **dense** ([`Method::Dense`]): an orthonormal basis `Z` of the null
//!   space of `B` from its singular value decomposition, the reduced
//!   matrices `Zᵀ M Z`, `Zᵀ C Z`, `Zᵀ K Z`, and either the symmetric
//!   generalized eigenproblem `K_r x = ω² M_r x` (no damping, `K`
//!   symmetric: Cholesky of `M_r` and a symmetric eigensolver) or the
//!   first-order form `[0 I; −M_r⁻¹K_r −M_r⁻¹C_r]` (its complex eigenvalues
//!   by a real Schur form, each shape the null vector of
//!   `s² M_r + s C_r + K_r` by a complex SVD).
//! - **sparse** ([`Method::Sparse`]): shift-invert Lanczos in the `M` inner
//!   product; each operator application solves the KKT system
//!   `[K − σM, Bᵀ; B, 0] [y; μ] = [M x; 0]` with one sparse factorization,
//!   so the iterates stay in the tangent space and nothing of size `n²` is
//!   formed. Undamped models with symmetric `K` only.
//!
//! Each mode is reported by its eigenvalue `s`: the undamped natural
//! frequency `|s|/2π` and the damping ratio `ζ = −Re(s)/|s|`, and its shape
//! normalized to unit modal mass.

mod dense;
mod lanczos;

use mstar_kkt::{Csc, KktError, KktOptions, KktSolver};
use mstar_linearize::{Coefficients, Linearization, LinearizeError};
use mstar_model::{StateRef, System};

/// Which eigensolver [`modes`] uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// Dense up to [`DENSE_LIMIT`] coordinates, sparse above.
    Auto,
    /// Null-space basis and a dense eigensolver (any damping).
    Dense,
    /// Shift-invert Lanczos on the sparse KKT matrix (undamped, symmetric).
    Sparse,
}

/// The largest number of coordinates [`Method::Auto`] solves densely.
pub const DENSE_LIMIT: usize = 600;

/// Settings of [`modes`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModesOptions {
    /// How many modes, lowest `|s|` first.
    pub count: usize,
    /// The time of the state (drivers held there), s.
    pub t0: f64,
    /// The eigensolver.
    pub method: Method,
}

impl Default for ModesOptions {
    fn default() -> Self {
        Self {
            count: 10,
            t0: 0.0,
            method: Method::Auto,
        }
    }
}

/// What a mode does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModeKind {
    /// `s = 0` to round-off: a rigid or neutral motion (nothing restores it).
    Rigid,
    /// A complex pair `s, s̄` (reported once, `Im s > 0`): it oscillates,
    /// decaying when `ζ > 0`.
    Oscillating,
    /// A real `s < 0`: it decays without oscillating (`ζ = 1`).
    Overdamped,
    /// A real `s > 0`: it grows (an unstable state, `ζ = −1`).
    Unstable,
}

/// One mode.
#[derive(Clone, Debug, PartialEq)]
pub struct Mode {
    /// The eigenvalue `s = (Re, Im)`, 1/s: `δu = φ e^{st}`.
    pub s: (f64, f64),
    /// The undamped natural frequency `|s|/2π`, Hz (0 for a rigid mode).
    pub frequency_hz: f64,
    /// `ζ = −Re(s)/|s|` (0 for a rigid mode).
    pub damping_ratio: f64,
    /// What the mode does.
    pub kind: ModeKind,
    /// The shape in the model's coordinates, `φᴴ M φ = 1`; for a complex
    /// shape the real part after rotating its phase so that its largest
    /// component is real and positive.
    pub shape: Vec<f64>,
    /// The imaginary part of the shape so rotated (all zeros when real).
    pub shape_imag: Vec<f64>,
}

/// The modes found by [`modes`].
#[derive(Clone, Debug, PartialEq)]
pub struct Modes {
    /// Lowest `|s|` first.
    pub modes: Vec<Mode>,
    /// Degrees of freedom: coordinates minus the rank of `B`.
    pub dof: usize,
    /// Whether the model has damping (`C ≠ 0`) or an unsymmetric `K`, so
    /// that the first-order form was solved.
    pub damped: bool,
    /// The eigensolver used.
    pub method: Method,
}

/// Why [`modes`] failed.
#[derive(Debug, thiserror::Error)]
pub enum ModesError {
    /// The system's declared patterns are inconsistent.
    #[error("the model's structure: {0}")]
    Structure(#[from] LinearizeError),
    /// More modes asked for than there are degrees of freedom.
    #[error(
        "{count} modes asked for, but the model has {dof} degrees of freedom ({n} coordinates, {rank} independent constraints): ask for at most {dof}"
    )]
    TooMany {
        /// Modes asked for.
        count: usize,
        /// Degrees of freedom.
        dof: usize,
        /// Coordinates.
        n: usize,
        /// Rank of `B`.
        rank: usize,
    },
    /// `M` is not positive definite on the tangent space.
    #[error(
        "the mass matrix is not positive definite on the motions the constraints allow (a coordinate without mass or inertia that no constraint fixes?): give every body a mass and an inertia"
    )]
    SingularMass,
    /// The KKT matrix is singular at every shift tried.
    #[error(
        "the KKT matrix [K − σM, Bᵀ; B, 0] cannot be factored ({0}): redundant constraints (see `mstar check`) or a mass matrix singular on the constraints' tangent space; try the dense method"
    )]
    Kkt(#[from] KktError),
    /// The acceleration problem at the pose is singular.
    #[error(
        "the acceleration problem [M + BᵀB, Bᵀ; B, 0] at the pose cannot be solved for the multipliers ({0}): redundant constraints (see `mstar check`) or a mass matrix singular on the constraints' tangent space"
    )]
    Multipliers(KktError),
    /// The sparse method cannot take a damped or unsymmetric model.
    #[error(
        "the sparse eigensolver takes undamped models with a symmetric stiffness only, and this one {0}: use the dense method (its time grows as n³: about a second at 1000 coordinates, half a minute at 2000) or remove the dampers"
    )]
    SparseNeedsSymmetric(&'static str),
    /// The Lanczos iteration did not converge.
    #[error(
        "the sparse eigensolver did not converge: {converged} of {count} modes after {steps} Lanczos steps; ask for fewer modes or use the dense method"
    )]
    NotConverged {
        /// Modes converged.
        converged: usize,
        /// Modes asked for.
        count: usize,
        /// Krylov dimension reached.
        steps: usize,
    },
}

/// The lowest `options.count` vibration modes of `sys` about the state at
/// rest `(u, u̇ = 0, λ)` at `options.t0` (an equilibrium from
/// [`crate::equilibrium::solve`], or any pose with its multipliers from
/// [`rest_multipliers`]).
///
/// # Errors
/// [`ModesError::TooMany`] when `count` exceeds the degrees of freedom;
/// [`ModesError::SingularMass`] when `M` is singular on the tangent space;
/// [`ModesError::Kkt`], [`ModesError::SparseNeedsSymmetric`] or
/// [`ModesError::NotConverged`] from the sparse method.
///
/// # Panics
/// If `u` or `lambda` do not have one value per coordinate or constraint.
pub fn modes<S: System + ?Sized>(
    sys: &S,
    u: &[f64],
    lambda: &[f64],
    options: &ModesOptions,
) -> Result<Modes, ModesError> {
    assert_eq!(u.len(), sys.n_coords(), "one value per coordinate");
    assert_eq!(
        lambda.len(),
        sys.n_constraints(),
        "one value per constraint"
    );
    let lin = linearize(sys, u, lambda, options.t0)?;
    let method = match options.method {
        Method::Auto if sys.n_coords() <= DENSE_LIMIT => Method::Dense,
        Method::Auto => Method::Sparse,
        m => m,
    };
    if method == Method::Dense {
        dense::modes(lin, options.count)
    } else {
        lanczos::modes(lin, options.count)
    }
}

/// The state at rest a model is linearized about (its modes,
/// [`crate::linear`]'s state-space models).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum About {
    /// The static equilibrium [`crate::equilibrium::solve`] finds from the
    /// initial pose (a neutral one as it is: its free direction is a rigid
    /// mode).
    #[default]
    Equilibrium,
    /// The initial pose, at rest, with the multipliers of the acceleration
    /// problem there ([`rest_multipliers`]).
    Initial,
}

/// A state at rest `(u, u̇ = 0, λ)` ([`rest_state`]).
#[derive(Clone, Debug, PartialEq)]
pub struct RestState {
    /// Coordinates.
    pub u: Vec<f64>,
    /// Multipliers.
    pub lambda: Vec<f64>,
    /// The equilibrium found is neutral (a direction without stiffness).
    pub neutral: bool,
}

/// Why [`rest_state`] found no state.
#[derive(Debug, thiserror::Error)]
pub enum RestStateError {
    /// No equilibrium was found.
    #[error("{0}; or linearize about the file's pose with --about initial")]
    Equilibrium(crate::equilibrium::EquilibriumError),
    /// The acceleration problem at the initial pose is singular.
    #[error("at the initial pose: {0}")]
    Initial(ModesError),
}

/// The state at rest `about` names for `sys` from the pose `u0` (drivers
/// held at `t = 0`): what `mstar modes --about` and Python's
/// `model.modes(about=…)` linearize about.
///
/// # Errors
/// [`RestStateError`] when there is no such state.
pub fn rest_state<S: System + ?Sized>(
    sys: &S,
    u0: &[f64],
    about: About,
) -> Result<RestState, RestStateError> {
    use crate::equilibrium::{EquilibriumError, EquilibriumOptions};
    if about == About::Initial {
        let lambda = rest_multipliers(sys, u0, 0.0).map_err(RestStateError::Initial)?;
        return Ok(RestState {
            u: u0.to_vec(),
            lambda,
            neutral: false,
        });
    }
    match crate::equilibrium::solve(sys, u0, &EquilibriumOptions::default()) {
        Ok(eq) => Ok(RestState {
            u: eq.u,
            lambda: eq.lambda,
            neutral: false,
        }),
        Err(EquilibriumError::Neutral { equilibrium, .. }) => Ok(RestState {
            u: equilibrium.u,
            lambda: equilibrium.lambda,
            neutral: true,
        }),
        Err(e) => Err(RestStateError::Equilibrium(e)),
    }
}

/// The multipliers of a state at rest at `u`: those of the acceleration
/// problem `M ü + Bᵀλ = g(u, 0, t₀)`, `B ü = 0` (solved with `M + BᵀB`,
/// regular when `M` is on the tangent space). At an equilibrium `ü = 0`
/// and these are its `λ`; elsewhere they are the constraint forces at the
/// instant of release.
///
/// With redundant constraints (dependent rows of `B` at `u`) the problem
/// is solved on the independent rows and the multipliers are the
/// minimum-norm ones of all rows ([`crate::redundant::all_multipliers`]).
///
/// # Errors
/// [`ModesError::Multipliers`] when the acceleration problem is singular,
/// [`ModesError::Structure`] for a malformed model.
pub fn rest_multipliers<S: System + ?Sized>(
    sys: &S,
    u: &[f64],
    t0: f64,
) -> Result<Vec<f64>, ModesError> {
    if let Some(kept) = crate::redundant::kept_if_dependent(sys, t0, u) {
        let subset = mstar_model::RowSubset::new(sys, kept.clone());
        let lambda = rest_multipliers_on(&subset, u, t0)?;
        return Ok(crate::redundant::all_multipliers(
            sys, &kept, t0, u, &lambda,
        ));
    }
    rest_multipliers_on(sys, u, t0)
}

/// [`rest_multipliers`] with all rows of `sys`.
fn rest_multipliers_on<S: System + ?Sized>(
    sys: &S,
    u: &[f64],
    t0: f64,
) -> Result<Vec<f64>, ModesError> {
    let (n, m) = (sys.n_coords(), sys.n_constraints());
    let mut lin = Linearization::new(sys)?;
    let (zeros, lambda0) = (vec![0.0; n], vec![0.0; m]);
    lin.eval_residual(sys, &at_rest(t0, &zeros, u, &lambda0));
    lin.assemble(&Coefficients {
        c_bb: 1.0,
        ..Coefficients::acceleration()
    });
    let mut rhs = vec![0.0; n + m];
    rhs[..n].copy_from_slice(lin.g());
    KktSolver::new(lin.kkt(), &KktOptions::default())
        .and_then(|mut solver| {
            solver.factor(&lin.kkt().values)?;
            solver.solve_in_place(&mut rhs)
        })
        .map_err(ModesError::Multipliers)?;
    Ok(rhs[n..].to_vec())
}

/// The state at rest `(t₀, u, 0, 0, λ)`.
fn at_rest<'s>(t0: f64, zeros: &'s [f64], u: &'s [f64], lambda: &'s [f64]) -> StateRef<'s> {
    StateRef {
        t: t0,
        u,
        v: &zeros[..u.len()],
        a: &zeros[..u.len()],
        lambda,
    }
}

/// `M`, `B`, `K` and `C` evaluated at the state at rest (in `lin`).
fn linearize<S: System + ?Sized>(
    sys: &S,
    u: &[f64],
    lambda: &[f64],
    t0: f64,
) -> Result<Linearization, ModesError> {
    let mut lin = Linearization::new(sys)?;
    let zeros = vec![0.0; u.len()];
    let x = at_rest(t0, &zeros, u, lambda);
    lin.eval_residual(sys, &x);
    lin.eval_jacobians(sys, &x);
    Ok(lin)
}

/// The KKT coefficients of `[c_u K + c_v C + c_a M, Bᵀ; B, 0]`.
fn blocks(c_u: f64, c_v: f64, c_a: f64) -> Coefficients {
    Coefficients {
        c_u,
        c_v,
        c_a,
        c_bb: 0.0,
        c_identity: 0.0,
        scale: 1.0,
    }
}

/// The entries `(row, column, value)` of the top-left `n × n` block of a
/// KKT matrix in CSC form.
fn top_left(kkt: &Csc, n: usize) -> impl Iterator<Item = (usize, usize, f64)> + '_ {
    (0..n).flat_map(move |j| {
        (kkt.col_ptr[j]..kkt.col_ptr[j + 1])
            .filter(move |&p| kkt.row_idx[p] < n)
            .map(move |p| (kkt.row_idx[p], j, kkt.values[p]))
    })
}

/// The scale `ω²_ref = max|K_ij| / max|M_ij|` (1/s²) below which an
/// eigenvalue `|s|²` counts as zero, times [`RIGID`]; 1 without stiffness.
fn omega2_ref(k_max: f64, m_max: f64) -> f64 {
    if k_max > 0.0 && m_max > 0.0 {
        k_max / m_max
    } else {
        1.0
    }
}

/// `|s|² ≤ RIGID · ω²_ref` is a rigid (neutral) mode: far above the
/// round-off of either eigensolver (`≈ 10⁻¹⁶ ω²_ref`) and of the
/// finite-difference defaults of the `System` trait (`≈ 10⁻¹⁰` relative,
/// on entries of size `ω²_ref`), far below any physical frequency a
/// model in double precision can resolve.
const RIGID: f64 = 1e-9;

/// A mode from its eigenvalue `s` and its complex shape `(re, im)`
/// normalized to `φᴴ M φ = 1`; rotates the phase so that the largest
/// component is real and positive.
fn mode(s: (f64, f64), omega2_zero: f64, shape: (Vec<f64>, Vec<f64>)) -> Mode {
    let abs = s.0.hypot(s.1);
    let kind = if abs * abs <= omega2_zero {
        ModeKind::Rigid
    } else if s.1 > 0.0 {
        ModeKind::Oscillating
    } else if s.0 < 0.0 {
        ModeKind::Overdamped
    } else {
        ModeKind::Unstable
    };
    let (frequency_hz, damping_ratio) = match kind {
        ModeKind::Rigid => (0.0, 0.0),
        ModeKind::Overdamped => (abs / std::f64::consts::TAU, 1.0),
        ModeKind::Unstable => (abs / std::f64::consts::TAU, -1.0),
        // (`s.0 = 0`: ζ = +0, not −0.)
        ModeKind::Oscillating => (abs / std::f64::consts::TAU, 0.0 - s.0 / abs),
    };
    let (re, im) = shape;
    let big = (0..re.len())
        .max_by(|&a, &b| re[a].hypot(im[a]).total_cmp(&re[b].hypot(im[b])))
        .unwrap_or(0);
    let r = re.get(big).map_or(1.0, |x| x.hypot(im[big]));
    // Multiply by conj(φ_big)/|φ_big|: φ_big becomes |φ_big|.
    let (c, d) = if r > 0.0 {
        (re[big] / r, -im[big] / r)
    } else {
        (1.0, 0.0)
    };
    let shape: Vec<f64> = re.iter().zip(&im).map(|(a, b)| a * c - b * d).collect();
    let shape_imag: Vec<f64> = re.iter().zip(&im).map(|(a, b)| a * d + b * c).collect();
    Mode {
        s,
        frequency_hz,
        damping_ratio,
        kind,
        shape,
        shape_imag,
    }
}

#[cfg(test)]
mod tests;
