//! The [`System`] trait: a constrained mechanical system in the notation of
//! `algorithm.md` §1 (the paper's eqs. 1-4).

use crate::Pattern;

/// A constrained mechanical system, the index-3 DAE (paper eqs. 3-4)
///
/// $$M(u)\,\ddot u + B(u,t)^\mathsf{T}\lambda = g(u,\dot u,t),\qquad \Phi(u,t) = 0.$$
///
/// Coordinates `u` (size [`n_coords`](System::n_coords)) are redundant absolute
/// coordinates; the constraints `Φ` (size [`n_constraints`](System::n_constraints))
/// are holonomic. `M` may be singular (the paper's point).
///
/// Every matrix is declared once as a [`Pattern`] and then written, value by
/// value in pattern order, into a caller-owned buffer by the matching `*_into`
/// method: nothing is allocated per call. Implementations must write every value
/// of the buffer (write `0.0` for a structural entry that happens to vanish).
///
/// Sign convention: the constraint force is `Bᵀλ` on the left-hand side (eq. 1),
/// `B = ∂Φ/∂u`.
pub trait System: Send + Sync {
    /// Number of generalized coordinates `n`.
    fn n_coords(&self) -> usize;

    /// Number of constraint equations `m`.
    fn n_constraints(&self) -> usize;

    /// Name of coordinate `i` (used in output headers and error messages).
    fn coord_name(&self, i: usize) -> String;

    /// Name of constraint `i` (used in error messages, e.g. a redundant constraint).
    fn constraint_name(&self, i: usize) -> String;

    /// Pattern of the `n × n` mass matrix `M` (both triangles).
    fn mass_pattern(&self) -> Pattern;

    /// Values of `M(u)` on [`mass_pattern`](System::mass_pattern).
    fn mass_into(&self, t: f64, u: &[f64], mass: &mut [f64]);

    /// Whether `M` depends on neither `u` nor `t` (default: `false`). When it
    /// does not, callers may evaluate it once; `∂(M ü)/∂u` must then be zero.
    fn mass_is_constant(&self) -> bool {
        false
    }

    /// Whether `g` depends on none of `u`, `u̇`, `t` (default: `false`). When
    /// it does not, callers may evaluate it once; `∂g/∂u` and `∂g/∂u̇` must then
    /// be zero.
    fn forces_are_constant(&self) -> bool {
        false
    }

    /// Generalized forces `g(u, u̇, t)`: external, internal and complementary
    /// inertia forces (eq. 3), size `n`.
    fn forces_into(&self, t: f64, u: &[f64], v: &[f64], g: &mut [f64]);

    /// Pattern of `∂g/∂u` (default: empty, forces independent of `u`).
    fn forces_du_pattern(&self) -> Pattern {
        Pattern::new(self.n_coords(), self.n_coords())
    }

    /// Values of `∂g/∂u` on [`forces_du_pattern`](System::forces_du_pattern).
    fn forces_du_into(&self, _t: f64, _u: &[f64], _v: &[f64], _g_u: &mut [f64]) {}

    /// Pattern of `∂g/∂u̇` (default: empty, no damping). `C_T = −∂g/∂u̇` (eq. 7).
    fn forces_dv_pattern(&self) -> Pattern {
        Pattern::new(self.n_coords(), self.n_coords())
    }

    /// Values of `∂g/∂u̇` on [`forces_dv_pattern`](System::forces_dv_pattern).
    fn forces_dv_into(&self, _t: f64, _u: &[f64], _v: &[f64], _g_v: &mut [f64]) {}

    /// Pattern of `∂(M(u) w)/∂u` for a vector `w` (default: empty, constant `M`).
    fn mass_du_pattern(&self) -> Pattern {
        Pattern::new(self.n_coords(), self.n_coords())
    }

    /// Values of `∂(M(u) w)/∂u` on [`mass_du_pattern`](System::mass_du_pattern); part
    /// of `K_T` (eq. 6) when the mass matrix depends on the coordinates.
    fn mass_du_into(&self, _t: f64, _u: &[f64], _w: &[f64], _out: &mut [f64]) {}

    /// Constraint values `Φ(u, t)` (eq. 4), size `m`.
    fn phi_into(&self, t: f64, u: &[f64], phi: &mut [f64]);

    /// Pattern of the `m × n` constraint Jacobian `B = ∂Φ/∂u` (eq. 1).
    fn b_pattern(&self) -> Pattern;

    /// Values of `B(u, t)` on [`b_pattern`](System::b_pattern).
    fn b_into(&self, t: f64, u: &[f64], b: &mut [f64]);

    /// `Φ` and `B` together (default: [`phi_into`](System::phi_into) then
    /// [`b_into`](System::b_into)); override when they share work.
    fn phi_b_into(&self, t: f64, u: &[f64], phi: &mut [f64], b: &mut [f64]) {
        self.phi_into(t, u, phi);
        self.b_into(t, u, b);
    }

    /// `Φ_t = ∂Φ/∂t`, size `m` (default: zero, scleronomic constraints). The
    /// velocity constraint is `B u̇ + Φ_t = 0`.
    fn phi_t_into(&self, _t: f64, _u: &[f64], phi_t: &mut [f64]) {
        phi_t.fill(0.0);
    }

    /// Pattern of the contracted constraint Hessian `Σᵢ μᵢ ∂²Φᵢ/∂u²` (`n × n`,
    /// both triangles).
    fn hessian_pattern(&self) -> Pattern;

    /// Values of `Σᵢ μᵢ ∂²Φᵢ/∂u² = ∂(Bᵀμ)/∂u` on
    /// [`hessian_pattern`](System::hessian_pattern): the constraint part of `K_T`
    /// (eq. 6, `algorithm.md` §2).
    fn hessian_into(&self, t: f64, u: &[f64], mu: &[f64], out: &mut [f64]);

    /// The acceleration-level right-hand side `c = −(B u̇)_u u̇ − 2 B_t u̇ − Φ_tt`,
    /// so that the second time derivative of `Φ = 0` reads `B ü = c`
    /// (`algorithm.md` §6, consistent initialization). Size `m`.
    fn accel_rhs_into(&self, t: f64, u: &[f64], v: &[f64], c: &mut [f64]);

    /// Potential energy of the conservative forces in `g` (default: 0), for the
    /// energy output. Kinetic energy is `½ u̇ᵀ M u̇`.
    fn potential_energy(&self, _t: f64, _u: &[f64]) -> f64 {
        0.0
    }
}

/// Names of all coordinates of `sys`, in order.
pub fn coord_names<S: System + ?Sized>(sys: &S) -> Vec<String> {
    (0..sys.n_coords()).map(|i| sys.coord_name(i)).collect()
}

/// Names of all constraints of `sys`, in order.
pub fn constraint_names<S: System + ?Sized>(sys: &S) -> Vec<String> {
    (0..sys.n_constraints())
        .map(|i| sys.constraint_name(i))
        .collect()
}

/// Kinetic energy `½ u̇ᵀ M u̇` from mass values on `pattern`.
#[must_use]
pub fn kinetic_energy(pattern: &Pattern, mass: &[f64], v: &[f64]) -> f64 {
    0.5 * pattern
        .entries
        .iter()
        .zip(mass)
        .map(|(&(i, j), &m)| v[i] * m * v[j])
        .sum::<f64>()
}
