//! `mstar check`: a model file checked without integrating it.

use std::path::PathBuf;
use std::process::ExitCode;

use mstar::file::MechanismFile;

/// Arguments of `mstar check`.
#[derive(clap::Args, Debug)]
pub struct CheckArgs {
    /// The model file.
    model: PathBuf,
    /// Override a key of the file (as for `mstar run`).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
}

/// `mstar check`: exit 0 when the model can run as written, 1 when it
/// cannot (or its redundant constraints could not be computed), 2 when the file cannot be read or holds a value out of range.
pub fn check(args: &CheckArgs) -> ExitCode {
    let file = match MechanismFile::load_with(&args.model, &args.set) {
        Ok(file) => file,
        Err(e) => {
            note!("error: {e}");
            return ExitCode::from(2);
        }
    };
    let config = match super::config(&file.simulation) {
        Ok((config, _)) => config,
        // A setting out of range, as a value the file cannot hold: 2 (at
        // its key, or naming the file when no key is to blame).
        Err(e) if e.downcast_ref::<mstar::file::FileError>().is_some() => {
            note!("error: {e}");
            return ExitCode::from(2);
        }
        Err(e) => {
            note!("error: {}: {e}", args.model.display());
            return ExitCode::from(2);
        }
    };
    let redundant = file.simulation.redundant.unwrap_or_default();
    for w in &file.warnings {
        note!("warning: {w}");
    }
    let sys = mstar::run::lookup(&file.mechanism);
    let report = mstar::run::check(sys, &config, redundant);
    // As `run`'s refusal: the violation first when the pose is far from a
    // joint (the dependence may be the pose's).
    let refusal = (!report.redundant.is_empty() && !report.minimum_norm).then(|| {
        mstar::run::RunError::redundant_at(report.redundant.clone(), sys, &sys.initial_position())
    });
    // As `run`'s refusal of a KKT solver that does not fit the model.
    let config_refusal =
        mstar::placed::kkt_refusal(&report, &file.simulation, &args.model.display().to_string());
    // As `run`: the process ends next.
    std::mem::forget(file);
    print!("{report}");
    if report.can_run() {
        ExitCode::SUCCESS
    } else {
        if let Some(why) = &report.not_computed {
            note!("error: the redundant constraints were not computed: {why}");
        }
        if let Some(e) = refusal {
            note!("error: {}: {e}", args.model.display());
        }
        if let Some(e) = config_refusal {
            note!("error: {e}");
        }
        ExitCode::from(1)
    }
}
