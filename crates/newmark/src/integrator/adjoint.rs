//! The discrete adjoint of the forward sensitivities (`sensitivity.rs`;
//! `docs/analysis.md`, "Adjoint gradients").
//!
//! The forward recurrence of `sensitivity.rs` is linear in the state
//! sensitivities `S_n = ∂(u, u̇, ü, a, λ)/∂p`. Step `n → n + 1` (size `h`,
//! the previous step's size `h_n`, `ρ = h / h_n`) applies the predictor `P`
//! with zero acceleration to `S_n`, solves `J x = c − T (u^p, u̇^p)` with
//! `c = [r_p; −Φ_p]`, `T = [K_T C_T; B 0]` and `J = [S Bᵀ; B 0]`,
//! `S = K_T + γ' C_T + β' M`, all at the converged state `n + 1`, and sets
//! `u = u^p + x_u`, `u̇ = u̇^p + γ' x_u`, `ü = β' x_u`, `a = a^p + x_u/(β h²)`,
//! `λ = x_λ`. For `Ψ = Σ_n w_nᵀ y_n`, `dΨ/dp = Σ_n w_nᵀ S_n`; running the
//! transposed recurrence backward from `s̄_N = w_N`,
//!
//! ```text
//! x̄ = (ū + γ' ū̇ + β' ǖ + ā/(β h²), λ̄),   Jᵀ μ = x̄,
//! (ū^p, ū̇^p, ā^p) = (ū − K_Tᵀ μ_u − Bᵀ μ_λ, ū̇ − C_Tᵀ μ_u, ā),
//! s̄_n = Pᵀ (ū^p, ū̇^p, ā^p) + w_n,
//! ```
//!
//! gives `dΨ/dp_k = Σ_{n ≥ 1} μ_nᵀ c_{n,k} + s̄_0ᵀ S_{0,k}`: one transposed
//! solve per step whatever the number of parameters; only the partials
//! `c_{n,k}` (the forward code's central differences) and the initial
//! sensitivities `S_{0,k}` are per parameter.
//!
//! `Jᵀ` is solved with a factorization of its own: the backward pass
//! re-evaluates the Jacobians at each stored state (the forward pass's
//! factorizations are not kept per step), so forming `Jᵀ` costs what
//! refactoring `J` would. The factored matrix `A` (scaled, possibly
//! augmented `J`) is `[S' Bᵀ; B D]` and `Aᵀ = [S'ᵀ Bᵀ; B D]`: the same
//! blocks with `S'` transposed. It is assembled in the structure the forward
//! run's KKT backend reads and factored by that backend (block by block with
//! `schur-lu`), with the sparse LU of the augmented matrix as the fallback
//! when the backend refuses `Aᵀ`'s pattern (an `S` pattern that is not
//! structurally symmetric may break its block structure).

use mstar_kkt::{Backend, Csc, KktError, KktOptions, KktSolver, Structure};
use mstar_linearize::Linearization;
use mstar_model::System;

use super::sensitivity::{Parameter, Parameterized};
use super::{Integrator, State};
use crate::{IntegrationError, RunStats};

/// A column of the state that an [`Objective`] reads, by index.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Column {
    /// The coordinate `u_i`.
    Position(usize),
    /// The velocity `u̇_i`.
    Velocity(usize),
    /// The acceleration `ü_i`.
    Acceleration(usize),
    /// The multiplier `λ_i`.
    Multiplier(usize),
}

/// A scalar objective `Ψ` over a run's samples: the initial state and the
/// state after every accepted step (those [`Integrator::run`] observes).
/// Outputs computed from the state (sensors, reactions) are not columns
/// here yet.
#[derive(Clone, Debug, PartialEq)]
pub enum Objective {
    /// `Ψ = y_N`, the column's value at the end.
    Final(Column),
    /// `Ψ = Σ_n y_n` over all samples.
    Sum(Column),
    /// `Ψ = Σ_n (y_n − d_n)²` against measured values `d_n`, one per sample.
    Fit {
        /// The column `y`.
        column: Column,
        /// `d_n`, one per sample (the number of steps plus one).
        measured: Vec<f64>,
    },
}

impl Objective {
    /// The column the objective reads.
    #[must_use]
    pub fn column(&self) -> Column {
        match self {
            Self::Final(c) | Self::Sum(c) | Self::Fit { column: c, .. } => *c,
        }
    }

