//! The predictor-corrector Newton loop (paper §2.2, Fig. 2; `algorithm.md` §4),
//! initial conditions (§3, §6) and step control.

use mstar_kkt::{Backend, KktError, KktSolver};
use mstar_linearize::{Coefficients, Linearization, max_abs};
use mstar_model::{Sample, System, kinetic_energy};

use crate::{AlphaParams, Config, IntegrationError, Newton, Observer, Predictor, RunStats, Start};

/// What the initialization did, for the run summary.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StartReport {
    /// `‖Φ(u₀)‖∞` of the state as given.
    pub position_violation: f64,
    /// `‖B u̇₀ + Φ_t‖∞` of the state as given.
    pub velocity_violation: f64,
    /// How far projection moved each coordinate (all zero when nothing moved).
    pub position_correction: Vec<f64>,
    /// How far projection changed each velocity.
    pub velocity_correction: Vec<f64>,
    /// The third time derivative estimate `u⃛₀` used for the Arnold-Brüls start
    /// (empty when not used).
    pub jerk: Vec<f64>,
    /// The `O(h²)` starting velocity correction `δu̇` (normal to the constraints)
    /// that puts the start on the discrete solution (empty when not used).
    pub velocity_start_correction: Vec<f64>,
}

/// Why one attempt at a step failed (before step control decides).
enum Failure {
    NotConverged {
        iterations: usize,
        residual: f64,
        residual_tol: f64,
        constraint: f64,
        constraint_tol: f64,
    },
    NonFinite(String),
    Kkt(KktError),
}

/// The state at one time: `u, u̇, ü, λ` and the generalized-α acceleration-like
/// variable.
#[derive(Clone, Debug, Default)]
struct State {
    u: Vec<f64>,
    v: Vec<f64>,
    a: Vec<f64>,
    /// The acceleration-like variable `a` of Arnold & Brüls (2007); equals `ü`
    /// for Newmark.
    a_alpha: Vec<f64>,
    lambda: Vec<f64>,
}

impl State {
    fn zeros(n: usize, m: usize) -> Self {
        Self {
            u: vec![0.0; n],
            v: vec![0.0; n],
            a: vec![0.0; n],
            a_alpha: vec![0.0; n],
            lambda: vec![0.0; m],
        }
    }
}

/// Integrates a [`System`] in time with the configured scheme: Newmark /
/// HHT-α / generalized-α, Newton-Raphson on the KKT system (16), step control.
///
/// ```
/// use mstar_model::PendulumChain;
/// use mstar_newmark::{Config, Integrator, Trajectory};
///
/// let sys = PendulumChain::paper(1.0, 1.0, 9.81);
/// let u0 = sys.position(&[std::f64::consts::FRAC_PI_2]);
/// let mut integ = Integrator::new(&sys, Config::default(), 0.0, &u0, &[0.0; 3])?;
/// let mut traj = Trajectory::default();
/// let stats = integ.run(1.0, &mut traj)?;
/// assert_eq!(stats.steps, 100);
/// assert_eq!(traj.samples.len(), 101);
/// # Ok::<(), mstar_newmark::IntegrationError>(())
/// ```
pub struct Integrator<'s, S: System + ?Sized> {
    sys: &'s S,
    config: Config,
    p: AlphaParams,
    lin: Linearization,
    solver: KktSolver,
    t: f64,
    state: State,
    trial: State,
    /// The state before the last accepted step and that step's size (for the
    /// extrapolating predictor).
    previous: State,
    previous_h: Option<f64>,
    rhs: Vec<f64>,
    /// Current nominal step size (≤ config.h).
    h: f64,
    /// The step size the current factorization was made for.
    factored_h: Option<f64>,
    easy_steps: usize,
    /// Time bookkeeping without drift: `t = t_anchor + steps_at_h · h_anchor`.
    t_anchor: f64,
    h_anchor: f64,
    steps_at_h: u64,
    stats: RunStats,
    start: StartReport,
    residual: f64,
    constraint: f64,
    iterations: usize,
    observed_start: bool,
}

impl<S: System + ?Sized> std::fmt::Debug for Integrator<'_, S> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Integrator")
            .field("t", &self.t)
            .field("h", &self.h)
            .field("config", &self.config)
            .field("stats", &self.stats)
            .finish_non_exhaustive()
    }
}

