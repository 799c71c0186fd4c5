//! Static equilibrium: the pose at which a mechanism at rest stays at rest.
//!
//! With `u̇ = ü = 0` and the drivers held at `t₀`, the equations of motion
//! (paper eqs. 3-4, `M ü + Bᵀλ = g`, `Φ = 0`) become
//!
//! ```text
//! r(u, λ) = g(u, 0, t₀) − B(u, t₀)ᵀ λ = 0,     Φ(u, t₀) = 0,
//! ```
//!
//! solved by Newton's method on the KKT matrix of statics
//!
//! ```text
//! [ K_T + μ M   Bᵀ ] [Δu]   [ r ]
//! [ B           0  ] [Δλ] = [ −Φ ],    K_T = Σ λᵢ ∂²Φᵢ/∂u² − ∂g/∂u
//! ```
//!
//! (`mstar_linearize`'s matrix with `c_u = 1`, `c_v = c_bb = 0`, `c_a = μ`).
//! Plain Newton (`μ = 0`) is tried first. When its matrix is singular (a
//! pendulum released horizontally has `K_T = 0` along its swing) or its step
//! does not lower the merit `(‖r‖₂/F)² + (‖Φ‖₂/L)²` even after halving it
//! three times (each trial projected onto `Φ = 0`, with the multipliers of
//! the acceleration problem there), or moves a coordinate by more than
//! `L/2`, the step is damped by `μ M` (a Levenberg–Marquardt
//! regularization in the metric of the mass matrix: for large `μ` the step is
//! `M⁻¹ r / μ` projected onto the constraints, a steepest descent of the
//! potential energy), `μ` growing tenfold per failure from `10⁻⁶ ω²_ref`;
//! after a success plain Newton is tried first again. (`F` is the force
//! scale of the start, `L = max(1, ‖u₀‖∞)`, `ω²_ref = F / (L max|M|)`.) The
//! `System` trait has no hook to scale gravity and the
//! applied loads apart from the internal forces, so this damped Newton
//! replaces load stepping. When `μ` exceeds `10¹² ω²_ref` the residual
//! cannot be lowered: there is no equilibrium near the path taken.
//!
//! At a solution the plain matrix (`μ = 0`) is factored once more: when it
//! is singular the equilibrium is neutral along the null vector, found by
//! inverse iteration, and reported as such.

mod rewrite;
mod rows;
mod stability;

pub use rewrite::{RewriteError, model_text};
pub use stability::{Stability, stability};

use mstar_kkt::{KktError, KktOptions, KktSolver};
use mstar_linearize::{Coefficients, Linearization, LinearizeError};
use mstar_model::{StateRef, System};

/// Settings of [`solve`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EquilibriumOptions {
    /// The time at which drivers are held, s.
    pub t0: f64,
    /// Relative tolerance: converged when `‖r‖∞ ≤ tol · F` (`F` the force
    /// scale `max(‖g‖∞, ‖Bᵀλ‖∞, ‖λ‖∞)`) and `‖Φ‖∞ ≤ tol · L` (`L =
    /// max(1, ‖u₀‖∞)`).
    pub tol: f64,
    /// The most Newton steps tried, accepted or not.
    pub max_attempts: usize,
}

impl Default for EquilibriumOptions {
    fn default() -> Self {
        Self {
            t0: 0.0,
            tol: 1e-11,
            max_attempts: 300,
        }
    }
}

/// A static equilibrium found by [`solve`].
#[derive(Clone, Debug, PartialEq)]
pub struct Equilibrium {
    /// Coordinates `u`.
    pub u: Vec<f64>,
    /// Multipliers `λ` (the constraint forces are `Bᵀλ`).
    pub lambda: Vec<f64>,
    /// Newton steps accepted.
    pub iterations: usize,
    /// Of those, the steps damped by `μ M` (0: plain Newton throughout).
    pub damped: usize,
    /// `‖r‖∞` at the solution, N or N m.
    pub residual: f64,
    /// `‖Φ‖∞` at the solution.
    pub constraint: f64,
    /// The constraint rows left out of the solve because they depend on the
    /// others at the initial pose (redundant constraints; their multipliers
    /// are the minimum-norm ones), ascending; empty without.
    pub left_out: Vec<usize>,
    /// Whether it is stable, as [`solve`] checked it ([`stability()`]).
    pub stability: Stability,
}

