//! Forward parameter sensitivities of the discrete solution
//! (`docs/analysis.md`, "Parameter sensitivities").
//!
//! One step solves `R(x_{n+1}; x_n, p) = 0`: the residual `r = g − Bᵀλ − M ü`
//! and the constraints `Φ` at `t_{n+1}`, with `u, u̇, ü` and the
//! acceleration-like variable of the step tied to the correction `Δu` by the
//! corrector (15). Differentiating the converged step with respect to a
//! parameter `p` gives, with the step's Jacobian `J` at the converged state,
//!
//! ```text
//! J [δΔ; δλ] = [ r_p − K_T δu^p − C_T δu̇^p ;  −Φ_p − B δu^p ]
//! ```
//!
//! where `δu^p, δu̇^p` are the sensitivities of the predictor with zero
//! acceleration (linear in the previous step's sensitivities; the converged
//! step does not depend on the predictor) and `r_p, Φ_p` the residual's and
//! the constraints' partial derivatives at the converged state, by central
//! differences between the model at `p ± h_p`.
//! `J` at the converged state is solved by refinement with the step's own
//! factorization when there is one (once per step, full Newton: an iterate
//! of the same step; mostly one solve and one product `J x` from the
//! extrapolation of the parameter's last solutions, `refine.rs`), else
//! factored there. The initial sensitivities are
//! differentiated through the start's own linear systems (`initial.rs`),
//! or, for the paper's start and a start without projection, central
//! differences of the whole start at `p ± h_p`.

use std::collections::HashMap;

use mstar_kkt::{KktOptions, KktSolver, SharedAnalyses};
use mstar_linearize::{Linearization, MaxAbs, max_abs};
use mstar_model::{FlushSubnormals, StateRef, System};

use super::refine::{Contraction, PastSolutions, Scratch};
use super::{Integrator, State};
use crate::{IntegrationError, Newton};

/// A model at one value of a parameter: its system and its initial state
/// (as given, before the start projects it).
pub trait Variant {
    /// The system.
    fn system(&self) -> &dyn System;
    /// The initial coordinates `u₀`.
    fn initial_position(&self) -> &[f64];
    /// The initial velocities `u̇₀`.
    fn initial_velocity(&self) -> &[f64];
}

/// A parameter of a model: its name, its nominal value and the model at any
/// value (for a model file, the file read with `--set KEY=VALUE`).
pub trait Parameterized {
    /// The parameter's name (a model file's key, e.g. `body.rod.mass`).
    fn name(&self) -> String;
    /// The nominal value `p`, at which the run is made.
    fn value(&self) -> f64;
    /// The model with the parameter set to `value`.
    ///
    /// # Errors
    /// Why the model cannot be made at that value.
    fn at(&self, value: f64) -> Result<Box<dyn Variant>, String>;

    /// The part of the model the parameter enters, at `value`: a small
    /// system whose residual rows and constraints that change with the
    /// parameter are those of the whole model, its coordinates and
    /// constraint rows named as the whole model's (for a model file, the
    /// parameter's element and the bodies it acts on). The partials
    /// `∂r/∂p`, `∂Φ/∂p` are then central differences of the small system,
    /// scattered into the whole model's rows: a few rows a step instead of
    /// two residuals of the whole model. `None` (the default) for a global
    /// parameter: central differences of the whole model. Only its
    /// [`system`](Variant::system) is read.
    ///
    /// # Errors
    /// Why the small system cannot be made at that value.
    fn local_at(&self, value: f64) -> Result<Option<Box<dyn Variant>>, String> {
        let _ = value;
        Ok(None)
    }

    /// Whether the model's initial state as given (before the start)
    /// is the same at every value of the parameter (a mass, a stiffness):
    /// then, with a [`local_at`](Self::local_at) model, the whole model at
    /// `p ± h_p` is not made at all. `false` (the default): the given
    /// states' central difference is taken.
    fn keeps_initial_state(&self) -> bool {
        false
    }
}

/// The central-difference step relative to `|p|` (absolute when `p = 0`):
/// `≈ (3ε)^{1/3}`, which balances the truncation error `h_p² |∂³R/∂p³| / 6`
/// against the rounding error `ε |R| / h_p`, both then `≈ 1e-10` relative.
pub const DIFFERENCE_STEP: f64 = 1e-5;

/// One parameter: its partials' models at `p ± h_p` and the sensitivities
/// of the state.
pub(super) struct Parameter {
    name: String,
    value: f64,
    pub(super) step: f64,
    pub(super) partials: Partials,
    /// `∂(u, u̇, ü, a, λ)/∂p` of the current state.
    pub(super) s: State,
    /// The last three steps' solutions `[δΔ; δλ]` (`refine.rs`).
    past: PastSolutions,
}