impl<'s, S: System + ?Sized> Integrator<'s, S> {
    /// Prepares the integration of `sys` from `(u₀, u̇₀)` at `t0`: checks the
    /// configuration and the system's structure, analyses the KKT pattern once,
    /// checks (and if allowed projects) the initial state, and computes the
    /// initial accelerations and multipliers as [`Config::start`] says.
    ///
    /// # Errors
    /// [`IntegrationError`] for an invalid configuration or structure, wrong
    /// dimensions, an inconsistent initial state (with projection off), or a
    /// singular initial system.
    pub fn new(
        sys: &'s S,
        config: Config,
        t0: f64,
        u0: &[f64],
        v0: &[f64],
    ) -> Result<Self, IntegrationError> {
        let p = config.validate()?;
        let (n, m) = (sys.n_coords(), sys.n_constraints());
        for (what, got) in [("u0", u0.len()), ("v0", v0.len())] {
            if got != n {
                return Err(IntegrationError::Dimension { what, got, want: n });
            }
        }
        if let Start::Paper { lambda0 } = &config.start
            && lambda0.len() != m
        {
            return Err(IntegrationError::Dimension {
                what: "lambda0",
                got: lambda0.len(),
                want: m,
            });
        }
        let (lin, solver) = linear_algebra(sys, &config, t0, u0, v0)?;
        let h = config.h;
        let mut this = Self {
            sys,
            p,
            lin,
            solver,
            t: t0,
            state: State::zeros(n, m),
            trial: State::zeros(n, m),
            previous: State::zeros(n, m),
            previous_h: None,
            rhs: vec![0.0; n + m],
            h,
            factored_h: None,
            easy_steps: 0,
            t_anchor: t0,
            h_anchor: h,
            steps_at_h: 0,
            stats: RunStats {
                h_min_used: h,
                t: t0,
                ..RunStats::default()
            },
            start: StartReport::default(),
            residual: 0.0,
            constraint: 0.0,
            iterations: 0,
            observed_start: false,
            config,
        };
        this.state.u.copy_from_slice(u0);
        this.state.v.copy_from_slice(v0);
        this.check_finite_start()?;
        this.make_consistent_positions()?;
        this.initial_acceleration()?;
        // The state's own residual and constraint norms, for the t0 sample.
        let s = &this.state;
        this.lin.eval_residual(sys, t0, &s.u, &s.v, &s.a, &s.lambda);
        this.residual = this.lin.residual_norm();
        this.constraint = this.lin.constraint_norm();
        Ok(this)
    }

    /// The Newton variant in use.
    #[must_use]
    pub fn newton(&self) -> Newton {
        self.config.newton
    }

    /// The KKT backend in use ([`Backend::Auto`] resolved).
    #[must_use]
    pub fn backend(&self) -> Backend {
        self.solver.backend()
    }

    /// Current time.
    #[must_use]
    pub fn time(&self) -> f64 {
        self.t
    }

    /// Counters so far.
    #[must_use]
    pub fn stats(&self) -> RunStats {
        self.stats
    }

    /// What the initialization did.
    #[must_use]
    pub fn start_report(&self) -> &StartReport {
        &self.start
    }

    /// The scheme's parameters in use.
    #[must_use]
    pub fn params(&self) -> AlphaParams {
        self.p
    }

    /// The current state as a [`Sample`] (energies, last Newton figures).
    #[must_use]
    pub fn sample(&self) -> Sample {
        let s = &self.state;
        Sample {
            t: self.t,
            u: s.u.clone(),
            v: s.v.clone(),
            a: s.a.clone(),
            lambda: s.lambda.clone(),
            kinetic: kinetic_energy(self.lin.mass_pattern(), &self.lin.mass, &s.v),
            potential: self.sys.potential_energy(self.t, &s.u),
            iterations: self.iterations,
            residual: self.residual,
            constraint: self.constraint,
        }
    }

    /// Integrates to `t_end`, handing the initial state (on the first call) and
    /// every accepted step to `observer`.
    ///
    /// # Errors
    /// The first [`IntegrationError`] of a step that even step control could not
    /// save; every step accepted before it has been observed.
    pub fn run(
        &mut self,
        t_end: f64,
        observer: &mut dyn Observer,
    ) -> Result<RunStats, IntegrationError> {
        if !self.observed_start {
            observer.observe(&self.sample());
            self.observed_start = true;
        }
        while !self.reached(t_end) {
            self.step(t_end)?;
            observer.observe(&self.sample());
        }
        Ok(self.stats)
    }

    /// Whether the integration has reached `t_end` (within `1e-9 h`).
    #[must_use]
    pub fn reached(&self, t_end: f64) -> bool {
        t_end - self.t <= 1e-9 * self.config.h
    }

