//! What a run's local error estimate says about its results: the warning of
//! a fixed-step run whose estimate exceeded the tolerance, with the option
//! that fixes it (`docs/reliability.md`).

use mstar_newmark::{Config, RunStats, Scheme, StepMode};

/// The exit code of a run that reached its end with steps whose estimated
/// error exceeded the tolerance: its output is complete, and not accurate
/// to the tolerance (0 means both).
pub const EXIT_INACCURATE: u8 = 3;

/// A run that reached its end with steps beyond the error tolerance (the
/// warning says where): exit code [`EXIT_INACCURATE`].
#[derive(Debug, thiserror::Error)]
#[error("the run reached its end, but its estimated error exceeded the tolerance")]
pub struct Inaccurate;

/// `Err(Inaccurate)` when a warning was given.
///
/// # Errors
/// [`Inaccurate`] when `warned`.
pub fn verdict(warned: bool) -> Result<(), Inaccurate> {
    if warned { Err(Inaccurate) } else { Ok(()) }
}

/// The warning for `stats` of a run with `config` (`None` when every step
/// was within tolerance). `coord_name` names a coordinate. The advice names
/// the options that `mstar pendulum`, `mstar chain` and `mstar run` share
/// (`--h`, `--adaptive`, `--tol`, `--strict`), and the scheme's in the form
/// of `mstar run` when `files` (`--set simulation.…`).
#[must_use]
pub fn warning(
    stats: &RunStats,
    config: &Config,
    coord_name: &dyn Fn(usize) -> String,
    files: bool,
) -> Option<String> {
    let local = local_warning(stats, config, coord_name, files);
    let energy = energy_warning(stats, config, files);
    match (local, energy) {
        (Some(l), Some(e)) => Some(format!("{l}\n{e}")),
        (l, e) => l.or(e),
    }
}

/// The warning of the energy drift of a model that conserves energy
/// ([`mstar_newmark::EnergyReport`]), with a step size that brings it within
/// the tolerance ([`advised_h`]; adaptive runs get it as their largest step,
/// `--h-max`).
fn energy_warning(stats: &RunStats, config: &Config, files: bool) -> Option<String> {
    let e = &stats.energy;
    let rtol = config.error.rtol;
    if !e.exceeded(rtol) {
        return None;
    }
    let h = advised_h(stats, config);
    let adaptive = config.error.mode == StepMode::Adaptive;
    let advice = match (adaptive, files) {
        // An undamped scheme's growing period-2h mode is what drifts, and a
        // smaller h makes it grow sooner (as the local warning says).
        _ if undamped(config) => format!(
            "the scheme is undamped (γ = 1/2): on an index-3 system its period-2h oscillation \
             of ü and λ grows and carries the energy away, and a smaller h makes it grow sooner; \
             rerun with {}",
            damped_scheme(config, files)
        ),
        // The iterations left the constraints too loose: no step size
        // mends that (the local warning names the Newton tolerance too).
        _ if stats.error.newton_exceeded > 0 => format!(
            "the Newton tolerance --tol {} is too loose for it: rerun with --tol {}",
            short(config.tol),
            short(newton_tolerance(config))
        ),
        (false, _) => format!("rerun with --h {}", short(h)),
        (true, false) => format!("rerun with --h {0} --h-max {0}", short(h)),
        (true, true) => format!("rerun with --h {0} --set simulation.h_max={0}", short(h)),
    };
    let why = if stats.error.newton_exceeded > 0 && !undamped(config) {
        "the iterations stopped with the constraints violated beyond the tolerance"
    } else if adaptive {
        "adaptive steps keep each step's local error within the tolerance, not the run's, and \
         their errors added up to this loss"
    } else {
        "each step's error, however small, adds up over the run"
    };
    Some(format!(
        "warning: the energy of this model, which conserves energy, drifted by {} J by t = {} s, \
         {} times the tolerance 2 rtol · (largest kinetic energy {} J): {why}; the results are not \
         accurate to that tolerance; {advice}",
        short(e.drift),
        short(e.t_drift),
        short(e.drift / e.limit(rtol)),
        short(e.kinetic_max),
    ))
}