/// What the partials `c = [∂r/∂p; −∂Φ/∂p]` of one parameter are formed
/// from: the models at `p ± h_p` (the whole model's, or a small one's with
/// the places of its coordinates and rows in the whole model) and their
/// linearizations.
pub(super) struct Partials {
    pub(super) plus: Side,
    pub(super) minus: Side,
    /// `None`: the whole model.
    pub(super) places: Option<Places>,
    /// The whole model's state gathered onto the small model's coordinates
    /// and rows (unused for the whole model).
    pub(super) gathered: State,
}

/// The models at `p + h_p` and `p − h_p`.
type Sides = (Box<dyn Variant>, Box<dyn Variant>);

/// The model at one side of the difference and its linearization.
pub(super) struct Side {
    pub(super) variant: Box<dyn Variant>,
    pub(super) lin: Linearization,
}

/// Where a small model's coordinates and constraint rows are in the whole
/// model's.
pub(super) struct Places {
    pub(super) coords: Vec<usize>,
    pub(super) rows: Vec<usize>,
}

impl Partials {
    /// Evaluates both sides' residuals at `x`, the whole model's state,
    /// then calls `f(k, c_k)` for each entry of `c = [∂r/∂p; −∂Φ/∂p]` that
    /// the parameter can change (`k` indexes the whole model's `[u; λ]`;
    /// `n` its coordinates).
    pub(super) fn each(
        &mut self,
        x: &StateRef<'_>,
        n: usize,
        h: f64,
        mut f: impl FnMut(usize, f64),
    ) {
        let at = Self::gather(self.places.as_ref(), &mut self.gathered, x);
        self.plus.lin.eval_residual(self.plus.variant.system(), &at);
        self.minus
            .lin
            .eval_residual(self.minus.variant.system(), &at);
        let (lp, lm) = (&self.plus.lin, &self.minus.lin);
        let central = |a: f64, b: f64| (a - b) / (2.0 * h);
        match &self.places {
            None => {
                for (i, (a, b)) in lp.r().iter().zip(lm.r()).enumerate() {
                    f(i, central(*a, *b));
                }
                for (j, (a, b)) in lp.phi().iter().zip(lm.phi()).enumerate() {
                    f(n + j, -central(*a, *b));
                }
            }
            Some(places) => {
                for ((a, b), &k) in lp.r().iter().zip(lm.r()).zip(&places.coords) {
                    f(k, central(*a, *b));
                }
                for ((a, b), &k) in lp.phi().iter().zip(lm.phi()).zip(&places.rows) {
                    f(n + k, -central(*a, *b));
                }
            }
        }
    }

    /// `x` (the whole model's state) as the partials' model reads it:
    /// gathered into `g` for a small model at `places`.
    pub(super) fn gather<'a>(
        places: Option<&Places>,
        g: &'a mut State,
        x: &StateRef<'a>,
    ) -> StateRef<'a> {
        match places {
            None => *x,
            Some(places) => {
                for (i, &k) in places.coords.iter().enumerate() {
                    (g.u[i], g.v[i], g.a[i]) = (x.u[k], x.v[k], x.a[k]);
                }
                for (j, &k) in places.rows.iter().enumerate() {
                    g.lambda[j] = x.lambda[k];
                }
                g.at(x.t)
            }
        }
    }

    /// Whether the partials are of a small model.
    fn local(&self) -> bool {
        self.places.is_some()
    }
}

/// Forward sensitivities `∂x/∂p` of the integrator's discrete solution to
/// parameters of its model, advanced by [`Integrator::step_with`].
pub struct Sensitivities {
    pub(super) params: Vec<Parameter>,
    /// The buffers of a step's solves, kept from step to step.
    scratch: Scratch,
    /// Solves, one per parameter and step.
    solves: usize,
    /// Factorizations at the converged state, one per step.
    factorizations: usize,
    /// The refinement's contraction per drift (`refine.rs`).
    contraction: Contraction,
    /// Newton's iterations on the first steps that start from the
    /// sensitivities' factorization at the converged state (modified
    /// Newton by the automatic choice), and on those that start from their
    /// Jacobians (`Integrator::jacobians_of_state`).
    probes: [Probe; 2],
    /// Whether the next step's first factorization may take the
    /// sensitivities' Jacobians.
    sharing: bool,
    switched: Option<NewtonSwitch>,
}

/// Steps a [`Probe`] averages over.
const PROBE_STEPS: usize = 16;