impl Equilibrium {
    /// The state at rest as a sample at `t₀` (velocities and accelerations
    /// `zeros`, one per coordinate; energy the potential `potential`), for
    /// the columns `mstar run` writes.
    pub fn at_rest<'a>(
        &'a self,
        t0: f64,
        zeros: &'a [f64],
        potential: f64,
    ) -> crate::SampleRef<'a> {
        crate::SampleRef {
            t: t0,
            u: &self.u,
            v: zeros,
            a: zeros,
            lambda: &self.lambda,
            kinetic: 0.0,
            potential,
            iterations: self.iterations,
            residual: self.residual,
            constraint: self.constraint,
        }
    }
}

/// Why [`solve`] found no equilibrium.
#[derive(Debug, thiserror::Error)]
pub enum EquilibriumError {
    /// The system's declared patterns are inconsistent.
    #[error("the model's structure: {0}")]
    Structure(#[from] LinearizeError),
    /// The KKT matrix's structure could not be analysed.
    #[error("the KKT matrix: {0}")]
    Kkt(#[from] KktError),
    /// The residual could not be lowered to the tolerance.
    #[error(
        "no equilibrium found after {iterations} accepted Newton steps: ‖r‖∞ = {residual:.3e}, ‖Φ‖∞ = {constraint:.3e}; the generalized forces the constraints do not balance are largest at {}; a mechanism that keeps moving under its loads (an unbalanced free body, a torque larger than gravity can hold) has no equilibrium: add a constraint, a spring or a balancing load",
        list(unbalanced)
    )]
    NotFound {
        /// Accepted steps.
        iterations: usize,
        /// `‖r‖∞` at the last iterate.
        residual: f64,
        /// `‖Φ‖∞` at the last iterate.
        constraint: f64,
        /// The coordinates with the largest unbalanced generalized force
        /// `g − Bᵀλ` (λ of the acceleration problem `M ü + Bᵀλ = g`, `B ü
        /// = 0`), largest first, with its value.
        unbalanced: Vec<(String, f64)>,
    },
    /// Constraints that depend on the others at the initial pose (left out
    /// of the solve) do not hold at the pose found: they contradict the
    /// others.
    #[error(
        "the constraints {} are redundant at the initial pose (their equations depend on the others'), so the equilibrium was solved without them, but they do not hold at the pose found (‖Φ‖∞ = {violation:.3e}): a redundant joint must repeat what the others impose in every position (check its points); if the initial pose is a singular position of the mechanism (a parallelogram lying flat), start it away from there",
        .rows.join(", ")
    )]
    Contradicting {
        /// The violated rows, by name.
        rows: Vec<String>,
        /// `‖Φ‖∞` of all rows at the pose found.
        violation: f64,
    },
    /// A solution was found, but the tangent is singular there.
    #[error(
        "the equilibrium is neutral: the static tangent [K_T Bᵀ; B 0] is singular at the pose found, so it may move freely along the direction {} (nothing resists that motion: add a spring, a stop or a driver)",
        list(direction)
    )]
    Neutral {
        /// The pose found.
        equilibrium: Box<Equilibrium>,
        /// The coordinates the null vector moves, with its components
        /// (largest `1`), largest first.
        direction: Vec<(String, f64)>,
    },
}

/// `name = value, …` for an error message.
fn list(items: &[(String, f64)]) -> String {
    if items.is_empty() {
        return "(not resolved)".to_string();
    }
    let parts: Vec<String> = items
        .iter()
        .map(|(name, x)| format!("{name} ({x:.3e})"))
        .collect();
    parts.join(", ")
}

