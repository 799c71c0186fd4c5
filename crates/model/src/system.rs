//! The [`System`] trait: a constrained mechanical system in the notation of
//! `algorithm.md` §1 (the paper's eqs. 1-4).

use crate::{Pattern, fd};

/// A constrained mechanical system, the index-3 DAE (paper eqs. 3-4)
///
/// $$M(u)\,\ddot u + B(u,t)^\mathsf{T}\lambda = g(u,\dot u,t),\qquad \Phi(u,t) = 0.$$
///
/// Coordinates `u` (size [`n_coords`](System::n_coords)) are redundant absolute
/// coordinates; the constraints `Φ` (size [`n_constraints`](System::n_constraints))
/// are holonomic. `M` may be singular (the paper's point).
///
/// # Layers
///
/// **Required** (the equations themselves): the dimensions, `M` and its
/// pattern, the forces `g`, the constraints `Φ`, their Jacobian `B = ∂Φ/∂u`
/// and its pattern.
///
/// **Optional, with defaults** that analytic implementations override for
/// speed and accuracy:
/// - names: coordinates `u0, u1, …`, constraints `phi0, phi1, …`;
/// - the second-order terms the Newton iteration and the consistent start
///   need, by central finite differences of the required methods (step
///   `ε^{1/3} max(1, |x|)`, about 1e-10 relative accuracy; time derivatives
///   with step `ε^{1/3} max(1, |t|)` s, so override them for drivers faster
///   than about 10³ rad/s): `Φ_t` ([`phi_t_into`](System::phi_t_into)), the
///   contracted constraint Hessian ([`hessian_into`](System::hessian_into),
///   on the pattern of `B`'s row cliques), the acceleration right-hand side
///   ([`accel_rhs_into`](System::accel_rhs_into)), `∂g/∂u`, `∂g/∂u̇` and
///   `∂(M w)/∂u` (on dense patterns, empty when
///   [`forces_are_constant`](System::forces_are_constant) or
///   [`mass_is_constant`](System::mass_is_constant) say so);
/// - [`phi_b_into`](System::phi_b_into), `Φ` and `B` in one pass, with a
///   caller-owned workspace of [`workspace_len`](System::workspace_len);
/// - [`potential_energy`](System::potential_energy) (zero) for the energy
///   output.
///
/// The finite-difference defaults allocate scratch vectors and cost `O(n)`
/// evaluations of `B`, `g` or `M` per call: fine for small systems, override
/// them for large ones (the planar builder does). Check analytic overrides
/// with `mstar_linearize::check_derivatives` (`mstar::linearize` in the facade).
///
/// # Storage
///
/// Every matrix is declared once as a [`Pattern`] and then written, value by
/// value in pattern order, into a caller-owned buffer by the matching `*_into`
/// method. Implementations must write every value of the buffer (write `0.0`
/// for a structural entry that happens to vanish); analytic implementations
/// should not allocate (they run at every Newton iteration).
///
/// Sign convention: the constraint force is `Bᵀλ` on the left-hand side (eq. 1),
/// `B = ∂Φ/∂u`.
///
/// # Example: a bead on a rotating wire
///
/// A bead of mass `m` in the plane, `u = [x, y]`, on a straight wire through
/// the origin that turns at the rate `ω`: `Φ = −x sin ωt + y cos ωt` (a
/// rheonomic constraint, `Φ_t ≠ 0`). Only the required core is written; `Φ_t`,
/// the Hessian and the acceleration right-hand side come from the defaults.
///
/// ```
/// use mstar_model::{Pattern, System};
///
/// struct Bead { m: f64, omega: f64 }
///
/// impl System for Bead {
///     fn n_coords(&self) -> usize { 2 }
///     fn n_constraints(&self) -> usize { 1 }
///     fn mass_pattern(&self) -> Pattern { Pattern::diagonal(2) }
///     fn mass_into(&self, _t: f64, _u: &[f64], mass: &mut [f64]) { mass.fill(self.m) }
///     fn forces_into(&self, _t: f64, _u: &[f64], _v: &[f64], g: &mut [f64]) { g.fill(0.0) }
///     fn phi_into(&self, t: f64, u: &[f64], phi: &mut [f64]) {
///         let (s, c) = (self.omega * t).sin_cos();
///         phi[0] = -u[0] * s + u[1] * c;
///     }
///     fn b_pattern(&self) -> Pattern { Pattern::from_entries(1, 2, vec![(0, 0), (0, 1)]) }
///     fn b_into(&self, t: f64, _u: &[f64], b: &mut [f64]) {
///         let (s, c) = (self.omega * t).sin_cos();
///         b.copy_from_slice(&[-s, c]);
///     }
/// }
///
/// let bead = Bead { m: 1.0, omega: 2.0 };
/// // Φ_t = −ω (x cos ωt + y sin ωt): −2 at t = 0, u = [1, 0].
/// let mut phi_t = [0.0];
/// bead.phi_t_into(0.0, &[1.0, 0.0], &mut phi_t);
/// assert!((phi_t[0] + 2.0).abs() < 1e-9);
/// assert_eq!(bead.coord_name(1), "u1");
/// ```
pub trait System: Send + Sync {
    /// Number of generalized coordinates `n`.
    fn n_coords(&self) -> usize;