    /// Takes one accepted step towards `t_end` (shortened to land on it),
    /// rejecting and retrying with `h/2` while Newton fails and `h/2 ≥ h_min`,
    /// and regrowing `h` (never beyond [`Config::h`]) after a run of easy steps.
    ///
    /// # Errors
    /// [`IntegrationError::NewtonFailed`], [`IntegrationError::NonFinite`] or
    /// [`IntegrationError::Kkt`] when step control is off (`h_min = h`), and
    /// [`IntegrationError::StepSizeTooSmall`] when it gives up.
    pub fn step(&mut self, t_end: f64) -> Result<(), IntegrationError> {
        let h_min = self.config.h_min();
        let mut h = self.h;
        let mut retried_fresh = false;
        loop {
            let remaining = t_end - self.t;
            // Land on t_end without a tiny last step: the last one or two steps
            // share what remains.
            let h_try = if remaining <= h * (1.0 + 1e-9) {
                remaining
            } else if remaining < 2.0 * h {
                0.5 * remaining
            } else {
                h
            };
            let factorizations_before = self.stats.factorizations;
            match self.attempt(h_try) {
                Ok(iterations) => {
                    self.accept(h_try, iterations);
                    return Ok(());
                }
                Err(failure) => {
                    let fresh = self.stats.factorizations > factorizations_before;
                    let stale_jacobian = matches!(self.config.newton, Newton::Modified { .. })
                        && !(fresh && self.factorized_every_iteration());
                    if stale_jacobian && !retried_fresh {
                        // Retry the same step with a Jacobian evaluated here.
                        self.factored_h = None;
                        retried_fresh = true;
                        self.stats.rejected += 1;
                        continue;
                    }
                    if h * 0.5 >= h_min * (1.0 - 1e-12) {
                        h *= 0.5;
                        self.h = h;
                        self.easy_steps = 0;
                        self.factored_h = None;
                        retried_fresh = false;
                        self.stats.rejected += 1;
                        continue;
                    }
                    return Err(self.failure_error(failure, h_try, h_min));
                }
            }
        }
    }

    fn factorized_every_iteration(&self) -> bool {
        matches!(self.config.newton, Newton::Full)
    }

    fn failure_error(&self, failure: Failure, h: f64, h_min: f64) -> IntegrationError {
        let t = self.step_end(h);
        let step_control = h_min < self.config.h;
        match failure {
            Failure::NotConverged {
                iterations,
                residual,
                residual_tol,
                constraint,
                constraint_tol,
            } => {
                if step_control {
                    IntegrationError::StepSizeTooSmall {
                        t: self.t,
                        h,
                        h_min,
                        residual,
                        constraint,
                    }
                } else {
                    IntegrationError::NewtonFailed {
                        t,
                        h,
                        iterations,
                        residual,
                        residual_tol,
                        constraint,
                        constraint_tol,
                    }
                }
            }
            Failure::NonFinite(what) => IntegrationError::NonFinite { t, what },
            Failure::Kkt(source) => self.kkt_error("factoring the iteration matrix", t, h, source),
        }
    }

    /// Names the unknown of a KKT error.
    fn kkt_error(
        &self,
        context: &'static str,
        t: f64,
        h: f64,
        source: KktError,
    ) -> IntegrationError {
        let n = self.sys.n_coords();
        let unknown = match source {
            KktError::Singular { unknown: Some(k) } if k < n => {
                Some(format!("coordinate '{}'", self.sys.coord_name(k)))
            }
            KktError::Singular { unknown: Some(k) } if k < self.solver.dim() => Some(format!(
                "the multiplier of constraint '{}'",
                self.sys.constraint_name(k - n)
            )),
            _ => None,
        };
        IntegrationError::Kkt {
            context,
            t,
            h,
            unknown,
            source,
        }
    }

