//! `mstar equilibrium`: the static equilibrium of a model file
//! (`mstar::equilibrium`), reported, written as one CSV row and as a model
//! file that starts there.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result, bail};
use mstar::columns::{Columns, OutputColumns};
use mstar::equilibrium::{Equilibrium, EquilibriumOptions};
use mstar::run::ModelLookup;

/// Arguments of `mstar equilibrium`.
#[derive(clap::Args, Debug)]
pub struct EquilibriumArgs {
    /// The model file (TOML, JSON or URDF); the search starts from its
    /// initial pose.
    model: PathBuf,
    /// Write the equilibrium as one CSV row with the columns of `mstar run
    /// --out` (coordinates, multipliers, reactions, efforts, sensors).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Write the model file (TOML only) with the equilibrium as its initial
    /// pose, everything else kept.
    #[arg(long, value_name = "EQ.toml", conflicts_with = "set")]
    write_model: Option<PathBuf>,
    /// Override a key of the file (as for `mstar run`).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
}

impl EquilibriumArgs {
    /// `--out`, for the report to move to standard error when it is `-`.
    pub fn out(&self) -> Option<&Path> {
        self.out.as_deref()
    }
}

/// `mstar equilibrium`: exit 0 when an equilibrium is found (and written),
/// 1 when none is found, it is neutral, or an output cannot be written, 2
/// when the model file cannot be read.
pub fn equilibrium(args: &EquilibriumArgs) -> ExitCode {
    let outputs: Vec<(&str, &Path)> = [("--out", &args.out), ("--write-model", &args.write_model)]
        .into_iter()
        .filter_map(|(option, path)| Some((option, path.as_deref()?)))
        .filter(|(_, path)| path.as_os_str() != "-")
        .collect();
    if let Err(e) = crate::output::refuse_overwriting_model(&args.model, &[], &outputs) {
        note!("error: {e}");
        return ExitCode::from(2);
    }
    // (`--out` is checked as its stream opens; exit 1, a failure to write.)
    if let Err(e) = crate::output::refuse_read_only(&outputs) {
        note!("error: {e}");
        return ExitCode::from(1);
    }
    let file = match super::load_model(&args.model, &args.set) {
        Ok(file) => file,
        Err(code) => return code,
    };
    let sys = mstar::run::lookup(&file.mechanism);
    let u0 = sys.initial_position();
    let eq = match mstar::equilibrium::solve(sys, &u0, &EquilibriumOptions::default()) {
        Ok(eq) => eq,
        Err(e) => {
            note!("error: {}: {e}", args.model.display());
            return ExitCode::from(1);
        }
    };
    report(sys, &eq);
    if let mstar::equilibrium::Stability::Unstable {
        direction, rate, ..
    } = &eq.stability
    {
        note!("{}", unstable_note(direction, *rate));
    }
    if !eq.left_out.is_empty() {
        let rows: Vec<String> = eq
            .left_out
            .iter()
            .map(|&k| sys.constraint_name(k))
            .collect();
        note!(
            "note: the constraint rows {} repeat what the others impose (redundant): the equilibrium was solved without them, and the multipliers of all rows are the minimum-norm ones that give the same constraint forces",
            rows.join(", ")
        );
    }
    let written = write_csv(args.out.as_deref(), sys, &file.output, &eq)
        .and_then(|()| write_model(args, sys, &eq));
    match written {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            note!("error: {e:#}");
            ExitCode::from(1)
        }
    }
}

/// How many coordinates the report lists before "…".
const LISTED: usize = 20;

/// Prints the iterations, the final norms and the coordinates.
fn report(sys: &dyn ModelLookup, eq: &Equilibrium) {
    say!(
        "equilibrium found: {} Newton steps ({} damped), ‖r‖∞ = {:.3e}, ‖Φ‖∞ = {:.3e}",
        eq.iterations,
        eq.damped,
        eq.residual,
        eq.constraint
    );
    for (i, u) in eq.u.iter().enumerate().take(LISTED) {
        say!(
            "  {} = {}",
            sys.coord_name(i),
            mstar::csv::format_number(*u)
        );
    }
    if eq.u.len() > LISTED {
        say!("  … ({} coordinates in all)", eq.u.len());
    }
}

