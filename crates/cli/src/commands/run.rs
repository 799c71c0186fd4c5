//! `mstar run`: a model file (or a built-in model) on the command line.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use mstar::columns::Columns;
use mstar::columns::{OutputColumns, Selection};
use mstar::file::{MAX_MAGNITUDE, Mechanism, MechanismFile, Simulation};
use mstar::model::RowSubset;
use mstar::newmark::Parameterized;
use mstar::newmark::Short;
use mstar::pendulum::PendulumRun;
use mstar::redundant::Expanded;
use mstar::run::ModelLookup;
use mstar::sensitivity::{Chained, FileParameter, FileParameters, SensitivityColumns};
use mstar::{IntegrationError, Integrator, Observer, SampleRef, System, csv};

use crate::output::Stop;

/// Arguments of `mstar run`.
#[derive(clap::Args, Debug)]
pub struct RunArgs {
    /// The model file (TOML, or JSON by its `.json` extension); see
    /// docs/model-format.md.
    #[arg(required_unless_present = "builtin", conflicts_with = "builtin")]
    model: Option<PathBuf>,
    /// A built-in model instead of a file: the paper's pendulum (released
    /// horizontally; h = 0.01 s, t_end = 10 s) or a 10-bar chain (h = 1e-3 s,
    /// t_end = 1 s).
    #[arg(long, value_enum)]
    builtin: Option<Builtin>,
    /// Write the samples to this file: CSV, or NumPy's .npz when the name
    /// ends in .npz; `-` for standard output (CSV). Streamed: complete, or
    /// on a failure the samples so far in <name>.partial.csv (.partial.npz).
    #[arg(long)]
    pub(crate) out: Option<PathBuf>,
    /// End time, s (overrides [simulation] t_end).
    #[arg(long, allow_hyphen_values = true)]
    t_end: Option<f64>,
    /// Step size, s (overrides [simulation] h).
    #[arg(long, allow_hyphen_values = true)]
    h: Option<f64>,
    /// Adapt the step size to the local error estimate (sets
    /// [simulation] error_control = "adaptive"; ρ∞ defaults to 0.5).
    #[arg(long, conflicts_with = "strict")]
    adaptive: bool,
    /// Fixed step size, and an error at the first step whose estimated error
    /// exceeds the tolerance (sets [simulation] error_control = "strict").
    #[arg(long)]
    strict: bool,
    /// Relative tolerance of the local error estimate (overrides
    /// [simulation] rtol).
    #[arg(long, allow_hyphen_values = true)]
    rtol: Option<f64>,
    /// Absolute tolerance of the local error estimate, m or rad (overrides
    /// [simulation] atol).
    #[arg(long, allow_hyphen_values = true)]
    atol: Option<f64>,
    /// Newton tolerance (overrides [simulation] tol).
    #[arg(long, allow_hyphen_values = true)]
    tol: Option<f64>,
    /// Write the state every DT seconds instead of every step, interpolated
    /// within the steps (overrides [output] every_time and every).
    #[arg(long, value_name = "DT", allow_hyphen_values = true)]
    output_every: Option<f64>,
    /// Write only these columns, by name with `*` globs, comma-separated or
    /// repeated, e.g. --columns 't,sensor:*,reaction:O2.*' (overrides
    /// [output] columns; default: every column).
    #[arg(long, value_name = "NAMES", value_delimiter = ',')]
    columns: Vec<String>,
    /// Override a key of the file, e.g. --set simulation.rho=0.8,
    /// --set output.every=10, or of an element by its name,
    /// --set body.upper.mass=2 (repeatable; values in TOML syntax).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// Forward sensitivity of the discrete solution to a numeric key of
    /// the model file, named as --set names it (e.g. body.rod.mass,
    /// joint.rod.length); repeatable. Adds the columns
    /// d(<column>)/d(<KEY>) of u, v, a and lambda (docs/analysis.md).
    #[arg(long = "sensitivity", value_name = "KEY")]
    sensitivity: Vec<String>,
    /// A scalar objective over the run, whose gradient --gradient asks
    /// for: final:COLUMN, sum:COLUMN (over every step) or
    /// fit:COLUMN=FILE.csv (Σ (y − d)² against the measured column of a
    /// CSV with a t column at the run's steps); COLUMN a u:, v:, a: or
    /// lambda: column. Prints dΨ/d<KEY> instead of writing rows
    /// (docs/analysis.md, "Adjoint gradients").
    #[arg(long, value_name = "SPEC", requires = "gradient")]
    objective: Option<String>,
    /// A model-file key (as --set names it) to differentiate --objective
    /// by, with the discrete adjoint; repeatable.
    #[arg(long, value_name = "KEY", num_args = 1.., requires = "objective")]
    gradient: Vec<String>,
    /// Write the gradient as JSON.
    #[arg(long, value_name = "G.json", requires = "objective")]
    gradient_out: Option<PathBuf>,
}