    fn accept(&mut self, h: f64, iterations: usize) {
        // Buffers change roles instead of being copied: the predictor rewrites
        // every field of `trial` before it is read again.
        if self.config.predictor == Predictor::Extrapolated {
            std::mem::swap(&mut self.previous, &mut self.state);
            self.previous_h = Some(h);
        }
        std::mem::swap(&mut self.state, &mut self.trial);
        if h == self.h_anchor {
            self.steps_at_h += 1;
        } else {
            (self.t_anchor, self.h_anchor, self.steps_at_h) = (self.t, h, 1);
        }
        self.t = self.t_anchor + self.steps_at_h as f64 * self.h_anchor;
        self.residual = self.lin.residual_norm();
        self.constraint = self.lin.constraint_norm();
        self.iterations = iterations;
        let st = &mut self.stats;
        st.steps += 1;
        st.max_iterations = st.max_iterations.max(iterations);
        st.h_min_used = st.h_min_used.min(h);
        st.t = self.t;
        // A step that needed many iterations with a reused Jacobian asks for a
        // fresh one at the next step.
        if iterations > 4 {
            self.factored_h = None;
        }
        // Regrow h after a run of easy steps. With a fresh Jacobian at every
        // iteration a resolved step takes one correction (two at most); more
        // means the predictor is far off, i.e. the motion is fast for this h,
        // and regrowing would step straight back into it (a whip).
        let easy = match self.config.newton {
            Newton::Full => 2,
            Newton::Modified { .. } => (self.config.max_iterations / 4).max(3),
        };
        if iterations <= easy {
            self.easy_steps += 1;
        } else {
            self.easy_steps = 0;
        }
        if self.easy_steps >= 5 && self.h < self.config.h {
            self.h = (2.0 * self.h).min(self.config.h);
            self.easy_steps = 0;
        }
    }

    /// One Newton attempt at the step `t → t + h`; returns the iterations.
    fn attempt(&mut self, h: f64) -> Result<usize, Failure> {
        let beta = self.p.beta;
        let t1 = self.step_end(h);
        self.predict(h);
        // Corrector factors (15): Δü = β' Δu, Δu̇ = γ' Δu.
        let coefficients = self.p.coefficients(h, self.config.scaling);
        let (beta_p, gamma_p) = (coefficients.c_a, coefficients.c_v);
        let a_p = 1.0 / (beta * h * h);
        let n = self.sys.n_coords();
        let max_rate = match self.config.newton {
            Newton::Modified { max_rate } => max_rate,
            Newton::Full => f64::INFINITY,
        };
        let mut force_refactor = false;
        let mut previous_step = f64::INFINITY;
        // ‖u‖∞ of the iterate, kept up to date by the corrector's loop.
        let mut u_max = max_abs(&self.trial.u);
        for k in 0..=self.config.max_iterations {
            let s = &self.trial;
            // r is formed straight into the right-hand side of (16).
            let rhs_norm = self.lin.eval_kkt_rhs(
                self.sys,
                t1,
                &s.u,
                &s.v,
                &s.a,
                &s.lambda,
                coefficients.scale,
                &mut self.rhs,
            );
            let residual = self.lin.residual_norm();
            let constraint = self.lin.constraint_norm();
            if !residual.is_finite() || !constraint.is_finite() {
                return Err(Failure::NonFinite(self.locate_non_finite()));
            }
            // Without the exact multiplier update (the paper's scheme) each
            // correction shifts λ by c_bb·Φ, so round-off in Φ (ε‖u‖) comes back
            // as a residual floor c_bb·ε·‖u‖·‖B‖ ~ 4ε‖u‖/h²: the tolerance cannot
            // ask for less than that.
            let floor = if self.config.exact_multiplier_update {
                0.0
            } else {
                4.0 * coefficients.c_bb * f64::EPSILON * u_max.max(1.0) * max_abs(&self.lin.b)
            };
            let residual_tol = (self.config.tol * self.lin.force_scale()).max(floor);
            let constraint_tol = self.config.tol * u_max.max(1.0);
            self.stats.iterations += usize::from(k > 0);
            // At least one correction: a predictor that happens to meet the
            // tolerances (small h, near rest) still needs its λ and ü updated.
            if k > 0 && residual <= residual_tol && constraint <= constraint_tol {
                return Ok(k);
            }
            if k == self.config.max_iterations {
                return Err(Failure::NotConverged {
                    iterations: k,
                    residual,
                    residual_tol,
                    constraint,
                    constraint_tol,
                });
            }
            let refactor = match self.config.newton {
                Newton::Full => true,
                Newton::Modified { .. } => force_refactor || self.factored_h != Some(h),
            };
            if refactor {
                let s = &self.trial;
                self.lin
                    .eval_jacobians(self.sys, t1, &s.u, &s.v, &s.a, &s.lambda);
                self.lin.assemble(&coefficients);
                self.factored_h = None;
                self.solver
                    .factor(&self.lin.kkt().values)
                    .map_err(Failure::Kkt)?;
                self.factored_h = Some(h);
                self.stats.factorizations += 1;
                force_refactor = false;
                previous_step = f64::INFINITY;
            }
            self.solver
                .solve_in_place_with_norm(&mut self.rhs, rhs_norm)
                .map_err(Failure::Kkt)?;
            // Corrector (15).
            let (du, dl) = self.rhs.split_at(n);
            let s = &mut self.trial;
            let mut step = 0.0f64;
            u_max = 0.0;
            for i in 0..n {
                s.u[i] += du[i];
                s.v[i] += gamma_p * du[i];
                s.a[i] += beta_p * du[i];
                s.a_alpha[i] += a_p * du[i];
                u_max = u_max.max(s.u[i].abs());
                step = step.max(du[i].abs());
            }
            // With M* in S_T (eq. 17) the solve returns Δλ + c_bb Φ (see
            // `Config::exact_multiplier_update`), without the BᵀB term (Schur
            // backend, `Linearization::with_augmentation`) it returns Δλ; the
            // paper keeps the shift c_bb Φ, the exact update does not.
            let in_matrix = if self.lin.augmented() {
                coefficients.c_bb
            } else {
                0.0
            };
            let kept = if self.config.exact_multiplier_update {
                0.0
            } else {
                coefficients.c_bb
            };
            let shift = kept - in_matrix;
            for ((l, &d), &phi) in s.lambda.iter_mut().zip(dl).zip(&self.lin.phi) {
                *l += d / coefficients.scale + shift * phi;
            }
            if step > max_rate * previous_step {
                force_refactor = true;
            }
            previous_step = step;
        }
        unreachable!("the loop returns at k = max_iterations")
    }

