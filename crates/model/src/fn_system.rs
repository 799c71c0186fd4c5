//! [`FnSystem`]: a small system written as closures.

use crate::dims;
use crate::{Pattern, System};

/// `f(t, u, out)`.
type PositionFn = Box<dyn Fn(f64, &[f64], &mut [f64]) + Send + Sync>;
/// `f(t, u, u̇, out)`.
type StateFn = Box<dyn Fn(f64, &[f64], &[f64], &mut [f64]) + Send + Sync>;
/// `f(t, u)`.
type ScalarFn = Box<dyn Fn(f64, &[f64]) -> f64 + Send + Sync>;

/// A small [`System`] defined by closures: a mass matrix, forces, the
/// constraints `Φ(t, u)` and their Jacobian `B` as a dense row-major
/// `m × n` matrix. Everything else comes from the [`System`] trait's
/// finite-difference defaults (`Φ_t`, the constraint Hessian, the
/// acceleration right-hand side, the force and mass Jacobians) unless given.
/// Dense patterns: meant for systems of tens of coordinates.
///
/// A bead of mass `m` on a straight wire through the origin that turns at the
/// rate `ω`, under gravity (`u = [x, y]`, `Φ = −x sin ωt + y cos ωt`):
///
/// ```
/// use mstar_model::{FnSystem, System};
///
/// let (m, g0, omega) = (0.5, 9.81, 2.0);
/// let bead = FnSystem::new(
///     vec![m, m],
///     1,
///     move |t, u, phi| {
///         let (s, c) = (omega * t).sin_cos();
///         phi[0] = -u[0] * s + u[1] * c;
///     },
///     move |t, _u, b| {
///         let (s, c) = (omega * t).sin_cos();
///         b.copy_from_slice(&[-s, c]);
///     },
/// )
/// .with_forces(move |_t, _u, _v, g| g.copy_from_slice(&[0.0, -m * g0]))
/// .with_potential(move |_t, u| m * g0 * u[1])
/// .with_names(&["x", "y"], &["wire"])?;
/// assert_eq!(bead.n_coords(), 2);
/// assert_eq!(bead.constraint_name(0), "wire");
/// # Ok::<(), mstar_model::NamesError>(())
/// ```
pub struct FnSystem {
    n: usize,
    m: usize,
    coord_names: Vec<String>,
    constraint_names: Vec<String>,
    /// `None`: the constant diagonal `diagonal`.
    mass: Option<PositionFn>,
    diagonal: Vec<f64>,
    forces: Option<StateFn>,
    phi: PositionFn,
    b: PositionFn,
    phi_t: Option<PositionFn>,
    potential: Option<ScalarFn>,
}

impl std::fmt::Debug for FnSystem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FnSystem")
            .field("n", &self.n)
            .field("m", &self.m)
            .field("coord_names", &self.coord_names)
            .field("constraint_names", &self.constraint_names)
            .finish_non_exhaustive()
    }
}

/// A name list of the wrong length given to [`FnSystem::with_names`].
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{got} {what} names given for {want} {what}s")]
pub struct NamesError {
    /// `"coordinate"` or `"constraint"`.
    pub what: &'static str,
    /// Names given.
    pub got: usize,
    /// Names needed.
    pub want: usize,
}

impl FnSystem {
    /// `n = mass.len()` coordinates with the constant diagonal mass matrix
    /// `diag(mass)`, `m` constraints `phi(t, u, Φ)` with the Jacobian
    /// `b(t, u, B)` written as a dense row-major `m × n` matrix; no forces
    /// until [`with_forces`](Self::with_forces).
    #[must_use]
    pub fn new(
        mass: Vec<f64>,
        m: usize,
        phi: impl Fn(f64, &[f64], &mut [f64]) + Send + Sync + 'static,
        b: impl Fn(f64, &[f64], &mut [f64]) + Send + Sync + 'static,
    ) -> Self {
        let n = mass.len();
        Self {
            n,
            m,
            coord_names: (0..n).map(|i| format!("u{i}")).collect(),
            constraint_names: (0..m).map(|i| format!("phi{i}")).collect(),
            mass: None,
            diagonal: mass,
            forces: None,
            phi: Box::new(phi),
            b: Box::new(b),
            phi_t: None,
            potential: None,
        }
    }

