//! The local error estimate and step control (`docs/theory.md`, "Local error
//! estimate and step control") against the RK4 oracle.

use mstar::{Config, ErrorControl, Integrator, Observer, PendulumChain, Scheme, StepMode, System};
use mstar_rk4::ChainOracle;

const SCHEMES: [Scheme; 4] = [
    Scheme::Newmark {
        beta: 0.25,
        gamma: 0.5,
    },
    Scheme::Hht { alpha: -0.1 },
    Scheme::GeneralizedAlpha { rho_inf: 0.9 },
    Scheme::GeneralizedAlpha { rho_inf: 0.5 },
];

/// One step from the exact state at θ = 1 rad, θ̇ = 0.5 rad/s: the estimate
/// of the angle's error over its true error (RK4 at 1e-5 s).
fn estimate_over_truth(scheme: Scheme, h: f64) -> f64 {
    let sys = PendulumChain::paper(1.0, 1.0, 9.81);
    let (theta0, omega0) = ([1.0], [0.5]);
    let config = Config {
        h,
        scheme,
        tol: 1e-14,
        error: ErrorControl {
            rtol: 1.0,
            atol: 1.0,
            mode: StepMode::Adaptive,
            h_max: None,
        },
        ..Config::default()
    };
    let u0 = sys.position(&theta0);
    let v0 = sys.velocity(&theta0, &omega0);
    let mut integ = Integrator::new(&sys, config, 0.0, &u0, &v0).expect("start");
    integ.step(h).expect("one step");
    let mut oracle = ChainOracle::new(&sys);
    oracle.max_step = 1e-5;
    let exact = oracle.solve(&theta0, &omega0, &[h]);
    let truth = integ.sample().u[2] - exact[0].u[2];
    integ.error_estimate()[2] / truth
}

/// The estimate's relative error is `O(h)` (the next term of the local
/// error's expansion): it must halve with `h` (a ratio of successive
/// deviations from 10 ms to 5 ms between 1.6 and 2.6) and be below 10 % at
/// 5 ms.
#[test]
fn the_estimate_is_asymptotically_the_local_error() {
    for scheme in SCHEMES {
        let ratios: Vec<f64> = [0.02, 0.01, 0.005]
            .iter()
            .map(|&h| estimate_over_truth(scheme, h))
            .collect();
        let dev: Vec<f64> = ratios.iter().map(|r| (r - 1.0).abs()).collect();
        let shrink = dev[1] / dev[2];
        assert!(
            (1.6..=2.6).contains(&shrink),
            "{scheme:?}: estimate/truth = {ratios:?}"
        );
        assert!(dev[2] < 0.1, "{scheme:?}: estimate/truth = {ratios:?}");
    }
}

/// The angle's error at t = 2 s after steps `h_k = H f_k`, against RK4.
fn variable_step_error(scheme: Scheme, big_h: f64, pattern: fn(f64, usize) -> f64) -> f64 {
    let sys = PendulumChain::paper(1.0, 1.0, 9.81);
    let (theta0, omega0) = ([1.0], [0.0]);
    let config = Config {
        h: 2.0 * big_h,
        scheme,
        tol: 1e-11,
        ..Config::default()
    };
    let u0 = sys.position(&theta0);
    let v0 = sys.velocity(&theta0, &omega0);
    let mut integ = Integrator::new(&sys, config, 0.0, &u0, &v0).expect("start");
    let t_end = 2.0;
    let mut k = 0;
    while !integ.reached(t_end) {
        let t = integ.time();
        let h = (big_h * pattern(t, k)).min(t_end - t);
        if let Err(e) = integ.step(t + h) {
            panic!("k = {k}, t = {t}, h = {h}, stats {:?}: {e}", integ.stats());
        }
        k += 1;
    }
    let mut oracle = ChainOracle::new(&sys);
    oracle.max_step = 1e-4;
    let exact = oracle.solve(&theta0, &omega0, &[t_end]);
    (integ.sample().u[2] - exact[0].u[2]).abs()
}