    /// The time at the end of a step of size `h` (as [`accept`](Self::accept) will
    /// set it).
    fn step_end(&self, h: f64) -> f64 {
        if h == self.h_anchor {
            self.t_anchor + (self.steps_at_h + 1) as f64 * h
        } else {
            self.t + h
        }
    }

    /// Predictor: eq. (14) generalized (Arnold & Brüls 2007, Algorithm 1).
    fn predict(&mut self, h: f64) {
        let AlphaParams {
            alpha_m,
            alpha_f,
            beta,
            gamma,
        } = self.p;
        let (s, t) = (&self.state, &mut self.trial);
        // Linear extrapolation needs the previous step (of any size).
        let ratio = match (self.config.predictor, self.previous_h) {
            (Predictor::Extrapolated, Some(h_prev)) => h / h_prev,
            _ => 0.0,
        };
        for i in 0..s.u.len() {
            let a1 = match self.config.predictor {
                Predictor::ZeroAcceleration => 0.0,
                Predictor::ConstantAcceleration => s.a[i],
                Predictor::Extrapolated => s.a[i] + ratio * (s.a[i] - self.previous.a[i]),
            };
            let aa1 = (alpha_f * s.a[i] - alpha_m * s.a_alpha[i] + (1.0 - alpha_f) * a1)
                / (1.0 - alpha_m);
            t.a[i] = a1;
            t.a_alpha[i] = aa1;
            t.v[i] = s.v[i] + h * ((1.0 - gamma) * s.a_alpha[i] + gamma * aa1);
            t.u[i] = s.u[i] + h * s.v[i] + h * h * ((0.5 - beta) * s.a_alpha[i] + beta * aa1);
        }
        for (i, l) in t.lambda.iter_mut().enumerate() {
            *l = s.lambda[i] + ratio * (s.lambda[i] - self.previous.lambda[i]);
        }
    }

    fn locate_non_finite(&self) -> String {
        let s = &self.trial;
        let n = self.sys.n_coords();
        let coord = |what: &str, x: &[f64]| {
            x.iter()
                .position(|v| !v.is_finite())
                .map(|i| format!("{what}, coordinate '{}'", self.sys.coord_name(i)))
        };
        coord("the coordinates u", &s.u)
            .or_else(|| coord("the velocities u̇", &s.v))
            .or_else(|| coord("the accelerations ü", &s.a))
            .or_else(|| coord("the forces g", &self.lin.g))
            .or_else(|| {
                s.lambda.iter().position(|v| !v.is_finite()).map(|i| {
                    format!(
                        "the multiplier of constraint '{}'",
                        self.sys.constraint_name(i)
                    )
                })
            })
            .or_else(|| {
                self.lin
                    .phi
                    .iter()
                    .position(|v| !v.is_finite())
                    .map(|i| format!("constraint '{}'", self.sys.constraint_name(i)))
            })
            .unwrap_or_else(|| format!("the state ({n} coordinates)"))
    }