/// The Newton iterations a step from which a probed choice is undone:
/// modified Newton from the sensitivities' factorization then costs at
/// least an iteration a step more than once per step's one, which the
/// sensitivities refine with (a solve and a product); a step from their
/// Jacobians likewise costs more than the evaluation it saves
/// (docs/performance.md, "Sensitivities choose once per step").
const PROBE_MEAN: f64 = 1.5;

/// Newton's iterations a step over a run's first [`PROBE_STEPS`] steps of
/// one kind.
#[derive(Clone, Copy, Debug, Default)]
struct Probe {
    steps: usize,
    iterations: usize,
}

impl Probe {
    /// Adds a step of `iterations`; the mean once the last step is in (and
    /// only then).
    fn record(&mut self, iterations: usize) -> Option<f64> {
        if self.steps >= PROBE_STEPS {
            return None;
        }
        self.steps += 1;
        self.iterations += iterations;
        (self.steps == PROBE_STEPS).then(|| self.iterations as f64 / PROBE_STEPS as f64)
    }
}

/// The run at the start of a step, for [`Integrator::probe`].
struct Start {
    iterations: usize,
    rejected: usize,
    /// Newton's factorization in hand was the sensitivities' at the last
    /// converged state.
    from_converged: bool,
    /// The step's first factorization was to take the sensitivities'
    /// Jacobians.
    from_shared: bool,
}

/// Modified Newton (the automatic choice) turned into once per step by a
/// run's sensitivities ([`Sensitivities::switched_newton`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NewtonSwitch {
    /// The time of the switch, s.
    pub t: f64,
    /// Modified Newton's iterations a step from the sensitivities'
    /// factorization, over the steps before the switch.
    pub iterations: f64,
}

impl std::fmt::Debug for Sensitivities {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Sensitivities")
            .field("parameters", &self.names())
            .field("solves", &self.solves)
            .field("factorizations", &self.factorizations)
            .finish_non_exhaustive()
    }
}

impl Sensitivities {
    /// When the run's modified Newton (the automatic choice) turned into
    /// once per step: its steps from the sensitivities' factorization at
    /// the converged state took 1.5 iterations or more on average over the
    /// first 16 (`None`: it did not).
    #[must_use]
    pub fn switched_newton(&self) -> Option<NewtonSwitch> {
        self.switched
    }

    /// How many parameters.
    #[must_use]
    pub fn len(&self) -> usize {
        self.params.len()
    }

    /// Whether there are none.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.params.is_empty()
    }

    /// The parameters' names, in order.
    #[must_use]
    pub fn names(&self) -> Vec<String> {
        self.params.iter().map(|p| p.name.clone()).collect()
    }

    /// The nominal value and the difference step `h_p` of parameter `k`.
    #[must_use]
    pub fn value_and_step(&self, k: usize) -> (f64, f64) {
        (self.params[k].value, self.params[k].step)
    }

    /// `∂u/∂p_k` of the current state.
    #[must_use]
    pub fn u(&self, k: usize) -> &[f64] {
        &self.params[k].s.u
    }

    /// `∂u̇/∂p_k`.
    #[must_use]
    pub fn v(&self, k: usize) -> &[f64] {
        &self.params[k].s.v
    }

    /// `∂ü/∂p_k`.
    #[must_use]
    pub fn a(&self, k: usize) -> &[f64] {
        &self.params[k].s.a
    }

    /// `∂λ/∂p_k`.
    #[must_use]
    pub fn lambda(&self, k: usize) -> &[f64] {
        &self.params[k].s.lambda
    }

    /// Whether parameter `k`'s partials `∂r/∂p`, `∂Φ/∂p` are formed from
    /// the small model of [`Parameterized::local_at`] (else from the whole
    /// model at `p ± h_p`).
    #[must_use]
    pub fn local(&self, k: usize) -> bool {
        self.params[k].partials.local()
    }

    /// Solves made so far: one per parameter and step.
    #[must_use]
    pub fn solves(&self) -> usize {
        self.solves
    }

    /// Factorizations made for the sensitivities: one per step, at the
    /// converged state.
    #[must_use]
    pub fn factorizations(&self) -> usize {
        self.factorizations
    }
}

/// The difference step for a parameter of value `p`.
fn difference_step(p: f64) -> f64 {
    if p == 0.0 {
        DIFFERENCE_STEP
    } else {
        DIFFERENCE_STEP * p.abs()
    }
}