/// The built-in models of `mstar run --builtin`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Builtin {
    /// The paper's pendulum in u = [x, y, θ] (`mstar pendulum` runs it too).
    Pendulum,
    /// Ten slender bars on revolute joints (`mstar chain --links 10`).
    Chain,
}

/// A model to run: the system, its start and its settings.
struct Loaded {
    label: String,
    system: Model,
    u0: Vec<f64>,
    v0: Vec<f64>,
    simulation: Simulation,
    every: usize,
    /// `[output] every_time`, s.
    every_time: Option<f64>,
    /// `[[sensor]]`s.
    sensors: Vec<mstar::model::sensor::Sensor>,
    /// `[output] columns`.
    columns: Option<Vec<String>>,
    /// Where `[output] columns` is (an error with the key's place and an
    /// empty reason), for an entry that names no column.
    columns_error: Option<mstar::file::FileError>,
}

/// A model file's mechanism, planar or spatial (whose CSV has reaction
/// columns), or another system.
enum Model {
    Named(Box<Mechanism>),
    Other(Box<dyn System>),
}

impl Model {
    fn system(&self) -> &(dyn System + 'static) {
        match self {
            Self::Named(m) => m.system(),
            Self::Other(sys) => sys.as_ref(),
        }
    }

    /// The mechanism with its joints by name, when it is a model file's.
    fn named(&self) -> Option<&dyn ModelLookup> {
        match self {
            Self::Named(m) => Some(mstar::run::lookup(m)),
            Self::Other(_) => None,
        }
    }
}

/// Refuses an output (`--out`, `--gradient-out`) that names an input (the
/// model file, the URDF it reads, a `fit:` objective's CSV) or the other
/// output (exit 2), and a `--gradient-out` that is read-only (exit 1; `--out`
/// is checked as its stream opens).
fn refuse_overwrites(args: &RunArgs) -> Result<()> {
    let outputs: Vec<(&str, &Path)> =
        [("--out", &args.out), ("--gradient-out", &args.gradient_out)]
            .into_iter()
            .filter_map(|(option, path)| Some((option, path.as_deref()?)))
            .filter(|(_, path)| !crate::output::is_stdout(Some(path)))
            .collect();
    let fit = args
        .objective
        .as_deref()
        .and_then(super::gradient::fit_file);
    let others: Vec<(&str, &Path)> = fit.iter().map(|f| ("the fit file", f.as_path())).collect();
    match &args.model {
        Some(model) => crate::output::refuse_overwriting_model(model, &others, &outputs)?,
        None => crate::output::refuse_overwrites(&others, &outputs)?,
    }
    let gradient_out: Vec<(&str, &Path)> = outputs
        .into_iter()
        .filter(|(o, _)| *o == "--gradient-out")
        .collect();
    crate::output::refuse_read_only(&gradient_out)
}

/// `mstar run`: exit 0 when the run reaches its end within the error
/// tolerance, 3 when it reaches its end beyond it (`mstar::accuracy`), 2 when
/// the model file cannot be read (as `mstar check`), 130/143 after SIGINT /
/// SIGTERM, 1 on any other failure.
pub fn run(args: &RunArgs) -> ExitCode {
    if let Err(e) = refuse_overwrites(args) {
        return failed(e, None);
    }
    let model = match load(args) {
        Ok(model) => model,
        Err(e) => return failed(named_as_given(e, args), None),
    };
    let code = match run_model(args, &model) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => failed(named_as_given(e, args), Some(&model)),
    };
    // The process ends next and its memory with it: freeing a 10⁵-body
    // model piece by piece took 0.3 s.
    std::mem::forget(model);
    code
}

/// Reports a failure of `mstar run` (with a hint where there is one) and
/// its exit code: 2 for a file that cannot be read, 130/143 for an
/// interrupted run (`crate::output::exit_code`), else 1.
fn failed(e: anyhow::Error, model: Option<&Loaded>) -> ExitCode {
    if e.downcast_ref::<mstar::accuracy::Inaccurate>().is_some() {
        return ExitCode::from(mstar::accuracy::EXIT_INACCURATE);
    }
    if e.downcast_ref::<crate::signals::Interrupted>().is_some() {
        return ExitCode::from(crate::output::exit_code(Err(e), true, 1));
    }
    note!("error: {}", crate::messages::report(&e));
    if e.downcast_ref::<crate::output::Usage>().is_some() {
        return ExitCode::from(2);
    }
    let settings = matches!(
        e.downcast_ref::<mstar::run::RunError>(),
        Some(mstar::run::RunError::Settings(_))
    );
    if settings || e.downcast_ref::<mstar::file::FileError>().is_some() {
        return ExitCode::from(2);
    }
    if let Some(e) = e.downcast_ref::<IntegrationError>() {
        let hint = model
            .and_then(|m| m.system.named())
            .and_then(|sys| start_hint(sys, e));
        if let Some(hint) = hint.or_else(|| crate::messages::hint(e, true).map(String::from)) {
            note!("hint: {hint}");
        }
    }
    ExitCode::FAILURE
}

