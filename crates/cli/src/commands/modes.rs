//! `mstar modes`: the constrained vibration modes of a model file
//! (`mstar::modes`) about its equilibrium or its initial pose, printed one
//! line a mode and written as CSV.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};
use mstar::modes::{Method, ModeKind, Modes, ModesError, ModesOptions};
use mstar::run::ModelLookup;

/// The state the motion is linearized about.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum About {
    /// The static equilibrium `mstar equilibrium` finds from the file's pose.
    Equilibrium,
    /// The file's initial pose, at rest, with the multipliers of the
    /// acceleration problem there (`mstar linearize` writes the drift
    /// `xdot0` it leaves).
    Initial,
}

impl About {
    /// The library's [`mstar::modes::About`].
    pub fn library(self) -> mstar::modes::About {
        match self {
            Self::Equilibrium => mstar::modes::About::Equilibrium,
            Self::Initial => mstar::modes::About::Initial,
        }
    }
}

/// The eigensolver (`mstar::modes::Method`).
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum MethodArg {
    /// Dense up to 600 coordinates, sparse above.
    Auto,
    /// Null-space basis and a dense eigensolver (any damping).
    Dense,
    /// Shift-invert Lanczos on the sparse KKT matrix (undamped models).
    Sparse,
}

/// Arguments of `mstar modes`.
#[derive(clap::Args, Debug)]
pub struct ModesArgs {
    /// The model file (TOML, JSON or URDF).
    model: PathBuf,
    /// The state to linearize about.
    #[arg(long, value_enum, default_value = "equilibrium")]
    about: About,
    /// How many modes, lowest frequency first [default: 10, or the degrees
    /// of freedom when fewer].
    #[arg(long)]
    count: Option<usize>,
    /// Write the modes as CSV: `mode`, `frequency_hz`, `damping_ratio`,
    /// then the shape `u:<coordinate>` (unit modal mass); `-` for standard
    /// output.
    #[arg(long)]
    out: Option<PathBuf>,
    /// The eigensolver.
    #[arg(long, value_enum, default_value = "auto")]
    method: MethodArg,
    /// Override a key of the file (as for `mstar run`).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
}

impl ModesArgs {
    /// `--out`, for the report to move to standard error when it is `-`.
    pub fn out(&self) -> Option<&Path> {
        self.out.as_deref()
    }
}

/// `mstar modes`: exit 0 when the modes are found (and written), 1 when
/// there is no equilibrium, the eigenproblem fails or the output cannot
/// be written, 2 when the model file cannot be read or the command line is
/// wrong.
pub fn modes(args: &ModesArgs) -> ExitCode {
    if let Some(out) = args.out.as_deref().filter(|p| p.as_os_str() != "-")
        && let Err(e) = crate::output::refuse_overwriting_model(&args.model, &[], &[("--out", out)])
    {
        note!("error: {e}");
        return ExitCode::from(2);
    }
    let file = match super::load_model(&args.model, &args.set) {
        Ok(file) => file,
        Err(code) => return code,
    };
    let sys = mstar::run::lookup(&file.mechanism);
    let result = state(args.about, sys)
        .and_then(|(u, lambda)| solve(args, sys, &u, &lambda))
        .and_then(|found| {
            report(args, &found);
            write_csv(args.out.as_deref(), sys, &found)
        });
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            note!("error: {}: {e:#}", args.model.display());
            ExitCode::from(1)
        }
    }
}

/// The state at rest `(u, λ)` to linearize about
/// ([`mstar::modes::rest_state`]).
pub fn state(about: About, sys: &dyn ModelLookup) -> Result<(Vec<f64>, Vec<f64>)> {
    let found = mstar::modes::rest_state(sys, &sys.initial_position(), about.library())
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    if found.neutral {
        // A neutral direction is a rigid mode: the modes say so.
        note!(
            "note: the equilibrium is neutral (a direction without stiffness): it appears as a rigid mode"
        );
    }
    Ok((found.u, found.lambda))
}

