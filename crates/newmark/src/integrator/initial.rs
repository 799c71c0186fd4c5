//! The initial sensitivities `S₀ = ∂(u₀, u̇₀, ü₀, a₀, λ₀)/∂p` through the
//! start's own linear systems (`start.rs`; `docs/analysis.md`, "Parameter
//! sensitivities").
//!
//! The start is a chain of stages, each the solution `y` of equations
//! `E(y; z, p) = 0` whose Jacobian in `y` is a KKT matrix `K` (`z`: the
//! earlier stages' results, `F = −E`):
//!
//! ```text
//! positions     K = [I Bᵀ; B 0](u₀)   F = [0; −Φ(u)]                      u₀ = u_g + y_u
//! velocities    K = [I Bᵀ; B 0](u₀)   F = [−Bᵀμ; −(B u̇ + Φ_t)]            u̇₀ = u̇_g + y_u
//! accelerations K = [M Bᵀ; B 0](u₀)   F = [r(u, u̇, ü, λ); c(u, u̇) − B ü]  (ü₀, λ₀) = y
//! Taylor states K = [M Bᵀ; B 0](u±)   the same at (t₀ ± h, u±, u̇±)       u⃛₀ = (ü₊ − ü₋)/2h
//! correction    K = [M Bᵀ; B 0](u₀)   F = [−M δu̇ − Bᵀμ; −B(δu̇ + k u⃛₀)]   u̇ = u̇₀ + δu̇
//! ```
//!
//! with `u± = u₀ ± h u̇₀ + h²/2 ü₀`, `u̇± = u̇₀ ± h ü₀` and `k = c h²`
//! (`start.rs`, the Arnold–Brüls start). Differentiating a stage,
//! `K δy = F_z δz + F_p`. Each of the four matrices is factored once for all
//! parameters; `F_p` is a central difference of the parameter's models at
//! `p ± h_p` (its small model where it has one), `F_z δz` a central
//! difference of the whole model along `δz`, and `δu_g, δu̇_g` (the given
//! state's) a central difference of the given states at `p ± h_p`, or zero
//! for a parameter that keeps them ([`Parameterized::keeps_initial_state`]).
//!
//! The velocity projection is linear in the given velocities and is
//! differentiated exactly (its multipliers `μ`). The position projection
//! (minimum-norm Newton iterations) is differentiated as the projection of
//! a consistent state, `δu₀ = δu_g + y_u` with `F = [0; −Φ]`: exact when the
//! given positions satisfy the constraints, and off by the order of the move
//! otherwise, so a start that moved them by more than [`MOVED`] (relative)
//! takes central differences of whole starts instead (`sensitivity.rs`).

use mstar_kkt::{KktOptions, KktSolver};
use mstar_linearize::{Coefficients, Linearization, max_abs};
use mstar_model::{StateRef, System};

use super::sensitivity::{DIFFERENCE_STEP, Parameter, Partials};
use super::{Integrator, State};
use crate::{AlphaParams, IntegrationError};

/// The largest move of the given positions by the start's projection,
/// relative to `max(1, ‖u‖∞)`, with which the initial sensitivities are
/// differentiated through the stages: the position stage's error is of the
/// order of the move, here below the central differences' `1e-10`.
pub(super) const MOVED: f64 = 1e-10;

/// What a stage's `F` evaluates (see the module's table): `n + m` rows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Level {
    /// `[0; −Φ(u)]`.
    Position,
    /// `[−Bᵀμ; −(B u̇ + Φ_t)]`, read with `λ = μ`, the projection's
    /// multipliers: the projection `u̇₀ = u̇_g − Bᵀμ` with `B u̇₀ + Φ_t = 0`
    /// is linear in `u̇_g`, and `−Bᵀμ` carries the change of its direction
    /// with `B` (zero when the given velocities were consistent).
    Velocity,
    /// `[r(u, u̇, ü, λ); c(u, u̇) − B ü]`.
    Acceleration,
    /// `[r(u, 0, ü, λ) − r(u, 0, 0, 0); −B u̇]`, read with `ü = δu̇`,
    /// `λ = μ` and `u̇ = δu̇ + k u⃛₀`: `[−M δu̇ − Bᵀμ; −B(δu̇ + k u⃛₀)]`.
    Correction,
}