/// What to edit in the model file when the start fails on a constraint the
/// initial pose violates: the pose of the bodies, or the points of the
/// joint that owns it (or the driver's function).
fn start_hint(sys: &dyn ModelLookup, e: &IntegrationError) -> Option<String> {
    let name = match e {
        IntegrationError::ProjectionFailed { initial, .. } => initial,
        IntegrationError::StartFailed {
            violated: Some((name, _)),
            ..
        } => name,
        _ => return None,
    };
    let row = (0..sys.n_constraints()).find(|&i| sys.constraint_name(i) == *name)?;
    let owner = sys.constraint_owner(row)?;
    let what = if sys.is_driver(owner) == Some(true) {
        format!("or the value of driver '{owner}' at t = 0")
    } else {
        format!("or the points of joint '{owner}'")
    };
    Some(format!(
        "'{name}' is a row of '{owner}': in the model file, fix the initial pose of the bodies it joins ({}) {what}, so that it holds at t = 0; mstar check shows the initial violation",
        sys.pose_keys()
    ))
}

fn run_model(args: &RunArgs, model: &Loaded) -> Result<()> {
    let (every, every_time) = match args.output_every {
        Some(dt) => (1, Some(dt)),
        None => (model.every, model.every_time),
    };
    let (config, t_end) = super::config(&model.simulation)?;
    check_tolerances(&config.error, &model.u0)?;
    let sys = model.system.system();
    say!(
        "{}: {} coordinates, {} constraints; h = {} s, t_end = {} s",
        model.label,
        sys.n_coords(),
        sys.n_constraints(),
        Short(config.h),
        Short(t_end)
    );
    if let Some(sys) = model.system.named() {
        warn_far_start(sys);
    }
    let rows = independent_rows(model)?;
    if let Some(spec) = &args.objective {
        let request = super::gradient::Request {
            model: args.model.as_deref(),
            set: &overrides(args),
            spec,
            keys: &args.gradient,
            out: args.gradient_out.as_deref(),
            rows_out: args.out.is_some(),
            redundant: rows.is_some(),
            every_time,
        };
        return super::gradient::run(&request, sys, (config, &model.u0, &model.v0, t_end));
    }
    let params = sensitivity_parameters(args, &config, rows.is_some(), every_time)?;
    let sensitivity_columns = (!params.is_empty()).then(|| {
        let keys: Vec<String> = params.iter().map(|p| p.name()).collect();
        SensitivityColumns::new(sys, &keys)
    });
    let model_columns = match model.system.named() {
        Some(named) => Some(OutputColumns::new(named, &model.sensors)?),
        None => None,
    };
    let model_columns = model_columns.as_ref().map(|c| c as &dyn Columns);
    let chained = sensitivity_columns
        .as_ref()
        .map(|s| Chained(model_columns, s));
    let columns = match &chained {
        Some(c) => Some(c as &dyn Columns),
        None => model_columns,
    };
    // Named only for a CSV file: 6·10⁵ names for 10⁵ bodies.
    let extra = match (&columns, &args.out) {
        (Some(c), Some(_)) => c.names(),
        _ => Vec::new(),
    };
    let patterns = if args.columns.is_empty() {
        model.columns.clone()
    } else {
        Some(args.columns.clone())
    };
    let selection = match (&patterns, &args.out) {
        (Some(patterns), Some(_)) => {
            let mut names = csv::header(sys);
            names.extend_from_slice(&extra);
            let source = if args.columns.is_empty() {
                "[output] columns"
            } else {
                "--columns"
            };
            let chosen = Selection::new(&names, patterns).map_err(|e| {
                match model
                    .columns_error
                    .clone()
                    .filter(|_| args.columns.is_empty())
                {
                    // `FILE:LINE:COLUMN: [output]: columns: why`.
                    Some(mut at) => {
                        at.message.push_str(&e.to_string());
                        anyhow::Error::new(at)
                    }
                    None => crate::output::usage(format!("{source}: {e}")),
                }
            })?;
            Some(chosen)
        }
        _ => None,
    };
    crate::limits::check_steps(t_end, config.h)?;
    let fields = selection.as_ref().map_or_else(
        || csv::header_len(sys) + columns.map_or(0, Columns::count),
        Selection::len,
    );
    super::check_output(
        args.out.as_deref(),
        fields,
        (t_end, config.h),
        (args.builtin.is_none().then_some(every), every_time),
    )?;
    let stream = super::open_output(args.out.as_deref(), sys, &extra, selection.as_ref())?;
    let grid = crate::output::Grid::new(every_time)?;
    let mut output = RunOutput::new(stream, columns, (every, grid), t_end);
    let config_used = config.clone();
    let start = (config, &model.u0[..], &model.v0[..], t_end);
    // The largest violation of the rows left out (redundant constraints).
    let mut left_out = None;
    let (outcome, drift) = match (model.system.named(), rows) {
        (Some(named), Some(rows)) => {
            let subset = RowSubset::new(sys, rows.kept.clone());
            let hold = |u: &[f64]| mstar::run::left_out_rows_hold(named, &rows, u);
            let mut expanded = Expanded::new(&subset, &mut output);
            let outcome = integrate(
                (&subset, &model.simulation),
                start,
                &hold,
                None,
                &mut expanded,
            );
            let drift = expanded
                .drifted()
                .map(|d| mstar::run::redundancy_changed(named, d));
            left_out = Some(expanded.largest_violation());
            (outcome, drift)
        }
        _ => {
            let refs: Vec<&dyn Parameterized> =
                params.iter().map(|p| p as &dyn Parameterized).collect();
            let sensitivities = sensitivity_columns.as_ref().map(|c| (&refs[..], c));
            let outcome = integrate(
                (sys, &model.simulation),
                start,
                &|_| Ok(()),
                sensitivities,
                &mut output,
            );
            (outcome, None)
        }
    };
    output.progress.finish_and_clear();
    output.recorder.finish_rows();
    let (stats, t, wall, ended) = outcome?;
    print_summary(stats, t, &output, wall);
    if let Some(largest) = left_out {
        say!(
            "rows left out of the solve (redundant): max |Φ| = {largest:.3e} (the max ‖Φ‖∞ above is of the rows solved)"
        );
    }
    let warned = super::warn_accuracy(&stats, &config_used, sys, true);
    crate::output::conclude(output.recorder.into_stream(), args.out.as_deref(), ended, t)?;
    // The samples are written; they are wrong from the drift on.
    if let (Some(mstar::run::RunError::RedundancyChanged { t, .. }), Some(out)) =
        (&drift, &args.out)
    {
        note!(
            "note: {} holds the whole run, and from t = {} s on it is not the mechanism's motion",
            out.display(),
            Short(*t)
        );
    }
    if let Some(e) = drift {
        return Err(e.into());
    }
    Ok(mstar::accuracy::verdict(warned)?)
}

