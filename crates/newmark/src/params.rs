//! Integrator parameters and configuration.

use mstar_kkt::KktOptions;
use mstar_linearize::Coefficients;

use crate::{IntegrationError, Short};

/// The time-integration scheme. All three are members of the generalized-α
/// family in the form of Arnold & Brüls (2007):
///
/// ```text
/// (1 − α_m) a_{n+1} + α_m a_n = (1 − α_f) ü_{n+1} + α_f ü_n
/// u_{n+1} = u_n + h u̇_n + h² (½ − β) a_n + h² β a_{n+1}      (cf. eq. 13)
/// u̇_{n+1} = u̇_n + h (1 − γ) a_n + h γ a_{n+1}                (cf. eq. 12)
/// M ü_{n+1} + Bᵀ λ_{n+1} = g(u_{n+1}, u̇_{n+1}, t_{n+1}),  Φ(u_{n+1}, t_{n+1}) = 0
/// ```
///
/// With `α_m = α_f = 0` the acceleration-like variable `a` equals `ü` and this is
/// the paper's Newmark scheme (eqs. 12-13).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Scheme {
    /// Newmark(β, γ), the paper's scheme with `β = 1/4, γ = 1/2` (trapezoidal
    /// rule, non-dissipative; unstable in `λ` for index-3 systems).
    Newmark {
        /// β (the paper: 1/4).
        beta: f64,
        /// γ (the paper: 1/2).
        gamma: f64,
    },
    /// Hilber-Hughes-Taylor α, `α ∈ [−1/3, 0]` in the original sign convention
    /// (`α = 0` is the trapezoidal rule); `γ = ½ − α`, `β = (1 − α)²/4`.
    Hht {
        /// α ∈ [−1/3, 0].
        alpha: f64,
    },
    /// Generalized-α of Chung & Hulbert (1993) with the spectral radius at
    /// infinite frequency `ρ∞ ∈ [0, 1]` as the one knob (`ρ∞ = 1` is the
    /// trapezoidal rule): `α_m = (2ρ∞ − 1)/(ρ∞ + 1)`, `α_f = ρ∞/(ρ∞ + 1)`,
    /// `γ = ½ + α_f − α_m`, `β = ¼ (γ + ½)²`.
    GeneralizedAlpha {
        /// ρ∞ ∈ [0, 1] (default 0.9).
        rho_inf: f64,
    },
}

impl Default for Scheme {
    /// Generalized-α with `ρ∞ = 0.9`.
    fn default() -> Self {
        Self::GeneralizedAlpha { rho_inf: 0.9 }
    }
}

/// The four parameters of the generalized-α family (Arnold & Brüls form).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AlphaParams {
    /// α_m.
    pub alpha_m: f64,
    /// α_f.
    pub alpha_f: f64,
    /// β.
    pub beta: f64,
    /// γ.
    pub gamma: f64,
}

impl AlphaParams {
    /// `β' = (1 − α_m) / ((1 − α_f) β h²)`: the corrector's `Δü = β' Δu` (15a).
    #[must_use]
    pub fn beta_prime(&self, h: f64) -> f64 {
        (1.0 - self.alpha_m) / ((1.0 - self.alpha_f) * self.beta * h * h)
    }

    /// `γ' = γ / (β h)`: the corrector's `Δu̇ = γ' Δu` (15b).
    #[must_use]
    pub fn gamma_prime(&self, h: f64) -> f64 {
        self.gamma / (self.beta * h)
    }

    /// The KKT coefficients of one Newton iteration with step `h`:
    /// `S_T = K_T + γ' C_T + β' M*` (eq. 17 with `M* = M + BᵀB`, eq. 11), and,
    /// with `scaling`, the equilibrium rows multiplied (the multipliers divided)
    /// by `1/β'` so that the matrix stays `O(1)` as `h → 0`.
    #[must_use]
    pub fn coefficients(&self, h: f64, scaling: bool) -> Coefficients {
        let beta_p = self.beta_prime(h);
        Coefficients {
            c_u: 1.0,
            c_v: self.gamma_prime(h),
            c_a: beta_p,
            c_bb: beta_p,
            c_identity: 0.0,
            scale: if scaling { 1.0 / beta_p } else { 1.0 },
        }
    }
}

