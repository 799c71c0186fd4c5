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
    let free = limits::free_space(path);
    if let Some(dt) = every_time {
        let on_disk = free.map(|f| limits::grid_rows_on_disk(path, fields, f));
        limits::check_rows(rows, (t_end, h), dt, on_disk)?;
    }
    let o = limits::Output {
        path,
        rows,
        fields,
        t_end,
        every_time,
    };
    limits::check_output(&o, free)
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
/// `[simulation]`, a refused setting blamed on the key that gives it
/// ([`mstar::placed::config`]).
///
/// # Errors
/// [`mstar::file::FileError`] at the key; [`mstar::run::RunError::Settings`]
/// when no key given is to blame (a built-in model's defaults).
pub fn config(sim: &mstar::file::Simulation) -> Result<(Config, f64)> {
    mstar::placed::config(sim).map_err(|e| match e {
        mstar::placed::Refusal::Placed(placed) => placed.into(),
        mstar::placed::Refusal::Settings(e) => mstar::run::RunError::Settings(e).into(),
    })
}

/// The integrator's refusal to start `e`, placed at `[simulation] kkt`
/// when the model gives that key (a KKT solver named there that this model
/// does not fit: `ldlt` or `schur` with a damper, `schur` with a singular
/// mass matrix): `FILE:LINE:COLUMN: [simulation]: kkt: …`, or the `--set`
/// that gave it. The error stays an [`mstar::IntegrationError`] (exit 1, a
/// refused run).
pub fn start_error(sim: &mstar::file::Simulation, e: mstar::IntegrationError) -> anyhow::Error {
    let at = match &e {
        mstar::IntegrationError::Config(_) => sim.error_at("kkt", ""),
        _ => None,
    };
    match at {
        Some(at) => {
            let at = at.to_string();
            let at = at.trim_end_matches(": ").to_string();
            anyhow::Error::new(e).context(at)
        }
        None => e.into(),
    }
}