/// The buffers and scales of one solve.
struct Statics<'a, S: System + ?Sized> {
    sys: &'a S,
    lin: Linearization,
    solver: KktSolver,
    t0: f64,
    zeros: Vec<f64>,
    /// Force and length scales of the merit function.
    force: f64,
    /// The largest force scale of the iterates, for the convergence test.
    force_seen: f64,
    length: f64,
    /// `ω²_ref = F / (L m_max)`, 1/s², the unit of `μ`.
    omega2: f64,
    /// Every accepted step lowers the potential energy (up to round-off).
    descend: bool,
}

impl<'a, S: System + ?Sized> Statics<'a, S> {
    fn new(sys: &'a S, u0: &[f64], t0: f64) -> Result<Self, EquilibriumError> {
        let n = sys.n_coords();
        let mut lin = Linearization::new(sys)?;
        let solver = KktSolver::new(lin.kkt(), &KktOptions::default())?;
        let zeros = vec![0.0; n.max(sys.n_constraints())];
        let lambda0 = vec![0.0; sys.n_constraints()];
        let x = StateRef {
            t: t0,
            u: u0,
            v: &zeros[..n],
            a: &zeros[..n],
            lambda: &lambda0,
        };
        lin.eval_residual(sys, &x);
        let force = lin.force_scale().max(f64::MIN_POSITIVE);
        let length = u0.iter().fold(1.0_f64, |l, x| l.max(x.abs()));
        let m_max = lin.mass().iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        // Without forces or masses there is no natural scale: 1/s².
        let omega2 = if m_max > 0.0 && force > f64::MIN_POSITIVE {
            force / (length * m_max)
        } else {
            1.0
        };
        Ok(Self {
            sys,
            lin,
            solver,
            t0,
            zeros,
            force,
            force_seen: force,
            length,
            omega2,
            descend: false,
        })
    }

    /// Evaluates `r` and `Φ` at `(u, λ)`; returns the merit.
    fn merit(&mut self, u: &[f64], lambda: &[f64]) -> f64 {
        let x = at_rest(self.t0, &self.zeros, u, lambda);
        let (sys, lin) = (self.sys, &mut self.lin);
        lin.eval_residual(sys, &x);
        let r2: f64 = lin.r().iter().map(|r| r * r).sum();
        let p2: f64 = lin.phi().iter().map(|p| p * p).sum();
        r2 / (self.force * self.force) + p2 / (self.length * self.length)
    }

    /// Whether the last evaluation meets the tolerance. The force scale is
    /// the largest seen so far, not the current one: where a spring balances
    /// gravity the net forces `g` vanish, but their parts do not.
    fn converged(&mut self, tol: f64) -> bool {
        self.force_seen = self.force_seen.max(self.lin.force_scale());
        self.lin.residual_norm() <= tol * self.force_seen
            && self.lin.constraint_norm() <= tol * self.length
    }

    /// The multipliers of the acceleration problem `M ü + Bᵀλ = g`, `B ü =
    /// 0` at `u` (with `M* = M + BᵀB`, which is regular when `M` is on the
    /// constraints' null space): at an equilibrium `ü = 0` and these are its
    /// `λ`. Also returns `M ü = g − Bᵀλ`, the unbalanced generalized forces.
    fn acceleration_multipliers(&mut self, u: &[f64]) -> Option<(Vec<f64>, Vec<f64>)> {
        let (n, m) = (u.len(), self.sys.n_constraints());
        let lambda0 = vec![0.0; m];
        let x = at_rest(self.t0, &self.zeros, u, &lambda0);
        let (sys, lin) = (self.sys, &mut self.lin);
        lin.eval_residual(sys, &x);
        lin.eval_jacobians(sys, &x);
        lin.assemble(&Coefficients {
            c_bb: 1.0,
            ..Coefficients::acceleration()
        });
        let mut rhs = vec![0.0; n + m];
        rhs[..n].copy_from_slice(lin.g());
        self.solver.factor(&lin.kkt().values).ok()?;
        self.solver.solve_in_place(&mut rhs).ok()?;
        let lambda = rhs[n..].to_vec();
        self.merit(u, &lambda);
        Some((lambda, self.lin.r().to_vec()))
    }

