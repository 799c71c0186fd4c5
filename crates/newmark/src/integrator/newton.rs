//! One step's Newton iteration (paper §2.2, Fig. 2; `algorithm.md` §4): the
//! predictor (14), the residual and its tolerances, the iteration matrix
//! (16)-(17) when it is refreshed, and the corrector (15).

use mstar_linearize::{Coefficients, max_abs};
use mstar_model::System;

use super::history::{Misses, Past, Rule, five_step};
use super::{Failure, Integrator, State};
use crate::{AlphaParams, Newton};

/// What stays fixed over one attempt's iterations.
struct Corrector {
    /// The end of the step.
    t1: f64,
    /// The KKT coefficients (17) and scaling.
    coefficients: Coefficients,
    /// `Δü = β' Δu`, `Δu̇ = γ' Δu` (15), and the acceleration-like
    /// variable's `Δa = Δu / (β h²)`.
    beta_p: f64,
    gamma_p: f64,
    a_p: f64,
    /// Modified Newton refactors when `‖Δu_k‖ > max_rate ‖Δu_{k−1}‖`.
    max_rate: f64,
    /// The multiplier shift per correction, times `Φ` (see
    /// [`Integrator::correct`]).
    shift: f64,
}

/// The norms of one iteration's residual and their tolerances.
struct Norms {
    /// `‖[scale·r; −Φ]‖∞`.
    rhs: f64,
    residual: f64,
    residual_tol: f64,
    constraint: f64,
    constraint_tol: f64,
    /// The violation whose force `β' M Φ` is within the residual's
    /// tolerance, or the positions' round-off `ε max(1, ‖u‖∞)`; infinite
    /// (not read) when the residual is above its tolerance.
    constraint_settled: f64,
}

impl Norms {
    /// Within the tolerances, and `‖Φ‖∞` within `constraint_settled` unless
    /// `anyway`. A violation `δ` left in one step is removed by the next
    /// one's positions, and its accelerations and multipliers take it as a
    /// kick `β' M δ` (15) that the scheme's double root `−ρ∞` rings for tens
    /// of steps: `1e-14` m left at `h = 2.5e-4` swung a reaction by `1e-6` N
    /// (docs/theory.md, "Round-off in the multipliers").
    fn converged(&self, anyway: bool) -> bool {
        self.residual <= self.residual_tol
            && self.constraint <= self.constraint_tol
            && (anyway || self.constraint <= self.constraint_settled)
    }

    /// The residual within its tolerance, and `‖Φ‖∞` above
    /// `constraint_settled` and no longer halving from the last iterate's
    /// `previous`: round-off after a fresh Jacobian, a Jacobian to refresh
    /// after a reused one.
    fn stalled(&self, previous: f64) -> bool {
        self.residual <= self.residual_tol
            && self.constraint > self.constraint_settled
            && self.constraint > 0.5 * previous
    }

    fn not_converged(&self, iterations: usize) -> Failure {
        Failure::NotConverged {
            iterations,
            residual: self.residual,
            residual_tol: self.residual_tol,
            constraint: self.constraint,
            constraint_tol: self.constraint_tol,
        }
    }
}