/// Names the joint an initial pose is far from, before the start projects
/// the state onto the constraints ([`mstar::run::far_start_note`]).
fn warn_far_start(sys: &dyn ModelLookup) {
    if let Some(n) = mstar::run::far_start_note(sys) {
        note!("{n}");
    }
}

/// Warns when the start's projection changed a given position or velocity
/// ([`mstar::run::projection_notes`]).
fn warn_projection<S: System + ?Sized>(
    sys: &S,
    report: &mstar::StartReport,
    u0: &[f64],
    v0: &[f64],
) {
    for n in mstar::run::projection_notes(sys, report, u0, v0) {
        note!("{n}");
    }
}

/// The rows to solve on when the model has redundant constraints and asks
/// for minimum-norm multipliers (`None`: all rows).
///
/// # Errors
/// Redundant constraints in a model that does not ask for them, by name,
/// with what to do.
fn independent_rows(model: &Loaded) -> Result<Option<mstar::redundant::Rows>> {
    let Some(sys) = model.system.named() else {
        return Ok(None);
    };
    let choice = model.simulation.redundant.unwrap_or_default();
    let rows =
        mstar::run::solve_rows(sys, &model.u0, choice).with_context(|| model.label.clone())?;
    let Some(rows) = rows else {
        return Ok(None);
    };
    say!(
        "redundant constraints: {} (left out of the solve: minimum-norm multipliers)",
        mstar::run::owners(sys, &rows.dependent).join(", ")
    );
    Ok(Some(rows))
}

/// A run's statistics, end time, wall time and outcome.
type Outcome = (mstar::RunStats, f64, f64, Result<(), Stop>);

