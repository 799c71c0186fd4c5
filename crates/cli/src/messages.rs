//! Messages shared by the commands: an error on one line, the advice for a
//! library error in the command line's terms.

use mstar::IntegrationError;

/// An error and its causes on one line, `a: b: c` as `{:#}` prints them,
/// but without a cause whose text the line already holds (a library error
/// that quotes its solver's error would otherwise say it twice).
pub fn report(e: &anyhow::Error) -> String {
    mstar::run::error_message(e.as_ref())
}

/// "the sample" or "the n samples".
pub fn samples_phrase(n: usize) -> String {
    if n == 1 {
        "the sample".to_string()
    } else {
        format!("the {n} samples")
    }
}

/// The command-line form of a library error's advice: for `mstar run`
/// (`files`), the model file's keys; for the built-in commands, their options.
pub fn hint(e: &IntegrationError, files: bool) -> Option<&'static str> {
    match (e, files) {
        (IntegrationError::NewtonFailed { .. }, true) => Some(
            "the step size is --h (or [simulation] h), the tolerance --set simulation.tol=…, the scheme --set simulation.integrator=generalized-alpha (with --set simulation.rho=…)",
        ),
        (IntegrationError::NewtonFailed { .. }, false) => Some(
            "generalized-α is --integrator generalized-alpha (--rho sets ρ∞); the step size is --h, the tolerance --tol",
        ),
        (IntegrationError::StepSizeTooSmall { .. }, true) => Some(
            "the step size is --h (or [simulation] h), the smallest step size --set simulation.h_min=…",
        ),
        (IntegrationError::StepSizeTooSmall { .. }, false) => Some(
            "the step size is --h, adaptive steps --adaptive, the smallest step size --h-min, the Newton tolerance --tol, the scheme --integrator",
        ),
        (IntegrationError::ErrorTooLarge { .. }, true) => Some(
            "the step size is --h, the tolerances --rtol and --atol, adaptive steps --adaptive (or [simulation] error_control = \"adaptive\")",
        ),
        (IntegrationError::ErrorTooLarge { .. }, false) => Some(
            "the step size is --h, the tolerances --rtol and --atol, adaptive steps --adaptive, the smallest step size --h-min",
        ),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A library error that quotes its cause is printed once, with the
    /// context before it.
    #[test]
    fn a_quoted_cause_is_not_repeated() {
        let e = IntegrationError::Kkt {
            context: "solving with the iteration matrix",
            t: 1.0,
            h: 0.01,
            unknown: None,
            source: mstar::kkt::KktError::Singular { unknown: Some(3) },
        };
        let full = anyhow::Error::from(e).context("the run");
        assert_eq!(
            format!("{full:#}")
                .matches("no pivot for unknown 3")
                .count(),
            2
        );
        let line = report(&full);
        assert_eq!(line.matches("no pivot for unknown 3").count(), 1, "{line}");
        assert!(
            line.starts_with("the run: solving with the iteration matrix at t = 1"),
            "{line}"
        );
    }
}