    fn check_finite_start(&self) -> Result<(), IntegrationError> {
        let s = &self.state;
        for (what, x) in [
            ("the initial coordinates u0", &s.u),
            ("the initial velocities v0", &s.v),
        ] {
            if let Some(i) = x.iter().position(|v| !v.is_finite()) {
                return Err(IntegrationError::NonFinite {
                    t: self.t,
                    what: format!("{what}, coordinate '{}'", self.sys.coord_name(i)),
                });
            }
        }
        Ok(())
    }

    /// Checks `Φ(u₀) = 0` and `B u̇₀ + Φ_t = 0`; projects (minimum-norm Newton on
    /// `[I Bᵀ; B 0]`) when allowed, else reports the most violated constraint.
    fn make_consistent_positions(&mut self) -> Result<(), IntegrationError> {
        let (n, m) = (self.sys.n_coords(), self.sys.n_constraints());
        let t = self.t;
        let zeros_n = vec![0.0; n];
        let zeros_m = vec![0.0; m];
        let mut phi_t = vec![0.0; m];
        let u0 = self.state.u.clone();
        let v0 = self.state.v.clone();
        let tol = self.config.tol;
        let argmax = |x: &[f64]| {
            x.iter()
                .enumerate()
                .fold((0, 0.0f64), |(k, best), (i, &v)| {
                    if v.abs() > best {
                        (i, v.abs())
                    } else {
                        (k, best)
                    }
                })
        };
        // Positions.
        self.lin
            .eval_residual(self.sys, t, &self.state.u, &zeros_n, &zeros_n, &zeros_m);
        self.start.position_violation = self.lin.constraint_norm();
        let mut iterations = 0;
        loop {
            let phi = self.lin.constraint_norm();
            let ctol = tol * max_abs(&self.state.u).max(1.0);
            let projected = iterations > 0;
            if phi <= if projected { 1e-3 * ctol } else { ctol } {
                break;
            }
            if !self.config.project {
                let (k, value) = argmax(&self.lin.phi);
                return Err(IntegrationError::InconsistentInitialState {
                    t,
                    level: "position",
                    constraint: self.sys.constraint_name(k),
                    value,
                });
            }
            if iterations == 50 || (projected && phi <= ctol && iterations > 5) {
                if phi <= ctol {
                    break;
                }
                let (k, _) = argmax(&self.lin.phi);
                return Err(IntegrationError::ProjectionFailed {
                    t,
                    iterations,
                    residual: phi,
                    constraint: self.sys.constraint_name(k),
                });
            }
            self.lin.assemble(&Coefficients::projection());
            self.solver
                .factor(&self.lin.kkt().values)
                .map_err(|e| self.kkt_error("projecting the initial positions", t, 0.0, e))?;
            self.lin.kkt_rhs(0.0, &mut self.rhs);
            self.solver
                .solve_in_place(&mut self.rhs)
                .map_err(|e| self.kkt_error("projecting the initial positions", t, 0.0, e))?;
            for (x, d) in self.state.u.iter_mut().zip(&self.rhs[..n]) {
                *x += d;
            }
            iterations += 1;
            self.lin
                .eval_residual(self.sys, t, &self.state.u, &zeros_n, &zeros_n, &zeros_m);
        }
        // Velocities: B u̇ + Φ_t = 0.
        self.sys.phi_t_into(t, &self.state.u, &mut phi_t);
        let mut w = phi_t.clone();
        self.lin
            .b_pattern()
            .mul_add(&self.lin.b, &self.state.v, &mut w);
        self.start.velocity_violation = max_abs(&w);
        let vtol = tol * max_abs(&self.state.v).max(1.0);
        if self.start.velocity_violation > vtol {
            if !self.config.project {
                let (k, value) = argmax(&w);
                return Err(IntegrationError::InconsistentInitialState {
                    t,
                    level: "velocity",
                    constraint: self.sys.constraint_name(k),
                    value,
                });
            }
            self.lin.assemble(&Coefficients::projection());
            self.solver
                .factor(&self.lin.kkt().values)
                .map_err(|e| self.kkt_error("projecting the initial velocities", t, 0.0, e))?;
            self.rhs[..n].fill(0.0);
            for (x, &wi) in self.rhs[n..].iter_mut().zip(&w) {
                *x = -wi;
            }
            self.solver
                .solve_in_place(&mut self.rhs)
                .map_err(|e| self.kkt_error("projecting the initial velocities", t, 0.0, e))?;
            for (x, d) in self.state.v.iter_mut().zip(&self.rhs[..n]) {
                *x += d;
            }
        }
        self.start.position_correction = self.state.u.iter().zip(&u0).map(|(a, b)| a - b).collect();
        self.start.velocity_correction = self.state.v.iter().zip(&v0).map(|(a, b)| a - b).collect();
        Ok(())
    }