    /// Number of constraint equations `m`.
    fn n_constraints(&self) -> usize;

    /// Pattern of the `n × n` mass matrix `M` (both triangles).
    fn mass_pattern(&self) -> Pattern;

    /// Values of `M(u)` on [`mass_pattern`](System::mass_pattern).
    fn mass_into(&self, t: f64, u: &[f64], mass: &mut [f64]);

    /// Generalized forces `g(u, u̇, t)`: external, internal and complementary
    /// inertia forces (eq. 3), size `n`.
    fn forces_into(&self, t: f64, u: &[f64], v: &[f64], g: &mut [f64]);

    /// Constraint values `Φ(u, t)` (eq. 4), size `m`.
    fn phi_into(&self, t: f64, u: &[f64], phi: &mut [f64]);

    /// Pattern of the `m × n` constraint Jacobian `B = ∂Φ/∂u` (eq. 1).
    fn b_pattern(&self) -> Pattern;

    /// Values of `B(u, t)` on [`b_pattern`](System::b_pattern).
    fn b_into(&self, t: f64, u: &[f64], b: &mut [f64]);

    /// Name of coordinate `i`, used in output headers and error messages
    /// (default: `u<i>`).
    fn coord_name(&self, i: usize) -> String {
        format!("u{i}")
    }

    /// Name of constraint `i`, used in error messages, e.g. a redundant
    /// constraint (default: `phi<i>`).
    fn constraint_name(&self, i: usize) -> String {
        format!("phi{i}")
    }

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

    /// Whether the iteration matrix `S_T = c_u K_T + c_v C_T + c_a M` is
    /// symmetric at every state: `∂g/∂u` and `∂g/∂u̇` symmetric (conservative
    /// forces, dampers along a line) and `∂(M w)/∂u` zero. Velocity-dependent
    /// inertia forces, follower forces and a configuration-dependent `M`
    /// break it; KKT backends that need symmetry are then not used (default:
    /// `true` when both `M` and `g` are constant, else `false`).
    fn tangent_is_symmetric(&self) -> bool {
        self.mass_is_constant() && self.forces_are_constant()
    }

    /// Whether evaluating the Jacobians (the constraint Hessian contracted
    /// with `λ`, the force Jacobians) costs more than a solve and a product
    /// with the iteration matrix (default: `false`). An integrator carrying
    /// forward sensitivities evaluates them at every converged state; the
    /// next step's first factorization then takes those instead of
    /// evaluating them again at its predictor (`docs/analysis.md`,
    /// "Parameter sensitivities").
    fn jacobians_are_costly(&self) -> bool {
        false
    }

    /// Whether a fresh Jacobian at every step pays for itself in Newton
    /// iterations saved (default: `true`): `false` when evaluating the
    /// Jacobians costs several residuals, as second-order dual numbers do.
    /// The automatic Newton variant then keeps a factorization across
    /// steps (`Newton::resolve`; docs/performance.md, "Newton variant").
    fn fresh_jacobians_pay(&self) -> bool {
        true
    }

    /// Potential energy of the conservative forces in `g` (default: 0), for the
    /// energy output. Kinetic energy is `½ u̇ᵀ M u̇`.
    fn potential_energy(&self, _t: f64, _u: &[f64]) -> f64 {
        0.0
    }

    /// Whether the exact motion keeps the energy `½ u̇ᵀ M u̇ + V` constant
    /// (default: `false`): every force in `g` is an inertia force (which does
    /// no work) or derives from [`potential_energy`](System::potential_energy),
    /// and the constraints do not depend on time (no drivers). Integrators
    /// then report the energy drift of a run as a check of its accuracy
    /// (`docs/theory.md`, "Energy drift").
    fn conserves_energy(&self) -> bool {
        false
    }

    /// Length of the scratch buffer [`phi_b_into`](System::phi_b_into) uses
    /// (default: 0).
    fn workspace_len(&self) -> usize {
        0
    }

    /// `Φ` and `B` together, with a caller-owned scratch buffer of
    /// [`workspace_len`](System::workspace_len) values (default:
    /// [`phi_into`](System::phi_into) then [`b_into`](System::b_into));
    /// override when they share work.
    fn phi_b_into(&self, t: f64, u: &[f64], phi: &mut [f64], b: &mut [f64], _work: &mut [f64]) {
        self.phi_into(t, u, phi);
        self.b_into(t, u, b);
    }