/// Integrates `sys` from `(u0, v0)` to `t_end`, every sample to `observer`,
/// once `check_start` accepts the start state; a refusal to start is placed
/// at `sim`'s `kkt` ([`super::start_error`]).
fn integrate<S: System + ?Sized>(
    (sys, sim): (&S, &Simulation),
    (config, u0, v0, t_end): (mstar::Config, &[f64], &[f64], f64),
    check_start: &dyn Fn(&[f64]) -> Result<(), mstar::run::RunError>,
    sensitivities: Option<(&[&dyn Parameterized], &SensitivityColumns)>,
    observer: &mut dyn Observer,
) -> Result<Outcome> {
    let mut integ =
        Integrator::new(sys, config, 0.0, u0, v0).map_err(|e| super::start_error(sim, e))?;
    check_start(integ.view().u)?;
    let mut sens = match sensitivities {
        Some((params, columns)) => {
            let sens = integ.sensitivities(params)?;
            columns.set(&sens);
            Some((sens, columns))
        }
        None => None,
    };
    warn_projection(sys, integ.start_report(), u0, v0);
    say!(
        "KKT solver: {}; Newton: {}",
        integ.backend(),
        integ.newton()
    );
    let clock = Instant::now();
    let mut step = |integ: &mut Integrator<'_, S>, t_end: f64| match &mut sens {
        Some((sens, columns)) => {
            integ.step_with(t_end, sens)?;
            columns.set(sens);
            Ok(())
        }
        None => integ.step(t_end),
    };
    let result = crate::output::drive_with(&mut integ, t_end, &mut step, &mut |integ| {
        observer.observe(&integ.view());
    });
    if result.is_err() {
        // The last state reached, which `[output] every` may have skipped.
        observer.observe(&integ.view());
    }
    let wall = clock.elapsed().as_secs_f64();
    if let Some((sens, _)) = &sens {
        say!(
            "sensitivities: {} parameter(s), {} with local partials; {} solves, {} factorizations \
             of their own",
            sens.len(),
            (0..sens.len()).filter(|&k| sens.local(k)).count(),
            sens.solves(),
            sens.factorizations()
        );
        if let Some(switch) = sens.switched_newton() {
            say!(
                "Newton: once per step from t = {} s (modified Newton took {:.2} iterations a \
                 step from the sensitivities' factorizations)",
                Short(switch.t),
                switch.iterations
            );
        }
    }
    Ok((integ.stats(), integ.time(), wall, result))
}

/// The model of `mstar run`: a file or a built-in.
fn load(args: &RunArgs) -> Result<Loaded> {
    check_options(args)?;
    let set = overrides(args);
    if let Some(builtin) = args.builtin {
        let model = builtin_model(builtin, &set)?;
        check_builtin_settings(&model.simulation, args)?;
        return Ok(model);
    }
    let path = args.model.as_deref().context("a model file or --builtin")?;
    let file = MechanismFile::load_with(path, &set)?;
    for w in &file.warnings {
        note!("warning: {w}");
    }
    let sys = mstar::run::lookup(&file.mechanism);
    let columns_error = file
        .output
        .columns
        .as_ref()
        .and(file.output.columns_error(""));
    Ok(Loaded {
        columns_error,
        label: path.display().to_string(),
        u0: sys.initial_position(),
        v0: sys.initial_velocity(),
        every: file.output.every,
        every_time: file.output.every_time,
        sensors: file.output.sensors,
        columns: file.output.columns,
        simulation: file.simulation,
        system: Model::Named(Box::new(file.mechanism)),
    })
}

/// The parameters of `--sensitivity`, read from the model file (with the
/// run's overrides). Refused (usage errors, exit 2) with a built-in model,
/// adaptive steps (the step sizes would depend on the parameter), output
/// at fixed times (rows interpolated between steps) and redundant
/// constraints solved on a subset of rows.
///
/// # Errors
/// [`crate::output::Usage`] for those; [`mstar::file::FileError`] for a key
/// that names no number of the file.
fn sensitivity_parameters(
    args: &RunArgs,
    config: &mstar::Config,
    redundant: bool,
    every_time: Option<f64>,
) -> Result<Vec<FileParameter>> {
    if args.sensitivity.is_empty() {
        return Ok(Vec::new());
    }
    let refuse = |why: &str| Err(crate::output::usage(format!("--sensitivity {why}")));
    let Some(path) = args.model.as_deref() else {
        return refuse("needs a model file (its keys are the parameters), not --builtin");
    };
    if config.error.mode == mstar::StepMode::Adaptive {
        return refuse(
            "needs fixed steps: with adaptive steps the step sizes depend on the parameter; \
             drop --adaptive (or error_control = \"adaptive\") and choose h",
        );
    }
    if every_time.is_some() {
        return refuse(
            "writes the steps' own sensitivities: drop --output-every, and in place of \
             [output] every_time write rows every n steps ([output] every; on the command \
             line --set output.every=1, which replaces every_time)",
        );
    }
    if redundant {
        return refuse(
            "does not handle redundant constraints solved on a subset of rows yet; remove the \
             redundant joints",
        );
    }
    let set = overrides(args);
    let mut params = Vec::with_capacity(args.sensitivity.len());
    let mut file = FileParameters::new(path, &set);
    for key in &args.sensitivity {
        let param = file
            .parameter(key)
            .with_context(|| format!("--sensitivity {key}"))?;
        if params
            .iter()
            .any(|p: &FileParameter| p.name() == param.name())
        {
            return refuse(&format!("{key}: the key is given twice"));
        }
        params.push(param);
    }
    Ok(params)
}