impl Scheme {
    /// The scheme's parameters.
    ///
    /// # Errors
    /// [`IntegrationError::Config`] for parameters outside their range.
    pub fn params(&self) -> Result<AlphaParams, IntegrationError> {
        let bad = |s: String| Err(IntegrationError::Config(s));
        match *self {
            Self::Newmark { beta, gamma } => {
                if let Some(why) = newmark_instability(beta, gamma) {
                    return bad(why);
                }
                Ok(AlphaParams {
                    alpha_m: 0.0,
                    alpha_f: 0.0,
                    beta,
                    gamma,
                })
            }
            Self::Hht { alpha } => {
                if !(-1.0 / 3.0..=0.0).contains(&alpha) {
                    return bad(format!(
                        "HHT needs α in [−1/3, 0] (got {}); α = 0 is the trapezoidal rule, α = −0.1 a common choice",
                        Short(alpha)
                    ));
                }
                let alpha_f = -alpha;
                let gamma = 0.5 + alpha_f;
                Ok(AlphaParams {
                    alpha_m: 0.0,
                    alpha_f,
                    beta: 0.25 * (gamma + 0.5) * (gamma + 0.5),
                    gamma,
                })
            }
            Self::GeneralizedAlpha { rho_inf } => {
                if !(0.0..=1.0).contains(&rho_inf) {
                    return bad(format!(
                        "generalized-α needs ρ∞ in [0, 1] (got {}); 1 is the trapezoidal rule, 0.9 the default",
                        Short(rho_inf)
                    ));
                }
                let alpha_m = (2.0 * rho_inf - 1.0) / (rho_inf + 1.0);
                let alpha_f = rho_inf / (rho_inf + 1.0);
                let gamma = 0.5 + alpha_f - alpha_m;
                Ok(AlphaParams {
                    alpha_m,
                    alpha_f,
                    beta: 0.25 * (gamma + 0.5) * (gamma + 0.5),
                    gamma,
                })
            }
        }
    }
}

/// Why Newmark(β, γ) is refused, if it is: outside the range where the
/// scheme is unconditionally stable on linear undamped oscillators,
/// `γ ≥ ½` and `β ≥ γ/2` (Hughes, *The Finite Element Method*, §9.1). With
/// `γ < ½` the scheme adds energy (negative numerical damping) and every
/// mode grows, whatever `h`; with `β < γ/2` it is stable only for `ω h`
/// below a bound, which the stiff modes of a constrained system (and the
/// constraint directions themselves, of infinite frequency) exceed.
fn newmark_instability(beta: f64, gamma: f64) -> Option<String> {
    let (b, g) = (Short(beta), Short(gamma));
    if !(beta > 0.0 && beta.is_finite() && gamma.is_finite()) {
        return Some(format!(
            "Newmark needs a finite β > 0 (got β = {b}, γ = {g}); the paper uses β = 0.25, γ = 0.5"
        ));
    }
    if gamma < 0.5 {
        return Some(format!(
            "Newmark with γ = {g} < 1/2 is unstable (it adds energy at every step, whatever h): use γ ≥ 0.5 and β ≥ γ/2, e.g. β = 0.25, γ = 0.5"
        ));
    }
    // (γ/2 is exact in binary: β = 0.3, γ = 0.6 passes.)
    if beta < 0.5 * gamma {
        return Some(format!(
            "Newmark with β = {b} < γ/2 = {} is only conditionally stable, and a constrained system's stiff modes exceed its bound on h: use β ≥ γ/2, e.g. β = (γ + 1/2)²/4 = {}",
            Short(0.5 * gamma),
            Short(0.25 * (gamma + 0.5) * (gamma + 0.5))
        ));
    }
    None
}