    /// Solves the acceleration-level KKT system `[M Bᵀ; B 0][ü; λ] = [g; c]` at
    /// `(t, u, u̇)` into `a` and `lambda`.
    fn consistent_acceleration(
        &mut self,
        t: f64,
        u: &[f64],
        v: &[f64],
        a: &mut [f64],
        lambda: &mut [f64],
    ) -> Result<(), IntegrationError> {
        let n = u.len();
        let zeros_n = vec![0.0; n];
        let zeros_m = vec![0.0; lambda.len()];
        self.lin
            .eval_residual(self.sys, t, u, v, &zeros_n, &zeros_m);
        self.lin.assemble(&Coefficients::acceleration());
        let context = "solving for consistent initial accelerations";
        self.solver
            .factor(&self.lin.kkt().values)
            .map_err(|e| self.kkt_error(context, t, 0.0, e))?;
        self.rhs[..n].copy_from_slice(&self.lin.g);
        self.sys.accel_rhs_into(t, u, v, &mut self.rhs[n..]);
        self.solver
            .solve_in_place(&mut self.rhs)
            .map_err(|e| self.kkt_error(context, t, 0.0, e))?;
        a.copy_from_slice(&self.rhs[..n]);
        lambda.copy_from_slice(&self.rhs[n..]);
        Ok(())
    }

    /// The velocity perturbation `δu̇` with `[M Bᵀ; B 0][δu̇; μ] = [0; −k B u⃛₀]`:
    /// the given normal component, no tangential (inertia-weighted) part.
    fn velocity_start_correction(
        &mut self,
        t: f64,
        u: &[f64],
        jerk: &[f64],
        k: f64,
    ) -> Result<Vec<f64>, IntegrationError> {
        let (n, m) = (self.sys.n_coords(), self.sys.n_constraints());
        let (zeros_n, zeros_m) = (vec![0.0; n], vec![0.0; m]);
        let context = "computing the starting velocity correction";
        self.lin
            .eval_residual(self.sys, t, u, &zeros_n, &zeros_n, &zeros_m);
        self.lin.assemble(&Coefficients::acceleration());
        self.solver
            .factor(&self.lin.kkt().values)
            .map_err(|e| self.kkt_error(context, t, 0.0, e))?;
        self.rhs.fill(0.0);
        self.lin
            .b_pattern()
            .mul_add(&self.lin.b, jerk, &mut self.rhs[n..]);
        for x in &mut self.rhs[n..] {
            *x *= -k;
        }
        self.solver
            .solve_in_place(&mut self.rhs)
            .map_err(|e| self.kkt_error(context, t, 0.0, e))?;
        Ok(self.rhs[..n].to_vec())
    }