/// The `--set` overrides of the run: `--set` itself, then `--t-end`,
/// `--h`, `--rtol`, `--atol`, `--tol`, `--adaptive`, `--strict`.
fn overrides(args: &RunArgs) -> Vec<String> {
    let mut set = args.set.clone();
    set.extend(option_overrides(args).into_iter().map(|(_, a)| a));
    set
}

/// The overrides that options stand for, each with the option as given:
/// (`--atol 0`, `simulation.atol=0e0`).
fn option_overrides(args: &RunArgs) -> Vec<(String, String)> {
    let mut set = Vec::new();
    for (option, key, value) in [
        ("--t-end", "t_end", args.t_end),
        ("--h", "h", args.h),
        ("--rtol", "rtol", args.rtol),
        ("--atol", "atol", args.atol),
        ("--tol", "tol", args.tol),
    ] {
        if let Some(v) = value {
            let given = format!("{option} {}", Short(v));
            set.push((given, format!("simulation.{key}={v:e}")));
        }
    }
    for (flag, option, mode) in [
        (args.adaptive, "--adaptive", "adaptive"),
        (args.strict, "--strict", "strict"),
    ] {
        if flag {
            let assignment = format!("simulation.error_control={mode}");
            set.push((option.to_string(), assignment));
        }
    }
    set
}

/// How the command line gave `assignment`, one of [`overrides`]: the
/// option it stands for (`--atol 0`), else `--set ASSIGNMENT`.
fn as_given(args: &RunArgs, assignment: &str) -> String {
    if args.set.iter().any(|a| a == assignment) {
        return format!("--set {assignment}");
    }
    option_overrides(args)
        .into_iter()
        .find(|(_, a)| a == assignment)
        .map_or_else(|| format!("--set {assignment}"), |(given, _)| given)
}

/// `e` with an override that an option stands for named as the option
/// (`--atol 0: …`, not the `--set simulation.atol=0e0: …` the file reader
/// names).
fn named_as_given(mut e: anyhow::Error, args: &RunArgs) -> anyhow::Error {
    if let Some(fe) = e.downcast_mut::<mstar::file::FileError>() {
        for (given, assignment) in option_overrides(args) {
            let generated = format!("--set {assignment}: ");
            if let Some(rest) = fe.message.strip_prefix(&generated)
                && !args.set.contains(&assignment)
            {
                fe.message = format!("{given}: {rest}");
                break;
            }
        }
    }
    e
}

/// Refuses a command-line value out of range, naming the option (before
/// it becomes a `--set` of the model file, which would blame the file).
///
/// # Errors
/// [`crate::output::Usage`].
fn check_options(args: &RunArgs) -> Result<()> {
    let positive = [
        ("--t-end", args.t_end),
        ("--h", args.h),
        ("--tol", args.tol),
        ("--output-every", args.output_every),
    ];
    for (option, value) in positive {
        if let Some(v) = value
            && !(v > 0.0 && v.is_finite())
        {
            return Err(crate::output::usage(format!(
                "{option} must be a finite positive number (got {})",
                Short(v)
            )));
        }
    }
    for (option, value) in [("--rtol", args.rtol), ("--atol", args.atol)] {
        if let Some(v) = value
            && !(v >= 0.0 && v.is_finite())
        {
            return Err(crate::output::usage(format!(
                "{option} must be a finite number ≥ 0 (got {})",
                Short(v)
            )));
        }
    }
    let all = positive
        .into_iter()
        .chain([("--rtol", args.rtol), ("--atol", args.atol)]);
    for (option, value) in all {
        if let Some(v) = value
            && v > MAX_MAGNITUDE
        {
            return Err(crate::output::usage(format!(
                "{option} {} is out of range: at most 1e100, as every number of a model file \
                 (products of larger values overflow double precision)",
                Short(v)
            )));
        }
    }
    Ok(())
}

/// The smallest relative tolerance of the error estimate: below it, the
/// estimate is round-off (double precision's 2.2e-16 times the few hundred
/// operations of a step).
const RTOL_MIN: f64 = 1e-14;