/// How the step's Newton iteration starts (the predictor).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Predictor {
    /// `ü_{n+1}⁰ = 0`, the paper's eq. (14a) (and Arnold & Brüls' Algorithm 1).
    ZeroAcceleration,
    /// `ü_{n+1}⁰ = ü_n`, `λ⁰ = λ_n`.
    ConstantAcceleration,
    /// `ü_{n+1}⁰` and `λ⁰` extrapolated linearly from the last two steps:
    /// the predictor's error drops from `O(h)` to `O(h²)`.
    Linear,
    /// `ü_{n+1}⁰` and `λ⁰` extrapolated from the last five steps when they
    /// have this step's size, exactly for quadratic motion and for the
    /// step-to-step alternation the scheme's root `−ρ∞` rings with; linearly
    /// after a change of step size (default; `integrator/history.rs`,
    /// `docs/theory.md`, "The predictor").
    #[default]
    Extrapolated,
}

/// How the initial acceleration and multipliers are obtained.
#[derive(Clone, Debug, Default, PartialEq)]
pub enum Start {
    /// The paper's start: `M* ü₀ = g − Bᵀ λ₀` with `M* = M + BᵀB` (eq. 11) and
    /// a given `λ₀` (in general not consistent with the constraints).
    Paper {
        /// The initial multipliers `λ₀`.
        lambda0: Vec<f64>,
    },
    /// Consistent: solve `[M Bᵀ; B 0][ü₀; λ₀] = [g; c]` with the acceleration
    /// right-hand side `c = −(B u̇)_u u̇ − 2 B_t u̇ − Φ_tt` (default).
    #[default]
    Consistent,
}

/// Newton-Raphson variant.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Newton {
    /// Refactor the iteration matrix at every iteration. With the Schur
    /// backend one iteration per step meets the tolerance and it is the
    /// fastest variant on chains (docs/performance.md; the default of
    /// `mstar chain`). A motion too fast for `h` (a whip) converges in one
    /// iteration as readily as a resolved one: the local error estimate
    /// ([`ErrorControl`]) is what reports it, for either variant.
    Full,
    /// Keep the factorization across iterations and steps while the observed
    /// contraction rate `‖Δu_k‖/‖Δu_{k−1}‖` stays below `max_rate`; refactor when it
    /// does not, when the step size changes, after a step that needed more than
    /// 4 iterations, or after a failed attempt ([`Newton::MODIFIED`]: `max_rate = 0.5`).
    Modified {
        /// Largest accepted contraction rate before a refactorization (in (0, 1)).
        max_rate: f64,
    },
    /// A fresh Jacobian at the first iteration of every step, kept by the
    /// step's later iterations while each contracts by `max_rate` or better
    /// ([`Newton::PER_STEP`]: 0.5). A step that converges in one iteration
    /// costs what full Newton's does; a second iteration costs a residual and
    /// a solve instead of a factorization too (Newton's solves skip the
    /// backend's refinement step: [`mstar_kkt::KktSolver::solve_correction`];
    /// docs/performance.md, "The second Newton iteration at 10⁵ bodies").
    PerStep {
        /// Largest accepted contraction rate before a refactorization within
        /// the step (in (0, 1)).
        max_rate: f64,
    },
    /// Chosen with the KKT backend when the integrator is made
    /// ([`Newton::resolve`]): once per step with the Schur backends on a
    /// system above [`mstar_kkt::KktOptions::dense_threshold`] unknowns whose
    /// Jacobians are cheap
    /// ([`System::fresh_jacobians_pay`](mstar_model::System::fresh_jacobians_pay)): `schur-lu`, spatial bodies' exact, unsymmetric tangent, one
    /// iteration a step, 1.5–1.8× faster than modified Newton on the spatial
    /// chain; `schur`, the N-four-bar from 7 to 10⁵ bodies, 1.04–1.36
    /// iterations a step against modified Newton's 3.1–3.3, 10–35 % less
    /// time. Modified Newton otherwise: a dense or sparse LU's factorization
    /// costs more than the two iterations it saves; on a small system, or a
    /// spatial one with other joints or loads (the spatial slider-crank, 22 %
    /// more instructions once per step), or a linear one (one iteration a
    /// step either way), a factorization a step buys nothing
    /// (docs/performance.md, "Newton variant"). With one forward
    /// sensitivity, modified Newton by this choice turns into once per step
    /// when its first 16 steps from the sensitivities' factorizations take
    /// 1.5 iterations a step or more ([`crate::Sensitivities::switched_newton`]).
    /// The default.
    #[default]
    Automatic,
}