    /// `Ψ`'s share of sample `n` of `last` (the last sample's index) with
    /// value `y`, and its weight `∂Ψ/∂y_n`.
    fn term(&self, n: usize, last: usize, y: f64) -> (f64, f64) {
        match self {
            Self::Final(_) if n == last => (y, 1.0),
            Self::Final(_) => (0.0, 0.0),
            Self::Sum(_) => (y, 1.0),
            Self::Fit { measured, .. } => {
                let e = y - measured[n];
                (e * e, 2.0 * e)
            }
        }
    }
}

/// How the backward pass gets the forward pass's converged states.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Memory {
    /// Store every state: `(N + 1)(4n + m + 2)` numbers for `N` steps.
    Store,
    /// Keep the integrator's state every `every` steps and recompute each
    /// segment in the backward pass: about one more forward run, and
    /// `N / every` checkpoints plus `every + 1` states.
    Checkpoints {
        /// Steps per segment (≥ 1).
        every: usize,
    },
    /// [`Store`](Self::Store) when the states of `(t_end − t₀)/h` steps fit
    /// in `bytes`, else [`Checkpoints`](Self::Checkpoints) every `⌈√N⌉`
    /// steps (the least memory).
    Budget {
        /// The memory the stored states may take, bytes.
        bytes: usize,
    },
}

/// The gradient `dΨ/dp` of an [`Objective`] of the discrete solution.
#[derive(Clone, Debug, PartialEq)]
pub struct Gradient {
    /// The parameters' names, in order.
    pub names: Vec<String>,
    /// `dΨ/dp_k`, in order.
    pub values: Vec<f64>,
    /// `Ψ` of the run.
    pub objective: f64,
    /// The samples' times: the start and the end of every step.
    pub times: Vec<f64>,
    /// The forward run's steps.
    pub steps: usize,
    /// Steps per segment when checkpointing, else `None`.
    pub checkpoint_every: Option<usize>,
    /// Steps recomputed in the backward pass.
    pub recomputed_steps: usize,
    /// The KKT backend that factored `Aᵀ` in the backward pass: the forward
    /// run's, or [`Backend::SPARSE_LU`] when that one refused `Aᵀ`'s
    /// pattern.
    pub backend: Backend,
}

/// A converged state, its time and the size of the step that reached it
/// (at the start, the size the start was made for).
struct Record {
    t: f64,
    h: f64,
    state: State,
}

/// What the integrator needs to repeat its steps from a checkpoint.
struct Snapshot {
    t: f64,
    state: State,
    history: super::history::History,
    h: f64,
    h_last: f64,
    error: Vec<f64>,
    error_previous: f64,
    rejected_last: bool,
    easy_steps: usize,
    t_anchor: f64,
    h_anchor: f64,
    steps_at_h: u64,
    stats: RunStats,
    residual: f64,
    constraint: f64,
    iterations: usize,
    energies: Option<(f64, f64)>,
}

/// The transposed KKT matrix `Aᵀ` of the adjoint, its factorization and the
/// linearization it is assembled from (in the structure its backend reads).
struct Transposed {
    lin: Linearization,
    /// `Aᵀ`'s pattern and values.
    a_t: Csc,
    /// The position in `a_t` of each of `A`'s values.
    map: Vec<usize>,
    solver: KktSolver,
}

impl Transposed {
    /// Copies `A`'s values (as last assembled) into `Aᵀ`.
    fn fill(&mut self) {
        for (&k, &v) in self.map.iter().zip(&self.lin.kkt().values) {
            self.a_t.values[k] = v;
        }
    }
}

/// `Aᵀ`'s pattern for `A` stored as a KKT backend reads it, `n` primal
/// unknowns first, and where each of `A`'s values goes in it. `A = [S' Bᵀ;
/// B D]` has `Aᵀ = [S'ᵀ Bᵀ; B D]`: the entries of the primal block `S'` move
/// to their transposed places, those of `B`, of `Bᵀ` (when stored) and of
/// `D` stay where they are. So a structure without the `Bᵀ` block keeps its
/// meaning, and a structurally symmetric `S'` keeps its pattern.
fn transpose_pattern(a: &Csc, n: usize) -> (Csc, Vec<usize>) {
    let mut pairs = Vec::with_capacity(a.nnz());
    for j in 0..a.n {
        for &i in a.column(j) {
            // (column, row) in Aᵀ of entry (i, j) of A.
            pairs.push(if i < n && j < n { (i, j) } else { (j, i) });
        }
    }
    let a_t = Csc::from_pairs(a.n, &pairs);
    let map = pairs
        .iter()
        .map(|&(col, row)| a_t.position(row, col).unwrap_or(usize::MAX))
        .collect();
    (a_t, map)
}