/// The warning for an unstable equilibrium: the direction it runs away
/// along, and its rate.
fn unstable_note(direction: &[(String, f64)], rate: f64) -> String {
    let along: Vec<String> = direction
        .iter()
        .map(|(name, x)| format!("{name} ({x:.3})"))
        .collect();
    format!(
        "warning: this equilibrium is unstable: a small displacement along {} grows as e^(st), s = {rate:.4e} 1/s (a maximum or saddle of the potential, as an inverted pendulum), and the search from beside it, lowering the potential energy, reached no stable equilibrium (the model's potential energy does not hold every force, or it has none)",
        along.join(", ")
    )
}

/// The one CSV row of the equilibrium: the state at rest at t = 0, the
/// columns `[output] columns` chooses.
fn write_csv(
    out: Option<&Path>,
    sys: &dyn ModelLookup,
    output: &mstar::file::Output,
    eq: &Equilibrium,
) -> Result<()> {
    let Some(path) = out else {
        return Ok(());
    };
    let columns = OutputColumns::new(sys, &output.sensors)?;
    let extra = columns.names();
    // `[output] columns` chooses as for `mstar run`.
    let selection = match &output.columns {
        Some(patterns) => {
            let mut names = mstar::csv::header(sys);
            names.extend_from_slice(&extra);
            let chosen =
                mstar::columns::Selection::new(&names, patterns).map_err(|e| {
                    match output.columns_error(&e) {
                        Some(at) => anyhow::Error::new(at),
                        None => crate::output::usage(format!("[output] columns: {e}")),
                    }
                })?;
            Some(chosen)
        }
        None => None,
    };
    let Some(mut stream) = super::open_output(Some(path), sys, &extra, selection.as_ref())? else {
        return Ok(());
    };
    let zeros = vec![0.0; eq.u.len()];
    let sample = eq.at_rest(0.0, &zeros, sys.potential_energy(0.0, &eq.u));
    let mut values = Vec::with_capacity(extra.len());
    columns.values(&sample, &mut values);
    stream.push_with(&sample, &values);
    if !stream.write_pending() {
        bail!("{}: cannot write the row", path.display());
    }
    stream
        .finish()
        .with_context(|| format!("cannot write {}", path.display()))?;
    say!("wrote {} (1 row)", path.display());
    Ok(())
}

/// `--write-model`: the file's text with the equilibrium as its initial
/// pose, checked to be the same mechanism once read back
/// ([`mstar::equilibrium::model_text`]).
fn write_model(args: &EquilibriumArgs, sys: &dyn ModelLookup, eq: &Equilibrium) -> Result<()> {
    let Some(path) = args.write_model.as_deref() else {
        return Ok(());
    };
    let is_toml = args
        .model
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("toml"));
    if !is_toml {
        bail!(
            "--write-model rewrites TOML model files only, and {} is not one (a .json model can be rewritten as TOML by hand; a URDF with `mstar convert`)",
            args.model.display()
        );
    }
    let text = std::fs::read_to_string(&args.model)
        .with_context(|| format!("cannot read {}", args.model.display()))?;
    let origin = path.display().to_string();
    let written = mstar::equilibrium::model_text(&text, &origin, sys, &eq.u)
        .with_context(|| format!("{origin} not written"))?;
    // (Replaced whole, and never a read-only file: as every output.)
    mstar::csv::write_atomically(path, written.as_bytes())
        .with_context(|| format!("cannot write {origin}"))?;
    say!("wrote {origin} (its initial pose is the equilibrium)");
    Ok(())
}