/// `F` of `level` of `sys` at `x` into `out` (`n + m`); `lin` is a
/// linearization of `sys` (evaluated here).
pub(super) fn stage_rows<S: System + ?Sized>(
    sys: &S,
    lin: &mut Linearization,
    x: &StateRef<'_>,
    level: Level,
    out: &mut [f64],
) {
    let n = sys.n_coords();
    let zeros = vec![0.0; n];
    let zeros_m = vec![0.0; sys.n_constraints()];
    let (f, e) = out.split_at_mut(n);
    match level {
        Level::Position => {
            let at = StateRef {
                v: &zeros,
                a: &zeros,
                lambda: &zeros_m,
                ..*x
            };
            lin.eval_residual(sys, &at);
            f.fill(0.0);
            for (o, phi) in e.iter_mut().zip(lin.phi()) {
                *o = -phi;
            }
        }
        Level::Velocity => {
            let at = StateRef {
                a: &zeros,
                lambda: &zeros_m,
                ..*x
            };
            lin.eval_residual(sys, &at);
            f.fill(0.0);
            lin.b_pattern().mul_transpose_add(lin.b(), x.lambda, f);
            f.iter_mut().for_each(|o| *o = -*o);
            sys.phi_t_into(x.t, x.u, e);
            lin.b_pattern().mul_add(lin.b(), x.v, e);
            e.iter_mut().for_each(|o| *o = -*o);
        }
        Level::Acceleration => {
            lin.eval_residual(sys, x);
            f.copy_from_slice(lin.r());
            let mut b_a = zeros_m.clone();
            lin.b_pattern().mul_add(lin.b(), x.a, &mut b_a);
            sys.accel_rhs_into(x.t, x.u, x.v, e);
            for (o, b) in e.iter_mut().zip(&b_a) {
                *o -= b;
            }
        }
        Level::Correction => {
            let rest = StateRef {
                v: &zeros,
                a: &zeros,
                lambda: &zeros_m,
                ..*x
            };
            lin.eval_residual(sys, &rest);
            f.copy_from_slice(lin.r());
            lin.eval_residual(sys, &StateRef { v: &zeros, ..*x });
            for (o, r) in f.iter_mut().zip(lin.r()) {
                *o = r - *o;
            }
            e.fill(0.0);
            lin.b_pattern().mul_add(lin.b(), x.v, e);
            e.iter_mut().for_each(|o| *o = -*o);
        }
    }
}