/// The backward pass's running quantities.
struct Backward<'a> {
    params: &'a mut [Parameter],
    objective: &'a Objective,
    /// The column's value at every sample.
    values: &'a [f64],
    /// `s̄`, the adjoint of the current state.
    bar: State,
    /// `dΨ/dp_k` so far.
    grad: Vec<f64>,
}

impl Backward<'_> {
    /// Adds `w_n = ∂Ψ/∂y_n` to `s̄`.
    fn add_weight(&mut self, n: usize) {
        let last = self.values.len() - 1;
        let (_, w) = self.objective.term(n, last, self.values[n]);
        let b = &mut self.bar;
        match self.objective.column() {
            Column::Position(i) => b.u[i] += w,
            Column::Velocity(i) => b.v[i] += w,
            Column::Acceleration(i) => b.a[i] += w,
            Column::Multiplier(i) => b.lambda[i] += w,
        }
    }
}

impl<S: System + ?Sized> Integrator<'_, S> {
    /// The gradient `dΨ/dp` of `objective` over the run from the current
    /// (initial) state to `t_end`, for all of `params` at once: a forward
    /// run and the discrete adjoint backward (module documentation; the
    /// exact derivative of the solution this run computes, as the forward
    /// [`Sensitivities`](super::Sensitivities) are). With
    /// [`Memory::Checkpoints`] the integrator refactors at every checkpoint
    /// (as its recomputation does), which with modified Newton moves the
    /// solution within the Newton tolerance. The integrator ends at `t_end`.
    ///
    /// # Errors
    /// [`IntegrationError::Config`] after the first step, for a column out
    /// of range, measured values of the wrong count, zero steps per
    /// checkpoint, and a parameter's model that cannot be made at `p ± h_p`;
    /// the run's errors; [`IntegrationError::Kkt`] when the transposed
    /// matrix cannot be factored or solved; [`IntegrationError::NonFinite`]
    /// for an adjoint that is not finite.
    pub fn gradient(
        &mut self,
        t_end: f64,
        params: &[&dyn Parameterized],
        objective: &Objective,
        memory: Memory,
    ) -> Result<Gradient, IntegrationError> {
        self.check_column(objective.column())?;
        let mut sens = self.sensitivities(params)?;
        let every = self.checkpoint_every(t_end, memory)?;
        let (times, values, records, snapshots) = self.forward(t_end, objective.column(), every)?;
        let steps = values.len() - 1;
        if let Objective::Fit { measured, .. } = objective
            && measured.len() != values.len()
        {
            return Err(IntegrationError::Config(format!(
                "the objective's measured values: {} given, and the run has {} samples \
                 (the initial state and {steps} steps); give one value per sample",
                measured.len(),
                values.len()
            )));
        }
        let psi = (0..values.len())
            .map(|n| objective.term(n, steps, values[n]).0)
            .sum();
        let end = self.snapshot();
        let mut transposed = self.transposed()?;
        let backend = transposed.solver.backend();
        let (n, m) = (self.sys.n_coords(), self.sys.n_constraints());
        let mut back = Backward {
            params: &mut sens.params,
            objective,
            values: &values,
            bar: State::zeros(n, m),
            grad: vec![0.0; params.len()],
        };
        back.add_weight(steps);
        let recomputed = match every {
            None => {
                self.backward_over(&mut transposed, &mut back, &records, 0)?;
                0
            }
            Some(k) => {
                self.backward_checkpointed(t_end, &mut transposed, &mut back, &snapshots, k)?
            }
        };
        self.restore(&end);
        let mut grad = back.grad;
        for (g, p) in grad.iter_mut().zip(back.params.iter()) {
            *g += dot_state(&back.bar, &p.s);
        }
        Ok(Gradient {
            names: sens.names(),
            values: grad,
            objective: psi,
            times,
            steps,
            checkpoint_every: every,
            recomputed_steps: recomputed,
            backend,
        })
    }

    /// A [`Config`](IntegrationError::Config) error for a column out of range.
    fn check_column(&self, column: Column) -> Result<(), IntegrationError> {
        let (n, m) = (self.sys.n_coords(), self.sys.n_constraints());
        let (i, len, what) = match column {
            Column::Position(i) => (i, n, "coordinate"),
            Column::Velocity(i) => (i, n, "velocity"),
            Column::Acceleration(i) => (i, n, "acceleration"),
            Column::Multiplier(i) => (i, m, "multiplier"),
        };
        if i < len {
            return Ok(());
        }
        Err(IntegrationError::Config(format!(
            "the objective's column: {what} {i} of a model with {len} (indices from 0)"
        )))
    }

    /// Steps per checkpoint (`None`: store every state) for `memory`.
    fn checkpoint_every(
        &self,
        t_end: f64,
        memory: Memory,
    ) -> Result<Option<usize>, IntegrationError> {
        match memory {
            Memory::Store => Ok(None),
            Memory::Checkpoints { every: 0 } => Err(IntegrationError::Config(
                "checkpoints every 0 steps: give at least 1".into(),
            )),
            Memory::Checkpoints { every } => Ok(Some(every)),
            Memory::Budget { bytes } => {
                let (n, m) = (self.sys.n_coords(), self.sys.n_constraints());
                let steps = ((t_end - self.t) / self.config.h).ceil().max(1.0);
                let per_state = (8 * (4 * n + m + 2)) as f64;
                if (steps + 1.0) * per_state <= bytes as f64 {
                    Ok(None)
                } else {
                    Ok(Some(steps.sqrt().ceil() as usize))
                }
            }
        }
    }

    /// The forward run: the time and the column's value at every sample,
    /// and every state (`every = None`) or a checkpoint every `every` steps.
    #[allow(clippy::type_complexity)]
    fn forward(
        &mut self,
        t_end: f64,
        column: Column,
        every: Option<usize>,
    ) -> Result<(Vec<f64>, Vec<f64>, Vec<Record>, Vec<Snapshot>), IntegrationError> {
        let (mut records, mut snapshots) = (Vec::new(), Vec::new());
        let mut values = vec![self.column_value(column)];
        let mut times = vec![self.t];
        match every {
            None => records.push(self.record()),
            Some(_) => snapshots.push(self.snapshot()),
        }
        let mut steps = 0;
        while !self.reached(t_end) {
            self.step(t_end)?;
            steps += 1;
            values.push(self.column_value(column));
            times.push(self.t);
            match every {
                None => records.push(self.record()),
                Some(k) if steps % k == 0 && !self.reached(t_end) => {
                    snapshots.push(self.snapshot());
                }
                Some(_) => {}
            }
        }
        Ok((times, values, records, snapshots))
    }

    /// The backward pass segment by segment, the last first: each is
    /// recomputed from its checkpoint; returns the steps recomputed.
    fn backward_checkpointed(
        &mut self,
        t_end: f64,
        transposed: &mut Transposed,
        back: &mut Backward<'_>,
        snapshots: &[Snapshot],
        every: usize,
    ) -> Result<usize, IntegrationError> {
        let steps = back.values.len() - 1;
        let mut recomputed = 0;
        for (j, snapshot) in snapshots.iter().enumerate().rev() {
            let (first, last) = (j * every, ((j + 1) * every).min(steps));
            self.restore(snapshot);
            let mut records = vec![self.record()];
            for _ in first..last {
                self.step(t_end)?;
                records.push(self.record());
            }
            recomputed += last - first;
            self.backward_over(transposed, back, &records, first)?;
        }
        Ok(recomputed)
    }

    /// The adjoint steps over `records` (the states of samples `first`,
    /// `first + 1`, …), last to first; `s̄` ends as the adjoint of sample
    /// `first`, its weight added.
    fn backward_over(
        &self,
        transposed: &mut Transposed,
        back: &mut Backward<'_>,
        records: &[Record],
        first: usize,
    ) -> Result<(), IntegrationError> {
        for k in (1..records.len()).rev() {
            self.adjoint_step(transposed, back, &records[k], records[k - 1].h)?;
            back.add_weight(first + k - 1);
        }
        Ok(())
    }

    /// One step of the transposed recurrence (module documentation) at the
    /// converged state `rec`, reached by a step of size `rec.h` after one of
    /// `h_before`: `μ`, its share `μᵀ c_k` of every parameter's gradient, and
    /// `s̄` carried back to the state before the step (without its weight).
    fn adjoint_step(
        &self,
        transposed: &mut Transposed,
        back: &mut Backward<'_>,
        rec: &Record,
        h_before: f64,
    ) -> Result<(), IntegrationError> {
        let n = self.sys.n_coords();
        let mu = self.adjoint_solve(transposed, &back.bar, rec)?;
        let x = rec.state.at(rec.t);
        for (g, param) in back.grad.iter_mut().zip(back.params.iter_mut()) {
            *g += partials_dot(param, &x, &mu, n);
        }
        // (ū^p, ū̇^p, ā^p) = (ū − K_Tᵀ μ_u − Bᵀ μ_λ, ū̇ − C_Tᵀ μ_u, ā).
        let lin = &transposed.lin;
        let (mut k_mu, mut c_mu) = (vec![0.0; n], vec![0.0; n]);
        lin.tangent_mul_transpose_add(&mu[..n], &mut k_mu, &mut c_mu);
        lin.b_pattern()
            .mul_transpose_add(lin.b(), &mu[n..], &mut k_mu);
        let bar = &mut back.bar;
        for i in 0..n {
            bar.u[i] -= k_mu[i];
            bar.v[i] -= c_mu[i];
        }
        self.predictor_transpose(bar, rec.h, rec.h / h_before);
        Ok(())
    }

    /// `μ = J⁻ᵀ x̄` at the state `rec`, with `x̄` formed from `s̄` (module
    /// documentation). The factored matrix is `A = D₁ L J D₂` with
    /// `D₁ = diag(scale I, I)`, `D₂ = diag(I, I/scale)` and `L = [I c_bb Bᵀ;
    /// 0 I]` (the augmentation; `L = I` for a structure without it), so
    /// `μ = Lᵀ D₁ A⁻ᵀ D₂ x̄`: with `z = A⁻ᵀ [x̄_u; x̄_λ/scale]`,
    /// `μ_u = scale z_u` and `μ_λ = z_λ + c_bb B μ_u`. Only `M`, `B` and the
    /// Jacobians are evaluated at the state: the residual and the forces are
    /// not needed.
    fn adjoint_solve(
        &self,
        transposed: &mut Transposed,
        bar: &State,
        rec: &Record,
    ) -> Result<Vec<f64>, IntegrationError> {
        let (n, h) = (self.sys.n_coords(), rec.h);
        let c = self.p.coefficients(h, self.config.scaling);
        let a_p = 1.0 / (self.p.beta * h * h);
        let x = rec.state.at(rec.t);
        transposed.lin.eval_matrices(self.sys, rec.t, &rec.state.u);
        transposed.lin.eval_jacobians(self.sys, &x);
        transposed.lin.assemble(&c);
        transposed.fill();
        let fail = |context, source| self.kkt_error(context, rec.t, h, source);
        transposed
            .solver
            .factor(&transposed.a_t.values)
            .map_err(|e| fail("factoring the transposed iteration matrix (adjoint)", e))?;
        let mut z: Vec<f64> = (0..n)
            .map(|i| bar.u[i] + c.c_v * bar.v[i] + c.c_a * bar.a[i] + a_p * bar.a_alpha[i])
            .collect();
        z.extend(bar.lambda.iter().map(|l| l / c.scale));
        transposed
            .solver
            .solve_in_place(&mut z)
            .map_err(|e| fail("solving with the transposed iteration matrix (adjoint)", e))?;
        for z in &mut z[..n] {
            *z *= c.scale;
        }
        let lin = &transposed.lin;
        if lin.augmented() {
            let mut b_mu = vec![0.0; self.sys.n_constraints()];
            lin.b_pattern().mul_add(lin.b(), &z[..n], &mut b_mu);
            for (z, b) in z[n..].iter_mut().zip(&b_mu) {
                *z += c.c_bb * b;
            }
        }
        if let Some(i) = z.iter().position(|x| !x.is_finite()) {
            return Err(IntegrationError::NonFinite {
                t: rec.t,
                what: format!("the adjoint (unknown {i} of the transposed KKT system)"),
            });
        }
        Ok(z)
    }

    /// `s̄ ← Pᵀ (ū^p, ū̇^p, ā^p)`: the transpose of the predictor with zero
    /// acceleration (`predicted_sensitivity` in `sensitivity.rs`) for a step
    /// of size `h` after one `h / rescale`; `λ̄` becomes zero (the
    /// predictor does not read `λ`).
    fn predictor_transpose(&self, bar: &mut State, h: f64, rescale: f64) {
        let p = self.p;
        let to_aa1 = 1.0 / (1.0 - p.alpha_m);
        for i in 0..bar.u.len() {
            let (u_p, v_p, aa_p) = (bar.u[i], bar.v[i], bar.a_alpha[i]);
            // aa1 = (α_f a − α_m a_n)/(1 − α_m), a_n = (1 − ρ) a + ρ a_α.
            let aa1 = aa_p + h * p.gamma * v_p + h * h * p.beta * u_p;
            let a_n =
                h * (1.0 - p.gamma) * v_p + h * h * (0.5 - p.beta) * u_p - p.alpha_m * to_aa1 * aa1;
            bar.v[i] = v_p + h * u_p;
            bar.a[i] = p.alpha_f * to_aa1 * aa1 + (1.0 - rescale) * a_n;
            bar.a_alpha[i] = rescale * a_n;
        }
        bar.lambda.fill(0.0);
    }

    /// The column's current value.
    fn column_value(&self, column: Column) -> f64 {
        let s = &self.state;
        match column {
            Column::Position(i) => s.u[i],
            Column::Velocity(i) => s.v[i],
            Column::Acceleration(i) => s.a[i],
            Column::Multiplier(i) => s.lambda[i],
        }
    }

    /// The current state as a [`Record`].
    fn record(&self) -> Record {
        Record {
            t: self.t,
            h: self.h_last,
            state: self.state.clone(),
        }
    }

    /// The transposed KKT matrix in the structure of the forward run's
    /// backend, analysed by that backend; when it refuses the pattern, the
    /// augmented matrix (a singular `M` does not stop it) with the sparse LU.
    fn transposed(&self) -> Result<Transposed, IntegrationError> {
        let forward = self.solver.backend();
        match self.transposed_with(self.lin.structure(), forward)? {
            Ok(t) => Ok(t),
            Err(KktError::Structure(_)) if forward != Backend::SPARSE_LU => self
                .transposed_with(Structure::AUGMENTED, Backend::SPARSE_LU)?
                .map_err(|source| self.transposed_error(source)),
            Err(source) => Err(self.transposed_error(source)),
        }
    }

    /// [`Transposed`] in `structure`, analysed by `backend` (the inner error
    /// is the analysis's, for [`transposed`](Self::transposed) to fall back).
    fn transposed_with(
        &self,
        structure: Structure,
        backend: Backend,
    ) -> Result<Result<Transposed, KktError>, IntegrationError> {
        let n = self.sys.n_coords();
        let lin = Linearization::with_structure(self.sys, structure)?;
        let (a_t, map) = transpose_pattern(lin.kkt(), n);
        // The forward run's options (as `linear_algebra` in `mod.rs` sets
        // them), with its backend resolved.
        let options = KktOptions {
            backend,
            n_primal: self.config.kkt.n_primal.or(Some(n)),
            ..self.config.kkt
        };
        Ok(KktSolver::new(&a_t, &options).map(|solver| Transposed {
            lin,
            a_t,
            map,
            solver,
        }))
    }

    /// A failed analysis of `Aᵀ`'s pattern.
    fn transposed_error(&self, source: KktError) -> IntegrationError {
        self.kkt_error(
            "analysing the transposed KKT pattern",
            self.t,
            self.h,
            source,
        )
    }

    /// The state to repeat the steps from; the next step refactors (so the
    /// recomputation, which starts without a factorization, repeats it).
    fn snapshot(&mut self) -> Snapshot {
        self.factored_h = None;
        self.jacobians_of_state = false;
        Snapshot {
            t: self.t,
            state: self.state.clone(),
            history: self.history.clone(),
            h: self.h,
            h_last: self.h_last,
            error: self.error.clone(),
            error_previous: self.error_previous,
            rejected_last: self.rejected_last,
            easy_steps: self.easy_steps,
            t_anchor: self.t_anchor,
            h_anchor: self.h_anchor,
            steps_at_h: self.steps_at_h,
            stats: self.stats,
            residual: self.residual,
            constraint: self.constraint,
            iterations: self.iterations,
            energies: self.energies,
        }
    }

    /// Puts the integrator back at `s`, without a factorization.
    fn restore(&mut self, s: &Snapshot) {
        self.factored_h = None;
        self.jacobians_of_state = false;
        self.t = s.t;
        self.state.clone_from(&s.state);
        self.history.clone_from(&s.history);
        self.h = s.h;
        self.h_last = s.h_last;
        self.error.clone_from(&s.error);
        self.error_previous = s.error_previous;
        self.rejected_last = s.rejected_last;
        self.easy_steps = s.easy_steps;
        self.t_anchor = s.t_anchor;
        self.h_anchor = s.h_anchor;
        self.steps_at_h = s.steps_at_h;
        self.stats = s.stats;
        self.residual = s.residual;
        self.constraint = s.constraint;
        self.iterations = s.iterations;
        self.energies = s.energies;
    }
}

