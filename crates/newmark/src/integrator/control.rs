//! The local error estimate of a converged step and what is done with it:
//! monitoring, a strict limit, or adaptive step sizes with a PI controller
//! (`docs/theory.md`, "Local error estimate and step control").
//!
//! **Estimate.** With `a_n ≈ ü(t_n + Δ h)`, `Δ = α_m − α_f` (Arnold & Brüls
//! 2007), the position update
//! `u_{n+1} = u_n + h u̇_n + h² ((½ − β) a_n + β a_{n+1})` has the local error
//! `c h³ u⃛ + O(h⁴)` with `c = β − 1/6 + Δ/2`, and `h u⃛ ≈ a_{n+1} − a_n`:
//! `e = c h² (a_{n+1} − a_n)`, the estimator of Zienkiewicz & Xie (1991) for
//! Newmark (`Δ = 0`), here for the whole generalized-α family. Along the
//! constraints' normals the positions are fixed by `Φ = 0`, not by the
//! update, so the estimate is projected onto `B e = 0` with the step's
//! iteration matrix: `[S_T Bᵀ; B 0] [y; μ] = [0; B e]`, `e ← e − y`.
//!
//! **Step size changes.** `a_n` belongs to the step size it was computed
//! with: `a_n − ü_n ≈ Δ h u⃛`. A step of another size uses
//! `ü_n + (h_new/h_old)(a_n − ü_n)` (`newton.rs`, `predict`), which keeps
//! second order on variable steps (`tests/error_control.rs`).

use mstar_model::System;

use super::{Failure, Integrator};
use crate::{ErrorControl, IntegrationError, Short, StepMode};

/// A converged step's estimate, as a ratio to the tolerance.
#[derive(Clone, Copy, Debug)]
pub(super) struct Estimate {
    /// The largest of the truncation ratio and the Newton ratio.
    pub ratio: f64,
    /// The truncation error's ratio (what the step size controls).
    pub truncation: f64,
    /// The coordinate where the truncation ratio is largest (`None` when the
    /// converged constraint violation dominates: a loose Newton tolerance).
    pub coordinate: Option<usize>,
    /// The converged `‖Φ‖∞` over the tolerance.
    pub newton: f64,
}

/// The PI controller's exponents for a local error `O(h³)` (Gustafsson's
/// `0.7/k`, `0.4/k` with `k = 3`; Hairer & Wanner II, §IV.2), its safety
/// factor and the bounds of one step's change (growth capped at 1.5: each
/// change of `h` excites the scheme's period-2 mode a little; with 5, the
/// pendulum's adaptive runs rejected 2-8 times more steps, measured).
const K_I: f64 = 0.7 / 3.0;
const K_P: f64 = 0.4 / 3.0;
const SAFETY: f64 = 0.9;
const GROW_MAX: f64 = 1.5;
const SHRINK_MAX: f64 = 0.2;
/// Changes of `h` smaller than this keep `h` (and modified Newton's
/// factorization) as it is.
const GROW_MIN: f64 = 1.25;
/// Newton tolerances below this cannot be met in double precision (the
/// pendulum converges at 1e-15 and not at 1e-16).
const ROUND_OFF_TOL: f64 = 1e-15;