/// Steps that change size every step (a smooth profile, and a jumpy one,
/// `1 + 0.6 sin 7k`) keep order 2 with the dissipative schemes: the
/// acceleration-like variable is rescaled to each step's size (without it
/// the jumpy profile gives orders 1.7-1.8 with HHT and ρ∞ = 0.5, measured).
/// The trapezoidal rule (Newmark γ = ½) is left out: without damping,
/// varying steps excite its period-2 mode of λ on index 3.
#[test]
fn order_two_on_variable_steps() {
    let smooth: fn(f64, usize) -> f64 = |t, _| 1.0 + 0.5 * (2.0 * std::f64::consts::PI * t).sin();
    let jumpy: fn(f64, usize) -> f64 = |_, k| 1.0 + 0.6 * ((7 * k) as f64).sin();
    for &scheme in &SCHEMES[1..] {
        for (name, pattern) in [("smooth", smooth), ("jumpy", jumpy)] {
            let e: Vec<f64> = [0.02, 0.01, 0.005]
                .iter()
                .map(|&h| variable_step_error(scheme, h, pattern))
                .collect();
            let order = (e[1] / e[2]).log2();
            assert!(
                (order - 2.0).abs() < 0.1,
                "{scheme:?}, {name} steps: errors {e:?}, order {order:.3}"
            );
        }
    }
}