impl<S: System + ?Sized> Integrator<'_, S> {
    /// One Newton attempt at the step `t → t + h`; returns the iterations.
    /// Its solves leave the residual check of a new factorization to the
    /// end ([`mstar_kkt::KktSolver::solve_unverified_correction`]): a converged
    /// iterate is certified by its own residual, and an attempt that fails
    /// checks the factorization on its last residual, so that an inaccurate
    /// solve is reported as the solver's.
    pub(super) fn attempt(&mut self, h: f64) -> Result<usize, Failure> {
        let result = self.iterate(h);
        if let Err(Failure::NotConverged { .. } | Failure::NonFinite(_)) = result {
            // The last residual `[scale r; −Φ]` (in `rhs`), or ones where it
            // is not finite.
            let mut probe = self.rhs.clone();
            if !max_abs(&probe).is_finite() {
                probe.fill(1.0);
            }
            if let Err(source) = self.solver.verify(&mut probe) {
                return Err(Failure::Kkt {
                    context: "solving with the iteration matrix",
                    source,
                });
            }
        }
        result
    }

    /// The iterations of [`attempt`](Self::attempt).
    fn iterate(&mut self, h: f64) -> Result<usize, Failure> {
        self.predict(h);
        let k = self.corrector(h);
        let mut force_refactor = false;
        let mut previous_step = f64::INFINITY;
        // The last iterate's ‖Φ‖∞, and whether its correction was made with
        // a Jacobian evaluated at it.
        let (mut previous_constraint, mut fresh) = (f64::INFINITY, false);
        // ‖u‖∞ of the iterate, kept up to date by the corrector.
        let mut u_max = max_abs(&self.trial.u);
        for it in 0..=self.config.max_iterations {
            let norms = self.residual(&k, u_max)?;
            self.stats.iterations += usize::from(it > 0);
            let last = it == self.config.max_iterations;
            let stalled = norms.stalled(previous_constraint);
            // At least one correction: a predictor that happens to meet the
            // tolerances (small h, near rest) still needs its λ and ü updated.
            if it > 0 && norms.converged(last || (fresh && stalled)) {
                return Ok(it);
            }
            if last {
                return Err(norms.not_converged(it));
            }
            previous_constraint = norms.constraint;
            let refactor =
                self.refactors(h, force_refactor || stalled || (it == 0 && self.per_step()));
            fresh = refactor;
            if refactor {
                self.refactor(&k, h)?;
                force_refactor = false;
                previous_step = f64::INFINITY;
            }
            // Without the backend's refinement step (`schur-lu`'s): the
            // next iteration's residual corrects what it would, and it no
            // longer saves iterations (docs/performance.md, "Newton's solves
            // without `schur-lu`'s refinement").
            let solved = self
                .solver
                .solve_unverified_correction(&mut self.rhs, norms.rhs);
            solved.map_err(|source| Failure::Kkt {
                context: "solving with the iteration matrix",
                source,
            })?;
            let step;
            (step, u_max) = self.correct(&k);
            self.drift += step;
            if step > k.max_rate * previous_step {
                force_refactor = true;
            }
            previous_step = step;
        }
        unreachable!("the loop returns at max_iterations")
    }

    /// Whether this iteration refactors: always with full Newton, else for a
    /// new step size or when `asked`.
    fn refactors(&self, h: f64, asked: bool) -> bool {
        match self.config.newton {
            Newton::Full => true,
            // (Automatic is resolved when the integrator is made.)
            Newton::Modified { .. } | Newton::PerStep { .. } | Newton::Automatic => {
                asked || self.factored_h != Some(h)
            }
        }
    }

    /// Whether every step starts with a fresh Jacobian ([`Newton::PerStep`]).
    fn per_step(&self) -> bool {
        matches!(self.config.newton, Newton::PerStep { .. })
    }

    /// The corrector's coefficients for a step of size `h`.
    fn corrector(&self, h: f64) -> Corrector {
        let coefficients = self.p.coefficients(h, self.config.scaling);
        // With M* in S_T (eq. 17) the solve returns Δλ + c_bb Φ (see
        // `Config::exact_multiplier_update`), without the BᵀB term (the
        // Schur backend's structure) it returns Δλ; the paper keeps the
        // shift c_bb Φ, the exact update does not.
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
        Corrector {
            t1: self.step_end(h),
            beta_p: coefficients.c_a,
            gamma_p: coefficients.c_v,
            a_p: 1.0 / (self.p.beta * h * h),
            max_rate: match self.config.newton {
                Newton::Modified { max_rate } | Newton::PerStep { max_rate } => max_rate,
                Newton::Automatic => 0.5,
                Newton::Full => f64::INFINITY,
            },
            shift: kept - in_matrix,
            coefficients,
        }
    }

    /// The residual formed straight into the right-hand side of (16), its
    /// norms and tolerances.
    fn residual(&mut self, k: &Corrector, u_max: f64) -> Result<Norms, Failure> {
        let s = &self.trial;
        let rhs = self
            .lin
            .eval_kkt_rhs(self.sys, &s.at(k.t1), k.coefficients.scale, &mut self.rhs);
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
            4.0 * k.coefficients.c_bb * f64::EPSILON * u_max.max(1.0) * max_abs(self.lin.b())
        };
        let residual_tol = (self.config.tol * self.lin.force_scale()).max(floor);
        // Both checks that read `constraint_settled` need the residual
        // within its tolerance first: above it the pass over `M` is skipped
        // (most predictors' residuals).
        let constraint_settled = if residual <= residual_tol {
            let kick = k.coefficients.c_a * max_abs(self.lin.mass());
            (residual_tol / kick).max(f64::EPSILON * u_max.max(1.0))
        } else {
            f64::INFINITY
        };
        Ok(Norms {
            rhs,
            residual,
            residual_tol,
            constraint,
            constraint_tol: self.config.tol * u_max.max(1.0),
            constraint_settled,
        })
    }

    /// Evaluates the Jacobians at the iterate (or takes those of the state
    /// before the step that the sensitivities left,
    /// [`System::jacobians_are_costly`]), assembles the iteration matrix
    /// (16)-(17) with `M` and `B` of the iterate, and factors it.
    fn refactor(&mut self, k: &Corrector, h: f64) -> Result<(), Failure> {
        let s = &self.trial;
        let reused = std::mem::take(&mut self.jacobians_of_state);
        if !reused {
            self.lin.eval_jacobians(self.sys, &s.at(k.t1));
        }
        self.lin.assemble(&k.coefficients);
        self.factored_h = None;
        self.solver
            .factor(&self.lin.kkt().values)
            .map_err(|source| Failure::Kkt {
                context: "factoring the iteration matrix",
                source,
            })?;
        self.factored_h = Some(h);
        self.factored_at_converged = false;
        self.drift = if reused {
            max_abs_difference(&self.trial.u, &self.state.u)
        } else {
            0.0
        };
        self.stats.factorizations += 1;
        Ok(())
    }

    /// The corrector (15) from the solution in `rhs`; returns `‖Δu‖∞` and
    /// the new `‖u‖∞`.
    fn correct(&mut self, k: &Corrector) -> (f64, f64) {
        let n = self.trial.u.len();
        let (du, dl) = self.rhs.split_at(n);
        let s = &mut self.trial;
        let (mut step, mut u_max) = (0.0f64, 0.0f64);
        // Plain comparisons, as `f64::max` with a maximum that is never NaN
        // (a NaN entry is passed over) but without its NaN rules' blends in
        // the loop's chain.
        let bigger = |m: f64, x: f64| if x > m { x } else { m };
        for i in 0..n {
            s.u[i] += du[i];
            s.v[i] += k.gamma_p * du[i];
            s.a[i] += k.beta_p * du[i];
            s.a_alpha[i] += k.a_p * du[i];
            u_max = bigger(u_max, s.u[i].abs());
            step = bigger(step, du[i].abs());
        }
        let scale = k.coefficients.scale;
        for ((l, &d), &phi) in s.lambda.iter_mut().zip(dl).zip(self.lin.phi()) {
            *l += d / scale + k.shift * phi;
        }
        (step, u_max)
    }

    /// Predictor: eq. (14) generalized (Arnold & Brüls 2007, Algorithm 1),
    /// with `ü_{n+1}⁰` and `λ⁰` by the history's rules, which are judged
    /// for the next step on the state this one starts from (`history.rs`).
    pub(super) fn predict(&mut self, h: f64) {
        let predictor = self.config.predictor;
        let [rule_a, rule_lambda] = self.history.rules(predictor, h);
        let (s, past) = (&self.state, &self.history);
        let (eligible, judging) = (past.eligible(predictor, h), past.judging(predictor, h));
        let misses = judging.then(|| {
            [
                Misses::of(&s.a, past.a()),
                Misses::of(&s.lambda, past.lambda()),
            ]
        });
        // a_n belongs to the last step's size; rescaled to this one's.
        let coefficients = (self.p, h, h / self.h_last);
        predict_positions(coefficients, s, &mut self.trial, rule_a, past.a());
        rule_lambda.extrapolate_into(&s.lambda, past.lambda(), &mut self.trial.lambda);
        self.history.judge(misses, eligible);
    }
}