    /// Moves `u` onto `Φ(u, t₀) = 0` by the minimum-norm Newton iteration
    /// on `[I Bᵀ; B 0]`, to round-off (`‖Φ‖∞ ≤ 10⁻¹⁴ L`, at most eight
    /// solves); returns whether it got there.
    fn project(&mut self, u: &mut [f64]) -> bool {
        let (n, m) = (u.len(), self.sys.n_constraints());
        let lambda0 = vec![0.0; m];
        for _ in 0..8 {
            let x = at_rest(self.t0, &self.zeros, u, &lambda0);
            let (sys, lin) = (self.sys, &mut self.lin);
            lin.eval_residual(sys, &x);
            if lin.constraint_norm() <= 1e-14 * self.length {
                return true;
            }
            lin.assemble(&Coefficients::projection());
            let mut rhs = vec![0.0; n + m];
            for (r, p) in rhs[n..].iter_mut().zip(lin.phi()) {
                *r = -p;
            }
            let solved = self.solver.factor(&lin.kkt().values).is_ok()
                && self.solver.solve_in_place(&mut rhs).is_ok();
            if !solved {
                return false;
            }
            for (x, d) in u.iter_mut().zip(&rhs[..n]) {
                *x += d;
            }
        }
        false
    }

    /// The Newton step `[Δu; Δλ]` with damping `μ`, from the last residual
    /// evaluation at `(u, λ)`; `None` when the matrix is singular.
    fn step(&mut self, u: &[f64], lambda: &[f64], mu: f64) -> Option<Vec<f64>> {
        let x = at_rest(self.t0, &self.zeros, u, lambda);
        let (sys, lin) = (self.sys, &mut self.lin);
        lin.eval_residual(sys, &x);
        lin.eval_jacobians(sys, &x);
        lin.assemble(&statics(mu));
        let mut rhs = vec![0.0; lin.kkt().n];
        let norm = lin.kkt_rhs(1.0, &mut rhs);
        self.solver.factor(&lin.kkt().values).ok()?;
        self.solver.solve_in_place_with_norm(&mut rhs, norm).ok()?;
        Some(rhs)
    }
}

/// The state at rest `(t₀, u, 0, 0, λ)`.
fn at_rest<'s>(t0: f64, zeros: &'s [f64], u: &'s [f64], lambda: &'s [f64]) -> StateRef<'s> {
    let n = u.len();
    StateRef {
        t: t0,
        u,
        v: &zeros[..n],
        a: &zeros[..n],
        lambda,
    }
}

/// The coefficients of the static KKT matrix `[K_T + μ M, Bᵀ; B, 0]`.
fn statics(mu: f64) -> Coefficients {
    Coefficients {
        c_u: 1.0,
        c_v: 0.0,
        c_a: mu,
        c_bb: 0.0,
        c_identity: 0.0,
        scale: 1.0,
    }
}

/// The static equilibrium of `sys` nearest (along the damped Newton path)
/// to the pose `u0`, with velocities zero and drivers held at
/// [`EquilibriumOptions::t0`].
///
/// # Errors
/// [`EquilibriumError::NotFound`] when the residual cannot be lowered to the
/// tolerance, naming the coordinates with the largest unbalanced
/// generalized forces; [`EquilibriumError::Neutral`] when the tangent is
/// singular at the solution; `Structure`/`Kkt` for a malformed model.
///
/// With redundant constraints (rows of `B` at `u0` that depend on the
/// others) it is solved on the independent rows, and the multipliers are
/// the minimum-norm ones of all rows (`rows.rs`);
/// [`EquilibriumError::Contradicting`] when a left-out row does not hold
/// at the pose found.
///
/// # Panics
/// If `u0` does not have one value per coordinate.
pub fn solve<S: System + ?Sized>(
    sys: &S,
    u0: &[f64],
    options: &EquilibriumOptions,
) -> Result<Equilibrium, EquilibriumError> {
    let found = solve_from(sys, u0, options, false);
    stability::stable_or_as_found(sys, found, options)
}