impl Newton {
    /// The modified variant with its usual rate bound, 0.5.
    pub const MODIFIED: Self = Self::Modified { max_rate: 0.5 };

    /// The once-per-step variant with the same rate bound, 0.5.
    pub const PER_STEP: Self = Self::PerStep { max_rate: 0.5 };

    /// The variant to use with `backend`: [`Automatic`](Self::Automatic)
    /// resolved (once per step with the Schur backends when
    /// `once_per_step_pays`: the system is larger than the dense threshold
    /// and its Jacobians are not costly), the others as they are.
    #[must_use]
    pub fn resolve(self, backend: mstar_kkt::Backend, once_per_step_pays: bool) -> Self {
        use mstar_kkt::Backend;
        match self {
            Self::Automatic
                if once_per_step_pays
                    && (backend == Backend::SCHUR_LU || backend == Backend::SCHUR) =>
            {
                Self::PER_STEP
            }
            Self::Automatic => Self::MODIFIED,
            chosen => chosen,
        }
    }
}

impl std::fmt::Display for Newton {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Full => f.write_str("full (a fresh Jacobian at every iteration)"),
            Self::Modified { max_rate } => write!(
                f,
                "modified (the Jacobian kept while each iteration contracts by {} or better)",
                crate::Short(*max_rate)
            ),
            Self::PerStep { max_rate } => write!(
                f,
                "once per step (a fresh Jacobian at each step's first iteration, kept while the step's iterations contract by {} or better)",
                crate::Short(*max_rate)
            ),
            Self::Automatic => {
                f.write_str("automatic (once per step with schur and schur-lu on a large model with cheap Jacobians, else modified)")
            }
        }
    }
}