/// `F_z δz`: the central difference of the whole model's `F` along
/// `(δu, δu̇)` at `x` (the accelerations and multipliers held), added to
/// `out`. The step makes the move `DIFFERENCE_STEP · max(1, ‖u‖∞, ‖u̇‖∞)`
/// in the largest entry of the direction; nothing is added along a zero
/// direction.
fn add_directional<S: System + ?Sized>(
    sys: &S,
    lin: &mut Linearization,
    (x, level): (&StateRef<'_>, Level),
    du: &[f64],
    dv: &[f64],
    out: &mut [f64],
) {
    let size = max_abs(du).max(max_abs(dv));
    if size == 0.0 {
        return;
    }
    let scale = 1f64.max(max_abs(x.u)).max(max_abs(x.v));
    let eps = DIFFERENCE_STEP * scale / size;
    let mut sides = [vec![0.0; out.len()], vec![0.0; out.len()]];
    for (side, sign) in sides.iter_mut().zip([1.0, -1.0]) {
        let u: Vec<f64> =
            x.u.iter()
                .zip(du)
                .map(|(u, d)| u + sign * eps * d)
                .collect();
        let v: Vec<f64> =
            x.v.iter()
                .zip(dv)
                .map(|(v, d)| v + sign * eps * d)
                .collect();
        let at = StateRef { u: &u, v: &v, ..*x };
        stage_rows(sys, lin, &at, level, side);
    }
    for ((o, p), m) in out.iter_mut().zip(&sides[0]).zip(&sides[1]) {
        *o += (p - m) / (2.0 * eps);
    }
}

/// The linear algebra of the stages: a linearization the matrices are
/// assembled on (`B` of the factored point kept for the augmented
/// right-hand side), one the directional differences evaluate, and a
/// solver with the run's backend.
struct Stages {
    matrix: Linearization,
    eval: Linearization,
    solver: KktSolver,
    n: usize,
}

impl Stages {
    /// `[I Bᵀ; B 0]` (`projection`) or `[M Bᵀ; B 0]` at `(t, u)` factored.
    fn factor<S: System + ?Sized>(
        &mut self,
        sys: &S,
        (t, u): (f64, &[f64]),
        projection: bool,
    ) -> Result<(), mstar_kkt::KktError> {
        let mut rows = vec![0.0; self.n + sys.n_constraints()];
        let (zeros, zeros_m) = (vec![0.0; self.n], vec![0.0; sys.n_constraints()]);
        let at = StateRef {
            t,
            u,
            v: &zeros,
            a: &zeros,
            lambda: &zeros_m,
        };
        // (Evaluates `M` and `B` at `u` on the matrix's linearization.)
        stage_rows(sys, &mut self.matrix, &at, Level::Position, &mut rows);
        let c = if projection {
            Coefficients::projection()
        } else {
            Coefficients {
                c_bb: if self.matrix.augmented() { 1.0 } else { 0.0 },
                ..Coefficients::acceleration()
            }
        };
        self.matrix.assemble(&c);
        self.solver.factor(&self.matrix.kkt().values)
    }

    /// `K y = rhs` in place, `K` as last [`factor`](Self::factor)ed; on the
    /// augmented structure `[M + BᵀB, Bᵀ; B, 0] y = [f + Bᵀe; e]`, which
    /// has the same solution (`start.rs`, `consistent_acceleration`).
    /// Nothing is solved for a zero `rhs`.
    fn solve(&mut self, rhs: &mut [f64], projection: bool) -> Result<(), mstar_kkt::KktError> {
        // (A zero right-hand side, a mass's projections: the solution is 0.)
        if rhs.iter().all(|x| *x == 0.0) {
            return Ok(());
        }
        if !projection && self.matrix.augmented() {
            let (f, e) = rhs.split_at_mut(self.n);
            self.matrix
                .b_pattern()
                .mul_transpose_add(self.matrix.b(), e, f);
        }
        self.solver.solve_in_place(rhs)
    }
}

impl Partials {
    /// `F_p` of a start's stage (`initial.rs`): the central difference of
    /// the stage's rows of the models at `p ± h_p` at `x` (the whole
    /// model's state), `f(k, ∂F_k/∂p)` for each row `k` of the whole
    /// model's `n + m` that the parameter can change.
    pub(super) fn each_stage(
        &mut self,
        x: &StateRef<'_>,
        n: usize,
        h: f64,
        level: Level,
        mut f: impl FnMut(usize, f64),
    ) {
        let at = Self::gather(self.places.as_ref(), &mut self.gathered, x);
        let (n_small, m_small) = (at.u.len(), at.lambda.len());
        let mut sides = [vec![0.0; n_small + m_small], vec![0.0; n_small + m_small]];
        for (side, out) in [&mut self.plus, &mut self.minus]
            .into_iter()
            .zip(&mut sides)
        {
            stage_rows(side.variant.system(), &mut side.lin, &at, level, out);
        }
        let central = (0..n_small + m_small).map(|i| (sides[0][i] - sides[1][i]) / (2.0 * h));
        match &self.places {
            None => central.enumerate().for_each(|(k, c)| f(k, c)),
            Some(places) => {
                let rows = places.coords.iter().copied();
                let rows = rows.chain(places.rows.iter().map(|j| n + j));
                rows.zip(central).for_each(|(k, c)| f(k, c));
            }
        }
    }
}

/// The nominal start's values the stages are differentiated at.
struct Nominal {
    u: Vec<f64>,
    /// `u̇₀`, before the start's velocity correction.
    v: Vec<f64>,
    a: Vec<f64>,
    lambda: Vec<f64>,
}

impl<S: System + ?Sized> Integrator<'_, S> {
    /// Whether the initial sensitivities are differentiated through the
    /// start's stages (`initial.rs`): for the consistent start with
    /// projection, when the projection did not move the given positions
    /// beyond [`MOVED`]. Else (the paper's
    /// start with given `λ₀`, a start that may not project, given positions
    /// off the constraints) they are central differences of whole starts.
    pub(super) fn starts_by_stages(&self) -> bool {
        let moved = max_abs(&self.start.position_correction);
        matches!(self.config.start, crate::Start::Consistent)
            && self.config.project
            && moved <= MOVED * max_abs(&self.state.u).max(1.0)
    }

    /// Fills the initial sensitivities `S₀` of `params` through the start's
    /// stages (the module's doc); `given[k]`: `∂(u_g, u̇_g)/∂p_k` of the
    /// given initial state (its `u` and `v`).
    pub(super) fn initial_by_stages(
        &self,
        params: &mut [Parameter],
        given: &[State],
    ) -> Result<(), IntegrationError> {
        let mut stages = self.stages()?;
        let nominal = self.nominal();
        self.projected(&mut stages, &nominal, params, given)?;
        self.accelerations(&mut stages, &nominal, params)?;
        if self.config.corrected_start {
            self.corrected(&mut stages, &nominal, params)?;
        }
        Ok(())
    }

    /// The stages' linearizations (of this model, nothing carried over) and
    /// solver (this run's backend).
    fn stages(&self) -> Result<Stages, IntegrationError> {
        let fail = |e| self.kkt_error("analysing the start's sensitivities", self.t, 0.0, e);
        let matrix = self
            .lin
            .like(self.sys)
            .ok_or_else(|| IntegrationError::Config("the model's patterns changed".into()))?;
        let options = KktOptions {
            backend: self.solver.backend(),
            n_primal: self.config.kkt.n_primal.or(Some(self.sys.n_coords())),
            ..self.config.kkt
        };
        let solver = KktSolver::new(matrix.kkt(), &options).map_err(fail)?;
        Ok(Stages {
            eval: matrix.clone(),
            matrix,
            solver,
            n: self.sys.n_coords(),
        })
    }

    /// The start's values (the state before the first step, the velocity
    /// correction taken off).
    fn nominal(&self) -> Nominal {
        let dv = &self.start.velocity_start_correction;
        let v = if dv.len() == self.state.v.len() {
            self.state.v.iter().zip(dv).map(|(v, d)| v - d).collect()
        } else {
            self.state.v.clone()
        };
        Nominal {
            u: self.state.u.clone(),
            v,
            a: self.state.a.clone(),
            lambda: self.state.lambda.clone(),
        }
    }

    /// `K⁻¹ (F_p + F_z δz)` of one stage at `x` for one parameter, `K` as
    /// `stages` last factored it (`projection`: `[I Bᵀ; B 0]`).
    fn solve_stage(
        &self,
        stages: &mut Stages,
        (x, level): (&StateRef<'_>, Level),
        (partials, step): (&mut Partials, f64),
        (du, dv): (&[f64], &[f64]),
        projection: bool,
    ) -> Result<Vec<f64>, mstar_kkt::KktError> {
        let n = self.sys.n_coords();
        let mut rhs = vec![0.0; n + self.sys.n_constraints()];
        partials.each_stage(x, n, step, level, |k, c| rhs[k] = c);
        add_directional(self.sys, &mut stages.eval, (x, level), du, dv, &mut rhs);
        stages.solve(&mut rhs, projection)?;
        Ok(rhs)
    }

    /// `K⁻¹ F` of the nominal start at `x`: a stage's values as the start
    /// solved them (`K` as `stages` last factored it).
    fn solve_nominal(
        &self,
        stages: &mut Stages,
        (x, level): (&StateRef<'_>, Level),
        projection: bool,
    ) -> Result<Vec<f64>, mstar_kkt::KktError> {
        let mut y = vec![0.0; self.sys.n_coords() + self.sys.n_constraints()];
        stage_rows(self.sys, &mut stages.eval, x, level, &mut y);
        stages.solve(&mut y, projection)?;
        Ok(y)
    }

    /// The two projections: `δu₀` and `δu̇₀` (before the correction).
    fn projected(
        &self,
        stages: &mut Stages,
        nominal: &Nominal,
        params: &mut [Parameter],
        given: &[State],
    ) -> Result<(), IntegrationError> {
        let (t, n) = (self.t, self.sys.n_coords());
        let fail = |e| self.kkt_error("projecting the start's sensitivities", t, 0.0, e);
        stages
            .factor(self.sys, (t, &nominal.u), true)
            .map_err(fail)?;
        let zeros_n = vec![0.0; n];
        let mu = self.velocity_multipliers(stages, nominal).map_err(fail)?;
        let x = StateRef {
            t,
            u: &nominal.u,
            v: &nominal.v,
            a: &zeros_n,
            lambda: &mu,
        };
        for (param, g) in params.iter_mut().zip(given) {
            let level = (&x, Level::Position);
            let y = self
                .solve_stage(
                    stages,
                    level,
                    (&mut param.partials, param.step),
                    (&g.u, &zeros_n),
                    true,
                )
                .map_err(fail)?;
            param.s.u = g.u.iter().zip(&y).map(|(g, y)| g + y).collect();
            let level = (&x, Level::Velocity);
            let y = self
                .solve_stage(
                    stages,
                    level,
                    (&mut param.partials, param.step),
                    (&param.s.u, &g.v),
                    true,
                )
                .map_err(fail)?;
            param.s.v = g.v.iter().zip(&y).map(|(g, y)| g + y).collect();
        }
        Ok(())
    }

    /// The multipliers `μ` of the start's velocity projection (zero when
    /// it did not move the given velocities), solved again from the given
    /// velocities with the projection matrix factored at `u₀`.
    fn velocity_multipliers(
        &self,
        stages: &mut Stages,
        nominal: &Nominal,
    ) -> Result<Vec<f64>, mstar_kkt::KktError> {
        let (n, m) = (self.sys.n_coords(), self.sys.n_constraints());
        let moved = &self.start.velocity_correction;
        if moved.len() != n || moved.iter().all(|d| *d == 0.0) {
            return Ok(vec![0.0; m]);
        }
        let given: Vec<f64> = nominal.v.iter().zip(moved).map(|(v, d)| v - d).collect();
        let (zeros_n, zeros_m) = (vec![0.0; n], vec![0.0; m]);
        let x = StateRef {
            t: self.t,
            u: &nominal.u,
            v: &given,
            a: &zeros_n,
            lambda: &zeros_m,
        };
        let mut y = self.solve_nominal(stages, (&x, Level::Velocity), true)?;
        Ok(y.split_off(n))
    }

    /// The consistent accelerations and multipliers: `δü₀`, `δλ₀` (and
    /// `δa₀ = δü₀` until the corrected start changes it).
    fn accelerations(
        &self,
        stages: &mut Stages,
        nominal: &Nominal,
        params: &mut [Parameter],
    ) -> Result<(), IntegrationError> {
        let (t, n) = (self.t, self.sys.n_coords());
        let fail = |e| self.kkt_error("the start's sensitivities of the accelerations", t, 0.0, e);
        stages
            .factor(self.sys, (t, &nominal.u), false)
            .map_err(fail)?;
        let x = StateRef {
            t,
            u: &nominal.u,
            v: &nominal.v,
            a: &nominal.a,
            lambda: &nominal.lambda,
        };
        for param in params.iter_mut() {
            let level = (&x, Level::Acceleration);
            let y = self
                .solve_stage(
                    stages,
                    level,
                    (&mut param.partials, param.step),
                    (&param.s.u, &param.s.v),
                    false,
                )
                .map_err(fail)?;
            param.s.a = y[..n].to_vec();
            param.s.a_alpha = param.s.a.clone();
            param.s.lambda = y[n..].to_vec();
        }
        Ok(())
    }

    /// The corrected start: `δa₀ = δü₀ + (α_m − α_f) h δu⃛₀` and the
    /// velocity correction's `δ(δu̇)`.
    fn corrected(
        &self,
        stages: &mut Stages,
        nominal: &Nominal,
        params: &mut [Parameter],
    ) -> Result<(), IntegrationError> {
        let AlphaParams {
            alpha_m,
            alpha_f,
            beta,
            ..
        } = self.p;
        let d = self.config.h;
        let plus = self.taylor(stages, nominal, params, d)?;
        let minus = self.taylor(stages, nominal, params, -d)?;
        let jerks: Vec<Vec<f64>> = plus
            .iter()
            .zip(&minus)
            .map(|(p, m)| super::sensitivity::central(p, m, d))
            .collect();
        for (param, dj) in params.iter_mut().zip(&jerks) {
            for ((aa, a), j) in param.s.a_alpha.iter_mut().zip(&param.s.a).zip(dj) {
                *aa = a + (alpha_m - alpha_f) * d * j;
            }
        }
        let k = (beta + 0.5 * (alpha_m - alpha_f) - 1.0 / 6.0) * d * d;
        self.correction(stages, nominal, params, &jerks, k)
    }

    /// `δü` at the Taylor state `t₀ + ds` of every parameter.
    fn taylor(
        &self,
        stages: &mut Stages,
        nominal: &Nominal,
        params: &mut [Parameter],
        ds: f64,
    ) -> Result<Vec<Vec<f64>>, IntegrationError> {
        let (t, n, m) = (self.t + ds, self.sys.n_coords(), self.sys.n_constraints());
        let fail = |e| self.kkt_error("the start's sensitivities at a Taylor state", t, 0.0, e);
        let shift = |u: &[f64], v: &[f64], a: &[f64]| -> (Vec<f64>, Vec<f64>) {
            let us = (0..n)
                .map(|i| u[i] + ds * v[i] + 0.5 * ds * ds * a[i])
                .collect();
            let vs = (0..n).map(|i| v[i] + ds * a[i]).collect();
            (us, vs)
        };
        let (us, vs) = shift(&nominal.u, &nominal.v, &nominal.a);
        stages.factor(self.sys, (t, &us), false).map_err(fail)?;
        // The accelerations and multipliers there, as the start solved them.
        let zeros = (vec![0.0; n], vec![0.0; m]);
        let rest = StateRef {
            t,
            u: &us,
            v: &vs,
            a: &zeros.0,
            lambda: &zeros.1,
        };
        let y = self
            .solve_nominal(stages, (&rest, Level::Acceleration), false)
            .map_err(fail)?;
        let (a, lambda) = y.split_at(n);
        let x = StateRef { a, lambda, ..rest };
        let mut out = Vec::with_capacity(params.len());
        for param in params.iter_mut() {
            let (dus, dvs) = shift(&param.s.u, &param.s.v, &param.s.a);
            let level = (&x, Level::Acceleration);
            let y = self
                .solve_stage(
                    stages,
                    level,
                    (&mut param.partials, param.step),
                    (&dus, &dvs),
                    false,
                )
                .map_err(fail)?;
            out.push(y[..n].to_vec());
        }
        Ok(out)
    }

    /// The velocity correction's sensitivity added to `δu̇₀` of every
    /// parameter (`jerks`: their `δu⃛₀`).
    fn correction(
        &self,
        stages: &mut Stages,
        nominal: &Nominal,
        params: &mut [Parameter],
        jerks: &[Vec<f64>],
        k: f64,
    ) -> Result<(), IntegrationError> {
        let (t, n, m) = (self.t, self.sys.n_coords(), self.sys.n_constraints());
        let fail = |e| {
            self.kkt_error(
                "the start's sensitivities of its velocity correction",
                t,
                0.0,
                e,
            )
        };
        stages
            .factor(self.sys, (t, &nominal.u), false)
            .map_err(fail)?;
        // The correction and its multipliers, as the start solved them.
        let kj: Vec<f64> = self.start.jerk.iter().map(|j| k * j).collect();
        let zeros = (vec![0.0; n], vec![0.0; m]);
        let rest = StateRef {
            t,
            u: &nominal.u,
            v: &kj,
            a: &zeros.0,
            lambda: &zeros.1,
        };
        let y = self
            .solve_nominal(stages, (&rest, Level::Correction), false)
            .map_err(fail)?;
        let (dv, mu) = y.split_at(n);
        let w: Vec<f64> = dv.iter().zip(&kj).map(|(d, j)| d + j).collect();
        let x = StateRef {
            v: &w,
            a: dv,
            lambda: mu,
            ..rest
        };
        for (param, dj) in params.iter_mut().zip(jerks) {
            let kdj: Vec<f64> = dj.iter().map(|j| k * j).collect();
            let level = (&x, Level::Correction);
            let y = self
                .solve_stage(
                    stages,
                    level,
                    (&mut param.partials, param.step),
                    (&param.s.u, &kdj),
                    false,
                )
                .map_err(fail)?;
            for (v, y) in param.s.v.iter_mut().zip(&y) {
                *v += y;
            }
        }
        Ok(())
    }
}