/// `μᵀ c` with `c = [r_p; −Φ_p]` at `x`: central differences of the
/// residual and the constraints of the parameter's models at `p ± h_p` (the
/// whole model's, or its small one's on the rows it changes), as the
/// forward sensitivities form them.
fn partials_dot(param: &mut Parameter, x: &mstar_model::StateRef<'_>, mu: &[f64], n: usize) -> f64 {
    let mut dot = 0.0;
    param
        .partials
        .each(x, n, param.step, |k, c| dot += mu[k] * c);
    dot
}

/// `s̄ᵀ S` over all five parts of the state.
fn dot_state(bar: &State, s: &State) -> f64 {
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    dot(&bar.u, &s.u)
        + dot(&bar.v, &s.v)
        + dot(&bar.a, &s.a)
        + dot(&bar.a_alpha, &s.a_alpha)
        + dot(&bar.lambda, &s.lambda)
}

#[cfg(test)]
mod tests {
    use super::transpose_pattern;
    use mstar_kkt::Csc;

    /// `A`'s values carried into `Aᵀ`'s pattern by the map, as a dense matrix.
    fn transposed_dense(a: &Csc, n: usize) -> Vec<Vec<f64>> {
        let (mut a_t, map) = transpose_pattern(a, n);
        for (&k, &v) in map.iter().zip(&a.values) {
            a_t.values[k] = v;
        }
        a_t.to_dense()
    }