/// Run of the pendulum from θ₀ over 5 s: (angle error at the end against
/// RK4, accepted steps, rejected, largest estimate over tolerance).
fn pendulum_run(
    theta: f64,
    h: f64,
    mode: StepMode,
    tol: f64,
    rho: f64,
) -> (f64, usize, usize, f64) {
    let sys = PendulumChain::paper(1.0, 1.0, 9.81);
    let (theta0, omega0) = ([theta], [0.0]);
    let config = Config {
        h,
        tol: 1e-12,
        scheme: Scheme::GeneralizedAlpha { rho_inf: rho },
        error: ErrorControl {
            rtol: tol,
            atol: tol,
            mode,
            h_max: None,
        },
        ..Config::default()
    };
    let u0 = sys.position(&theta0);
    let v0 = sys.velocity(&theta0, &omega0);
    let mut integ = Integrator::new(&sys, config, 0.0, &u0, &v0).expect("start");
    let t_end = 5.0;
    integ
        .run(t_end, &mut |_: &mstar::SampleRef<'_>| {})
        .expect("run");
    let mut oracle = ChainOracle::new(&sys);
    oracle.max_step = 1e-4;
    let exact = oracle.solve(&theta0, &omega0, &[t_end]);
    let st = integ.stats();
    let e = (integ.sample().u[2] - exact[0].u[2]).abs();
    (e, st.steps, st.rejected, st.error.max_ratio)
}

/// Adaptive steps (ρ∞ = 0.5, the recommended damping for adaptive runs):
/// no accepted step beyond the tolerance, the error falls with it, and the
/// steps grow like `tol^(−1/3)` (local error `O(h³)`: 10^(1/3) ≈ 2.15 per
/// decade, accepted between 1.6 and 3).
#[test]
fn adaptive_steps_follow_the_tolerance() {
    let runs: Vec<_> = [1e-5, 1e-6, 1e-7]
        .iter()
        .map(|&tol| pendulum_run(2.0, 1e-3, StepMode::Adaptive, tol, 0.5))
        .collect();
    for w in runs.windows(2) {
        let ((e0, n0, _, r0), (e1, n1, _, r1)) = (w[0], w[1]);
        assert!(e1 < e0, "errors {runs:?}");
        let growth = n1 as f64 / n0 as f64;
        assert!((1.6..=3.0).contains(&growth), "steps {runs:?}");
        assert!(r0 <= 1.0 && r1 <= 1.0, "accepted ratios {runs:?}");
    }
    // At 1e-6 the adaptive run beats fixed steps of the same count (the
    // pendulum from 2 rad slows down at its turning points).
    let (e, n, _, _) = runs[1];
    let (e_fixed, ..) = pendulum_run(2.0, 5.0 / n as f64, StepMode::Monitor, 1e-6, 0.5);
    assert!(
        e < e_fixed,
        "adaptive {e:e} vs fixed {e_fixed:e} with {n} steps"
    );
}

/// A fixed step too large for the tolerance is reported (monitor), refused
/// (strict), and the step size the refusal suggests passes.
#[test]
fn monitor_and_strict_report_a_step_too_large() {
    let (.., small) = pendulum_run(2.0, 0.005, StepMode::Monitor, 1e-3, 0.9);
    assert!(
        small <= 1.0,
        "h = 5 ms is within rtol = atol = 1e-3: {small}"
    );
    let (.., large) = pendulum_run(2.0, 0.1, StepMode::Monitor, 1e-3, 0.9);
    assert!(large > 1.0, "h = 0.1 s is not: {large}");
    let sys = PendulumChain::paper(1.0, 1.0, 9.81);
    let strict = |h: f64, mode: StepMode| {
        let config = Config {
            h,
            scheme: Scheme::GeneralizedAlpha { rho_inf: 0.5 },
            error: ErrorControl {
                rtol: 1e-3,
                atol: 1e-3,
                mode,
                h_max: None,
            },
            ..Config::default()
        };
        let u0 = sys.position(&[2.0]);
        let mut integ = Integrator::new(&sys, config, 0.0, &u0, &[0.0; 3]).expect("start");
        let result = integ.run(5.0, &mut |_: &mstar::SampleRef<'_>| {});
        (result, integ.time())
    };
    let (result, _) = strict(0.1, StepMode::Strict);
    let Err(error @ mstar::IntegrationError::ErrorTooLarge { ratio, .. }) = result else {
        panic!("strict mode must refuse h = 0.1 s");
    };
    // The advice: a smaller h (the error falls like h³); the pendulum
    // conserves energy, so not adaptive steps (their errors add up in it).
    let message = error.to_string();
    assert!(
        message.contains("Reduce h")
            && message.contains("falls like h³")
            && !message.contains("Let the step size adapt"),
        "{message}"
    );
    assert!(ratio > 1.0 && ratio < 64.0, "{message}");
    let (smaller, _) = strict(0.1 / 4.0, StepMode::Strict);
    assert!(smaller.is_ok(), "h/4 divides the error by 64: {smaller:?}");
    let (adaptive, _) = strict(0.1, StepMode::Adaptive);
    assert!(adaptive.is_ok(), "adaptive steps must pass: {adaptive:?}");
}

/// Output at requested times: rows at exactly `0, Δt, 2Δt, …` whatever the
/// steps (here 13.7 ms, adaptive too), as accurate as the steps themselves
/// against RK4 (the interpolation's `O(h⁴)` is below the method's `O(h²)`).
#[test]
fn resampled_output_is_as_accurate_as_the_steps() {
    use mstar::{Resample, Trajectory};
    let sys = PendulumChain::paper(1.0, 1.0, 9.81);
    let theta0 = [2.0];
    let u0 = sys.position(&theta0);
    let mut oracle = ChainOracle::new(&sys);
    oracle.max_step = 1e-4;
    let worst = |samples: &[mstar::Sample]| {
        let times: Vec<f64> = samples.iter().map(|s| s.t).collect();
        let exact = oracle.solve(&theta0, &[0.0], &times);
        samples
            .iter()
            .zip(&exact)
            .map(|(s, e)| (s.u[2] - e.u[2]).abs().max((s.v[2] - e.v[2]).abs()))
            .fold(0.0, f64::max)
    };
    for mode in [StepMode::Monitor, StepMode::Adaptive] {
        let config = Config {
            h: 0.0137,
            scheme: Scheme::GeneralizedAlpha { rho_inf: 0.5 },
            error: ErrorControl {
                mode,
                rtol: 1e-6,
                atol: 1e-6,
                h_max: None,
            },
            ..Config::default()
        };
        let mut integ = Integrator::new(&sys, config, 0.0, &u0, &[0.0; 3]).expect("start");
        let mut steps = Trajectory::default();
        let mut grid = Resample::new(0.1, Trajectory::default());
        integ
            .run(2.05, &mut |s: &mstar::SampleRef<'_>| {
                steps.observe(s);
                grid.observe(s);
            })
            .expect("run");
        let grid = grid.finish().samples;
        // 0, 0.1, …, 2.0 and the end, 2.05.
        assert_eq!(grid.len(), 22, "{mode:?}");
        for (k, s) in grid.iter().take(21).enumerate() {
            assert!(
                (s.t - 0.1 * k as f64).abs() < 1e-12,
                "{mode:?}: row {k} at {}",
                s.t
            );
        }
        assert!((grid[21].t - 2.05).abs() < 1e-12);
        let (at_grid, at_steps) = (worst(&grid), worst(&steps.samples));
        assert!(
            at_grid <= 1.1 * at_steps,
            "{mode:?}: error {at_grid:e} on the grid, {at_steps:e} at the steps"
        );
    }
}

/// Adaptive steps stay within `[h_min, h_max]` (the last one, shortened to
/// land on `t_end`, excepted), and a step that needs less than `h_min` is
/// an error that says so.
#[test]
fn adaptive_steps_respect_h_min_and_h_max() {
    let sys = PendulumChain::paper(1.0, 1.0, 9.81);
    let u0 = sys.position(&[2.0]);
    let run = |h_min: f64, h_max: f64| {
        let config = Config {
            h: 0.05,
            h_min: Some(h_min),
            error: ErrorControl {
                mode: StepMode::Adaptive,
                h_max: Some(h_max),
                ..ErrorControl::default()
            },
            ..Config::default()
        };
        let mut integ = Integrator::new(&sys, config, 0.0, &u0, &[0.0; 3]).expect("start");
        let mut times = vec![0.0];
        let result = integ.run(3.0, &mut |s: &mstar::SampleRef<'_>| times.push(s.t));
        let steps: Vec<f64> = times[1..].windows(2).map(|w| w[1] - w[0]).collect();
        (result, steps)
    };
    let (result, steps) = run(1e-3, 0.06);
    assert!(result.is_ok(), "{result:?}");
    let inner = &steps[..steps.len() - 1];
    assert!(
        inner
            .iter()
            .all(|&h| (1e-3 - 1e-12..=0.06 + 1e-12).contains(&h)),
        "{steps:?}"
    );
    let (result, steps) = run(0.04, 0.06);
    assert!(steps.iter().all(|&h| h >= 0.04 - 1e-12), "{steps:?}");
    let Err(e) = result else {
        panic!("h_min = 0.04 is too large for rtol = 1e-3 here");
    };
    assert!(e.to_string().contains("below h_min"), "{e}");
}

/// The energy warning of the paper's preset (Newmark β = 1/4, γ = 1/2) and
/// whether the rerun it advises warns again: the warning over 5 s (before
/// the undamped mode stops Newton at 5.9 s).
fn paper_energy_warning(scheme: Option<Scheme>) -> Option<String> {
    let mut run = mstar::pendulum::PendulumRun::paper();
    run.t_end = 5.0;
    if let Some(scheme) = scheme {
        run.config.scheme = scheme;
    }
    let (_, stats) = run.run();
    let stats = stats.expect("the run reaches 5 s");
    let sys = run.system();
    mstar::accuracy::warning(&stats, &run.config, &|i| sys.coord_name(i), false)
}

#[test]
fn an_undamped_scheme_s_energy_drift_advises_a_damped_scheme_that_passes() {
    // The trapezoidal rule's period-2h mode carries the energy away; a
    // smaller h makes it grow sooner, so the advice is the damped scheme
    // (`mstar pendulum --preset paper --integrator generalized-alpha`).
    let warned = paper_energy_warning(None).expect("the undamped run drifts");
    let energy = warned
        .lines()
        .find(|l| l.contains("the energy of this model"))
        .expect("an energy warning");
    assert!(
        energy.contains("--integrator generalized-alpha"),
        "{energy}"
    );
    assert!(!energy.contains("--h "), "no smaller h: {energy}");
    let advised = paper_energy_warning(Some(Scheme::GeneralizedAlpha { rho_inf: 0.9 }));
    assert_eq!(advised, None, "the damped scheme passes");
}
