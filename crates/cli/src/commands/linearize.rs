//! `mstar linearize`: a linear state-space model of a model file about its
//! equilibrium or its initial pose (`mstar::linear`), written as JSON.

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use mstar::equilibrium::{EquilibriumError, EquilibriumOptions};
use mstar::file::MechanismFile;
use mstar::linear::{Input, OperatingPoint, StateSpace};
use mstar::run::ModelLookup;

/// The state a model is linearized about.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum About {
    /// The static equilibrium `mstar equilibrium` finds from the file's pose.
    Equilibrium,
    /// The file's initial pose, at rest (the multipliers of the
    /// acceleration problem there; the drift `xdot0` is written).
    Initial,
}

/// Arguments of `mstar linearize`.
#[derive(clap::Args, Debug)]
pub struct LinearizeArgs {
    /// The model file (TOML, JSON or URDF).
    model: PathBuf,
    /// Inputs: keys of the model file in the `--set` syntax that hold a
    /// force or torque value (`force.push.fx`,
    /// `force.motor.function.constant`); the input is the change of that
    /// value.
    #[arg(long, num_args = 1.., value_name = "KEY")]
    inputs: Vec<String>,
    /// Outputs: columns of `mstar run` (`u:…`, `v:…`, `a:…`, `lambda:…`,
    /// `energy`, `reaction:…`, `effort:…`, `sensor:…`; `*` matches any text).
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

/// Loads the model, finds the operating point and forms the model.
fn build(args: &LinearizeArgs) -> Result<StateSpace, Failure> {
    if args.out.as_os_str() != "-" {
        let outputs = [("--out", args.out.as_path())];
        crate::output::refuse_overwrites(&[("the model file", &args.model)], &outputs)
            .map_err(|e| (e.to_string(), 2))?;
    }
    let file = MechanismFile::load_with(&args.model, &args.set).map_err(|e| (e.to_string(), 2))?;
    for w in &file.warnings {
        note!("warning: {w}");
    }
    let sys = mstar::run::lookup(&file.mechanism);
    let op = operating_point(args, sys)?;
    let inputs = args
        .inputs
        .iter()
        .map(|key| input(args, key, &op))
        .collect::<Result<Vec<_>, _>>()?;
    let model = args.model.display();
    let ss = mstar::linear::state_space(sys, &op, &inputs, &args.outputs, &file.output.sensors)
        .map_err(|e| {
            let code = if matches!(e, mstar::linear::LinearError::Output(_)) {
                2
            } else {
                1
            };
            (format!("{model}: {e}"), code)
        })?;
    Ok(ss)
}

/// The equilibrium (`mstar equilibrium`'s search) or the initial pose at
/// rest.
fn operating_point(args: &LinearizeArgs, sys: &dyn ModelLookup) -> Result<OperatingPoint, Failure> {
    let model = args.model.display();
    let u0 = sys.initial_position();
    let n = sys.n_coords();
    if n > mstar::linear::MAX_COORDS {
        let e = mstar::linear::LinearError::TooLarge {
            n,
            max: mstar::linear::MAX_COORDS,
        };
        return Err((format!("{model}: {e}"), 1));
    }
    match args.about {
        About::Equilibrium => equilibrium(sys, &u0).map_err(|e| {
            let hint = "(or linearize about the file's pose: --about initial)";
            (format!("{model}: {e} {hint}"), 1)
        }),
        About::Initial => {
            mstar::linear::at_rest(sys, 0.0, &u0).map_err(|e| (format!("{model}: {e}"), 1))
        }
    }
}

/// The equilibrium from `u0`; a neutral one (its free direction a zero
/// eigenvalue pair of `A`) with a warning.
fn equilibrium(sys: &dyn ModelLookup, u0: &[f64]) -> Result<OperatingPoint, EquilibriumError> {
    let eq = match mstar::equilibrium::solve(sys, u0, &EquilibriumOptions::default()) {
        Ok(eq) => eq,
        Err(EquilibriumError::Neutral {
            equilibrium,
            direction,
        }) => {
            let along: Vec<&str> = direction.iter().map(|(n, _)| n.as_str()).collect();
            note!(
                "warning: the equilibrium is neutral along {}: nothing resists that motion, and A has a zero eigenvalue pair for it",
                along.join(", ")
            );
            *equilibrium
        }
        Err(e) => return Err(e),
    };
    Ok(OperatingPoint {
        about: "equilibrium".into(),
        t: 0.0,
        a: vec![0.0; eq.u.len()],
        u: eq.u,
        lambda: eq.lambda,
    })
}

/// The input `key`: its value in the file, and `∂g/∂p` from the models
/// built with it changed by `± h`.
fn input(args: &LinearizeArgs, key: &str, op: &OperatingPoint) -> Result<Input, Failure> {
    if key.trim().starts_with("driver.") {
        return Err((
            format!(
                "{}: --inputs {key}: a driver prescribes a coordinate's position, and a step in a position is an impulse: it enters the equations through its first and second time derivatives, which ẋ = A x + B p has no place for; drive the coordinate with a force or torque (a [[force]] of type force or torque, or a stiff spring-damper whose end you move) and name its value instead",
                args.model.display()
            ),
            2,
        ));
    }
    let value =
        mstar::file::number_at(&args.model, &args.set, key).map_err(|e| (e.to_string(), 2))?;
    let h = mstar::linear::input_step(value);
    let build = |p: f64| {
        let mut sets = args.set.clone();
        sets.push(format!("{key}={p:e}"));
        MechanismFile::load_with(&args.model, &sets).map_err(|e| (e.to_string(), 2))
    };
    let (plus, minus) = (build(value + h)?, build(value - h)?);
    let systems = [plus.mechanism.system(), minus.mechanism.system()];
    mstar::linear::input(key, value, h, systems, op)
        .map_err(|e| (format!("{}: {e}", args.model.display()), 2))
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
