//! The integrator: state, step control and output. The Newton iteration of
//! one step (paper §2.2, Fig. 2; `algorithm.md` §4) is in `newton.rs`, the
//! initial conditions (§3, §6) in `start.rs`.

mod adjoint;
mod control;
mod history;
mod initial;
mod newton;
mod refine;
mod sensitivity;
mod start;

pub use adjoint::{Column, Gradient, Memory, Objective};
pub use sensitivity::{DIFFERENCE_STEP, NewtonSwitch, Parameterized, Sensitivities, Variant};

use mstar_kkt::{Backend, KktError, KktSolver};
use mstar_linearize::{Linearization, max_abs};
use mstar_model::{FlushSubnormals, Sample, SampleRef, StateRef, System, kinetic_energy};

use crate::{
    AlphaParams, Config, IntegrationError, Newton, Observer, Predictor, RunStats, Start, StepMode,
};

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
    Kkt {
        /// What the solver was doing: factoring or solving.
        context: &'static str,
        source: KktError,
    },
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
    /// The point `(t, u, u̇, ü, λ)` at which the system is evaluated.
    fn at(&self, t: f64) -> StateRef<'_> {
        StateRef {
            t,
            u: &self.u,
            v: &self.v,
            a: &self.a,
            lambda: &self.lambda,
        }
    }

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
    /// The states before the last accepted step and the steps' sizes (for
    /// the extrapolating predictor).
    history: history::History,
    rhs: Vec<f64>,
    /// Current nominal step size (≤ config.h unless adaptive).
    h: f64,
    /// The size of the last accepted step (at the start: `config.h`, the step
    /// the corrected start was made for). The acceleration-like variable
    /// `a_n ≈ ü(t_n + (α_m − α_f) h)` belongs to it and is rescaled when the
    /// next step's size differs (`control.rs`).
    h_last: f64,
    /// The local error estimate of the trial step, per coordinate.
    error: Vec<f64>,

    /// The previous accepted step's error ratio (the PI controller's memory).
    error_previous: f64,
    /// Whether the last attempt was rejected (then `h` may not grow).
    rejected_last: bool,
    /// The step size the current factorization was made for.
    factored_h: Option<f64>,
    /// A bound on how far the state moved from where the factored matrix's
    /// Jacobians were evaluated (`refine.rs`): `Σ ‖Δu‖∞` of the corrections
    /// since the factorization, plus, when it took the Jacobians of the
    /// state before the step (`jacobians_of_state`), `‖u − u_n‖∞` of the
    /// iterate it was made at.
    drift: f64,
    /// The linearization holds the Jacobians of the current state (the
    /// sensitivities evaluated them): the next step's first factorization
    /// takes them instead of evaluating them at its predictor.
    jacobians_of_state: bool,
    /// The factorization in hand is the sensitivities' at the last
    /// converged state (`sensitivity.rs`, `factor_converged`), not Newton's.
    factored_at_converged: bool,
    /// Modified Newton is the automatic choice (which sensitivities may
    /// turn into once per step, `sensitivity.rs`).
    modified_by_choice: bool,
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
    /// The current state's kinetic and potential energies, when
    /// [`record_energy`](Self::record_energy) evaluated them.
    energies: Option<(f64, f64)>,
    /// [`System::conserves_energy`], asked once: the system cannot change
    /// while the integrator borrows it, and on a model file the answer is
    /// a scan of every element (4.5 % of an N-four-bar step when asked at
    /// every step).
    conserves_energy: bool,
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
    /// dimensions, a non-finite `t0`, an inconsistent initial state (with
    /// projection off), or a singular initial system (reported "at start-up",
    /// naming the constraint the given state violated most).
    pub fn new(
        sys: &'s S,
        config: Config,
        t0: f64,
        u0: &[f64],
        v0: &[f64],
    ) -> Result<Self, IntegrationError> {
        if !t0.is_finite() {
            return Err(IntegrationError::Time {
                what: "t0",
                value: t0,
                why: "the start time must be finite".into(),
            });
        }
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
        let (lin, solver) = linear_algebra(sys, &config, t0, u0)?;
        Self::started(sys, config, p, (t0, u0, v0), lin, solver)
    }

    /// [`new`](Self::new) with the linearization and the KKT solver given
    /// (those of a model with the same structure; the start of a
    /// parameter's model at `p ± h_p`, `sensitivity.rs`).
    pub(super) fn with_linear_algebra(
        sys: &'s S,
        config: Config,
        (t0, u0, v0): (f64, &[f64], &[f64]),
        lin: Linearization,
        solver: KktSolver,
    ) -> Result<Self, IntegrationError> {
        let p = config.validate()?;
        let n = sys.n_coords();
        for (what, got) in [("u0", u0.len()), ("v0", v0.len())] {
            if got != n {
                return Err(IntegrationError::Dimension { what, got, want: n });
            }
        }
        Self::started(sys, config, p, (t0, u0, v0), lin, solver)
    }

    /// The integrator on `lin` and `solver`, its initial state made
    /// consistent and started (the rest of [`new`](Self::new)).
    fn started(
        sys: &'s S,
        config: Config,
        p: AlphaParams,
        (t0, u0, v0): (f64, &[f64], &[f64]),
        lin: Linearization,
        solver: KktSolver,
    ) -> Result<Self, IntegrationError> {
        let (n, m) = (sys.n_coords(), sys.n_constraints());
        let automatic = config.newton == Newton::Automatic;
        let config = Config {
            newton: config.newton.resolve(
                solver.backend(),
                n + m > config.kkt.dense_threshold && sys.fresh_jacobians_pay(),
            ),
            ..config
        };
        let h = config.h;
        let mut this = Self {
            sys,
            p,
            lin,
            solver,
            t: t0,
            state: State::zeros(n, m),
            trial: State::zeros(n, m),
            history: history::History::new(n, m, config.predictor),
            rhs: vec![0.0; n + m],
            h,
            h_last: h,
            error: vec![0.0; n],
            error_previous: 1.0,
            rejected_last: false,
            factored_h: None,
            drift: 0.0,
            jacobians_of_state: false,
            factored_at_converged: false,
            modified_by_choice: automatic && matches!(config.newton, Newton::Modified { .. }),
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
            energies: None,
            conserves_energy: sys.conserves_energy(),
            config,
        };
        this.state.u.copy_from_slice(u0);
        this.state.v.copy_from_slice(v0);
        this.check_finite_start()?;
        this.start_up()?;
        // The state's own residual and constraint norms, for the t0 sample.
        let s = &this.state;
        this.lin.eval_residual(sys, &s.at(t0));
        this.residual = this.lin.residual_norm();
        this.constraint = this.lin.constraint_norm();
        this.record_energy();
        Ok(this)
    }

    /// Adds the current state's energy to the run's energy report when the
    /// system conserves energy ([`System::conserves_energy`]; `output.rs`,
    /// [`EnergyReport`](crate::EnergyReport)).
    fn record_energy(&mut self) {
        self.energies = None;
        if !self.conserves_energy {
            return;
        }
        let (kinetic, potential) = self.energies_now();
        // The forces are those of the state's last residual evaluation.
        let force: f64 = self.lin.g().iter().map(|g| g.abs()).sum();
        let work = force * max_abs(&self.state.u).max(1.0);
        self.stats.energy.record(self.t, kinetic, potential, work);
        self.energies = Some((kinetic, potential));
    }

    /// The current state's kinetic and potential energies.
    fn energies_now(&self) -> (f64, f64) {
        let s = &self.state;
        (
            kinetic_energy(self.lin.mass_pattern(), self.lin.mass(), &s.v),
            self.sys.potential_energy(self.t, &s.u),
        )
    }

    /// The Newton variant in use.
    #[must_use]
    pub fn newton(&self) -> Newton {
        self.config.newton
    }

    /// The KKT backend in use ([`Backend::AUTO`] resolved).
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

    /// The local error estimate of the last accepted step, per coordinate
    /// (`control.rs`; projected onto `B e = 0` with adaptive steps or when
    /// it exceeded the tolerance, else as first computed).
    #[must_use]
    pub fn error_estimate(&self) -> &[f64] {
        &self.error
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

    /// The current state as an owned [`Sample`] (energies, last Newton
    /// figures).
    #[must_use]
    pub fn sample(&self) -> Sample {
        self.view().to_sample()
    }

    /// The current state, borrowed (what observers see).
    #[must_use]
    pub fn view(&self) -> SampleRef<'_> {
        self.view_with(true)
    }

    /// The current state, with its energies (else NaN).
    fn view_with(&self, energy: bool) -> SampleRef<'_> {
        let s = &self.state;
        // Evaluated once a step: [`record_energy`](Self::record_energy) may
        // have done it already.
        let (kinetic, potential) = if energy {
            self.energies.unwrap_or_else(|| self.energies_now())
        } else {
            (f64::NAN, f64::NAN)
        };
        SampleRef {
            t: self.t,
            u: &s.u,
            v: &s.v,
            a: &s.a,
            lambda: &s.lambda,
            kinetic,
            potential,
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
    /// [`IntegrationError::Time`] for a `t_end` that is not finite (one at or
    /// before the current time returns at once, with nothing to do).
    pub fn run(
        &mut self,
        t_end: f64,
        observer: &mut dyn Observer,
    ) -> Result<RunStats, IntegrationError> {
        // (NaN is never reached and +∞ only after forever.)
        if !t_end.is_finite() {
            return Err(self.bad_end(t_end, "the end time must be finite"));
        }
        let energy = observer.reads_energy();
        if !self.observed_start {
            observer.observe(&self.view_with(energy));
            self.observed_start = true;
        }
        while !self.reached(t_end) {
            self.step(t_end)?;
            observer.observe(&self.view_with(energy));
        }
        Ok(self.stats)
    }

    /// Whether the integration has reached `t_end` (within `1e-9 h`).
    #[must_use]
    pub fn reached(&self, t_end: f64) -> bool {
        t_end - self.t <= 1e-9 * self.config.h.min(self.h)
    }

    /// Takes one accepted step towards `t_end` (shortened to land on it),
    /// rejecting and retrying with `h/2` while Newton fails and `h/2 ≥ h_min`,
    /// and regrowing `h` (never beyond [`Config::h`]) after a run of easy steps.
    ///
    /// # Errors
    /// [`IntegrationError::NewtonFailed`], [`IntegrationError::NonFinite`] or
    /// [`IntegrationError::Kkt`] when step control is off (`h_min = h`), and
    /// [`IntegrationError::StepSizeTooSmall`] when it gives up;
    /// [`IntegrationError::Time`] for a `t_end` that is not finite or not
    /// after the current time (within `1e-9 h`, as [`reached`](Self::reached)).
    pub fn step(&mut self, t_end: f64) -> Result<(), IntegrationError> {
        // Subnormal numbers (a disturbance decayed along a long chain) as
        // zero while the step computes: mstar_model::subnormal.
        let _flush = FlushSubnormals::new();
        // A step towards a t_end at or before t would be of size ≤ 0.
        if !t_end.is_finite() || self.reached(t_end) {
            return Err(self.bad_end(t_end, "step needs a finite end time after the current one"));
        }
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
                Ok(iterations) => match self.judge(h_try)? {
                    Some(estimate) => {
                        self.accept(h_try, iterations, estimate);
                        return Ok(());
                    }
                    None => {
                        // Rejected by the error estimate: `judge` set `self.h`.
                        h = self.h;
                        retried_fresh = false;
                        continue;
                    }
                },
                Err(failure) => {
                    let fresh = self.stats.factorizations > factorizations_before;
                    let stale_jacobian = matches!(self.config.newton, Newton::Modified { .. })
                        && !(fresh && self.factorized_every_iteration());
                    if stale_jacobian && !retried_fresh {
                        // Retry the same step with a Jacobian evaluated here.
                        self.factored_h = None;
                        self.jacobians_of_state = false;
                        retried_fresh = true;
                        self.stats.rejected += 1;
                        continue;
                    }
                    if h * 0.5 >= h_min * (1.0 - 1e-12) {
                        h *= 0.5;
                        self.h = h;
                        self.easy_steps = 0;
                        self.factored_h = None;
                        self.jacobians_of_state = false;
                        retried_fresh = false;
                        self.stats.rejected += 1;
                        continue;
                    }
                    return Err(self.failure_error(failure, h_try, h_min));
                }
            }
        }
    }

    /// A `t_end` that `run` or `step` cannot integrate to.
    fn bad_end(&self, t_end: f64, why: &str) -> IntegrationError {
        IntegrationError::Time {
            what: "t_end",
            value: t_end,
            why: format!("{why} (the integration is at t = {})", crate::Short(self.t)),
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
                        advice: self.diagnose_failure(),
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
                        advice: self.diagnose_failure(),
                    }
                }
            }
            Failure::NonFinite(what) => IntegrationError::NonFinite { t, what },
            Failure::Kkt { context, source } => self.kkt_error(context, t, h, source),
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

    fn accept(&mut self, h: f64, iterations: usize, estimate: control::Estimate) {
        // Buffers change roles instead of being copied: the predictor rewrites
        // every field of `trial` before it is read again.
        if matches!(
            self.config.predictor,
            Predictor::Extrapolated | Predictor::Linear
        ) {
            let resolved = estimate.truncation <= 1.0;
            self.history.push(&mut self.state, h, resolved);
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
        st.h_max_used = st.h_max_used.max(h);
        st.t = self.t;
        st.error
            .record(estimate.ratio, self.t, h, estimate.coordinate);
        st.error.record_newton(estimate.newton);
        self.record_energy();
        self.h_last = h;
        if self.config.error.mode == StepMode::Adaptive {
            self.adapt(h, &estimate);
            return;
        }
        // A step that needed many iterations with a reused Jacobian asks for a
        // fresh one at the next step.
        if iterations > 4 {
            self.factored_h = None;
            self.jacobians_of_state = false;
        }
        // Regrow h after a run of easy steps. With a fresh Jacobian at every
        // iteration a resolved step takes one correction (two at most); more
        // means the predictor is far off, i.e. the motion is fast for this h,
        // and regrowing would step straight back into it (a whip).
        let easy = match self.config.newton {
            Newton::Full => 2,
            // A second iteration with the step's Jacobian may take a third.
            Newton::PerStep { .. } => 3,
            Newton::Modified { .. } | Newton::Automatic => (self.config.max_iterations / 4).max(3),
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

    /// The time at the end of a step of size `h` (as [`accept`](Self::accept) will
    /// set it).
    fn step_end(&self, h: f64) -> f64 {
        if h == self.h_anchor {
            self.t_anchor + (self.steps_at_h + 1) as f64 * h
        } else {
            self.t + h
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
            .or_else(|| coord("the forces g", self.lin.g()))
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
                    .phi()
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
}

/// The linearization and the KKT solver for `sys`: the first backend of
/// [`mstar_kkt::KktOptions::candidates`] that takes the structure it asks for
/// ([`mstar_kkt::Backend::structure`]). With the automatic choice, a backend
/// that needs a symmetric matrix is only tried when the system's tangent is
/// symmetric ([`System::tangent_is_symmetric`]; chosen explicitly for an
/// unsymmetric one, it is an error), and one that works on `S_T` without the
/// `BᵀB` term (whose blocks then hold `β' M`) only when `M`'s blocks are
/// positive definite at the start ([`singular_mass_coordinate`]).
fn linear_algebra<S: System + ?Sized>(
    sys: &S,
    config: &Config,
    t0: f64,
    u0: &[f64],
) -> Result<(Linearization, KktSolver), IntegrationError> {
    let (n, m) = (sys.n_coords(), sys.n_constraints());
    // The KKT matrix's leading n unknowns are the coordinates.
    let options = mstar_kkt::KktOptions {
        n_primal: config.kkt.n_primal.or(Some(n)),
        ..config.kkt
    };
    let auto = options.backend == Backend::AUTO;
    let candidates = options.candidates(n + m);
    let mut last = None;
    for (k, &backend) in candidates.iter().enumerate() {
        let Some(registration) = backend.registration() else {
            return Err(IntegrationError::Config(format!(
                "no KKT backend is called '{backend}'"
            )));
        };
        let structure = registration.structure;
        if registration.symmetric && !sys.tangent_is_symmetric() {
            if auto {
                continue;
            }
            return Err(IntegrationError::Config(format!(
                "the {backend} KKT backend needs a symmetric iteration matrix, and this model's is not \
                 (a damper, another velocity-dependent or non-conservative force, or a \
                 configuration-dependent mass matrix: see System::tangent_is_symmetric); use the lu or \
                 dense backend, or the automatic choice"
            )));
        }
        if !structure.augmented
            && let Some(i) = singular_mass_coordinate(sys, t0, u0)
        {
            if auto {
                continue;
            }
            return Err(singular_mass_error(sys, backend, i));
        }
        let lin = Linearization::with_structure(sys, structure)?;
        let single = mstar_kkt::KktOptions { backend, ..options };
        match KktSolver::new(lin.kkt(), &single) {
            Ok(solver) => return Ok((lin, solver)),
            // The next candidate may take what this one refuses.
            Err(KktError::Structure(why)) if k + 1 < candidates.len() => {
                last = Some(KktError::Structure(why));
            }
            Err(source) => return Err(analysis_error(t0, config.h, source)),
        }
    }
    let source = last.unwrap_or_else(|| KktError::Structure("no KKT backend fits".to_string()));
    Err(analysis_error(t0, config.h, source))
}

/// A failed analysis of the KKT structure.
fn analysis_error(t: f64, h: f64, source: KktError) -> IntegrationError {
    IntegrationError::Kkt {
        context: "analysing the KKT pattern",
        t,
        h,
        unknown: None,
        source,
    }
}

/// Largest block of `M` checked for positive definiteness: larger blocks
/// are left to the backends (the Schur backends refuse them).
const MASS_BLOCK_CHECKED: usize = 16;

/// The first coordinate at which `M(u₀)` is not positive definite, block by
/// block (`None` when every block is, as backends that factor `M` without
/// `BᵀB` need). The blocks are the connected groups of coordinates in `M`'s
/// pattern (a body's coordinates); each is factored by Cholesky, and a pivot
/// at the rounding level of its block's diagonal marks it singular. A
/// positive diagonal is not enough: an Euler-parameter body's rotational
/// block `4 Gᵀ J' G` has rank 3 in any orientation, with a positive
/// diagonal once the body is turned.
fn singular_mass_coordinate<S: System + ?Sized>(sys: &S, t: f64, u: &[f64]) -> Option<usize> {
    let n = sys.n_coords();
    let pattern = sys.mass_pattern();
    let mut mass = vec![0.0; pattern.len()];
    sys.mass_into(t, u, &mut mass);
    let blocks = mass_blocks(n, &pattern.entries);
    let mut members: Vec<Vec<usize>> = vec![Vec::new(); n];
    for i in 0..n {
        members[blocks[i]].push(i);
    }
    let mut local = vec![usize::MAX; n];
    let mut dense: Vec<Vec<f64>> = vec![Vec::new(); n];
    for (b, m) in members.iter().enumerate() {
        if m.len() <= MASS_BLOCK_CHECKED {
            dense[b] = vec![0.0; m.len() * m.len()];
            for (k, &i) in m.iter().enumerate() {
                local[i] = k;
            }
        }
    }
    for (&(i, j), &v) in pattern.entries.iter().zip(&mass) {
        let b = blocks[i];
        if !dense[b].is_empty() {
            let k = members[b].len();
            dense[b][local[i] * k + local[j]] += v;
        }
    }
    members
        .iter()
        .zip(&dense)
        .filter(|(m, d)| !m.is_empty() && !d.is_empty())
        .find_map(|(m, d)| cholesky_fails(d, m.len()).map(|k| m[k]))
}

/// The block (a representative coordinate) of every coordinate: the
/// connected components of `M`'s pattern, by union-find.
fn mass_blocks(n: usize, entries: &[(usize, usize)]) -> Vec<usize> {
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    let mut parent: Vec<usize> = (0..n).collect();
    for &(i, j) in entries {
        if i < n && j < n {
            let (a, b) = (root(&mut parent, i), root(&mut parent, j));
            parent[a.max(b)] = a.min(b);
        }
    }
    (0..n).map(|i| root(&mut parent, i)).collect()
}

/// The first pivot of the Cholesky factorization of the symmetric `k × k`
/// matrix `a` (row-major) that is not positive beyond rounding (relative to
/// the largest diagonal entry), or NaN.
fn cholesky_fails(a: &[f64], k: usize) -> Option<usize> {
    let scale = (0..k).map(|i| a[i * k + i].abs()).fold(0.0, f64::max);
    let mut l = a.to_vec();
    for c in 0..k {
        let mut d = l[c * k + c];
        for p in 0..c {
            d -= l[c * k + p] * l[c * k + p];
        }
        if d.is_nan() || d <= 1e-12 * scale {
            return Some(c);
        }
        let d = d.sqrt();
        l[c * k + c] = d;
        for r in c + 1..k {
            let mut x = l[r * k + c];
            for p in 0..c {
                x -= l[r * k + p] * l[c * k + p];
            }
            l[r * k + c] = x / d;
        }
    }
    None
}

/// A backend that factors `S` without `BᵀB` chosen for a model whose `M` is
/// singular at coordinate `i`: its first solve (the consistent accelerations,
/// `S = M`) has no pivot. Names the backends that factor `M + BᵀB` instead
/// (eq. 11), which a singular `M` does not stop.
fn singular_mass_error<S: System + ?Sized>(
    sys: &S,
    backend: Backend,
    i: usize,
) -> IntegrationError {
    let symmetric = sys.tangent_is_symmetric();
    let working: Vec<&str> = mstar_kkt::backends()
        .iter()
        .filter(|r| r.structure.augmented && (symmetric || !r.symmetric))
        .map(|r| r.backend.name())
        .collect();
    IntegrationError::Config(format!(
        "the {backend} KKT backend needs a mass matrix with a positive diagonal and no singular \
         block (it factors M without the BᵀB term), and this model's is singular at coordinate \
         '{}' (the paper's singular M: a coordinate without mass, or a spatial body's rotational \
         block with rotational_mass = \"singular\"); use the {} backend, or the automatic \
         choice, which factor M + BᵀB",
        sys.coord_name(i),
        match working.split_last() {
            Some((last, [])) => (*last).to_string(),
            Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
            None => "lu".to_string(),
        }
    ))
}
