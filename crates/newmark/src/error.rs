//! Errors of the integrators, each saying where and what to try.

use mstar_kkt::KktError;
use mstar_linearize::LinearizeError;

/// Why an integration could not go on.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum IntegrationError {
    /// An option is out of range.
    #[error("invalid configuration: {0}")]
    Config(String),
    /// The system's declared structure is inconsistent.
    #[error("invalid system structure: {0}")]
    Structure(#[from] LinearizeError),
    /// The state vectors have the wrong length.
    #[error("{what} has {got} entries, the system has {want}")]
    Dimension {
        /// Which vector.
        what: &'static str,
        /// Given length.
        got: usize,
        /// Expected length.
        want: usize,
    },
    /// The initial state violates a constraint and projection is disabled.
    #[error(
        "inconsistent initial state at t = {}: {level} constraint '{constraint}' is violated by {value:.3e}; \
         enable projection (the default) or give a state that satisfies Φ = 0 and B u̇ + Φ_t = 0", Short(*.t))]
    InconsistentInitialState {
        /// Time.
        t: f64,
        /// `"position"` or `"velocity"`.
        level: &'static str,
        /// The most violated constraint.
        constraint: String,
        /// Its violation.
        value: f64,
    },
    /// Projection of the initial positions onto `Φ = 0` did not converge.
    #[error(
        "at start-up (t = {}): the initial state violates constraint '{initial}' by {initial_value:.3e}, and \
         projecting it onto the constraints did not converge (‖Φ‖∞ = {residual:.3e} after {iterations} Newton \
         iterations, most violated: '{constraint}'); start from positions that satisfy '{initial}' \
         (or check how that constraint is defined)",
        Short(*.t)
    )]
    ProjectionFailed {
        /// Time.
        t: f64,
        /// Iterations spent.
        iterations: usize,
        /// Final `‖Φ‖∞`.
        residual: f64,
        /// The most violated constraint after the last iteration.
        constraint: String,
        /// The constraint the given state violated most, before projection.
        initial: String,
        /// Its violation.
        initial_value: f64,
    },
    /// A linear solve of the start-up failed: projecting the initial state,
    /// or solving for the initial accelerations and multipliers.
    #[error("{}", start_failed(*.t, context, unknown, violated, cause))]
    StartFailed {
        /// Time.
        t: f64,
        /// Which solve.
        context: &'static str,
        /// The named unknown without a pivot, when known.
        unknown: Option<String>,
        /// The constraint the given state violated most and by how much,
        /// when projection moved it: the likely fault rather than the
        /// unknown without a pivot, which is where the projected state ended.
        violated: Option<(String, f64)>,
        /// The solver's error (part of this message, not a separate cause).
        cause: KktError,
    },
    /// The KKT matrix could not be factored or solved.
    #[error("{context} at t = {} s (h = {h:e}): {source}{}", Short(*.t), describe_unknown(.unknown))]
    Kkt {
        /// Which solve.
        context: &'static str,
        /// Time.
        t: f64,
        /// Step size.
        h: f64,
        /// The named unknown without a pivot, when known.
        unknown: Option<String>,
        /// The solver's error.
        source: KktError,
    },
    /// The Newton iteration did not converge (and step control could not help).
    #[error(
        "Newton iteration did not converge at t = {} s (h = {h:e}): after {iterations} iterations \
         ‖r‖∞ = {residual:.3e} (tolerance {residual_tol:.3e}) and ‖Φ‖∞ = {constraint:.3e} (tolerance {constraint_tol:.3e}). \
         {advice}", Short(*.t))]
    NewtonFailed {
        /// Time of the failed step's end.
        t: f64,
        /// Step size.
        h: f64,
        /// Iterations spent.
        iterations: usize,
        /// Final `‖r‖∞`.
        residual: f64,
        /// Tolerance on `‖r‖∞`.
        residual_tol: f64,
        /// Final `‖Φ‖∞`.
        constraint: f64,
        /// Tolerance on `‖Φ‖∞`.
        constraint_tol: f64,
        /// What to try, from what the run knows (the scheme, the
        /// tolerance, the error estimate so far).
        advice: String,
    },
    /// Step control reached the smallest allowed step.
    #[error(
        "step size too small at t = {} s: the step with h = {h:e} failed and h/2 would be below h_min = {h_min:e} \
         (‖r‖∞ = {residual:.3e}, ‖Φ‖∞ = {constraint:.3e}). {advice}", Short(*.t))]
    StepSizeTooSmall {
        /// Time at the start of the failed step.
        t: f64,
        /// The last step size tried.
        h: f64,
        /// The smallest allowed step size.
        h_min: f64,
        /// Final `‖r‖∞` of the last attempt.
        residual: f64,
        /// Final `‖Φ‖∞` of the last attempt.
        constraint: f64,
        /// What to try, from what the run knows.
        advice: String,
    },
    /// The local error estimate exceeded the tolerance: a step in strict
    /// mode, or adaptive stepping at its smallest step size.
    #[error(
        "the estimated local error exceeds the tolerance at t = {} s (h = {h:e}): {ratio:.3} times \
         atol + rtol·|u| (rtol = {rtol:e}, atol = {atol:e}) at coordinate '{coordinate}'. {advice}", Short(*.t))]
    ErrorTooLarge {
        /// The end of the step.
        t: f64,
        /// Its size.
        h: f64,
        /// The estimate over the tolerance.
        ratio: f64,
        /// The coordinate where it is largest.
        coordinate: String,
        /// The relative tolerance.
        rtol: f64,
        /// The absolute tolerance.
        atol: f64,
        /// What to try.
        advice: String,
    },
    /// A time given to [`Integrator::new`](crate::Integrator::new),
    /// [`run`](crate::Integrator::run) or [`step`](crate::Integrator::step)
    /// cannot be integrated from or to: not finite, or (for `step`) not after
    /// the current time.
    #[error("{what} = {} cannot be used: {why}", Short(*.value))]
    Time {
        /// Which argument: `"t0"` or `"t_end"`.
        what: &'static str,
        /// Its value.
        value: f64,
        /// Why, with the current time where it matters.
        why: String,
    },
    /// NaN or infinity appeared in the state.
    #[error(
        "NaN or infinity in {what} at t = {} s; the step size may be too large for the model's stiffness", Short(*.t))]
    NonFinite {
        /// Time.
        t: f64,
        /// Where (e.g. "the forces g, coordinate 'theta'").
        what: String,
    },
}

