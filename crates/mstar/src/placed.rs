//! A model file's `[simulation]` settings that the integrator refuses,
//! blamed on the key that gives them, as the reader's errors are (the
//! command line and the Python package share it).

use mstar_file::{FileError, Simulation};
use mstar_newmark::{Config, IntegrationError};

use crate::run::SettingsError;

/// Why [`config`] refuses the settings.
#[derive(Debug, thiserror::Error)]
pub enum Refusal {
    /// At the key that gives the refused value: `FILE:LINE:COLUMN:
    /// [simulation]: beta: …`, or `FILE: --set simulation.beta=0.2:
    /// [simulation]: beta: …` for a value an override gave.
    #[error(transparent)]
    Placed(FileError),
    /// No key given is to blame (a built-in model's defaults).
    #[error(transparent)]
    Settings(SettingsError),
}

/// The integrator configuration and end time of `sim`
/// ([`crate::run::config`]), a refusal (a Newmark β below γ/2, an `h_min`
/// above the default `h`, a KKT solver that does not exist) placed at the
/// key that gives it.
///
/// # Errors
/// [`Refusal::Placed`] at the key; [`Refusal::Settings`] when no key given
/// is to blame.
pub fn config(sim: &Simulation) -> Result<(Config, f64), Refusal> {
    let e = match crate::run::config(sim) {
        Ok(c) => return Ok(c),
        Err(e) => e,
    };
    let placed = match &e {
        SettingsError::UnknownKkt { name, known } => sim.error_at(
            "kkt",
            format!(
                "no KKT solver is called '{name}'; the solvers are: auto, {}",
                known.join(", ")
            ),
        ),
        SettingsError::Refused(refused) => refused_key(sim).and_then(|key| {
            let why = match refused {
                IntegrationError::Config(why) => why.clone(),
                other => other.to_string(),
            };
            sim.error_at(key, why)
        }),
        _ => None,
    };
    Err(match placed {
        Some(placed) => Refusal::Placed(placed),
        None => Refusal::Settings(e),
    })
}

/// A check's refusal of the KKT solver the model does not fit
/// ([`crate::run::CheckReport::start_refuses_config`]) as `mstar run`
/// words it: at `[simulation] kkt` (or the `--set` that gave it), else
/// after `origin` (the file's name); `None` when the start was not refused
/// for its configuration.
#[must_use]
pub fn kkt_refusal(
    report: &crate::run::CheckReport,
    sim: &Simulation,
    origin: &str,
) -> Option<String> {
    let why = report
        .start_error
        .as_deref()
        .filter(|_| report.start_refuses_config)?;
    Some(match sim.error_at("kkt", why) {
        Some(placed) => placed.to_string(),
        None => format!("{origin}: {why}"),
    })
}

/// The keys of `[simulation]` the integrator may refuse after the reader
/// accepted each alone, the scheme's first (`beta` before `gamma`: the
/// condition β ≥ γ/2 is about β).
const REFUSABLE: [&str; 11] = [
    "beta",
    "gamma",
    "alpha",
    "rho",
    "h_min",
    "h_max",
    "h",
    "tol",
    "rtol",
    "atol",
    "max_iterations",
];

/// The key given in `sim` that the integrator refuses: the first whose
/// default makes the settings pass, else the first given.
fn refused_key(sim: &Simulation) -> Option<&'static str> {
    let given = || REFUSABLE.into_iter().filter(|k| sim.is_given(k));
    let passes_without = |key: &str| {
        let mut s = sim.clone();
        match key {
            "beta" => s.beta = None,
            "gamma" => s.gamma = None,
            "alpha" => s.alpha = None,
            "rho" => s.rho = None,
            "h_min" => s.h_min = None,
            "h_max" => s.h_max = None,
            "h" => s.h = None,
            "tol" => s.tol = None,
            "rtol" => s.rtol = None,
            "atol" => s.atol = None,
            _ => s.max_iterations = None,
        }
        crate::run::config(&s).is_ok()
    };
    given()
        .find(|k| passes_without(k))
        .or_else(|| given().next())
}