    /// A configuration-dependent mass matrix `mass(t, u, M)`, written as a
    /// dense row-major `n × n` matrix, instead of the constant diagonal.
    #[must_use]
    pub fn with_mass(
        mut self,
        mass: impl Fn(f64, &[f64], &mut [f64]) + Send + Sync + 'static,
    ) -> Self {
        self.mass = Some(Box::new(mass));
        self
    }

    /// The forces `forces(t, u, u̇, g)` (default: none).
    #[must_use]
    pub fn with_forces(
        mut self,
        forces: impl Fn(f64, &[f64], &[f64], &mut [f64]) + Send + Sync + 'static,
    ) -> Self {
        self.forces = Some(Box::new(forces));
        self
    }

    /// The analytic `Φ_t`, `phi_t(t, u, Φ_t)` (default: finite differences).
    #[must_use]
    pub fn with_phi_t(
        mut self,
        phi_t: impl Fn(f64, &[f64], &mut [f64]) + Send + Sync + 'static,
    ) -> Self {
        self.phi_t = Some(Box::new(phi_t));
        self
    }

    /// The potential energy of the forces, `potential(t, u)` (default: 0).
    #[must_use]
    pub fn with_potential(
        mut self,
        potential: impl Fn(f64, &[f64]) -> f64 + Send + Sync + 'static,
    ) -> Self {
        self.potential = Some(Box::new(potential));
        self
    }

    /// Names of the coordinates and the constraints.
    ///
    /// # Errors
    /// [`NamesError`] when a list does not have one name per coordinate or
    /// constraint.
    pub fn with_names(mut self, coords: &[&str], constraints: &[&str]) -> Result<Self, NamesError> {
        for (what, got, want) in [
            ("coordinate", coords.len(), self.n),
            ("constraint", constraints.len(), self.m),
        ] {
            if got != want {
                return Err(NamesError { what, got, want });
            }
        }
        self.coord_names = coords.iter().map(|s| (*s).to_string()).collect();
        self.constraint_names = constraints.iter().map(|s| (*s).to_string()).collect();
        Ok(self)
    }

    /// Every `(row, column)` of a dense `rows × cols` matrix, row-major.
    fn dense(rows: usize, cols: usize) -> Pattern {
        Pattern::from_entries(
            rows,
            cols,
            (0..rows)
                .flat_map(|i| (0..cols).map(move |j| (i, j)))
                .collect(),
        )
    }
}

impl System for FnSystem {
    dims::sizes_and_row_names!();

    fn coord_name(&self, i: usize) -> String {
        self.coord_names[i].clone()
    }

    fn mass_pattern(&self) -> Pattern {
        match self.mass {
            Some(_) => Self::dense(self.n, self.n),
            None => Pattern::diagonal(self.n),
        }
    }

    fn mass_is_constant(&self) -> bool {
        self.mass.is_none()
    }

    fn mass_into(&self, t: f64, u: &[f64], mass: &mut [f64]) {
        match &self.mass {
            Some(f) => f(t, u, mass),
            None => mass.copy_from_slice(&self.diagonal),
        }
    }

    fn forces_are_constant(&self) -> bool {
        self.forces.is_none()
    }

    fn forces_into(&self, t: f64, u: &[f64], v: &[f64], g: &mut [f64]) {
        match &self.forces {
            Some(f) => f(t, u, v, g),
            None => g.fill(0.0),
        }
    }

    fn phi_into(&self, t: f64, u: &[f64], phi: &mut [f64]) {
        (self.phi)(t, u, phi);
    }

    fn b_pattern(&self) -> Pattern {
        Self::dense(self.m, self.n)
    }

    fn b_into(&self, t: f64, u: &[f64], b: &mut [f64]) {
        (self.b)(t, u, b);
    }

    fn phi_t_into(&self, t: f64, u: &[f64], phi_t: &mut [f64]) {
        match &self.phi_t {
            Some(f) => f(t, u, phi_t),
            None => crate::fd::phi_t(self, t, u, phi_t),
        }
    }

    fn potential_energy(&self, t: f64, u: &[f64]) -> f64 {
        self.potential.as_ref().map_or(0.0, |f| f(t, u))
    }
}