/// Configuration of an [`Integrator`](crate::Integrator). Each field states its
/// default; [`Config::paper`] is the paper's setting.
#[derive(Clone, Debug, PartialEq)]
pub struct Config {
    /// Scheme (default: generalized-α, `ρ∞ = 0.9`).
    pub scheme: Scheme,
    /// Step size `h`, s (default: 0.01). Step control never exceeds it.
    pub h: f64,
    /// Smallest step size step control may use (default: `h / 1024`); `h_min = h`
    /// disables step control.
    pub h_min: Option<f64>,
    /// Newton tolerance, relative (default: 1e-10): converged when
    /// `‖r‖∞ ≤ tol · max(‖g‖∞, ‖Bᵀλ‖∞, ‖Mü‖∞, ‖λ‖∞)` and `‖Φ‖∞ ≤ tol · max(1, ‖u‖∞)`
    /// after at least one correction, with `Φ` settled: `β' max|M| ‖Φ‖∞`
    /// within the residual's tolerance, or `‖Φ‖∞` at round-off (docs/theory.md,
    /// "Round-off in the multipliers"). Without
    /// [`exact_multiplier_update`](Config::exact_multiplier_update) the residual
    /// cannot go below the round-off floor `4 c_bb ε ‖u‖∞ ‖B‖∞` (`c_bb = β'`,
    /// about `4ε‖u‖/h²`), which then replaces a smaller tolerance.
    pub tol: f64,
    /// Newton iterations per attempt before the step is rejected (default: 20).
    pub max_iterations: usize,
    /// Newton variant (default: modified, contraction rate 0.5).
    pub newton: Newton,
    /// Predictor (default: extrapolated; the paper: zero acceleration).
    pub predictor: Predictor,
    /// Initial acceleration and multipliers (default: consistent).
    pub start: Start,
    /// Start on the discrete solution, so that there is no `O(h)` period-2h
    /// transient in `ü` and `λ` (default: true; only with [`Start::Consistent`]):
    /// the acceleration-like variable starts at `a₀ = ü₀ + (α_m − α_f) h u⃛₀`
    /// (Arnold & Brüls 2007) and the velocity gets the `O(h²)` normal component
    /// `B δu̇₀ = −c h² B u⃛₀`, `c = β + (α_m − α_f)/2 − 1/6`, that the index-3
    /// discrete solution carries (`docs/stability.md`). `u⃛₀` comes from central
    /// differences of consistent accelerations at `t₀ ± h`.
    pub corrected_start: bool,
    /// Project the initial state onto `Φ = 0` and `B u̇ + Φ_t = 0` (minimum-norm
    /// corrections) when it violates them; when false such a state is an error
    /// (default: true).
    pub project: bool,
    /// Remove from the multiplier update the shift that `M* = M + BᵀB` in `S_T`
    /// introduces. With `S_T + c BᵀB` in (16) and `B Δu = −Φ`, the solve returns
    /// the exact Newton `Δu` but `Δλ + c Φ`; subtracting `c Φ` makes the iteration
    /// an exact Newton method again, which saves about one iteration per step.
    /// The paper's scheme keeps the shift (default: true; [`Config::paper`]:
    /// false).
    pub exact_multiplier_update: bool,
    /// Scale the KKT system (equilibrium rows × `1/c_a`, multipliers ÷ `1/c_a`)
    /// so that its conditioning does not grow like `h⁻⁴` (default: true).
    pub scaling: bool,
    /// The local error estimate and what is done with it (default: monitor
    /// with `rtol = 1e-3`, `atol = 1e-6`; [`ErrorControl`]).
    pub error: ErrorControl,
    /// Linear solver options (default: [`KktOptions::default`], the automatic
    /// choice: dense up to 24 unknowns; above, the Schur complement when `S_T`
    /// without `BᵀB` is block-diagonal and `M`'s diagonal is positive, else
    /// sparse LDLᵀ of the augmented matrix; see
    /// [`KktOptions::candidates`]). The integrator sets
    /// [`KktOptions::n_primal`] to the number of coordinates.
    pub kkt: KktOptions,
}

impl Default for Config {
    fn default() -> Self {
        Self {
            scheme: Scheme::default(),
            h: 0.01,
            h_min: None,
            tol: 1e-10,
            max_iterations: 20,
            newton: Newton::default(),
            predictor: Predictor::default(),
            start: Start::Consistent,
            corrected_start: true,
            project: true,
            exact_multiplier_update: true,
            scaling: true,
            error: ErrorControl::default(),
            kkt: KktOptions::default(),
        }
    }
}

impl Config {
    /// The paper's algorithm exactly (§2.2, Fig. 2): Newmark `β = 1/4, γ = 1/2`,
    /// `ü⁰ = 0` predictor (14), full Newton on (16)-(17) with `M*`, the start
    /// `M* ü₀ = g − Bᵀλ₀` (eq. 11) with the given `λ₀`, no step control, no
    /// scaling.
    #[must_use]
    pub fn paper(h: f64, lambda0: Vec<f64>) -> Self {
        Self {
            scheme: Scheme::Newmark {
                beta: 0.25,
                gamma: 0.5,
            },
            h,
            h_min: Some(h),
            newton: Newton::Full,
            predictor: Predictor::ZeroAcceleration,
            start: Start::Paper { lambda0 },
            corrected_start: false,
            exact_multiplier_update: false,
            scaling: false,
            ..Self::default()
        }
    }