/// Refuses an error tolerance below round-off: `rtol` under [`RTOL_MIN`]
/// with an `atol` under `RTOL_MIN` times the largest initial coordinate
/// (at least 1): no step could meet it, and the advice the accuracy warning
/// works out from it would be meaningless.
///
/// # Errors
/// [`crate::output::Usage`] with tolerances that work.
fn check_tolerances(error: &mstar::ErrorControl, u0: &[f64]) -> Result<()> {
    let scale = u0.iter().fold(1.0_f64, |m, x| m.max(x.abs()));
    if error.rtol >= RTOL_MIN || error.atol >= RTOL_MIN * scale {
        return Ok(());
    }
    Err(crate::output::usage(format!(
        "the error tolerance rtol = {}, atol = {} is below what double precision resolves \
         (round-off is about 1e-14 of the coordinates): use --rtol {} or more, or --atol {} \
         or more (or [simulation] rtol, atol)",
        Short(error.rtol),
        Short(error.atol),
        Short(RTOL_MIN),
        crate::limits::round2(RTOL_MIN * scale, true)
    )))
}

/// One override of a built-in model: the command line's `--t-end`, `--h`,
/// `--tol`, `--rtol`, `--atol`, `--adaptive`, `--strict` (as
/// `simulation.<key>=…`), or `--set` of those keys; other keys are refused
/// with [`BUILTIN_TAKES`].
fn builtin_setting(simulation: &mut Simulation, assignment: &str) -> Result<()> {
    builtin_value(simulation, assignment).with_context(|| format!("--set {assignment}"))
}

/// What a built-in model takes: the keys [`builtin_value`] sets, and the
/// options that do not change the model (`run_model` reads them alike for
/// a file and a built-in).
const BUILTIN_TAKES: &str = "a built-in model has no model file: --set takes simulation.t_end, \
     simulation.h, simulation.tol, simulation.rtol, simulation.atol and \
     simulation.error_control only (as --t-end, --h, --tol, --rtol, --atol, --adaptive and \
     --strict set them); beside those, it takes --out, --columns and --output-every";

/// [`builtin_setting`]'s work: the value of `assignment` in `simulation`.
fn builtin_value(simulation: &mut Simulation, assignment: &str) -> Result<()> {
    let (key, value) = assignment.split_once('=').unwrap_or((assignment, ""));
    let (key, value) = (key.trim(), value.trim());
    if !BUILTIN_KEYS.contains(&key) {
        bail!("{BUILTIN_TAKES}");
    }
    if key == "simulation.error_control" {
        simulation.error_control = Some(match value {
            "adaptive" => mstar::file::ErrorControlChoice::Adaptive,
            "strict" => mstar::file::ErrorControlChoice::Strict,
            "monitor" => mstar::file::ErrorControlChoice::Monitor,
            _ => bail!("{key}: expected monitor, strict or adaptive, got '{value}'"),
        });
        return Ok(());
    }
    let number: f64 = value
        .parse()
        .ok()
        .filter(|v: &f64| v.is_finite() && *v >= 0.0)
        .with_context(|| format!("{key}: expected a number ≥ 0, got '{value}'"))?;
    let positive = || -> Result<f64> {
        if number > 0.0 {
            Ok(number)
        } else {
            bail!("{key}: expected a positive number, got '{value}'")
        }
    };
    match key {
        "simulation.t_end" => simulation.t_end = Some(positive()?),
        "simulation.h" => simulation.h = Some(positive()?),
        "simulation.tol" => simulation.tol = Some(positive()?),
        "simulation.rtol" => simulation.rtol = Some(number),
        _ => simulation.atol = Some(number),
    }
    Ok(())
}

/// The keys of `[simulation]` a built-in model takes ([`builtin_value`]).
const BUILTIN_KEYS: [&str; 6] = [
    "simulation.t_end",
    "simulation.h",
    "simulation.tol",
    "simulation.rtol",
    "simulation.atol",
    "simulation.error_control",
];

/// Refuses a built-in model's settings (`simulation`, with the command
/// line's overrides) that the integrator refuses, naming the override to
/// blame: the last one given whose default makes the settings pass, else
/// the last one given.
///
/// # Errors
/// [`mstar::run::RunError::Settings`] (exit 2), with the override as given
/// (`--set simulation.tol=2`, `--atol 0`).
fn check_builtin_settings(simulation: &Simulation, args: &RunArgs) -> Result<()> {
    let Err(e) = mstar::run::config(simulation) else {
        return Ok(());
    };
    let set = overrides(args);
    let passes_without = |assignment: &&String| {
        let mut s = simulation.clone();
        match assignment.split_once('=').map(|(k, _)| k.trim()) {
            Some("simulation.tol") => s.tol = None,
            Some("simulation.rtol") => s.rtol = None,
            Some("simulation.atol") => s.atol = None,
            Some("simulation.error_control") => s.error_control = None,
            _ => return false,
        }
        mstar::run::config(&s).is_ok()
    };
    let blamed = set.iter().rev().find(passes_without).or(set.last());
    let e = anyhow::Error::from(mstar::run::RunError::Settings(e));
    Err(match blamed {
        Some(assignment) => e.context(as_given(args, assignment)),
        None => e,
    })
}

