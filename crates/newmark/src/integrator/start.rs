//! Initial conditions (`algorithm.md` §3, §6): the initial state checked and
//! projected onto the constraints, the consistent (or the paper's) initial
//! accelerations and multipliers, and the start on the discrete solution.

use mstar_kkt::{Backend, KktOptions, KktSolver, argmax_abs};
use mstar_linearize::{Coefficients, Linearization, max_abs};
use mstar_model::{StateRef, System};

use super::Integrator;
use crate::{AlphaParams, IntegrationError, Start};

impl<S: System + ?Sized> Integrator<'_, S> {
    /// The whole start (§3, §6): the state made consistent, then the initial
    /// accelerations and multipliers. Its errors say "at start-up", not a
    /// step size, and, when projection had to move the given state, name the
    /// constraint that state violated most: the likely fault, where a
    /// failure after projection would only name where the projected state
    /// ended (a singular configuration), not why it went there.
    pub(super) fn start_up(&mut self) -> Result<(), IntegrationError> {
        let violated = self.initial_violation();
        self.make_consistent()
            .and_then(|()| self.initial_acceleration())
            .map_err(|e| self.at_start_up(e, violated))
    }

    /// The constraint the given positions violate most and by how much,
    /// when that is beyond the tolerance (projection will move them).
    fn initial_violation(&mut self) -> Option<(usize, f64)> {
        let m = self.sys.n_constraints();
        at_rest(&mut self.lin, self.sys, self.t, &self.state.u);
        let ctol = self.config.tol * max_abs(&self.state.u).max(1.0);
        let (k, value) = argmax_abs(self.lin.phi());
        (m > 0 && value.abs() > ctol).then_some((k, value))
    }

    /// A start-up error with the initial violation `violated` (from
    /// [`initial_violation`](Self::initial_violation)) and without a step size.
    fn at_start_up(&self, e: IntegrationError, violated: Option<(usize, f64)>) -> IntegrationError {
        let named = violated.map(|(k, value)| (self.sys.constraint_name(k), value));
        match e {
            IntegrationError::Kkt {
                context,
                t,
                unknown,
                source,
                ..
            } => IntegrationError::StartFailed {
                t,
                context,
                unknown,
                violated: named,
                cause: source,
            },
            IntegrationError::ProjectionFailed {
                t,
                iterations,
                residual,
                constraint,
                ..
            } => {
                let (initial, initial_value) =
                    named.unwrap_or_else(|| (constraint.clone(), residual));
                IntegrationError::ProjectionFailed {
                    t,
                    iterations,
                    residual,
                    constraint,
                    initial,
                    initial_value,
                }
            }
            other => other,
        }
    }

    /// Checks `Φ(u₀) = 0` and `B u̇₀ + Φ_t = 0`; projects (minimum-norm Newton
    /// on `[I Bᵀ; B 0]`) when allowed, else reports the most violated
    /// constraint; records the corrections in the start report.
    pub(super) fn make_consistent(&mut self) -> Result<(), IntegrationError> {
        let (u0, v0) = (self.state.u.clone(), self.state.v.clone());
        self.project_positions()?;
        self.project_velocities()?;
        self.start.position_correction = self.state.u.iter().zip(&u0).map(|(a, b)| a - b).collect();
        self.start.velocity_correction = self.state.v.iter().zip(&v0).map(|(a, b)| a - b).collect();
        Ok(())
    }

    /// `Φ(u) = 0` by minimum-norm Newton corrections of `u`.
    fn project_positions(&mut self) -> Result<(), IntegrationError> {
        let t = self.t;
        at_rest(&mut self.lin, self.sys, t, &self.state.u);
        self.start.position_violation = self.lin.constraint_norm();
        let mut iterations = 0;
        loop {
            let phi = self.lin.constraint_norm();
            let ctol = self.config.tol * max_abs(&self.state.u).max(1.0);
            let projected = iterations > 0;
            if phi <= if projected { 1e-3 * ctol } else { ctol } {
                return Ok(());
            }
            if !self.config.project {
                let (k, value) = argmax_abs(self.lin.phi());
                return Err(self.inconsistent("position", k, value));
            }
            if iterations == 50 || (projected && phi <= ctol && iterations > 5) {
                if phi <= ctol {
                    return Ok(());
                }
                let (k, _) = argmax_abs(self.lin.phi());
                let constraint = self.sys.constraint_name(k);
                return Err(IntegrationError::ProjectionFailed {
                    t,
                    iterations,
                    residual: phi,
                    // (`start_up` puts the given state's violation here.)
                    initial: constraint.clone(),
                    initial_value: phi,
                    constraint,
                });
            }
            self.lin.kkt_rhs(0.0, &mut self.rhs);
            self.solve_projection("projecting the initial positions")?;
            for (x, d) in self.state.u.iter_mut().zip(&self.rhs) {
                *x += d;
            }
            iterations += 1;
            at_rest(&mut self.lin, self.sys, t, &self.state.u);
        }
    }

    /// `B u̇ + Φ_t = 0` by the minimum-norm correction of `u̇`, at the
    /// positions of the last residual evaluation.
    fn project_velocities(&mut self) -> Result<(), IntegrationError> {
        let (t, n) = (self.t, self.sys.n_coords());
        let mut w = vec![0.0; self.sys.n_constraints()];
        self.sys.phi_t_into(t, &self.state.u, &mut w);
        self.lin
            .b_pattern()
            .mul_add(self.lin.b(), &self.state.v, &mut w);
        self.start.velocity_violation = max_abs(&w);
        let vtol = self.config.tol * max_abs(&self.state.v).max(1.0);
        if self.start.velocity_violation <= vtol {
            return Ok(());
        }
        if !self.config.project {
            let (k, value) = argmax_abs(&w);
            return Err(self.inconsistent("velocity", k, value));
        }
        self.rhs[..n].fill(0.0);
        for (x, &wi) in self.rhs[n..].iter_mut().zip(&w) {
            *x = -wi;
        }
        self.solve_projection("projecting the initial velocities")?;
        for (x, d) in self.state.v.iter_mut().zip(&self.rhs) {
            *x += d;
        }
        Ok(())
    }

    /// Solves `[I Bᵀ; B 0] x = rhs` in place (`B` from the last residual
    /// evaluation).
    fn solve_projection(&mut self, context: &'static str) -> Result<(), IntegrationError> {
        self.lin.assemble(&Coefficients::projection());
        self.factor_and_solve(context)
    }

    /// Factors the assembled matrix and solves with `rhs` in place.
    fn factor_and_solve(&mut self, context: &'static str) -> Result<(), IntegrationError> {
        let t = self.t;
        self.solver
            .factor(&self.lin.kkt().values)
            .map_err(|e| self.kkt_error(context, t, 0.0, e))?;
        self.solver
            .solve_in_place(&mut self.rhs)
            .map_err(|e| self.kkt_error(context, t, 0.0, e))
    }

    /// The state violates constraint `k` by `value` and may not be projected.
    fn inconsistent(&self, level: &'static str, k: usize, value: f64) -> IntegrationError {
        IntegrationError::InconsistentInitialState {
            t: self.t,
            level,
            constraint: self.sys.constraint_name(k),
            value,
        }
    }

    /// Solves the acceleration-level KKT system `[M Bᵀ; B 0][ü; λ] = [g; c]` at
    /// `(t, u, u̇)` into `a` and `lambda`. On the augmented structure it
    /// solves `[M + BᵀB, Bᵀ; B, 0][ü; λ] = [g + Bᵀc; c]` instead, which has
    /// the same solution (`B ü = c` makes the added `BᵀB ü` and `Bᵀc` equal)
    /// and a positive definite `M + BᵀB` where `M` is singular (eq. 11, the
    /// paper's pendulum): backends that factor without pivoting need it.
    fn consistent_acceleration(
        &mut self,
        t: f64,
        u: &[f64],
        v: &[f64],
        a: &mut [f64],
        lambda: &mut [f64],
    ) -> Result<(), IntegrationError> {
        let n = u.len();
        let (zeros_n, zeros_m) = (vec![0.0; n], vec![0.0; lambda.len()]);
        self.lin.eval_residual(
            self.sys,
            &StateRef {
                t,
                u,
                v,
                a: &zeros_n,
                lambda: &zeros_m,
            },
        );
        self.rhs[..n].copy_from_slice(self.lin.g());
        self.sys.accel_rhs_into(t, u, v, &mut self.rhs[n..]);
        self.augment_acceleration_system();
        self.factor_and_solve("solving for consistent initial accelerations")?;
        a.copy_from_slice(&self.rhs[..n]);
        lambda.copy_from_slice(&self.rhs[n..]);
        Ok(())
    }

    /// Assembles `[M Bᵀ; B 0]`, with `+BᵀB` and `+Bᵀc` (for the constraint
    /// part `c` of `rhs`) on the augmented structure; see
    /// [`consistent_acceleration`](Self::consistent_acceleration).
    fn augment_acceleration_system(&mut self) {
        let n = self.sys.n_coords();
        let c_bb = if self.lin.augmented() { 1.0 } else { 0.0 };
        self.lin.assemble(&Coefficients {
            c_bb,
            ..Coefficients::acceleration()
        });
        if c_bb != 0.0 {
            let (primal, c) = self.rhs.split_at_mut(n);
            self.lin
                .b_pattern()
                .mul_transpose_add(self.lin.b(), c, primal);
        }
    }

    /// The velocity perturbation `δu̇` with `[M Bᵀ; B 0][δu̇; μ] = [0; −k B u⃛₀]`:
    /// the given normal component, no tangential (inertia-weighted) part
    /// (augmented like the accelerations' system).
    fn velocity_start_correction(
        &mut self,
        u: &[f64],
        jerk: &[f64],
        k: f64,
    ) -> Result<Vec<f64>, IntegrationError> {
        let n = self.sys.n_coords();
        at_rest(&mut self.lin, self.sys, self.t, u);
        self.rhs.fill(0.0);
        self.lin
            .b_pattern()
            .mul_add(self.lin.b(), jerk, &mut self.rhs[n..]);
        for x in &mut self.rhs[n..] {
            *x *= -k;
        }
        // (With M + BᵀB on the augmented structure, as for the accelerations.)
        self.augment_acceleration_system();
        self.factor_and_solve("computing the starting velocity correction")?;
        Ok(self.rhs[..n].to_vec())
    }

    /// Initial `ü₀`, `λ₀` and the acceleration-like variable `a₀`.
    pub(super) fn initial_acceleration(&mut self) -> Result<(), IntegrationError> {
        let (n, m) = (self.sys.n_coords(), self.sys.n_constraints());
        let mut a = vec![0.0; n];
        let mut lambda = vec![0.0; m];
        match self.config.start.clone() {
            Start::Paper { lambda0 } => {
                self.paper_acceleration(&lambda0, &mut a)?;
                lambda.copy_from_slice(&lambda0);
                self.state.a_alpha.copy_from_slice(&a);
            }
            Start::Consistent => {
                let (u, v) = (self.state.u.clone(), self.state.v.clone());
                self.consistent_acceleration(self.t, &u, &v, &mut a, &mut lambda)?;
                self.state.a_alpha.copy_from_slice(&a);
                if self.config.corrected_start {
                    self.start_on_the_discrete_solution(&a)?;
                }
            }
        }
        self.state.a.copy_from_slice(&a);
        self.state.lambda.copy_from_slice(&lambda);
        if let Some(i) = a.iter().chain(&lambda).position(|x| !x.is_finite()) {
            return Err(IntegrationError::NonFinite {
                t: self.t,
                what: format!("the initial accelerations or multipliers (entry {i})"),
            });
        }
        Ok(())
    }

    /// The paper's start: `M* ü₀ = g − Bᵀλ₀` (eqs. 3 and 11), into `a`. `M*`
    /// is not a KKT matrix: it is solved with the automatic choice of backend.
    fn paper_acceleration(
        &mut self,
        lambda0: &[f64],
        a: &mut [f64],
    ) -> Result<(), IntegrationError> {
        let t = self.t;
        let (u, v) = (self.state.u.clone(), self.state.v.clone());
        self.lin.eval_residual(
            self.sys,
            &StateRef {
                t,
                u: &u,
                v: &v,
                a,
                lambda: lambda0,
            },
        );
        let m_star = self.lin.m_star().clone();
        let context = "solving M* ü₀ = g − Bᵀλ₀ (eq. 11)";
        let options = KktOptions {
            backend: Backend::AUTO,
            n_primal: None,
            ..self.config.kkt
        };
        let mut solver = KktSolver::new(&m_star, &options)
            .and_then(|mut s| s.factor(&m_star.values).map(|()| s))
            .map_err(|e| self.kkt_error(context, t, 0.0, e))?;
        a.copy_from_slice(self.lin.r());
        solver
            .solve_in_place(a)
            .map_err(|e| self.kkt_error(context, t, 0.0, e))
    }

    /// The Arnold–Brüls start (`Config::corrected_start`): `a₀ = ü₀ + (α_m −
    /// α_f) h u⃛₀` and the velocity's `O(h²)` normal component, from `u⃛₀` by
    /// central differences of consistent accelerations at the Taylor states
    /// `u₀ ± δu̇₀ + δ²/2 ü₀`, `u̇₀ ± δü₀` (the `O(δ²)` velocity error is even in
    /// `δ` and cancels).
    fn start_on_the_discrete_solution(&mut self, a: &[f64]) -> Result<(), IntegrationError> {
        let (n, m) = (self.sys.n_coords(), self.sys.n_constraints());
        let AlphaParams {
            alpha_m,
            alpha_f,
            beta,
            ..
        } = self.p;
        let (t, d) = (self.t, self.config.h);
        let (u, v) = (self.state.u.clone(), self.state.v.clone());
        let (mut plus, mut minus, mut scratch) = (vec![0.0; n], vec![0.0; n], vec![0.0; m]);
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
        // B u̇_n = −c h² B u⃛ (c = β + Δα/2 − 1/6 is the position update's
        // local error constant): without it the first step absorbs the O(h³)
        // normal position defect into an O(h) jump of a, which rings as a
        // period-2h transient.
        let c = beta + 0.5 * (alpha_m - alpha_f) - 1.0 / 6.0;
        let dv = self.velocity_start_correction(&u, &jerk, c * d * d)?;
        for (x, d) in self.state.v.iter_mut().zip(&dv) {
            *x += d;
        }
        self.start.velocity_start_correction = dv;
        self.start.jerk = jerk;
        Ok(())
    }
}

/// Evaluates the residual's parts (`M`, `B`, `g`, `Φ`) at positions `u` and
/// time `t` with zero velocities, accelerations and multipliers: what the
/// start's projections and checks read.
fn at_rest<S: System + ?Sized>(lin: &mut Linearization, sys: &S, t: f64, u: &[f64]) {
    let (zeros_n, zeros_m) = (vec![0.0; sys.n_coords()], vec![0.0; sys.n_constraints()]);
    let x = StateRef {
        t,
        u,
        v: &zeros_n,
        a: &zeros_n,
        lambda: &zeros_m,
    };
    lin.eval_residual(sys, &x);
}
