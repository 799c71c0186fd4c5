//! `mstar equilibrium`: the static equilibrium of a model file
//! (`mstar::equilibrium`), reported, written as one CSV row and as a model
//! file that starts there.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result, bail};
use mstar::SampleRef;
use mstar::columns::{Columns, OutputColumns};
use mstar::equilibrium::{Equilibrium, EquilibriumOptions};
use mstar::file::MechanismFile;
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
    if let Err(e) = crate::output::refuse_overwrites(&[("the model file", &args.model)], &outputs) {
        note!("error: {e}");
        return ExitCode::from(2);
    }
    let file = match MechanismFile::load_with(&args.model, &args.set) {
        Ok(file) => file,
        Err(e) => {
            note!("error: {e}");
            return ExitCode::from(2);
        }
    };
    for w in &file.warnings {
        note!("warning: {w}");
    }
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
            let chosen = mstar::columns::Selection::new(&names, patterns)
                .map_err(|e| crate::output::usage(format!("[output] columns: {e}")))?;
            Some(chosen)
        }
        None => None,
    };
    let Some(mut stream) = super::open_output(Some(path), sys, &extra, selection.as_ref())? else {
        return Ok(());
    };
    let zeros = vec![0.0; eq.u.len()];
    let sample = SampleRef {
        t: 0.0,
        u: &eq.u,
        v: &zeros,
        a: &zeros,
        lambda: &eq.lambda,
        kinetic: 0.0,
        potential: sys.potential_energy(0.0, &eq.u),
        iterations: eq.iterations,
        residual: eq.residual,
        constraint: eq.constraint,
    };
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

/// The elements' coordinates by name: `body.x, body.y, body.theta` →
/// `("body", [x, y, θ])`, in the model's order.
fn poses(sys: &dyn ModelLookup, u: &[f64]) -> Vec<(String, Vec<f64>)> {
    let mut out: Vec<(String, Vec<f64>)> = Vec::new();
    for (i, &x) in u.iter().enumerate() {
        let name = sys.coord_name(i);
        let element = name.rsplit_once('.').map_or(name.as_str(), |(e, _)| e);
        match out.last_mut() {
            Some((last, values)) if last == element => values.push(x),
            _ => out.push((element.to_string(), vec![x])),
        }
    }
    out
}

/// `--write-model`: the file's text with the equilibrium as its initial
/// pose, checked to be the same mechanism once read back.
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
    let written = mstar::file::pose::with_initial_pose(&text, &poses(sys, &eq.u))
        .map_err(|e| anyhow::anyhow!("{}: {e}", args.model.display()))?;
    std::fs::write(path, written).with_context(|| format!("cannot write {}", path.display()))?;
    if let Err(e) = same_mechanism(path, sys, eq) {
        // A file that means another mechanism is not left behind.
        let _ = std::fs::remove_file(path);
        return Err(e);
    }
    say!(
        "wrote {} (its initial pose is the equilibrium)",
        path.display()
    );
    Ok(())
}

/// Reads the written model back and compares its constraints and forces at
/// the equilibrium with the original's: an element defined from the
/// initial pose (a joint's `at`, a default length or rest angle) would
/// change with it.
fn same_mechanism(path: &Path, old: &dyn ModelLookup, eq: &Equilibrium) -> Result<()> {
    let file = MechanismFile::load_with(path, &[])
        .map_err(|e| anyhow::anyhow!("the written model cannot be read back: {e}"))?;
    let new = mstar::run::lookup(&file.mechanism);
    let (n, m) = (old.n_coords(), old.n_constraints());
    if new.n_coords() != n || new.n_constraints() != m {
        bail!("the written model {} has other dimensions", path.display());
    }
    let u = &eq.u;
    let zeros = vec![0.0; n];
    let (mut phi_old, mut phi_new) = (vec![0.0; m], vec![0.0; m]);
    old.phi_into(0.0, u, &mut phi_old);
    new.phi_into(0.0, u, &mut phi_new);
    let (mut g_old, mut g_new) = (vec![0.0; n], vec![0.0; n]);
    old.forces_into(0.0, u, &zeros, &mut g_old);
    new.forces_into(0.0, u, &zeros, &mut g_new);
    // Round-off of the pose written and read back, relative to the sizes.
    let length = u.iter().fold(1.0_f64, |a, x| a.max(x.abs()));
    let force = g_old.iter().fold(f64::MIN_POSITIVE, |a, x| a.max(x.abs()));
    let pose_dependent = |what: String| {
        anyhow::anyhow!(
            "{what} is not the same in the written model: an element of {} is defined from the initial pose (a joint's `at` or `axis`, a default `length` or `rest_length`, a rotational spring's rest angle); give it explicitly in the file and run again",
            path.display()
        )
    };
    for i in 0..m {
        if (phi_old[i] - phi_new[i]).abs() > 1e-9 * length {
            return Err(pose_dependent(format!(
                "the constraint {}",
                old.constraint_name(i)
            )));
        }
    }
    for i in 0..n {
        if (g_old[i] - g_new[i]).abs() > 1e-9 * force {
            return Err(pose_dependent(format!(
                "the force on {}",
                old.coord_name(i)
            )));
        }
    }
    Ok(())
}