    /// Checks ranges.
    ///
    /// # Errors
    /// [`IntegrationError::Config`] naming the offending field.
    pub fn validate(&self) -> Result<AlphaParams, IntegrationError> {
        let bad = |s: String| Err(IntegrationError::Config(s));
        if !(self.h > 0.0 && self.h.is_finite()) {
            return bad(format!(
                "the step size h must be positive (got {})",
                Short(self.h)
            ));
        }
        if let Some(h_min) = self.h_min
            && !(h_min > 0.0 && h_min <= self.h)
        {
            return bad(format!(
                "h_min must be in (0, h] (got h_min = {}, h = {})",
                Short(h_min),
                Short(self.h)
            ));
        }
        if !(self.tol > 0.0 && self.tol < 1.0) {
            return bad(format!(
                "the Newton tolerance must be in (0, 1) (got {})",
                Short(self.tol)
            ));
        }
        self.error.validate(self.h)?;
        if self.max_iterations == 0 {
            return bad("max_iterations must be at least 1".into());
        }
        if let Newton::Modified { max_rate } = self.newton
            && !(max_rate > 0.0 && max_rate < 1.0)
        {
            return bad(format!(
                "the modified-Newton contraction rate must be in (0, 1) (got {})",
                Short(max_rate)
            ));
        }
        self.scheme.params()
    }

    /// `h_min` with its default applied: `h / 1024` at a fixed step size,
    /// `h · 1e-6` with adaptive steps.
    #[must_use]
    pub fn h_min(&self) -> f64 {
        let factor = match self.error.mode {
            StepMode::Adaptive => 1e-6,
            StepMode::Monitor | StepMode::Strict => 1.0 / 1024.0,
        };
        self.h_min.unwrap_or(self.h * factor)
    }
}

/// What the integrator does with its local error estimate
/// (`docs/theory.md`, "Local error estimate and step control").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum StepMode {
    /// Fixed step size `h`; the estimate is computed and reported in
    /// [`RunStats::error`](crate::RunStats::error), for a warning (default).
    #[default]
    Monitor,
    /// Fixed step size; a step whose estimate exceeds the tolerance is an
    /// error ([`IntegrationError::ErrorTooLarge`]).
    Strict,
    /// The step size follows the estimate: a PI controller, steps rejected
    /// and retried while the estimate exceeds the tolerance, `h` the first
    /// step, bounded by `h_min` and [`ErrorControl::h_max`].
    Adaptive,
}

/// The local error estimate's tolerances and use.
///
/// A step is within tolerance when `|e_i| ≤ atol + rtol · max(|u_n,i|, |u_n+1,i|)`
/// for every coordinate `i`, where `e` is the estimate of the local error
/// in the positions (Zienkiewicz & Xie 1991, extended to generalized-α:
/// `docs/theory.md`). The defaults are those of SciPy's `solve_ivp`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorControl {
    /// Relative tolerance (default 1e-3).
    pub rtol: f64,
    /// Absolute tolerance, in the coordinates' units (m, rad; default 1e-6).
    pub atol: f64,
    /// What the estimate is used for (default: [`StepMode::Monitor`]).
    pub mode: StepMode,
    /// Largest step size of adaptive stepping (default: none).
    pub h_max: Option<f64>,
}

impl Default for ErrorControl {
    fn default() -> Self {
        Self {
            rtol: 1e-3,
            atol: 1e-6,
            mode: StepMode::Monitor,
            h_max: None,
        }
    }
}