impl<S: System + ?Sized> Integrator<'_, S> {
    /// Estimates the converged trial step's local error and decides: `Some`
    /// to accept it, `None` when adaptive stepping rejects it (with `self.h`
    /// set to the retry's size).
    ///
    /// # Errors
    /// [`IntegrationError::ErrorTooLarge`] in strict mode when the estimate
    /// exceeds the tolerance, or when adaptive stepping would go below `h_min`.
    pub(super) fn judge(&mut self, h: f64) -> Result<Option<Estimate>, IntegrationError> {
        let mode = self.config.error.mode;
        let estimate = self.estimate(h, mode == StepMode::Adaptive);
        match mode {
            StepMode::Monitor => Ok(Some(estimate)),
            StepMode::Strict if estimate.ratio <= 1.0 => Ok(Some(estimate)),
            StepMode::Strict => Err(self.too_large(h, &estimate, None)),
            StepMode::Adaptive if estimate.truncation <= 1.0 => Ok(Some(estimate)),
            StepMode::Adaptive => {
                let factor = (SAFETY * estimate.truncation.powf(-1.0 / 3.0)).max(SHRINK_MAX);
                let h_min = self.config.h_min();
                // Down to h_min, then an error once h_min itself fails.
                if h.is_nan() || h <= h_min * (1.0 + 1e-12) {
                    return Err(self.too_large(h, &estimate, Some(h_min)));
                }
                let h_new = (h * factor).max(h_min);
                self.h = h_new;
                self.rejected_last = true;
                self.stats.rejected += 1;
                self.stats.error.rejected += 1;
                Ok(None)
            }
        }
    }

    /// The next step size after an accepted step of size `h` (adaptive mode).
    pub(super) fn adapt(&mut self, h: f64, estimate: &Estimate) {
        let err = estimate.truncation.max(1e-6);
        let mut factor = SAFETY * err.powf(-K_I) * self.error_previous.max(1e-6).powf(K_P);
        factor = factor.clamp(SHRINK_MAX, GROW_MAX);
        if self.rejected_last {
            factor = factor.min(1.0);
        }
        self.rejected_last = false;
        self.error_previous = err;
        let proposed = h * factor;
        // A shortened last step says little about the nominal size's error.
        let nominal = if h < self.h {
            self.h.min(proposed)
        } else {
            proposed
        };
        if nominal < self.h || nominal >= GROW_MIN * self.h {
            // Within [h_min, h_max]: a step the estimate would take below
            // h_min is tried at h_min and judged (`judge`).
            self.h = nominal
                .min(self.config.error.h_max.unwrap_or(f64::INFINITY))
                .max(self.config.h_min());
        }
    }

    /// The local error estimate of the trial step of size `h` (module
    /// documentation), projected onto `B e = 0` when `project` is set or the
    /// unprojected estimate exceeds the tolerance.
    fn estimate(&mut self, h: f64, project: bool) -> Estimate {
        let c = ErrorControl::coefficient(&self.p) * h * h;
        let rescale = h / self.h_last;
        let (s, t) = (&self.state, &self.trial);
        for (i, e) in self.error.iter_mut().enumerate() {
            let a_n = s.a[i] + rescale * (s.a_alpha[i] - s.a[i]);
            *e = c * (t.a_alpha[i] - a_n);
        }
        let mut truncation = self.weighted_error();
        if (project || truncation.0 > 1.0) && self.project_error().is_ok() {
            truncation = self.weighted_error();
        }
        let ErrorControl { rtol, atol, .. } = self.config.error;
        let u_max = mstar_linearize::max_abs(&self.trial.u);
        let newton = self.lin.constraint_norm() / (atol + rtol * u_max);
        Estimate {
            ratio: if newton > truncation.0 {
                newton
            } else {
                truncation.0
            },
            truncation: truncation.0,
            coordinate: if newton > truncation.0 {
                None
            } else {
                truncation.1
            },
            newton,
        }
    }

    /// `max_i |e_i| / (atol + rtol max(|u_n,i|, |u_n+1,i|))` and its `i`
    /// (NaN-aware: a NaN is the largest).
    fn weighted_error(&self) -> (f64, Option<usize>) {
        let ErrorControl { rtol, atol, .. } = self.config.error;
        let mut worst = (0.0, None);
        for (i, e) in self.error.iter().enumerate() {
            let scale = atol + rtol * self.state.u[i].abs().max(self.trial.u[i].abs());
            let ratio = e.abs() / scale;
            if ratio > worst.0 || ratio.is_nan() && !worst.0.is_nan() {
                worst = (ratio, Some(i));
            }
        }
        worst
    }

    /// Removes from the estimate its component along the constraints'
    /// normals (module documentation), with the factorization in use.
    fn project_error(&mut self) -> Result<(), Failure> {
        let n = self.error.len();
        let (top, bottom) = self.rhs.split_at_mut(n);
        top.fill(0.0);
        bottom.fill(0.0);
        self.lin
            .b_pattern()
            .mul_add(self.lin.b(), &self.error, bottom);
        self.solver
            .solve_in_place(&mut self.rhs)
            .map_err(|source| Failure::Kkt {
                context: "projecting the error estimate",
                source,
            })?;
        for (e, y) in self.error.iter_mut().zip(&self.rhs[..n]) {
            *e -= y;
        }
        Ok(())
    }

    /// Why a step's Newton iteration may have failed, and what to try, from
    /// what the run knows: a tolerance below round-off, the trapezoidal
    /// rule's growing period-2h mode, a motion the estimate already found
    /// under-resolved, else a smaller step or a singular position.
    pub(super) fn diagnose_failure(&self) -> String {
        if self.config.tol < ROUND_OFF_TOL {
            return format!(
                "The Newton tolerance tol = {} is below what double precision reaches (about 1e-15 \
                 of the forces): use tol = 1e-14 or more",
                Short(self.config.tol)
            );
        }
        if (self.p.gamma - 0.5).abs() < 1e-12 {
            return "The scheme is undamped (γ = 1/2: the trapezoidal rule, HHT α = 0 or generalized-α \
                    ρ∞ = 1): on an index-3 system its period-2h oscillation of ü and λ grows until Newton \
                    fails, and a smaller h makes it grow sooner; use generalized-α with ρ∞ < 1 (the \
                    default scheme)"
                .to_string();
        }
        if let Some(advice) = self.loose_newton() {
            return advice;
        }
        if let Some(t) = self.stats.error.first_exceeded {
            return format!(
                "The estimated local error exceeded the tolerance from t = {} s on: the motion was \
                 under-resolved before Newton failed; integrate again with a smaller step size h, or \
                 with adaptive steps",
                Short(t)
            );
        }
        "Try a smaller step size h; if even tiny steps fail here, the model may be singular at this \
         position (a lock-up of the constraints), or lower h_min"
            .to_string()
    }

    /// The advice for a Newton tolerance too loose for the error tolerance,
    /// when accepted steps showed it (their converged `‖Φ‖∞` beyond
    /// `atol + rtol‖u‖∞`): a smaller step cannot help then.
    fn loose_newton(&self) -> Option<String> {
        let e = &self.stats.error;
        if e.newton_exceeded == 0 {
            return None;
        }
        let ErrorControl { rtol, atol, .. } = self.config.error;
        let floor = [rtol, atol]
            .into_iter()
            .filter(|&x| x > 0.0)
            .fold(f64::INFINITY, f64::min);
        Some(format!(
            "The converged constraint violation exceeded the error tolerance on {} steps (up to \
             {:.3} times): the Newton tolerance tol = {} is too loose, the state drifts off the \
             constraints and a smaller step cannot help; use tol = {} or less",
            e.newton_exceeded,
            e.newton_max_ratio,
            Short(self.config.tol),
            Short(0.01 * floor)
        ))
    }

    /// The error for an estimate beyond the tolerance, with what to try.
    fn too_large(&self, h: f64, estimate: &Estimate, h_min: Option<f64>) -> IntegrationError {
        let ErrorControl { rtol, atol, .. } = self.config.error;
        let advice = match (estimate.coordinate, h_min) {
            (None, _) => format!(
                "The converged constraint violation ‖Φ‖∞ = {:.3e} dominates: the Newton tolerance \
                 ({:e}) is loose for this error tolerance; lower it below {:e}",
                self.lin.constraint_norm(),
                self.config.tol,
                0.01 * (atol + rtol)
            ),
            // A model that conserves energy is not advised adaptive steps:
            // their local errors add up in its energy over the run
            // (docs/reliability.md, "Energy drift").
            (Some(_), None) if self.sys.conserves_energy() => "Reduce h: the local error \
                 falls like h³ (halving h divides it by about 8); adaptive steps are not advised \
                 for a model that conserves energy (their errors add up in its energy)"
                .to_string(),
            (Some(_), None) => "Let the step size adapt (adaptive stepping), or reduce h: \
                 the local error falls like h³ (halving h divides it by about 8)"
                .to_string(),
            (Some(_), Some(h_min)) => self.loose_newton().unwrap_or_else(|| {
                format!(
                    "Adaptive stepping would need a step below h_min = {h_min:e}: the motion is too \
                     fast for the tolerance here (a whip or an impact); loosen rtol and atol, or \
                     lower h_min"
                )
            }),
        };
        IntegrationError::ErrorTooLarge {
            t: self.step_end(h),
            h,
            ratio: estimate.ratio,
            coordinate: estimate
                .coordinate
                .map_or_else(|| "the constraints".to_string(), |i| self.sys.coord_name(i)),
            rtol,
            atol,
            advice,
        }
    }
}