/// `(x⁺ − x⁻) / (2 h)` element by element.
pub(super) fn central(plus: &[f64], minus: &[f64], h: f64) -> Vec<f64> {
    plus.iter()
        .zip(minus)
        .map(|(a, b)| (a - b) / (2.0 * h))
        .collect()
}

impl<S: System + ?Sized> Integrator<'_, S> {
    /// The sensitivities of the current (initial) state to `params`:
    /// through the start's stages (`initial.rs`) for the consistent start
    /// with projection, else central differences of the start made at
    /// `p ± h_p` ([`DIFFERENCE_STEP`]), with this integrator's
    /// configuration.
    ///
    /// # Errors
    /// [`IntegrationError::Config`] after the first step, for a parameter
    /// whose model cannot be made at `p ± h_p` or has other dimensions;
    /// the start's error of a perturbed model.
    pub fn sensitivities(
        &self,
        params: &[&dyn Parameterized],
    ) -> Result<Sensitivities, IntegrationError> {
        if self.stats.steps > 0 {
            return Err(IntegrationError::Config(
                "sensitivities start at the initial state, before the first step".into(),
            ));
        }
        // The models at p ± h_p share the analysis of the KKT pattern.
        let _shared = SharedAnalyses::begin();
        let by_stages = self.starts_by_stages();
        let (mut names, mut scratch) = (None, None);
        let (mut out, mut given) = (Vec::with_capacity(params.len()), Vec::new());
        for param in params {
            let (p, g) = self.parameter(*param, &mut names, &mut scratch, by_stages)?;
            out.push(p);
            given.push(g);
        }
        if by_stages && !out.is_empty() {
            self.initial_by_stages(&mut out, &given)?;
        }
        Ok(Sensitivities {
            params: out,
            scratch: Scratch::default(),
            solves: 0,
            factorizations: 0,
            contraction: Contraction::default(),
            probes: [Probe::default(); 2],
            sharing: true,
            switched: None,
        })
    }

    /// One parameter and the sensitivities `∂(u_g, u̇_g)/∂p` of the given
    /// initial state (`u` and `v` of the second; empty unless
    /// `by_stages`). Without `by_stages` the parameter's initial
    /// sensitivities are central differences of whole starts at `p ± h_p`;
    /// with it they are left to
    /// [`initial_by_stages`](Self::initial_by_stages). `names`: the whole
    /// model's names, indexed when a small model first needs them.
    fn parameter(
        &self,
        param: &dyn Parameterized,
        names: &mut Option<Names>,
        scratch: &mut Option<(Linearization, KktSolver)>,
        by_stages: bool,
    ) -> Result<(Parameter, State), IntegrationError> {
        let name = param.name();
        let value = param.value();
        let step = difference_step(value);
        let bad = |why: String| IntegrationError::Config(format!("sensitivity to '{name}': {why}"));
        let local = match (
            param.local_at(value + step).map_err(bad)?,
            param.local_at(value - step).map_err(bad)?,
        ) {
            (Some(p), Some(q)) => local_partials(self.sys, names, p, q),
            _ => None,
        };
        let (n, m) = (self.sys.n_coords(), self.sys.n_constraints());
        let mut s = State::zeros(n, m);
        let mut given = State::zeros(0, 0);
        let whole = if local.is_some() && by_stages && param.keeps_initial_state() {
            given = State::zeros(n, 0);
            None
        } else {
            let (plus, minus) = self.whole_models(param, step).map_err(bad)?;
            if by_stages {
                let (p, q) = (plus.as_ref(), minus.as_ref());
                given.u = central(p.initial_position(), q.initial_position(), step);
                given.v = central(p.initial_velocity(), q.initial_velocity(), step);
            } else {
                s = self.start_difference(plus.as_ref(), minus.as_ref(), step, scratch)?;
            }
            Some((plus, minus))
        };
        let partials = match (local, whole) {
            (Some(partials), _) => partials,
            (None, Some((plus, minus))) => self.whole_partials(plus, minus).map_err(bad)?,
            // (The whole models are made whenever there is no small one.)
            (None, None) => return Err(bad("no model at p ± h_p".into())),
        };
        let parameter = Parameter {
            name,
            value,
            step,
            partials,
            s,
            past: PastSolutions::default(),
        };
        Ok((parameter, given))
    }

    /// The whole model at `p ± step`, of this model's size.
    fn whole_models(&self, param: &dyn Parameterized, step: f64) -> Result<Sides, String> {
        let value = param.value();
        let plus = param.at(value + step)?;
        let minus = param.at(value - step)?;
        let (n, m) = (self.sys.n_coords(), self.sys.n_constraints());
        for v in [&plus, &minus] {
            let sys = v.system();
            if (sys.n_coords(), sys.n_constraints()) != (n, m) {
                return Err(format!(
                    "the model changes size with it ({} coordinates and {} constraints instead of {n} and {m})",
                    sys.n_coords(),
                    sys.n_constraints()
                ));
            }
            let (u, v) = (v.initial_position(), v.initial_velocity());
            if (u.len(), v.len()) != (n, n) {
                return Err(format!(
                    "its initial state has {} positions and {} velocities instead of {n}",
                    u.len(),
                    v.len()
                ));
            }
        }
        Ok((plus, minus))
    }

    /// The central difference of the whole starts of `plus` and `minus`.
    fn start_difference(
        &self,
        plus: &dyn Variant,
        minus: &dyn Variant,
        step: f64,
        scratch: &mut Option<(Linearization, KktSolver)>,
    ) -> Result<State, IntegrationError> {
        let s_plus = self.start_of(plus, scratch)?;
        let s_minus = self.start_of(minus, scratch)?;
        Ok(State {
            u: central(&s_plus.u, &s_minus.u, step),
            v: central(&s_plus.v, &s_minus.v, step),
            a: central(&s_plus.a, &s_minus.a, step),
            a_alpha: central(&s_plus.a_alpha, &s_minus.a_alpha, step),
            lambda: central(&s_plus.lambda, &s_minus.lambda, step),
        })
    }

    /// The partials from the whole models at `p ± h_p`, linearized on this
    /// integrator's structure when their patterns are the same.
    fn whole_partials(
        &self,
        plus: Box<dyn Variant>,
        minus: Box<dyn Variant>,
    ) -> Result<Partials, String> {
        let side = |variant: Box<dyn Variant>| -> Result<Side, String> {
            let lin = match self.lin.like(variant.system()) {
                Some(lin) => lin,
                None => Linearization::new(variant.system()).map_err(|e| e.to_string())?,
            };
            Ok(Side { variant, lin })
        };
        Ok(Partials {
            plus: side(plus)?,
            minus: side(minus)?,
            places: None,
            gathered: State::zeros(0, 0),
        })
    }

    /// The start of the model `v` (a parameter's model at `p ± h_p`) with
    /// this integrator's configuration. When its patterns are this
    /// model's, on the linearization and the solver of `scratch` (made
    /// once, from this integrator's, and reused by every parameter's
    /// starts: no structure built or analysed again); else as
    /// [`Integrator::new`].
    fn start_of(
        &self,
        v: &dyn Variant,
        scratch: &mut Option<(Linearization, KktSolver)>,
    ) -> Result<State, IntegrationError> {
        let sys = v.system();
        let x0 = (self.t, v.initial_position(), v.initial_velocity());
        let reused = match scratch.take() {
            Some((mut lin, solver)) => lin.reset_for(sys).then_some((lin, solver)),
            None => match self.lin.like(sys) {
                Some(lin) => {
                    let options = KktOptions {
                        backend: self.solver.backend(),
                        n_primal: self.config.kkt.n_primal.or(Some(sys.n_coords())),
                        ..self.config.kkt
                    };
                    let solver = KktSolver::new(lin.kkt(), &options).map_err(|e| {
                        self.kkt_error("analysing a parameter's model", self.t, 0.0, e)
                    })?;
                    Some((lin, solver))
                }
                None => None,
            },
        };
        let Some((lin, solver)) = reused else {
            let integ = Integrator::new(sys, self.config.clone(), x0.0, x0.1, x0.2)?;
            return Ok(integ.state);
        };
        let integ = Integrator::with_linear_algebra(sys, self.config.clone(), x0, lin, solver)?;
        *scratch = Some((integ.lin, integ.solver));
        Ok(integ.state)
    }

    /// [`step`](Self::step), then the sensitivities carried to the new state.
    ///
    /// # Errors
    /// As [`step`](Self::step); [`IntegrationError::Kkt`] when the
    /// sensitivities' solve fails; [`IntegrationError::NonFinite`] for a
    /// sensitivity that is not finite.
    pub fn step_with(
        &mut self,
        t_end: f64,
        sens: &mut Sensitivities,
    ) -> Result<(), IntegrationError> {
        // As in `step`: subnormal numbers as zero (mstar_model::subnormal).
        let _flush = FlushSubnormals::new();
        let h_before = self.h_last;
        let factored_before = self.stats.factorizations;
        let before = Start {
            iterations: self.stats.iterations,
            rejected: self.stats.rejected,
            from_converged: self.factored_at_converged,
            from_shared: self.jacobians_of_state,
        };
        self.step(t_end)?;
        if sens.params.is_empty() {
            return Ok(());
        }
        self.probe(sens, &before);
        let h = self.h_last;
        // `M`, `B`, `g`, `Φ` are those of Newton's last residual, at the
        // converged state; the Jacobians are evaluated there too.
        let s = &self.state;
        self.lin.eval_jacobians(self.sys, &s.at(self.t));
        // A factorization of this step's own iterate (once per step, full
        // Newton) is that of a matrix close to the converged one: refined
        // with it, a parameter costs a solve and a product (`refine.rs`). Otherwise
        // (an earlier step's Jacobian, modified Newton), or for many
        // parameters, the matrix is factored at the converged state once
        // for all of them.
        let mut refine = self.stats.factorizations > factored_before
            && self.factored_h == Some(h)
            && sens.params.len() <= REFINED_PARAMETERS;
        // With the step's own factorization (once per step, full Newton)
        // and Jacobians that cost more than a solve, the next step's first
        // factorization takes the ones evaluated here.
        let shares = refine && self.sys.jacobians_are_costly() && sens.sharing;
        if refine {
            sens.contraction.tick();
        } else {
            self.factor_converged(h)?;
            sens.factorizations += 1;
        }
        for k in 0..sens.params.len() {
            self.advance_sensitivity(sens, k, h, h / h_before, &mut refine)?;
        }
        self.jacobians_of_state = shares;
        Ok(())
    }

    /// Records the step just made (`before`: the run at its start) and
    /// undoes a choice its probe finds costly: modified Newton by the
    /// automatic choice, the step started from the sensitivities'
    /// factorization at the converged state (`factor_converged`), turns into
    /// once per step (with one parameter, which then refines with Newton's
    /// factorization; more share a factorization at the converged state
    /// either way); the next step's Jacobians stop coming from the
    /// sensitivities (the step's first factorization took them). A step
    /// with a rejected attempt is not recorded: its failed iterations say
    /// nothing of the converged ones.
    fn probe(&mut self, sens: &mut Sensitivities, before: &Start) {
        if self.stats.rejected != before.rejected {
            return;
        }
        let iterations = self.stats.iterations - before.iterations;
        let modified = matches!(self.config.newton, Newton::Modified { .. });
        if self.modified_by_choice
            && modified
            && before.from_converged
            && sens.params.len() <= REFINED_PARAMETERS
        {
            let mean = sens.probes[0].record(iterations);
            if let Some(mean) = mean.filter(|&m| m >= PROBE_MEAN) {
                self.config.newton = Newton::PER_STEP;
                sens.switched = Some(NewtonSwitch {
                    t: self.t,
                    iterations: mean,
                });
            }
        }
        let took_shared = before.from_shared && !self.jacobians_of_state;
        if took_shared
            && sens.probes[1]
                .record(iterations)
                .is_some_and(|m| m >= PROBE_MEAN)
        {
            sens.sharing = false;
        }
    }

    /// Parameter `k`'s sensitivities from the previous state to the new one
    /// (module documentation); `rescale` is the ratio of this step's size to
    /// the previous one's (the predictor's rescaling of `a_n`).
    fn advance_sensitivity(
        &mut self,
        sens: &mut Sensitivities,
        k: usize,
        h: f64,
        rescale: f64,
        refine: &mut bool,
    ) -> Result<(), IntegrationError> {
        let (n, m) = (self.sys.n_coords(), self.sys.n_constraints());
        let Sensitivities {
            params,
            scratch,
            solves,
            factorizations,
            contraction,
            ..
        } = sens;
        scratch.size(n, m);
        let param = &mut params[k];
        self.predict_sensitivity(&param.s, h, rescale, &mut scratch.predicted);
        // The system's right-hand side is `[r_p − K_T δu^p − C_T δu̇^p; −Φ_p −
        // B δu^p]`; the products are formed with those of `J x`
        // (`Integrator::kkt_residual`).
        self.partials_into(param, &mut scratch.partials);
        let refinement = (&param.past, contraction);
        self.solve_sensitivity(scratch, refinement, (solves, factorizations), h, refine)?;
        let c = self.p.coefficients(h, self.config.scaling);
        let a_p = 1.0 / (self.p.beta * h * h);
        let (x, pred, s) = (&scratch.x, &scratch.predicted, &mut param.s);
        // ‖·‖ is NaN or infinite exactly when an entry is (checked on the
        // way, not in a pass of its own).
        let mut norm = MaxAbs::new();
        for i in 0..n {
            let du = x[i];
            s.u[i] = pred.u[i] + du;
            norm.push(s.u[i]);
            s.v[i] = pred.v[i] + c.c_v * du;
            s.a[i] = c.c_a * du;
            s.a_alpha[i] = pred.a_alpha[i] + a_p * du;
        }
        s.lambda.copy_from_slice(&x[n..]);
        param.past.push(&mut scratch.x, h);
        let finite = norm.is_finite() && max_abs(&s.lambda).is_finite();
        if let Some(i) = (!finite)
            .then(|| s.u.iter().chain(&s.lambda).position(|x| !x.is_finite()))
            .flatten()
        {
            return Err(IntegrationError::NonFinite {
                t: self.t,
                what: format!(
                    "the sensitivity to '{}' ({})",
                    param.name,
                    if i < n {
                        format!("coordinate '{}'", self.sys.coord_name(i))
                    } else {
                        format!("multiplier of '{}'", self.sys.constraint_name(i - n))
                    }
                ),
            });
        }
        Ok(())
    }

    /// The predictor (14) with zero acceleration applied to the
    /// sensitivities `s` of the previous state (as `predict` with
    /// [`crate::Predictor::ZeroAcceleration`]), into `out`'s `u`, `v` and
    /// `a_alpha`.
    fn predict_sensitivity(&self, s: &State, h: f64, rescale: f64, out: &mut State) {
        let p = self.p;
        for i in 0..s.u.len() {
            let a_n = s.a[i] + rescale * (s.a_alpha[i] - s.a[i]);
            let aa1 = (p.alpha_f * s.a[i] - p.alpha_m * a_n) / (1.0 - p.alpha_m);
            out.a_alpha[i] = aa1;
            out.v[i] = s.v[i] + h * ((1.0 - p.gamma) * a_n + p.gamma * aa1);
            out.u[i] = s.u[i] + h * s.v[i] + h * h * ((0.5 - p.beta) * a_n + p.beta * aa1);
        }
    }

    /// The partials `[∂r/∂p_k; −∂Φ/∂p_k]` of parameter `k` of `sens` at the
    /// current state (what [`step_with`](Self::step_with) forms at each
    /// converged state): central differences of the residual and the
    /// constraints of the parameter's models at `p ± h_p`, the small model
    /// scattered into the whole model's rows when
    /// [`Sensitivities::local`] says so.
    ///
    /// # Panics
    /// If `k` is not below `sens.len()`.
    pub fn partials(&self, sens: &mut Sensitivities, k: usize) -> Vec<f64> {
        let mut rhs = Vec::new();
        self.partials_into(&mut sens.params[k], &mut rhs);
        rhs
    }

    /// `[r_p; −Φ_p]` at the converged state into `rhs` (sized `n + m`):
    /// central differences of the residual and the constraints of the
    /// models at `p ± h_p` (the whole model's or the parameter's small one,
    /// scattered into the whole model's rows).
    fn partials_into(&self, param: &mut Parameter, rhs: &mut Vec<f64>) {
        let n = self.sys.n_coords();
        rhs.clear();
        rhs.resize(n + self.sys.n_constraints(), 0.0);
        let x = self.state.at(self.t);
        param.partials.each(&x, n, param.step, |k, c| rhs[k] = c);
    }

    /// `J x = rhs` (`scratch`'s) with `J = [S Bᵀ; B 0]`, `S = K_T + γ' C_T +
    /// β' M`, at the converged state, into `scratch.x`. With `refine`, by
    /// refinement with the step's own factorization (of an iterate of this
    /// step, `refine.rs`); when that does not converge, the matrix is
    /// factored at the converged state and `refine` cleared (for the step's
    /// other parameters). Without, one solve with the factorization at the
    /// converged state. `counts`: the solves and factorizations made.
    fn solve_sensitivity(
        &mut self,
        scratch: &mut Scratch,
        refinement: (&PastSolutions, &mut Contraction),
        (solves, factorizations): (&mut usize, &mut usize),
        h: f64,
        refine: &mut bool,
    ) -> Result<(), IntegrationError> {
        if *refine {
            if self.refined(scratch, refinement, h, solves)? {
                return Ok(());
            }
            self.factor_converged(h)?;
            *factorizations += 1;
            *refine = false;
        }
        *solves += 1;
        self.kkt_residual(scratch, h, true);
        self.solve_scaled(&scratch.residual, h, &mut scratch.x, false)
    }

    /// `y = J⁻¹ f` with the factored (scaled, possibly augmented) KKT
    /// matrix: its right-hand side is `[scale f_u; f_λ]`, and its
    /// multiplier part is `scale (δλ − c_bb f_λ)` when `S` carries `c_bb
    /// BᵀB`. `unrefined`: a pass of the refinement against the converged
    /// matrix, without the backend's refinement step and without the
    /// residual check of Newton's factorization, which the refinement's own
    /// residual replaces
    /// ([`mstar_kkt::KktSolver::solve_unverified_correction`]).
    pub(super) fn solve_scaled(
        &mut self,
        f: &[f64],
        h: f64,
        y: &mut Vec<f64>,
        unrefined: bool,
    ) -> Result<(), IntegrationError> {
        let n = self.sys.n_coords();
        let c = self.p.coefficients(h, self.config.scaling);
        let in_matrix = if self.lin.augmented() { c.c_bb } else { 0.0 };
        y.clear();
        y.extend(f[..n].iter().map(|r| c.scale * r));
        y.extend_from_slice(&f[n..]);
        let solved = if unrefined {
            let norm = max_abs(y);
            self.solver.solve_unverified_correction(y, norm)
        } else {
            self.solver.solve_in_place(y)
        };
        solved.map_err(|source| self.kkt_error("solving for a sensitivity", self.t, h, source))?;
        for (y, f) in y[n..].iter_mut().zip(&f[n..]) {
            *y = *y / c.scale + in_matrix * f;
        }
        Ok(())
    }

    /// Factors the iteration matrix at the converged state (the Jacobians
    /// of [`step_with`](Self::step_with)), when the Newton factorization is
    /// an earlier step's (modified Newton: refining with it took 3–7 solves
    /// and products a step, docs/performance.md, "Forward sensitivities"),
    /// or for several parameters. The next step's modified Newton starts
    /// from it.
    fn factor_converged(&mut self, h: f64) -> Result<(), IntegrationError> {
        let c = self.p.coefficients(h, self.config.scaling);
        self.lin.assemble(&c);
        self.factored_h = None;
        self.solver
            .factor(&self.lin.kkt().values)
            .map_err(|source| self.kkt_error("factoring for a sensitivity", self.t, h, source))?;
        self.factored_h = Some(h);
        self.factored_at_converged = true;
        self.drift = 0.0;
        Ok(())
    }
}