impl ErrorControl {
    /// Checks ranges (`h` is the configuration's step size).
    ///
    /// # Errors
    /// [`IntegrationError::Config`] naming the offending field.
    pub fn validate(&self, h: f64) -> Result<(), IntegrationError> {
        let bad = |s: String| Err(IntegrationError::Config(s));
        for (name, x) in [("rtol", self.rtol), ("atol", self.atol)] {
            if !(x >= 0.0 && x.is_finite()) {
                return bad(format!("{name} must be finite and ≥ 0 (got {x:e})"));
            }
        }
        if self.rtol == 0.0 && self.atol == 0.0 {
            return bad("rtol and atol cannot both be 0".into());
        }
        if let Some(h_max) = self.h_max
            && !(h_max >= h && h_max.is_finite())
        {
            return bad(format!(
                "h_max must be finite and at least the step size h = {h:e} (got {h_max:e})"
            ));
        }
        Ok(())
    }

    /// The coefficient `c` of the local error `c h³ u⃛` of the positions:
    /// `c = β − 1/6 + (α_m − α_f)/2` (`1/12` for the trapezoidal rule).
    #[must_use]
    pub fn coefficient(p: &AlphaParams) -> f64 {
        p.beta - 1.0 / 6.0 + 0.5 * (p.alpha_m - p.alpha_f)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rho_one_is_the_trapezoidal_rule() {
        let p = Scheme::GeneralizedAlpha { rho_inf: 1.0 }
            .params()
            .expect("valid");
        assert!((p.alpha_m - 0.5).abs() < 1e-15 && (p.alpha_f - 0.5).abs() < 1e-15);
        assert!((p.beta - 0.25).abs() < 1e-15 && (p.gamma - 0.5).abs() < 1e-15);
        let h = Scheme::Hht { alpha: 0.0 }.params().expect("valid");
        assert_eq!(
            (h.alpha_m, h.alpha_f, h.beta, h.gamma),
            (0.0, 0.0, 0.25, 0.5)
        );
    }

    #[test]
    fn out_of_range_parameters_are_errors() {
        assert!(Scheme::GeneralizedAlpha { rho_inf: 1.5 }.params().is_err());
        assert!(Scheme::Hht { alpha: 0.1 }.params().is_err());
        assert!(
            Scheme::Newmark {
                beta: 0.0,
                gamma: 0.5
            }
            .params()
            .is_err()
        );
        let c = Config {
            h: -1.0,
            ..Config::default()
        };
        assert!(c.validate().is_err());
    }

    /// Newmark outside `γ ≥ ½, β ≥ γ/2` is refused with the reason, and the
    /// parameters the message suggests are accepted.
    #[test]
    fn unstable_newmark_parameters_are_refused_with_working_advice() {
        let newmark = |beta, gamma| Scheme::Newmark { beta, gamma }.params();
        let e = newmark(0.25, 0.4).err().map(|e| e.to_string());
        let e = e.unwrap_or_default();
        assert!(e.contains("γ = 0.4 < 1/2") && e.contains("unstable"), "{e}");
        assert!(newmark(0.25, 0.5).is_ok(), "the advised β = 0.25, γ = 0.5");
        let e = newmark(0.2, 0.6).err().map(|e| e.to_string());
        let e = e.unwrap_or_default();
        assert!(e.contains("β = 0.2 < γ/2 = 0.3"), "{e}");
        // The advice: β = (γ + 1/2)²/4 = 0.3025 for γ = 0.6.
        assert!(e.contains("= 0.3025"), "{e}");
        assert!(newmark(0.3025, 0.6).is_ok());
        // β = γ/2 exactly is the stability limit, accepted.
        assert!(newmark(0.3, 0.6).is_ok());
        assert!(newmark(f64::NAN, 0.5).is_err());
    }

    /// Echoed values are short, whatever their size.
    #[test]
    fn configuration_errors_print_short_numbers() {
        let c = Config {
            h: 1.0,
            h_min: Some(1e308),
            ..Config::default()
        };
        let e = c
            .validate()
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(e.contains("h_min = 1e308, h = 1)"), "{e}");
        let e = Scheme::Hht { alpha: -1e300 }.params().err();
        let e = e.map(|e| e.to_string()).unwrap_or_default();
        assert!(e.contains("(got -1e300)"), "{e}");
    }
}
