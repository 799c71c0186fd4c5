//! Forward sensitivities of the discrete solution (`Integrator::step_with`)
//! against references that share nothing with them: central differences of
//! whole runs with Richardson extrapolation, and the exact scaling of the
//! multipliers with the mass.

use mstar_model::{PendulumChain, System};
use mstar_newmark::{Config, DIFFERENCE_STEP, Integrator, Newton, Parameterized, Scheme, Variant};

/// Newton tolerance of every run here: the finite differences divide the
/// runs' own errors (about this, relative) by the difference step.
const TOL: f64 = 1e-12;

/// The paper's pendulum (mass `m`, length `l`, g = 9.81) released at rest
/// from θ₀ = 1 rad.
struct Pendulum {
    sys: PendulumChain,
    u0: Vec<f64>,
    v0: Vec<f64>,
}

impl Pendulum {
    fn new(m: f64, l: f64) -> Self {
        let sys = PendulumChain::paper(m, l, 9.81);
        let u0 = sys.position(&[1.0]);
        Self {
            sys,
            u0,
            v0: vec![0.0; 3],
        }
    }
}

impl Variant for Pendulum {
    fn system(&self) -> &dyn System {
        &self.sys
    }
    fn initial_position(&self) -> &[f64] {
        &self.u0
    }
    fn initial_velocity(&self) -> &[f64] {
        &self.v0
    }
}

/// The pendulum's length or mass as a parameter.
struct Param {
    length: bool,
    m: f64,
    l: f64,
}

impl Parameterized for Param {
    fn name(&self) -> String {
        (if self.length { "length" } else { "mass" }).into()
    }
    fn value(&self) -> f64 {
        if self.length { self.l } else { self.m }
    }
    fn at(&self, value: f64) -> Result<Box<dyn Variant>, String> {
        Ok(Box::new(if self.length {
            Pendulum::new(self.m, value)
        } else {
            Pendulum::new(value, self.l)
        }))
    }
}

fn config(newton: Newton, rho: f64) -> Config {
    Config {
        h: 0.01,
        tol: TOL,
        newton,
        scheme: Scheme::GeneralizedAlpha { rho_inf: rho },
        ..Config::default()
    }
}

/// The final state `[u; λ]` of a run of the pendulum of length `l` to `t_end`.
fn final_state(l: f64, config: &Config, t_end: f64) -> Vec<f64> {
    let p = Pendulum::new(1.0, l);
    let mut integ =
        Integrator::new(&p.sys, config.clone(), 0.0, &p.u0, &p.v0).expect("the pendulum starts");
    while !integ.reached(t_end) {
        integ.step(t_end).expect("the step converges");
    }
    let s = integ.view();
    s.u.iter().chain(s.lambda).copied().collect()
}

/// The final `[∂u/∂p; ∂λ/∂p]` and `[u; λ]` of the nominal run with
/// sensitivities to `param`.
fn sensitivity(param: &Param, config: &Config, t_end: f64) -> (Vec<f64>, Vec<f64>) {
    let p = Pendulum::new(param.m, param.l);
    let mut integ =
        Integrator::new(&p.sys, config.clone(), 0.0, &p.u0, &p.v0).expect("the pendulum starts");
    let mut sens = integ
        .sensitivities(&[param])
        .expect("the sensitivities start");
    while !integ.reached(t_end) {
        integ
            .step_with(t_end, &mut sens)
            .expect("the step converges");
    }
    let s = integ.view();
    let value = s.u.iter().chain(s.lambda).copied().collect();
    (
        sens.u(0).iter().chain(sens.lambda(0)).copied().collect(),
        value,
    )
}

/// Checks the sensitivity to the length against central differences of
/// whole runs at `l ± δ`, `l ± 2δ`, extrapolated (Richardson): `D₁` and
/// `D₂` have errors `c δ²` and `4 c δ²`, so `R = (4 D₁ − D₂)/3` removes
/// them and `|D₁ − D₂|/3` estimates `D₁`'s error, a bound on `R`'s (which is
/// `O(δ⁴)`). The runs' own errors `η` (Newton tolerance, times the
/// coordinates' and multipliers' size) enter `R` as at most `1.5 η / δ`.
fn check_against_differences(config: &Config, t_end: f64) {
    let (l, delta) = (1.0, 1e-3);
    let param = Param {
        length: true,
        m: 1.0,
        l,
    };
    let (s, nominal) = sensitivity(&param, config, t_end);
    let f = |k: f64| final_state(l + k * delta, config, t_end);
    let (p1, m1, p2, m2) = (f(1.0), f(-1.0), f(2.0), f(-2.0));
    for i in 0..s.len() {
        let d1 = (p1[i] - m1[i]) / (2.0 * delta);
        let d2 = (p2[i] - m2[i]) / (4.0 * delta);
        let richardson = (4.0 * d1 - d2) / 3.0;
        let eta = TOL * nominal[i].abs().max(10.0);
        let tolerance = (d1 - d2).abs() / 3.0 + 1.5 * eta / delta;
        assert!(
            (s[i] - richardson).abs() <= tolerance,
            "component {i}: sensitivity {} against extrapolated differences {richardson} \
             (tolerance {tolerance:.3e}, D1 = {d1}, D2 = {d2})",
            s[i]
        );
    }
}