/// The search from `u0`, on the independent rows when some depend on the
/// others; with `descend`, every step lowers the potential energy (the
/// search away from an unstable equilibrium, `stability.rs`).
fn solve_from<S: System + ?Sized>(
    sys: &S,
    u0: &[f64],
    options: &EquilibriumOptions,
    descend: bool,
) -> Result<Equilibrium, EquilibriumError> {
    match crate::redundant::kept_if_dependent(sys, options.t0, u0) {
        Some(kept) => rows::solve_on_rows(sys, kept, u0, options, descend),
        None => solve_on(sys, u0, options, descend),
    }
}

/// [`solve_from`] with all rows of `sys`, which are independent.
fn solve_on<S: System + ?Sized>(
    sys: &S,
    u0: &[f64],
    options: &EquilibriumOptions,
    descend: bool,
) -> Result<Equilibrium, EquilibriumError> {
    let mut st = Statics::new(sys, u0, options.t0)?;
    st.descend = descend;
    let mut u = u0.to_vec();
    let mut lambda = st
        .acceleration_multipliers(&u)
        .map_or_else(|| vec![0.0; sys.n_constraints()], |(l, _)| l);
    let (mut iterations, mut damped) = (0, 0);
    // `μ` of the next trial; after a damped success the next iteration tries
    // plain Newton first and falls back to a tenth of the damping that
    // worked, so that Newton's quadratic convergence takes over near the
    // solution.
    let (mut mu, mut fallback) = (0.0_f64, 0.0_f64);
    let mut merit = st.merit(&u, &lambda);
    let mu_min = 1e-6 * st.omega2;
    let mu_max = 1e12 * st.omega2;
    for _ in 0..options.max_attempts {
        if st.converged(options.tol) {
            return finish(&mut st, u, lambda, iterations, damped);
        }
        let accepted = st
            .step(&u, &lambda, mu)
            .filter(|dx| within_reach(&dx[..u.len()], st.length))
            .and_then(|dx| line_search(&mut st, (&u, &lambda), &dx, (merit, mu > 0.0)));
        match accepted {
            Some((u1, l1, f1)) => {
                (u, lambda, merit) = (u1, l1, f1);
                iterations += 1;
                damped += usize::from(mu > 0.0);
                fallback = if mu / 10.0 < mu_min { 0.0 } else { mu / 10.0 };
                mu = 0.0;
            }
            None => {
                mu = if mu == 0.0 {
                    fallback.max(mu_min)
                } else {
                    10.0 * mu
                };
                if mu > mu_max {
                    break;
                }
                // The current iterate's residual again, for the convergence
                // test (the rejected trials were evaluated elsewhere).
                merit = st.merit(&u, &lambda);
            }
        }
    }
    Err(not_found(&mut st, &u, iterations))
}

/// Whether a step stays within half the length scale `L` in every
/// coordinate (m or rad): a longer one, taken where the tangent is nearly
/// singular, would jump past the nearest equilibrium (or wind a rotation
/// round many turns), so it is refused and the damping grows instead.
fn within_reach(du: &[f64], length: f64) -> bool {
    du.iter().all(|d| d.abs() <= 0.5 * length)
}

