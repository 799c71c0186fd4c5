//! `mstar linearize`: a linear state-space model of a model file about its
//! equilibrium or its initial pose (`mstar::linear`), written as JSON.

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use mstar::linear::{self, LinearError, Request, StateSpace};

use super::modes::About;

/// Arguments of `mstar linearize`.
#[derive(clap::Args, Debug)]
pub struct LinearizeArgs {
    /// The model file (TOML, JSON or URDF).
    model: PathBuf,
    /// Inputs (optional; none: B and D have no columns): keys of the model
    /// file in the `--set` syntax that hold a force or torque value
    /// (`force.push.fx`, `force.motor.function.constant`); the input is the
    /// change of that value.
    #[arg(long, num_args = 1.., value_name = "KEY")]
    inputs: Vec<String>,
    /// Outputs (optional; none: C, D and y0 are empty): columns of `mstar
    /// run` (`u:…`, `v:…`, `a:…`, `lambda:…`, `energy`, `reaction:…`,
    /// `effort:…`, `sensor:…`; `*` matches any text).
    #[arg(long, num_args = 1.., value_name = "COLUMN")]
    outputs: Vec<String>,
    /// The JSON file to write (`-`: standard output).
    #[arg(long, value_name = "SS.json")]
    out: PathBuf,
    /// The state to linearize about.
    #[arg(long, value_enum, default_value = "equilibrium")]
    about: About,
    /// Override a key of the file (as for `mstar run`).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
}

impl LinearizeArgs {
    /// `--out`, for the report to move to standard error when it is `-`.
    pub fn out(&self) -> Option<&Path> {
        Some(&self.out)
    }
}

/// Why the command stopped: the message and the exit code.
type Failure = (String, u8);

/// `mstar linearize`: exit 0 when written, 1 when no model can be formed
/// (no equilibrium, redundant constraints, a singular mass) or the file
/// cannot be written, 2 when the model file, a key or a column is wrong.
pub fn linearize(args: &LinearizeArgs) -> ExitCode {
    match build(args).and_then(|ss| write(args, &ss)) {
        Ok(()) => ExitCode::SUCCESS,
        Err((message, code)) => {
            note!("error: {message}");
            ExitCode::from(code)
        }
    }
}

/// Loads the model, finds the operating point and forms the model
/// (`mstar::linear::from_file`).
fn build(args: &LinearizeArgs) -> Result<StateSpace, Failure> {
    if args.out.as_os_str() != "-" {
        let outputs = [("--out", args.out.as_path())];
        crate::output::refuse_overwriting_model(&args.model, &[], &outputs)
            .map_err(|e| (e.to_string(), 2))?;
    }
    let request = Request {
        about: args.about.library(),
        inputs: &args.inputs,
        outputs: &args.outputs,
        overrides: &args.set,
    };
    match linear::from_file(&args.model, &request) {
        Ok(formed) => {
            for w in &formed.warnings {
                note!("warning: {w}");
            }
            Ok(formed.model)
        }
        // A file error names the file (and where) itself.
        Err(e @ LinearError::File(_)) => Err((e.to_string(), 2)),
        Err(e) => {
            let code = if e.is_usage() { 2 } else { 1 };
            Err((format!("{}: {e}", args.model.display()), code))
        }
    }
}

/// Writes the JSON and reports what it holds.
fn write(args: &LinearizeArgs, ss: &StateSpace) -> Result<(), Failure> {
    let text = ss.to_json();
    if args.out.as_os_str() == "-" {
        let mut stdout = std::io::stdout().lock();
        match stdout
            .write_all(text.as_bytes())
            .and_then(|()| stdout.flush())
        {
            // A closed pipe (`mstar linearize … --out - | head`) ends quietly.
            Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
                return Err((format!("cannot write to standard output: {e}"), 1));
            }
            _ => {}
        }
    } else {
        mstar::csv::write_atomically(&args.out, text.as_bytes())
            .map_err(|e| (format!("cannot write {}: {e}", args.out.display()), 1))?;
    }
    say!(
        "linear model about the {} ({}): {}, {}, {}",
        ss.about,
        count(ss.coordinates.len(), "coordinate"),
        count(ss.states.len(), "state"),
        count(ss.inputs.len(), "input"),
        count(ss.outputs.len(), "output")
    );
    say!("  states: {}", ss.states.join(", "));
    let drift = ss.xdot0.iter().fold(0.0_f64, |a, x| a.max(x.abs()));
    if ss.about == "initial" && drift > 0.0 {
        say!(
            "  the initial pose is not at rest: ‖ẋ₀‖∞ = {drift:.3e} (xdot0 in the file); the model holds near it for short times only"
        );
    }
    if args.out.as_os_str() != "-" {
        say!("wrote {}", args.out.display());
    }
    Ok(())
}

/// `1 input`, `2 inputs`.
fn count(n: usize, what: &str) -> String {
    if n == 1 {
        format!("1 {what}")
    } else {
        format!("{n} {what}s")
    }
}
