//! What a run's local error estimate says about its results: the warning of
//! a fixed-step run whose estimate exceeded the tolerance, with the option
//! that fixes it (`docs/reliability.md`).

use mstar_newmark::{Config, RunStats, Scheme};

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
    let undamped = config
        .scheme
        .params()
        .is_ok_and(|p| (p.gamma - 0.5).abs() < 1e-12);
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
        Some(i) => (
            format!(
                "the estimated local error exceeded the tolerance ({tolerance}) {steps}, in '{}'",
                coord_name(i)
            ),
            if e.max_ratio <= FAR {
                format!(
                    "rerun with --h {} (estimated to bring every step within it) or with --adaptive",
                    short(e.suggested_h())
                )
            } else {
                format!(
                    "rerun with --adaptive, or with --h {} or smaller (an estimate this far beyond the \
                     tolerance is rough: check the rerun's warning again)",
                    short(e.suggested_h())
                )
            },
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