/// Tries the step `dx` at `α = 1, ½, ¼, ⅛`; the first that lowers the merit
/// gives the new `(u, λ, merit)`. Each trial pose is projected back onto
/// `Φ = 0` and its multipliers are those of the acceleration problem there,
/// so that the merit measures the generalized forces the constraints leave
/// unbalanced: a long damped step along a curved constraint (a pendulum
/// swinging down by a radian) would otherwise be judged by its linearization
/// error. Newton steps keep their quadratic convergence: their constraint
/// error is second order and so is the projection's correction. A damped
/// step is also taken when it lowers the potential energy (the model's
/// [`System::potential_energy`]): for large `μ` it descends the potential,
/// while the unbalanced force may grow on the way down (a double pendulum
/// released near horizontal). Any decrease is taken (no Armijo fraction of the merit): where `K_T` vanishes
/// along a direction (a pendulum held horizontally) a damped step lowers
/// the residual only at second order.
fn line_search<S: System + ?Sized>(
    st: &mut Statics<'_, S>,
    (u, lambda): (&[f64], &[f64]),
    dx: &[f64],
    (merit, damped): (f64, bool),
) -> Option<(Vec<f64>, Vec<f64>, f64)> {
    let n = u.len();
    let energy = st.sys.potential_energy(st.t0, u);
    let mut alpha = 1.0;
    for _ in 0..4 {
        let mut u1: Vec<f64> = u.iter().zip(&dx[..n]).map(|(x, d)| x + alpha * d).collect();
        let newton: Vec<f64> = lambda
            .iter()
            .zip(&dx[n..])
            .map(|(x, d)| x + alpha * d)
            .collect();
        let l1 = if st.project(&mut u1) {
            st.acceleration_multipliers(&u1).map_or(newton, |(l, _)| l)
        } else {
            newton
        };
        let f1 = st.merit(&u1, &l1);
        let e1 = st.sys.potential_energy(st.t0, &u1);
        let accepted = if st.descend {
            // Away from an unstable equilibrium: no step back up towards
            // it; near a minimum the energy changes at round-off only.
            let round_off = 1e-12 * energy.abs().max(st.force * st.length);
            e1 < energy || (f1 < merit && e1 <= energy + round_off)
        } else {
            f1 < merit || (damped && e1 < energy)
        };
        if f1.is_finite() && accepted {
            return Some((u1, l1, f1));
        }
        alpha *= 0.5;
    }
    None
}

/// The solution, once the plain tangent is checked for a null direction.
fn finish<S: System + ?Sized>(
    st: &mut Statics<'_, S>,
    u: Vec<f64>,
    lambda: Vec<f64>,
    iterations: usize,
    damped: usize,
) -> Result<Equilibrium, EquilibriumError> {
    st.merit(&u, &lambda);
    let (residual, constraint) = (st.lin.residual_norm(), st.lin.constraint_norm());
    let regular = st.step(&u, &lambda, 0.0).is_some();
    let eq = Equilibrium {
        u,
        lambda,
        iterations,
        damped,
        residual,
        constraint,
        left_out: Vec::new(),
        stability: Stability::Unchecked,
    };
    if regular {
        return Ok(eq);
    }
    let direction = null_direction(st, &eq.u, &eq.lambda);
    Err(EquilibriumError::Neutral {
        equilibrium: Box::new(eq),
        direction,
    })
}

/// The coordinates of the null vector of the static tangent at `(u, λ)`, by
/// three steps of inverse iteration on `[K_T + σ M, Bᵀ; B, 0]` with a small
/// shift `σ = 10⁻⁸ ω²_ref` (the unshifted matrix is singular): the `u` part
/// converges to the constrained mode of `K_T` nearest zero. Components of at
/// least a tenth of the largest, largest first.
fn null_direction<S: System + ?Sized>(
    st: &mut Statics<'_, S>,
    u: &[f64],
    lambda: &[f64],
) -> Vec<(String, f64)> {
    let (n, m) = (u.len(), lambda.len());
    let x = at_rest(st.t0, &st.zeros, u, lambda);
    let (sys, lin) = (st.sys, &mut st.lin);
    lin.eval_residual(sys, &x);
    lin.eval_jacobians(sys, &x);
    lin.assemble(&statics(1e-8 * st.omega2));
    if st.solver.factor(&lin.kkt().values).is_err() {
        return Vec::new();
    }
    // A start with every coordinate in it (a null vector orthogonal to it
    // would be missed; the golden-ratio sequence avoids symmetric ties).
    let mut w: Vec<f64> = (0..n)
        .map(|i| 0.5 + (i as f64 * 0.618_034).fract())
        .collect();
    for _ in 0..3 {
        let mut rhs = vec![0.0; n + m];
        rhs[..n].copy_from_slice(&w);
        if st.solver.solve_in_place(&mut rhs).is_err() {
            return Vec::new();
        }
        let big = rhs[..n].iter().fold(0.0_f64, |a, x| a.max(x.abs()));
        if !(big > 0.0 && big.is_finite()) {
            return Vec::new();
        }
        w = rhs[..n].iter().map(|x| x / big).collect();
    }
    largest(sys, &w, 0.1)
}