    /// `Φ_t = ∂Φ/∂t`, size `m`; the velocity constraint is `B u̇ + Φ_t = 0`
    /// (default: central differences in `t`, exactly zero for scleronomic
    /// constraints).
    fn phi_t_into(&self, t: f64, u: &[f64], phi_t: &mut [f64]) {
        fd::phi_t(self, t, u, phi_t);
    }

    /// Pattern of the contracted constraint Hessian `Σᵢ μᵢ ∂²Φᵢ/∂u²` (`n × n`,
    /// both triangles) (default: every pair of coordinates that share a row of
    /// `B`, the structural pattern of any constraint Hessian).
    fn hessian_pattern(&self) -> Pattern {
        fd::row_cliques(&self.b_pattern())
    }

    /// Values of `Σᵢ μᵢ ∂²Φᵢ/∂u² = ∂(Bᵀμ)/∂u` on
    /// [`hessian_pattern`](System::hessian_pattern): the constraint part of `K_T`
    /// (eq. 6, `algorithm.md` §2) (default: central differences of `Bᵀμ`).
    fn hessian_into(&self, t: f64, u: &[f64], mu: &[f64], out: &mut [f64]) {
        fd::hessian(self, t, u, mu, out);
    }

    /// [`hessian_into`](System::hessian_into) with the caller-owned scratch
    /// buffer of [`workspace_len`](System::workspace_len) values that
    /// [`phi_b_into`](System::phi_b_into) uses (default: `hessian_into`);
    /// override when the two share work (a planar model's table of each
    /// body's `sin θ, cos θ`).
    fn hessian_with_work(&self, t: f64, u: &[f64], mu: &[f64], out: &mut [f64], _work: &mut [f64]) {
        self.hessian_into(t, u, mu, out);
    }

    /// [`hessian_with_work`](System::hessian_with_work) when `work` holds
    /// what [`phi_b_into`](System::phi_b_into) wrote at this same `(t, u)`
    /// and nothing has written to it since (the caller knows: a Newton
    /// iteration's Jacobians at the state of its residual). A system whose
    /// workspace is then a table of `u` reads it instead of computing it
    /// again (default: `hessian_with_work`).
    fn hessian_after_phi_b(
        &self,
        t: f64,
        u: &[f64],
        mu: &[f64],
        out: &mut [f64],
        work: &mut [f64],
    ) {
        self.hessian_with_work(t, u, mu, out, work);
    }

    /// The acceleration-level right-hand side `c = −(B u̇)_u u̇ − 2 B_t u̇ − Φ_tt`,
    /// so that the second time derivative of `Φ = 0` reads `B ü = c`
    /// (`algorithm.md` §6, consistent initialization). Size `m` (default:
    /// central differences of `B` and, in time, of `Φ`).
    fn accel_rhs_into(&self, t: f64, u: &[f64], v: &[f64], c: &mut [f64]) {
        fd::accel_rhs(self, t, u, v, c);
    }

    /// Pattern of `∂g/∂u` (default: empty when
    /// [`forces_are_constant`](System::forces_are_constant), else dense).
    fn forces_du_pattern(&self) -> Pattern {
        fd::dense_unless(self.forces_are_constant(), self.n_coords())
    }

    /// Values of `∂g/∂u` on [`forces_du_pattern`](System::forces_du_pattern)
    /// (default: central differences of `g`).
    fn forces_du_into(&self, t: f64, u: &[f64], v: &[f64], g_u: &mut [f64]) {
        fd::forces_du(self, t, u, v, g_u);
    }

    /// Pattern of `∂g/∂u̇` (default: empty when
    /// [`forces_are_constant`](System::forces_are_constant), else dense).
    /// `C_T = −∂g/∂u̇` (eq. 7).
    fn forces_dv_pattern(&self) -> Pattern {
        fd::dense_unless(self.forces_are_constant(), self.n_coords())
    }

    /// Values of `∂g/∂u̇` on [`forces_dv_pattern`](System::forces_dv_pattern)
    /// (default: central differences of `g`).
    fn forces_dv_into(&self, t: f64, u: &[f64], v: &[f64], g_v: &mut [f64]) {
        fd::forces_dv(self, t, u, v, g_v);
    }

    /// Pattern of `∂(M(u) w)/∂u` for a vector `w` (default: empty when
    /// [`mass_is_constant`](System::mass_is_constant), else dense).
    fn mass_du_pattern(&self) -> Pattern {
        fd::dense_unless(self.mass_is_constant(), self.n_coords())
    }

    /// Values of `∂(M(u) w)/∂u` on [`mass_du_pattern`](System::mass_du_pattern);
    /// part of `K_T` (eq. 6) when the mass matrix depends on the coordinates
    /// (default: central differences of `M w`).
    fn mass_du_into(&self, t: f64, u: &[f64], w: &[f64], out: &mut [f64]) {
        fd::mass_du(self, t, u, w, out);
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