/// A number for a message: at most 6 significant digits, in exponent form
/// outside `[1e-4, 1e6)`, so that no value prints as the hundreds of digits
/// that `{}` gives `1e308` (`Short(0.1 + 0.2)` is `0.3`, `Short(1e308)` is
/// `1e308`).
///
/// ```
/// use mstar_newmark::Short;
/// assert_eq!(Short(0.1 + 0.2).to_string(), "0.3");
/// assert_eq!(Short(1e308).to_string(), "1e308");
/// assert_eq!(Short(-2.5e-7).to_string(), "-2.5e-7");
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Short(pub f64);

impl std::fmt::Display for Short {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let x = self.0;
        if x == 0.0 {
            return f.write_str("0");
        }
        if !x.is_finite() {
            return write!(f, "{x}");
        }
        // Rounded to 6 significant digits, then printed as the shortest
        // decimal that reads back as that value.
        let rounded: f64 = format!("{x:.5e}").parse().unwrap_or(x);
        if (1e-4..1e6).contains(&rounded.abs()) {
            write!(f, "{rounded}")
        } else {
            write!(f, "{rounded:e}")
        }
    }
}

/// The message of [`IntegrationError::StartFailed`].
fn start_failed(
    t: f64,
    context: &str,
    unknown: &Option<String>,
    violated: &Option<(String, f64)>,
    cause: &KktError,
) -> String {
    let unknown = describe_unknown(unknown);
    match violated {
        Some((constraint, value)) => format!(
            "at start-up (t = {}): the initial state violates constraint '{constraint}' by {value:.3e}, and \
             {context} failed: {cause}{unknown}. Projection moved the state to where the system is singular: \
             start from positions that satisfy '{constraint}' (or check how that constraint is defined)",
            Short(t)
        ),
        None => format!(
            "at start-up (t = {}), {context}: {cause}{unknown}",
            Short(t)
        ),
    }
}