/// Up to this many parameters refine with the step's factorization; more
/// share one factorization at the converged state. A refinement costs a
/// parameter a solve and a product more; on the N-four-bar (81 bars) two
/// parameters took 6 314 instructions a body-step refined against 5 998
/// with the factorization (docs/performance.md, "Forward sensitivities").
const REFINED_PARAMETERS: usize = 1;

/// The whole model's coordinates and constraint rows by name.
pub(super) struct Names {
    coords: HashMap<String, usize>,
    rows: HashMap<String, usize>,
}

impl Names {
    fn of<S: System + ?Sized>(sys: &S) -> Self {
        Self {
            coords: (0..sys.n_coords())
                .map(|i| (sys.coord_name(i), i))
                .collect(),
            rows: (0..sys.n_constraints())
                .map(|j| (sys.constraint_name(j), j))
                .collect(),
        }
    }

    /// The places of `small`'s coordinates and rows in the whole model;
    /// `None` when one of its names is not the whole model's.
    fn places(&self, small: &dyn System) -> Option<Places> {
        let coords = (0..small.n_coords())
            .map(|i| self.coords.get(&small.coord_name(i)).copied())
            .collect::<Option<Vec<_>>>()?;
        let rows = (0..small.n_constraints())
            .map(|j| self.rows.get(&small.constraint_name(j)).copied())
            .collect::<Option<Vec<_>>>()?;
        Some(Places { coords, rows })
    }
}

/// The partials of a parameter from its small models at `p ± h_p`; `None`
/// (the whole model's central differences are used) when their names are
/// not all the whole model's, the two differ in their coordinates or rows,
/// or they cannot be linearized.
fn local_partials<S: System + ?Sized>(
    sys: &S,
    names: &mut Option<Names>,
    plus: Box<dyn Variant>,
    minus: Box<dyn Variant>,
) -> Option<Partials> {
    let names = names.get_or_insert_with(|| Names::of(sys));
    let places = names.places(plus.system())?;
    let other = names.places(minus.system())?;
    if (&places.coords, &places.rows) != (&other.coords, &other.rows) {
        return None;
    }
    let (n, m) = (places.coords.len(), places.rows.len());
    let side = |variant: Box<dyn Variant>| {
        Linearization::new(variant.system())
            .ok()
            .map(|lin| Side { variant, lin })
    };
    Some(Partials {
        plus: side(plus)?,
        minus: side(minus)?,
        places: Some(places),
        gathered: State::zeros(n, m),
    })
}