    /// A structurally unsymmetric `S` (entry (0, 1) without (1, 0)), `B`
    /// and `Bᵀ` stored: the whole matrix transposed (written out by hand).
    #[test]
    fn whole_kkt_matrix_is_transposed() {
        // [[1, 2, 4], [0, 3, 5], [4, 5, 0]], column by column.
        let a = Csc {
            n: 3,
            col_ptr: vec![0, 2, 5, 7],
            row_idx: vec![0, 2, 0, 1, 2, 0, 1],
            values: vec![1.0, 4.0, 2.0, 3.0, 5.0, 4.0, 5.0],
        };
        let want = [[1.0, 0.0, 4.0], [2.0, 3.0, 5.0], [4.0, 5.0, 0.0]];
        assert_eq!(transposed_dense(&a, 2), want);
    }

    /// Without the `Bᵀ` block (the Schur backends' structure, read as
    /// `[S Bᵀ; B 0]`): `S` transposed, `B` where it was.
    #[test]
    fn structure_without_b_transpose_keeps_b_below() {
        // [[1, 2, 0], [0, 3, 0], [4, 5, 0]].
        let a = Csc {
            n: 3,
            col_ptr: vec![0, 2, 5, 5],
            row_idx: vec![0, 2, 0, 1, 2],
            values: vec![1.0, 4.0, 2.0, 3.0, 5.0],
        };
        let want = [[1.0, 0.0, 0.0], [2.0, 3.0, 0.0], [4.0, 5.0, 0.0]];
        assert_eq!(transposed_dense(&a, 2), want);
    }
}