/// The warning of the local error estimate (`None` when every step was
/// within the tolerance).
fn local_warning(
    stats: &RunStats,
    config: &Config,
    coord_name: &dyn Fn(usize) -> String,
    files: bool,
) -> Option<String> {
    let e = &stats.error;
    if !e.exceeded_tolerance() {
        return None;
    }
    let tolerance = format!(
        "rtol = {:e}, atol = {:e}",
        config.error.rtol, config.error.atol
    );
    let steps = format!(
        "on {} of {} steps, from t = {} s on, up to {:.3} times at t = {} s",
        e.exceeded,
        stats.steps,
        short(e.first_exceeded.unwrap_or(e.t_max)),
        e.max_ratio,
        short(e.t_max)
    );
    let newton_first = e.newton_exceeded > 0;
    let undamped = undamped(config);
    let (what, advice) = match e.coordinate.filter(|_| !newton_first) {
        Some(i) if undamped => (
            format!(
                "the estimated local error exceeded the tolerance ({tolerance}) {steps}, in '{}'",
                coord_name(i)
            ),
            format!(
                "the scheme is undamped (γ = 1/2): on an index-3 system its period-2h oscillation \
                 of ü and λ grows, which the estimate sees, and a smaller h makes it grow sooner; \
                 rerun with {}",
                damped_scheme(config, files)
            ),
        ),
        Some(i) if zero_allowance(stats, config) => (
            format!(
                "the estimated local error exceeded the tolerance ({tolerance}) {steps}, in '{}'",
                coord_name(i)
            ),
            format!(
                "with atol = 0 a coordinate is allowed rtol times its own value, nothing where it \
                 is 0, and '{}' is or passes through 0: no step size gets there; give an \
                 absolute tolerance (--atol {:e}, the default, in m or rad)",
                coord_name(i),
                mstar_newmark::ErrorControl::default().atol
            ),
        ),
        Some(i) => (
            format!(
                "the estimated local error exceeded the tolerance ({tolerance}) {steps}, in '{}'",
                coord_name(i)
            ),
            step_advice(stats, config),
        ),
        None => (
            format!(
                "the converged constraint violation exceeded the error tolerance ({tolerance}) on {} of {} steps, up to {:.3} times",
                e.newton_exceeded, stats.steps, e.newton_max_ratio
            ),
            format!(
                "the Newton tolerance --tol {} is too loose for it: rerun with --tol {}",
                short(config.tol),
                short(newton_tolerance(config))
            ),
        ),
    };
    Some(format!(
        "warning: {what}: the results are not accurate to that tolerance; {advice} (--strict stops at the first such step)"
    ))
}

/// Whether the scheme is undamped (`γ = 1/2`: the trapezoidal rule, HHT
/// `α = 0`, generalized-α `ρ∞ = 1`).
fn undamped(config: &Config) -> bool {
    config
        .scheme
        .params()
        .is_ok_and(|p| (p.gamma - 0.5).abs() < 1e-12)
}

/// Whether the estimate exceeded a tolerance without an absolute part
/// (`atol = 0`) by more than a step size can mend: a coordinate at 0 is
/// allowed no error at all, and its round-off alone exceeds that (the
/// slider of `models/slider-crank.toml`, held at `y = 0`: an infinite ratio).
fn zero_allowance(stats: &RunStats, config: &Config) -> bool {
    let ratio = stats.error.max_ratio;
    config.error.atol == 0.0 && (ratio.is_nan() || ratio > FAR)
}