/// The modes; without `--count`, 10 or the degrees of freedom when fewer.
fn solve(args: &ModesArgs, sys: &dyn ModelLookup, u: &[f64], lambda: &[f64]) -> Result<Modes> {
    let method = match args.method {
        MethodArg::Auto => Method::Auto,
        MethodArg::Dense => Method::Dense,
        MethodArg::Sparse => Method::Sparse,
    };
    let mut options = ModesOptions {
        count: args.count.unwrap_or(10),
        method,
        ..ModesOptions::default()
    };
    match mstar::modes::modes(sys, u, lambda, &options) {
        Err(ModesError::TooMany { dof, .. }) if args.count.is_none() => {
            options.count = dof;
            mstar::modes::modes(sys, u, lambda, &options).map_err(|e| anyhow::anyhow!("{e}"))
        }
        Err(ModesError::TooMany {
            count,
            dof,
            n,
            rank,
        }) => Err(anyhow::anyhow!(
            "--count {count}: the model has {} of freedom ({n} coordinates, {rank} independent constraints); give --count {dof} or fewer",
            plural(dof, "degree")
        )),
        // (The message alone: it already names its cause.)
        found => found.map_err(|e| anyhow::anyhow!("{e}")),
    }
}

/// One line a mode: `mode K: f = … Hz, ζ = …` and what it does.
fn report(args: &ModesArgs, found: &Modes) {
    let about = match args.about {
        About::Equilibrium => "the equilibrium",
        About::Initial => "the initial pose",
    };
    let method = if found.method == Method::Sparse {
        "shift-invert Lanczos"
    } else {
        "dense"
    };
    if found.dof == 0 {
        say!(
            "no modes: the model has no degrees of freedom about {about} (its joints and drivers fix every coordinate)"
        );
        return;
    }
    say!(
        "{} about {about} ({} of freedom, {}, {method}); f = |s|/2π, the undamped natural frequency; ζ = −Re(s)/|s|",
        plural(found.modes.len(), "mode"),
        plural(found.dof, "degree"),
        if found.damped { "damped" } else { "undamped" },
    );
    for (k, mode) in found.modes.iter().enumerate() {
        let what = match mode.kind {
            ModeKind::Rigid => " (rigid: nothing restores this motion)".to_string(),
            ModeKind::Overdamped => format!(" (overdamped: s = {:.6e} 1/s)", mode.s.0),
            ModeKind::Unstable => format!(" (unstable: grows as e^(st), s = {:.6e} 1/s)", mode.s.0),
            ModeKind::Oscillating if found.damped => format!(
                " (damped: Im(s)/2π = {:.6e} Hz)",
                mode.s.1 / std::f64::consts::TAU
            ),
            ModeKind::Oscillating => String::new(),
        };
        let zeta = if mode.damping_ratio == 0.0 {
            "0".to_string()
        } else {
            format!("{:.6e}", mode.damping_ratio)
        };
        say!(
            "mode {}: f = {:.9e} Hz, ζ = {zeta}{what}",
            k + 1,
            mode.frequency_hz
        );
    }
}

/// `1 mode`, `2 modes`.
fn plural(count: usize, noun: &str) -> String {
    if count == 1 {
        format!("1 {noun}")
    } else {
        format!("{count} {noun}s")
    }
}

/// `--out`: a header and one row a mode.
fn write_csv(out: Option<&Path>, sys: &dyn ModelLookup, found: &Modes) -> Result<()> {
    let Some(path) = out else {
        return Ok(());
    };
    let mut text = String::from("mode,frequency_hz,damping_ratio");
    for i in 0..sys.n_coords() {
        text.push_str(",u:");
        text.push_str(&sys.coord_name(i));
    }
    text.push('\n');
    for (k, mode) in found.modes.iter().enumerate() {
        text.push_str(&format!(
            "{},{},{}",
            k + 1,
            mstar::csv::format_number(mode.frequency_hz),
            mstar::csv::format_number(mode.damping_ratio)
        ));
        for x in &mode.shape {
            text.push(',');
            text.push_str(&mstar::csv::format_number(*x));
        }
        text.push('\n');
    }
    mstar::csv::write_atomically(path, text.as_bytes())
        .with_context(|| format!("cannot write {}", path.display()))?;
    let count = found.modes.len();
    let noun = if count == 1 { "mode" } else { "modes" };
    say!("wrote {} ({count} {noun})", path.display());
    Ok(())
}