fn describe_unknown(unknown: &Option<String>) -> String {
    match unknown {
        Some(u) => format!(
            "; {u} is undetermined (a redundant or inconsistent constraint, or a coordinate that neither inertia, stiffness nor a constraint determines)"
        ),
        None => String::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One of every variant, with sample values.
    fn every_error() -> Vec<IntegrationError> {
        vec![
            IntegrationError::Config("h must be positive".into()),
            IntegrationError::Structure(LinearizeError::TooLarge { nnz: 7 }),
            IntegrationError::Dimension {
                what: "u0",
                got: 2,
                want: 3,
            },
            IntegrationError::InconsistentInitialState {
                t: 0.0,
                level: "position",
                constraint: "pin.x".into(),
                value: 0.2,
            },
            IntegrationError::ProjectionFailed {
                t: 0.0,
                iterations: 50,
                residual: 1.0,
                constraint: "pin.x".into(),
                initial: "crank-pin.y".into(),
                initial_value: 0.2,
            },
            IntegrationError::StartFailed {
                t: 0.0,
                context: "solving for consistent initial accelerations",
                unknown: Some("the multiplier of constraint 'motor'".into()),
                violated: Some(("crank-pin.y".into(), 0.2)),
                cause: KktError::Singular { unknown: Some(7) },
            },
            IntegrationError::StartFailed {
                t: 0.0,
                context: "solving for consistent initial accelerations",
                unknown: None,
                violated: None,
                cause: KktError::Singular { unknown: None },
            },
            IntegrationError::Kkt {
                context: "solving with the iteration matrix",
                t: 1.0,
                h: 0.01,
                unknown: Some("coordinate 'x'".into()),
                source: KktError::Singular { unknown: Some(0) },
            },
            IntegrationError::NewtonFailed {
                t: 1.0,
                h: 0.01,
                iterations: 20,
                residual: 1.0,
                residual_tol: 1e-10,
                constraint: 1.0,
                constraint_tol: 1e-10,
                advice: "Try a smaller step size h".into(),
            },
            IntegrationError::StepSizeTooSmall {
                t: 1.0,
                h: 1e-5,
                h_min: 1e-5,
                residual: 1.0,
                constraint: 1.0,
                advice: "Try a smaller step size h".into(),
            },
            IntegrationError::NonFinite {
                t: 1.0,
                what: "the forces g".into(),
            },
            IntegrationError::Time {
                what: "t_end",
                value: f64::NAN,
                why: "the end time must be finite".into(),
            },
        ]
    }

    /// The library's messages speak of its own options (Scheme, h), not of
    /// the command line's flags, which a library user does not have; and
    /// they read as single lines of prose.
    #[test]
    fn library_errors_name_no_command_line_flag() {
        for e in every_error() {
            let text = e.to_string();
            assert!(!text.contains("--"), "{text}");
            assert!(!text.contains("  "), "a run of spaces: {text}");
        }
    }

    /// Start-up errors say "at start-up", give no step size, and lead with
    /// the constraint the given state violated, not the unknown without a
    /// pivot; their solver error is part of the message, not a repeated
    /// cause.
    #[test]
    fn start_up_errors_name_the_violated_constraint_once() {
        use std::error::Error as _;
        let e = IntegrationError::StartFailed {
            t: 0.0,
            context: "solving for consistent initial accelerations",
            unknown: Some("the multiplier of constraint 'motor'".into()),
            violated: Some(("crank-pin.y".into(), 0.2)),
            cause: KktError::Singular { unknown: Some(7) },
        };
        let text = e.to_string();
        assert!(text.starts_with("at start-up (t = 0): the initial state violates constraint 'crank-pin.y' by 2.000e-1"), "{text}");
        assert!(text.contains("satisfy 'crank-pin.y'"), "{text}");
        assert!(!text.contains("h ="), "{text}");
        assert!(e.source().is_none(), "the cause is not printed twice");
        assert_eq!(text.matches("singular (no pivot").count(), 1, "{text}");
    }
}