/// The coordinates whose `|w_i|` is at least `share` of the largest, largest
/// first, at most eight.
fn largest<S: System + ?Sized>(sys: &S, w: &[f64], share: f64) -> Vec<(String, f64)> {
    let big = w.iter().fold(0.0_f64, |a, x| a.max(x.abs()));
    let mut idx: Vec<usize> = (0..w.len())
        .filter(|&i| big > 0.0 && w[i].abs() >= share * big)
        .collect();
    idx.sort_by(|&a, &b| w[b].abs().total_cmp(&w[a].abs()));
    idx.truncate(8);
    idx.into_iter().map(|i| (sys.coord_name(i), w[i])).collect()
}

/// The failure, with the unbalanced generalized forces at the last iterate.
fn not_found<S: System + ?Sized>(
    st: &mut Statics<'_, S>,
    u: &[f64],
    iterations: usize,
) -> EquilibriumError {
    let sys = st.sys;
    let unbalanced = st
        .acceleration_multipliers(u)
        .map(|(_, r)| largest(sys, &r, 0.1))
        .unwrap_or_default();
    EquilibriumError::NotFound {
        iterations,
        residual: st.lin.residual_norm(),
        constraint: st.lin.constraint_norm(),
        unbalanced,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mstar_model::{Link, PendulumChain};

    /// A chain of three point masses on rods released at angles up to 80°
    /// hangs straight down: every `θ_k = 0`, the masses at `y_k = −Σ l_j`,
    /// each rod carrying the weight below it, `λ` for its `y` row being
    /// `−g₀ Σ_{j ≥ k} m_j` (the rod pulls up: `Bᵀλ = g` with `B`'s `y`
    /// entry `+1` for the mass at the rod's end). Tolerance: the solver's
    /// `10⁻¹¹` of forces ~ 60 N over a stiffness ≥ `g₀ m l` ~ 10, with room
    /// for the round-off of lengths of order one.
    #[test]
    fn chain_hangs_straight_down() {
        let links = vec![
            Link { m: 1.0, l: 1.0 },
            Link { m: 2.0, l: 0.5 },
            Link { m: 3.0, l: 0.8 },
        ];
        let g0 = 9.81;
        let sys = PendulumChain::new(links.clone(), g0);
        let u0 = sys.position(&[1.4, -0.6, 0.9]);
        let eq = solve(&sys, &u0, &EquilibriumOptions::default()).expect("an equilibrium");
        let mut y = 0.0;
        for (k, link) in links.iter().enumerate() {
            y -= link.l;
            let theta = eq.u[3 * k + 2].rem_euclid(std::f64::consts::TAU);
            let theta = theta.min(std::f64::consts::TAU - theta);
            assert!(eq.u[3 * k].abs() < 1e-9, "x_{k} = {}", eq.u[3 * k]);
            assert!(
                (eq.u[3 * k + 1] - y).abs() < 1e-9,
                "y_{k} = {}",
                eq.u[3 * k + 1]
            );
            assert!(theta < 1e-9, "θ_{k} = {theta}");
            let below: f64 = links[k..].iter().map(|l| l.m).sum();
            let want = -g0 * below;
            assert!(
                (eq.lambda[2 * k + 1] - want).abs() < 1e-8,
                "λ_{k}.y = {} (want {want})",
                eq.lambda[2 * k + 1]
            );
        }
    }

    /// Without gravity nothing acts: any pose is an equilibrium, and the
    /// swing of the pendulum is a neutral direction.
    #[test]
    fn weightless_pendulum_is_neutral() {
        let sys = PendulumChain::paper(1.0, 1.0, 0.0);
        let u0 = sys.position(&[0.3]);
        match solve(&sys, &u0, &EquilibriumOptions::default()) {
            Err(EquilibriumError::Neutral { direction, .. }) => {
                assert!(
                    direction.iter().any(|(name, _)| name == "theta"),
                    "{direction:?}"
                );
            }
            other => panic!("{other:?}"),
        }
    }
}
