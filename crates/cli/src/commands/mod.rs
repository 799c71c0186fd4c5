//! One module per command, and what the commands that integrate share:
//! checking and opening the CSV output, the accuracy warning.

pub mod animate;
pub mod chain;
pub mod check;
pub mod convert;
pub mod equilibrium;
pub mod gradient;
pub mod linearize;
pub mod modes;
pub mod options;
pub mod pendulum;
pub mod run;
pub mod sweep;

use std::path::Path;

use anyhow::Result;
use mstar::newmark::Short;
use mstar::{Config, System, csv};

use crate::{limits, output};

/// Refuses an output that would not fit on its file system (`every`: rows
/// every so many steps, `every_time`: rows every Δt seconds).
pub fn check_output(
    out: Option<&Path>,
    fields: usize,
    (t_end, h): (f64, f64),
    (every, every_time): (Option<usize>, Option<f64>),
) -> Result<()> {
    if let Some(dt) = every_time
        && !(dt > 0.0 && dt.is_finite())
    {
        return Err(output::usage(format!(
            "--output-every must be a finite positive number of seconds (got {})",
            Short(dt)
        )));
    }
    let Some(path) = out else {
        return Ok(());
    };
    let rows = match every_time {
        // The grid's rows and the last state.
        Some(dt) => t_end / dt + 2.0,
        None => t_end / h / every.unwrap_or(1) as f64 + 1.0,
    };
    // Also for devices and standard output, which have no free space to
    // tell: rows at a tiny Δt are not bounded by the steps.
    if let Some(dt) = every_time {
        limits::check_rows(rows, t_end, dt)?;
    }
    let o = limits::Output {
        path,
        rows,
        fields,
        t_end,
        every_time,
    };
    limits::check_output(&o, limits::free_space(path))
}

/// Opens the CSV output, if any, and says which leftovers of killed runs it
/// removed.
pub fn open_output<S: System + ?Sized>(
    out: Option<&Path>,
    sys: &S,
    extra: &[String],
    selection: Option<&mstar::columns::Selection>,
) -> Result<Option<csv::CsvStream>> {
    let Some(path) = out else {
        return Ok(None);
    };
    let stream = csv::CsvStream::create_selected(path, sys, extra, selection)?;
    for leftover in stream.removed_leftovers() {
        note!(
            "note: removed {}, left by an earlier run that was killed",
            leftover.display()
        );
    }
    Ok(Some(stream))
}

/// Prints the accuracy warning of a run (`mstar::accuracy::warning`), if
/// any; returns whether it did.
pub fn warn_accuracy<S: System + ?Sized>(
    stats: &mstar::RunStats,
    config: &Config,
    sys: &S,
    files: bool,
) -> bool {
    let warning = mstar::accuracy::warning(stats, config, &|i| sys.coord_name(i), files);
    if let Some(w) = &warning {
        note!("{w}");
    }
    warning.is_some()
}

/// The model file `path` with the overrides `set`, its reader's warnings
/// printed; an unreadable file is printed as an error and exit 2 (as the
/// analysis commands answer it).
pub fn load_model(
    path: &std::path::Path,
    set: &[String],
) -> Result<mstar::file::MechanismFile, std::process::ExitCode> {
    match mstar::file::MechanismFile::load_with(path, set) {
        Ok(file) => {
            for w in &file.warnings {
                note!("warning: {w}");
            }
            Ok(file)
        }
        Err(e) => {
            note!("error: {e}");
            Err(std::process::ExitCode::from(2))
        }
    }
}

/// The integrator configuration and end time of a model file's
/// `[simulation]` (`mstar::run::config`). A setting refused there (a
/// Newmark β below γ/2, an `h_min` above the default `h`, a KKT solver
/// that does not exist) is blamed on the key that gives it, as the
/// reader's errors are: `FILE:LINE:COLUMN: [simulation]: beta: …`, or the
/// `--set` that gave it.
///
/// # Errors
/// [`mstar::file::FileError`] at the key; [`mstar::run::RunError::Settings`]
/// when no key given is to blame (a built-in model's defaults).
pub fn config(sim: &mstar::file::Simulation) -> Result<(Config, f64)> {
    use mstar::run::SettingsError;
    let e = match mstar::run::config(sim) {
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
                mstar::IntegrationError::Config(why) => why.clone(),
                other => other.to_string(),
            };
            sim.error_at(key, why)
        }),
        _ => None,
    };
    // A value a `--set` gave is reported as the library reports it (what
    // Python's `run(**settings)` says too, `python/tests`): the place is
    // for a key written in the file.
    let placed = placed.filter(|p| p.place.is_some());
    Err(match placed {
        Some(placed) => placed.into(),
        None => mstar::run::RunError::Settings(e).into(),
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
fn refused_key(sim: &mstar::file::Simulation) -> Option<&'static str> {
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
        mstar::run::config(&s).is_ok()
    };
    given()
        .find(|k| passes_without(k))
        .or_else(|| given().next())
}