/// A built-in model with its defaults and the command line's overrides
/// ([`builtin_setting`]).
fn builtin_model(builtin: Builtin, set: &[String]) -> Result<Loaded> {
    let mut simulation = Simulation::default();
    for assignment in set {
        builtin_setting(&mut simulation, assignment)?;
    }
    Ok(match builtin {
        Builtin::Pendulum => {
            let run = PendulumRun::standard();
            let sys = run.system();
            simulation.t_end = simulation.t_end.or(Some(run.t_end));
            simulation.h = simulation.h.or(Some(run.config.h));
            Loaded {
                label: "built-in pendulum".to_string(),
                u0: sys.position(&[run.theta0]),
                v0: sys.velocity(&[run.theta0], &[run.omega0]),
                system: Model::Other(Box::new(sys)),
                simulation,
                every: 1,
                every_time: None,
                sensors: Vec::new(),
                columns: None,
                columns_error: None,
            }
        }
        Builtin::Chain => {
            let sys = mstar::planar::bar_chain(10);
            Loaded {
                label: "built-in 10-bar chain".to_string(),
                u0: sys.initial_position(),
                v0: sys.initial_velocity(),
                system: Model::Named(Box::new(Mechanism::Planar(sys))),
                simulation,
                every: 1,
                every_time: None,
                sensors: Vec::new(),
                columns: None,
                columns_error: None,
            }
        }
    })
}

/// What `mstar run` does with every sample: the CSV file and the figures of
/// the summary ([`mstar::record::Recorder`]), and the progress bar.
struct RunOutput<'a> {
    recorder: mstar::record::Recorder<'a>,
    t_end: f64,
    progress: ProgressBar,
    shown: bool,
    /// The bar's last position, in thousandths of `t_end`.
    position: Option<u64>,
    /// Steps observed (the clock is read every 128th).
    observed: u32,
    start: Instant,
}

impl<'a> RunOutput<'a> {
    fn new(
        stream: Option<csv::CsvStream>,
        columns: Option<&'a dyn Columns>,
        (every, grid): (usize, crate::output::Grid),
        t_end: f64,
    ) -> Self {
        let progress = ProgressBar::with_draw_target(Some(1000), ProgressDrawTarget::hidden());
        progress.set_style(
            ProgressStyle::with_template("{bar:40} t = {msg} s [{elapsed_precise}, {eta} left]")
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        let rows = mstar::record::Rows { every, grid };
        Self {
            recorder: mstar::record::Recorder::new(stream, columns, rows, t_end),
            t_end,
            progress,
            shown: false,
            position: None,
            observed: 0,
            start: Instant::now(),
        }
    }
}

impl Observer for RunOutput<'_> {
    fn observe(&mut self, s: &SampleRef<'_>) {
        self.recorder.observe(s);
        if let Some(stream) = self.recorder.stream() {
            crate::output::watch(stream);
        }
        // A bar on standard error for runs longer than a second (indicatif
        // draws nothing when it is not a terminal). The clock is read at the
        // steps 1, 2, 4, …, 128 and every 128th after: at every step it took
        // 4–5 % of a small model's run.
        self.observed = self.observed.wrapping_add(1);
        if !self.shown
            && (self.observed.is_power_of_two() || self.observed.is_multiple_of(128))
            && self.start.elapsed().as_secs_f64() > 1.0
        {
            self.progress.set_draw_target(ProgressDrawTarget::stderr());
            self.shown = true;
        }
        // Redrawn when the position moves (a thousandth of the run), not at
        // every step: the message is a formatted number.
        let position = (1000.0 * s.t / self.t_end) as u64;
        if self.shown && self.position != Some(position) {
            self.position = Some(position);
            self.progress.set_position(position);
            self.progress.set_message(format!("{:.4}", s.t));
        }
    }
}

fn print_summary(st: mstar::RunStats, t: f64, out: &RunOutput<'_>, wall: f64) {
    let steps = st.steps.max(1) as f64;
    say!("t reached: {} s", Short(t));
    // Iterations count every attempt, the maximum accepted steps only.
    let per_step = if st.steps == 0 {
        "no step accepted".to_string()
    } else {
        format!(
            "{:.2} per accepted step, at most {} in one",
            st.iterations as f64 / steps,
            st.max_iterations
        )
    };
    say!(
        "steps: {} accepted, {} rejected; Newton iterations: {} ({per_step}); factorizations: {}",
        st.steps,
        st.rejected,
        st.iterations,
        st.factorizations
    );
    say!(
        "max ‖Φ‖∞ = {:.3e}; energy drift max |E − E₀| = {:.3e} J",
        out.recorder.max_constraint(),
        out.recorder.energy_drift()
    );
    say!(
        "wall time: {wall:.3} s ({:.2} µs per step)",
        wall * 1e6 / steps
    );
}