/// `u, u̇, ü, a` of the predictor (14) from the state `s` into `t`, with
/// `ü_{n+1}⁰` by `rule` from `s.a` and `past` (one loop per rule, so that
/// each is a plain loop); `(p, h, rescale)`: the scheme, the step and the
/// ratio of `h` to the last step's size.
fn predict_positions(
    coefficients: (AlphaParams, f64, f64),
    s: &State,
    t: &mut State,
    rule: Rule,
    past: Past<'_>,
) {
    let x = &s.a;
    match rule {
        Rule::Zero => positions_with(coefficients, s, t, |_| 0.0),
        Rule::Constant => positions_with(coefficients, s, t, |i| x[i]),
        Rule::Linear { ratio } => {
            let p1 = past[0];
            positions_with(coefficients, s, t, |i| x[i] + ratio * (x[i] - p1[i]));
        }
        Rule::FiveStep => {
            let [p1, p2, p3, p4, _] = past;
            positions_with(coefficients, s, t, |i| {
                five_step(x[i], p1[i], p2[i], p3[i], p4[i])
            });
        }
    }
}

/// [`predict_positions`] with `ü_{n+1}⁰ = a1(i)`.
#[inline(always)]
fn positions_with(
    (p, h, rescale): (AlphaParams, f64, f64),
    s: &State,
    t: &mut State,
    a1: impl Fn(usize) -> f64,
) {
    let AlphaParams {
        alpha_m,
        alpha_f,
        beta,
        gamma,
    } = p;
    for i in 0..s.u.len() {
        let a_n = s.a[i] + rescale * (s.a_alpha[i] - s.a[i]);
        let a1 = a1(i);
        let aa1 = (alpha_f * s.a[i] - alpha_m * a_n + (1.0 - alpha_f) * a1) / (1.0 - alpha_m);
        t.a[i] = a1;
        t.a_alpha[i] = aa1;
        t.v[i] = s.v[i] + h * ((1.0 - gamma) * a_n + gamma * aa1);
        t.u[i] = s.u[i] + h * s.v[i] + h * h * ((0.5 - beta) * a_n + beta * aa1);
    }
}

/// `‖a − b‖∞`.
fn max_abs_difference(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).fold(0.0, |m, (x, y)| m.max((x - y).abs()))
}