    /// Initial `ü₀`, `λ₀` and the acceleration-like variable `a₀`.
    fn initial_acceleration(&mut self) -> Result<(), IntegrationError> {
        let (n, m) = (self.sys.n_coords(), self.sys.n_constraints());
        let t = self.t;
        let u = self.state.u.clone();
        let v = self.state.v.clone();
        let mut a = vec![0.0; n];
        let mut lambda = vec![0.0; m];
        match self.config.start.clone() {
            Start::Paper { lambda0 } => {
                // M* ü₀ = g − Bᵀλ₀ (eqs. 3 and 11).
                self.lin.eval_residual(self.sys, t, &u, &v, &a, &lambda0);
                let m_star = self.lin.m_star().clone();
                let context = "solving M* ü₀ = g − Bᵀλ₀ (eq. 11)";
                let options = mstar_kkt::KktOptions {
                    n_primal: None,
                    ..self.config.kkt
                };
                let mut solver = KktSolver::new(&m_star, &options)
                    .and_then(|mut s| s.factor(&m_star.values).map(|()| s))
                    .map_err(|e| self.kkt_error(context, t, 0.0, e))?;
                a.copy_from_slice(&self.lin.r);
                solver
                    .solve_in_place(&mut a)
                    .map_err(|e| self.kkt_error(context, t, 0.0, e))?;
                lambda.copy_from_slice(&lambda0);
                self.state.a_alpha.copy_from_slice(&a);
            }
            Start::Consistent => {
                self.consistent_acceleration(t, &u, &v, &mut a, &mut lambda)?;
                let AlphaParams {
                    alpha_m, alpha_f, ..
                } = self.p;
                self.state.a_alpha.copy_from_slice(&a);
                if self.config.corrected_start {
                    // u⃛₀ by central differences of consistent accelerations at
                    // the Taylor states u₀ ± δu̇₀ + δ²/2 ü₀, u̇₀ ± δü₀: the O(δ²)
                    // velocity error is even in δ and cancels.
                    let d = self.config.h;
                    let mut plus = vec![0.0; n];
                    let mut minus = vec![0.0; n];
                    let mut scratch = vec![0.0; m];
                    for (sign, out) in [(1.0, &mut plus), (-1.0, &mut minus)] {
                        let ds = sign * d;
                        let us: Vec<f64> = (0..n)
                            .map(|i| u[i] + ds * v[i] + 0.5 * ds * ds * a[i])
                            .collect();
                        let vs: Vec<f64> = (0..n).map(|i| v[i] + ds * a[i]).collect();
                        self.consistent_acceleration(t + ds, &us, &vs, out, &mut scratch)?;
                    }
                    let jerk: Vec<f64> = (0..n).map(|i| (plus[i] - minus[i]) / (2.0 * d)).collect();
                    for i in 0..n {
                        self.state.a_alpha[i] = a[i] + (alpha_m - alpha_f) * d * jerk[i];
                    }
                    // The discrete solution's velocity has a normal component
                    // B u̇_n = −c h² B u⃛ (c = β + Δα/2 − 1/6 is the
                    // position update's local error constant): without it the
                    // first step absorbs the O(h³) normal position defect into
                    // an O(h) jump of a, which rings as a period-2h transient.
                    let AlphaParams { beta, .. } = self.p;
                    let c = beta + 0.5 * (alpha_m - alpha_f) - 1.0 / 6.0;
                    let dv = self.velocity_start_correction(t, &u, &jerk, c * d * d)?;
                    for i in 0..n {
                        self.state.v[i] += dv[i];
                    }
                    self.start.velocity_start_correction = dv;
                    self.start.jerk = jerk;
                }
            }
        }
        self.state.a.copy_from_slice(&a);
        self.state.lambda.copy_from_slice(&lambda);
        if let Some(i) = a.iter().chain(&lambda).position(|x| !x.is_finite()) {
            return Err(IntegrationError::NonFinite {
                t,
                what: format!("the initial accelerations or multipliers (entry {i})"),
            });
        }
        Ok(())
    }
}

/// The linearization and the KKT solver for `sys`. With [`Backend::Auto`] or
/// [`Backend::Schur`] it first tries the KKT structure without the `BᵀB` term
/// (`S_T` block-diagonal when bodies interact only through constraints) and
/// keeps it when the Schur backend accepts it and, for `Auto`, `M`'s diagonal
/// is positive (without `BᵀB` the blocks of `S_T` hold `β' M`); otherwise the
/// augmented structure of eq. (17).
fn linear_algebra<S: System + ?Sized>(
    sys: &S,
    config: &Config,
    t0: f64,
    u0: &[f64],
    v0: &[f64],
) -> Result<(Linearization, KktSolver), IntegrationError> {
    let (n, m) = (sys.n_coords(), sys.n_constraints());
    // The KKT matrix's leading n unknowns are the coordinates.
    let options = mstar_kkt::KktOptions {
        n_primal: config.kkt.n_primal.or(Some(n)),
        ..config.kkt
    };
    let analyse = |lin: &Linearization| {
        KktSolver::new(lin.kkt(), &options).map_err(|source| IntegrationError::Kkt {
            context: "analysing the KKT pattern",
            t: t0,
            h: config.h,
            unknown: None,
            source,
        })
    };
    if matches!(options.backend, Backend::Auto | Backend::Schur) {
        let mut plain = Linearization::with_augmentation(sys, false)?;
        let solver = analyse(&plain)?;
        if solver.backend() == Backend::Schur {
            plain.eval_residual(sys, t0, u0, v0, &vec![0.0; n], &vec![0.0; m]);
            if options.backend == Backend::Schur || plain.mass_diagonal_positive() {
                // The Schur backend reads S, B and the multiplier block only.
                plain.set_fill_transpose(false);
                return Ok((plain, solver));
            }
        }
    }
    let lin = Linearization::new(sys)?;
    let solver = analyse(&lin)?;
    Ok((lin, solver))
}
