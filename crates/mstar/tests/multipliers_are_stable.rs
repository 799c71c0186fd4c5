//! The paper's open problem (`algorithm.md` §5-6): the trapezoidal rule
//! (Newmark γ = 1/2) has spectral radius 1 at infinite frequency, so on an
//! index-3 DAE the period-2h mode of `ü` and `λ` is never damped and grows until
//! Newton fails. Generalized-α with ρ∞ < 1 damps it, and started on the discrete
//! solution (Arnold & Brüls 2007 plus the velocity correction of
//! `docs/stability.md`) it is second order in `λ` from the first step. The
//! scaled KKT system keeps its condition number bounded as `h → 0`.

use mstar::analysis::{fitted_order, max_lambda_error, nyquist_amplitude};
use mstar::kkt::condition_number;
use mstar::linearize::Linearization;
use mstar::pendulum::PendulumRun;
use mstar::{Config, Sample, Scheme, StateRef};

fn with_reference(run: &PendulumRun) -> (Vec<Sample>, Vec<Sample>) {
    run.run_with_reference()
        .unwrap_or_else(|e| panic!("integration failed: {e}"))
}

/// Max λ error over the first 0.2 s from a moving start, for each h.
fn start_errors(corrected_start: bool, hs: &[f64]) -> Vec<f64> {
    hs.iter()
        .map(|&h| {
            let mut run = PendulumRun::paper();
            (run.theta0, run.omega0, run.t_end) = (0.5, 3.0, 0.2);
            run.config = Config {
                h,
                corrected_start,
                ..Config::default()
            };
            let (s, r) = with_reference(&run);
            max_lambda_error(&s, &r)
        })
        .collect()
}

#[test]
fn corrected_start_removes_the_first_order_transient() {
    let hs = [0.02, 0.01, 0.005, 0.0025];
    let corrected = fitted_order(&hs, &start_errors(true, &hs));
    assert!(
        (corrected - 2.0).abs() <= 0.1,
        "order {corrected:.3} with the corrected start"
    );
    // Without it the period-2h transient is O(h): the test can tell the two apart.
    let plain = fitted_order(&hs, &start_errors(false, &hs));
    assert!(plain < 1.5, "order {plain:.3} without the corrected start");
}

#[test]
fn generalized_alpha_keeps_lambda_second_order_accurate_over_100_s() {
    // Reference figure from an independent prototype: 0.4 N over 10 s at
    // ρ∞ = 0.8, h = 0.01, θ₀ = π/2, g₀ = 10. A second-order method's error on
    // this periodic motion is a phase error growing linearly in time, so over
    // 100 s: 10 × 0.4 N, with a 25 % margin; at h/2 a quarter of it.
    for rho_inf in [0.9, 0.8] {
        for (h, bound) in [(0.01, 5.0), (0.005, 1.25)] {
            let mut run = PendulumRun::paper();
            run.t_end = 100.0;
            run.config = Config {
                h,
                scheme: Scheme::GeneralizedAlpha { rho_inf },
                ..Config::default()
            };
            let (s, r) = with_reference(&run);
            let err = max_lambda_error(&s, &r);
            assert!(
                err <= bound,
                "ρ∞ = {rho_inf}, h = {h}: max |λ − λ_ref| = {err:.3} N > {bound} N"
            );
        }
    }
}

#[test]
fn paper_scheme_shows_the_growing_period_2h_oscillation() {
    let run = PendulumRun::paper();
    let (samples, result) = run.run();
    // The physics claim: the oscillation grows until Newton fails before 10 s.
    assert!(result.is_err(), "the paper's scheme reached t_end");
    let lambda1: Vec<f64> = samples.iter().map(|s| s.lambda[0]).collect();
    let window = |t0: f64| {
        let k = (t0 / run.config.h).round() as usize;
        nyquist_amplitude(&lambda1[k..k + 100])
    };
    let (early, late) = (window(0.0), window(4.0));
    assert!(
        late > 10.0 * early,
        "period-2h amplitude of λ₁: {early:.3e} in [0, 1] s, {late:.3e} in [4, 5] s"
    );
    let times: Vec<f64> = samples.iter().take(201).map(|s| s.t).collect();
    let reference = run.reference(&times);
    let err = max_lambda_error(&samples[..201], &reference);
    assert!(err > 100.0, "max |λ − λ_ref| over 2 s = {err:.3e} N");
    // The same start integrated with generalized-α has no such mode.
    let mut cured = PendulumRun::paper();
    cured.config = Config::default();
    let (samples, result) = cured.run();
    assert!(result.is_ok());
    let lambda1: Vec<f64> = samples.iter().map(|s| s.lambda[0]).collect();
    let amplitude = nyquist_amplitude(&lambda1[400..500]);
    assert!(
        amplitude < 1e-2 * late,
        "generalized-α period-2h amplitude {amplitude:.3e}"
    );
}

/// Condition number of the pendulum's iteration matrix at a moving state.
fn condition(h: f64, scaling: bool) -> f64 {
    let run = PendulumRun::standard();
    let sys = run.system();
    let u = sys.position(&[0.7]);
    let v = sys.velocity(&[0.7], &[2.0]);
    let (a, lambda) = ([-3.0, 2.0, -6.0], [4.0, -9.0]);
    let mut lin = Linearization::new(&sys).expect("valid model");
    let x = StateRef {
        t: 0.0,
        u: &u,
        v: &v,
        a: &a,
        lambda: &lambda,
    };
    lin.eval_residual(&sys, &x);
    lin.eval_jacobians(&sys, &x);
    let params = run.config.scheme.params().expect("valid scheme");
    lin.assemble(&params.coefficients(h, scaling));
    condition_number(lin.kkt())
}

#[test]
fn scaling_keeps_the_condition_number_bounded_as_h_shrinks() {
    let (coarse, fine) = (condition(1e-2, true), condition(1e-6, true));
    assert!(
        fine <= 10.0 * coarse,
        "scaled: cond {coarse:.3e} at h = 1e-2, {fine:.3e} at h = 1e-6"
    );
    // Unscaled it grows like h⁻⁴ (here 16 orders of magnitude between the two).
    let (coarse, fine) = (condition(1e-2, false), condition(1e-6, false));
    assert!(
        fine > 1e10 * coarse,
        "unscaled: cond {coarse:.3e} at h = 1e-2, {fine:.3e} at h = 1e-6"
    );
}