#[test]
fn length_sensitivity_matches_extrapolated_differences_full_newton() {
    check_against_differences(&config(Newton::Full, 0.9), 1.0);
}

#[test]
fn length_sensitivity_matches_extrapolated_differences_modified_newton() {
    check_against_differences(&config(Newton::Modified { max_rate: 0.5 }, 0.6), 1.0);
}

#[test]
fn length_sensitivity_on_a_shortened_last_step() {
    // t_end = 0.995 s is not a multiple of h: the last two steps share
    // what remains, and the predictor rescales the acceleration variable.
    check_against_differences(&config(Newton::Full, 0.8), 0.995);
}

/// In `u = [x, y, θ]` with `M = diag(m, m, 0)` and `g = [0, −m g₀, 0]`, the
/// discrete solution's positions do not depend on the mass and its
/// multipliers are proportional to it: `∂u/∂m = 0`, `∂λ/∂m = λ/m`. The
/// residual is linear in `m`, so its central difference has no truncation
/// error, only rounding, `ε F / h_m` with `F` the forces' size and `h_m =
/// DIFFERENCE_STEP · m`; each of the `N` steps may add that much force
/// error (a displacement of at most its `h²/m`), and the nominal `λ` is
/// within the Newton tolerance `TOL · F` of the discrete solution's.
#[test]
fn mass_sensitivity_scales_the_multipliers() {
    let (m, h, steps) = (2.0, 0.01, 100.0);
    let param = Param {
        length: false,
        m,
        l: 1.0,
    };
    let (s, nominal) = sensitivity(&param, &config(Newton::Full, 0.9), 1.0);
    // |λ| ≤ m (g₀ + l θ̇²) ≤ 3 m g₀ for a release from 1 rad.
    let force = 3.0 * m * 9.81;
    let force_error = steps * f64::EPSILON * force / (DIFFERENCE_STEP * m);
    for i in 0..3 {
        let tolerance = force_error * h * h / m;
        assert!(
            s[i].abs() <= tolerance,
            "∂u{i}/∂m = {} (tolerance {tolerance:.1e})",
            s[i]
        );
    }
    for i in 3..5 {
        let want = nominal[i] / m;
        let tolerance = (force_error + TOL * force) / m;
        assert!(
            (s[i] - want).abs() <= tolerance,
            "∂λ{}/∂m = {} against λ/m = {want} (tolerance {tolerance:.1e})",
            i - 3,
            s[i]
        );
    }
}

/// With a factorization of each step's own iterate (full Newton), one
/// parameter's solve refines with it instead of factoring at the converged
/// state, mostly in one pass from the extrapolation of its last two
/// solutions; two parameters share a factorization there. Both give the
/// sensitivity that the extrapolated differences check above (the same
/// to round-off: `[J_c]⁻¹` either way).
#[test]
fn one_parameter_refines_with_the_step_s_factorization_and_two_factor() {
    let (m, l) = (1.0, 1.0);
    let run = |params: &[&dyn Parameterized]| {
        let p = Pendulum::new(m, l);
        let mut integ = Integrator::new(&p.sys, config(Newton::Full, 0.9), 0.0, &p.u0, &p.v0)
            .expect("the pendulum starts");
        let mut sens = integ
            .sensitivities(params)
            .expect("the sensitivities start");
        for _ in 0..50 {
            integ.step_with(1.0, &mut sens).expect("the step converges");
        }
        let length: Vec<f64> = sens.u(0).iter().chain(sens.lambda(0)).copied().collect();
        (sens.factorizations(), sens.solves(), length)
    };
    let length = Param { length: true, m, l };
    let mass = Param {
        length: false,
        m,
        l,
    };
    let (factored_one, solves_one, refined) = run(&[&length]);
    let (factored_two, solves_two, factored) = run(&[&length, &mass]);
    assert_eq!(factored_one, 0, "one parameter refines");
    // One solve a step from the extrapolation of the last two steps'
    // solutions, two at the steps that measure the contraction (the first
    // and every 32nd) and where the first pass is not enough.
    assert!(
        (50..100).contains(&solves_one),
        "one solve a step, two at a few: {solves_one}"
    );
    assert_eq!(
        (factored_two, solves_two),
        (50, 100),
        "two parameters factor"
    );
    let scale = factored.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    for (r, f) in refined.iter().zip(&factored) {
        assert!(
            r.is_finite() && (r - f).abs() <= 1e-10 * scale,
            "{r} against {f}"
        );
    }
}