/// The advice of a step size beyond the tolerance: the `h` that brings every
/// step within it and, for a model that does not conserve energy, adaptive
/// steps. A conservative model is not advised adaptive steps: their errors
/// add up over the run and show in its energy drift (`energy_warning`),
/// measured larger than at fixed steps of the same count
/// (`docs/reliability.md`).
fn step_advice(stats: &RunStats, config: &Config) -> String {
    let e = &stats.error;
    let adaptive = !stats.energy.tracked;
    let h = short(advised_h(stats, config));
    match (e.max_ratio <= FAR, adaptive) {
        (true, true) => format!(
            "rerun with --h {h} (estimated to bring every step within it) or with --adaptive"
        ),
        (true, false) => format!("rerun with --h {h} (estimated to bring every step within it)"),
        (false, _) => format!(
            "rerun with {}--h {h} or smaller (an estimate this far beyond the tolerance is rough: \
             check the rerun's warning again)",
            if adaptive { "--adaptive, or with " } else { "" },
        ),
    }
}

/// The step size both warnings advise: the smaller of the one that brings
/// every step's local error within the tolerance (`O(h³)`,
/// [`mstar_newmark::ErrorReport::suggested_h`]) and the one that brings the
/// energy drift within it (second order: the drift falls like `h²`, so
/// `h_max · (limit / 4 drift)^(1/2)`, a quarter of the limit for margin; a
/// sixteenth for adaptive steps).
fn advised_h(stats: &RunStats, config: &Config) -> f64 {
    let (e, rtol) = (&stats.energy, config.error.rtol);
    let local = if stats.error.exceeded_tolerance() {
        stats.error.suggested_h()
    } else {
        f64::INFINITY
    };
    let energy = if e.exceeded(rtol) {
        // Adaptive steps capped at `h_max` take it more often than the
        // run's mix of steps took its largest: a sixteenth of the limit
        // (the double pendulum at `--h 0.02 --adaptive` drifted 1.03 times
        // the limit at the quarter's `h`).
        let margin = if config.error.mode == StepMode::Adaptive {
            1.0 / 16.0
        } else {
            0.25
        };
        let h = stats.h_max_used * (margin * e.limit(rtol) / e.drift).sqrt();
        if h.is_finite() {
            h
        } else {
            stats.h_min_used / 8.0
        }
    } else {
        f64::INFINITY
    };
    local.min(energy)
}

/// Beyond this ratio the estimate's `O(h³)` scaling is rough (the step is
/// far outside the asymptotic range) and the suggested `h` may need a
/// second look; within it one rerun at the suggested `h` passes
/// (`tests/cli_accuracy.rs`).
const FAR: f64 = 100.0;

/// The option that damps an undamped scheme: ρ∞ < 1 for generalized-α,
/// α < 0 for HHT, generalized-α instead of the trapezoidal rule.
fn damped_scheme(config: &Config, files: bool) -> &'static str {
    match (config.scheme, files) {
        (Scheme::GeneralizedAlpha { .. }, false) => "--rho 0.9",
        (Scheme::GeneralizedAlpha { .. }, true) => "--set simulation.rho=0.9",
        (Scheme::Hht { .. }, false) => "--alpha -0.1",
        (Scheme::Hht { .. }, true) => "--set simulation.alpha=-0.1",
        (Scheme::Newmark { .. }, false) => "--integrator generalized-alpha",
        (Scheme::Newmark { .. }, true) => "--set simulation.integrator=generalized-alpha",
    }
}

/// A Newton tolerance that keeps the converged `‖Φ‖∞ ≤ tol·max(1, ‖u‖∞)`
/// a hundred times below the error tolerance.
#[must_use]
pub fn newton_tolerance(config: &Config) -> f64 {
    let floor = [config.error.rtol, config.error.atol]
        .into_iter()
        .filter(|&x| x > 0.0)
        .fold(f64::INFINITY, f64::min);
    0.01 * floor
}

/// A number with at most four significant digits, for messages.
#[must_use]
pub fn short(x: f64) -> String {
    let s = format!("{x:.4}");
    if x != 0.0 && (x.abs() < 1e-3 || x.abs() >= 1e6) {
        format!("{x:.3e}")
    } else {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    }
}
