//! A model to run: a model file (a path or TOML text) or a planar builder's
//! system, with its `[simulation]`; runs and checks as `mstar run` and
//! `mstar check` do them.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use mstar::System;
use mstar::columns::{Columns, ReactionColumns};
use mstar::file::{FileError, Format, Mechanism, MechanismFile, Simulation};
use mstar::model::sensor::Sensor;
use mstar::newmark::Parameterized;
use mstar::run::{CheckReport, RunError};
use mstar::sensitivity::{Chained, FileParameter, FileParameters, SensitivityColumns};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::collect::{Collect, Extra, constraint_names, extra_columns, stats_dict};
use crate::{IntegrationError, ModelError};

/// Where a model came from: what a run with settings re-reads.
#[derive(Debug)]
enum Source {
    /// A model file (TOML, or JSON by its `.json` extension).
    Path(PathBuf),
    /// TOML text.
    Text(String),
    /// A planar builder (`[simulation]` has its defaults).
    Built,
}

/// A model: its mechanism, `[simulation]` settings and where it came from.
#[pyclass(module = "mstar._native", frozen)]
#[derive(Debug)]
pub(crate) struct NativeModel {
    source: Source,
    /// What names the model in messages (the path as given).
    origin: String,
    mechanism: Mechanism,
    simulation: Simulation,
    /// The model file's `[[sensor]]`s (none for a builder's model).
    sensors: Vec<Sensor>,
    warnings: Vec<String>,
}

fn model_error(e: &FileError) -> PyErr {
    ModelError::new_err(crate::message(e))
}

/// Reads the model file at `path` (TOML, or JSON by its `.json` extension).
#[pyfunction]
pub(crate) fn load_path(path: PathBuf) -> PyResult<NativeModel> {
    let file = MechanismFile::load_with(&path, &[]).map_err(|e| model_error(&e))?;
    Ok(NativeModel::of_file(
        path.display().to_string(),
        Source::Path(path),
        file,
    ))
}

/// Reads a model from TOML text (named `<string>` in messages).
#[pyfunction]
pub(crate) fn load_text(text: String) -> PyResult<NativeModel> {
    let origin = "<string>".to_string();
    let file = MechanismFile::parse_with(&text, &origin, Format::Toml, &[])
        .map_err(|e| model_error(&e))?;
    Ok(NativeModel::of_file(origin, Source::Text(text), file))
}

impl NativeModel {
    fn of_file(origin: String, source: Source, file: MechanismFile) -> Self {
        Self {
            source,
            origin,
            mechanism: file.mechanism,
            simulation: file.simulation,
            sensors: file.output.sensors,
            warnings: file.warnings,
        }
    }

    /// A planar builder's system, with the default settings.
    pub(crate) fn built(system: mstar::planar::PlanarSystem) -> Self {
        Self {
            source: Source::Built,
            origin: "<builder>".to_string(),
            mechanism: Mechanism::Planar(system),
            simulation: Simulation::default(),
            sensors: Vec::new(),
            warnings: Vec::new(),
        }
    }

    /// A spatial builder's system, with the default settings.
    pub(crate) fn built_spatial(system: mstar::model::spatial::SpatialSystem) -> Self {
        Self {
            source: Source::Built,
            origin: "<builder>".to_string(),
            mechanism: Mechanism::Spatial(system),
            simulation: Simulation::default(),
            sensors: Vec::new(),
            warnings: Vec::new(),
        }
    }

    /// The settings with `overrides` (`simulation.key=value`) applied, read
    /// as `--set` reads them, and the mechanism read again when they change
    /// it (`None`: this one).
    fn settings(&self, overrides: &[String]) -> Result<(Option<Mechanism>, Simulation), FileError> {
        if overrides.is_empty() {
            return Ok((None, self.simulation.clone()));
        }
        let file = match &self.source {
            Source::Path(path) => MechanismFile::load_with(path, overrides)?,
            Source::Text(text) => {
                MechanismFile::parse_with(text, &self.origin, Format::Toml, overrides)?
            }
            Source::Built => {
                return Ok((None, Simulation::with_overrides(&self.origin, overrides)?));
            }
        };
        Ok((Some(file.mechanism), file.simulation))
    }

    /// The model-file keys `keys` as parameters of forward sensitivities
    /// (`mstar run --sensitivity`), read with `overrides`.
    ///
    /// # Errors
    /// `ModelError` for a model not read from a file, a key that names no
    /// number of the file (with the closest), or a key given twice.
    fn parameters(&self, overrides: &[String], keys: &[String]) -> PyResult<Vec<FileParameter>> {
        if keys.is_empty() {
            return Ok(Vec::new());
        }
        let Source::Path(path) = &self.source else {
            return Err(ModelError::new_err(format!(
                "{}: sensitivities need a model read from a file (its keys are the parameters); save the text to a .toml file and load that",
                self.origin
            )));
        };
        let mut params: Vec<FileParameter> = Vec::with_capacity(keys.len());
        let mut file = FileParameters::new(path, overrides);
        for (i, key) in keys.iter().enumerate() {
            if keys[..i].iter().any(|k| k.trim() == key.trim()) {
                return Err(ModelError::new_err(format!(
                    "sensitivities: '{key}' is given twice"
                )));
            }
            params.push(file.parameter(key).map_err(|e| model_error(&e))?);
        }
        Ok(params)
    }
}

/// Asks Python every 50 ms, with the GIL taken back briefly, whether a
/// signal handler raised (Ctrl-C: `KeyboardInterrupt`).
struct Poll<'a> {
    last: Instant,
    raised: &'a mut Option<PyErr>,
}

impl Poll<'_> {
    const EVERY: Duration = Duration::from_millis(50);

    fn stop(&mut self) -> bool {
        if self.last.elapsed() < Self::EVERY {
            return false;
        }
        self.last = Instant::now();
        match Python::attach(|py| py.check_signals()) {
            Ok(()) => false,
            Err(e) => {
                *self.raised = Some(e);
                true
            }
        }
    }
}

#[pymethods]
impl NativeModel {
    /// What names the model in messages: the path as given, `<string>` or
    /// `<builder>`.
    #[getter]
    fn origin(&self) -> &str {
        &self.origin
    }

    /// `"planar"` or `"spatial"`.
    #[getter]
    fn kind(&self) -> &'static str {
        match self.mechanism {
            Mechanism::Planar(_) => "planar",
            Mechanism::Spatial(_) => "spatial",
        }
    }

    /// The coordinates' names (`body.x`, `body.theta`, ...).
    #[getter]
    fn coords(&self) -> Vec<String> {
        mstar::model::coord_names(self.mechanism.system())
    }

    /// The constraint rows' names.
    #[getter]
    fn constraints(&self) -> Vec<String> {
        constraint_names(self.mechanism.system())
    }

    /// The reader's warnings (`mstar run` prints them as `warning: ...`).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.warnings.clone()
    }

    /// `mstar check`'s findings with the settings `overrides`.
    fn check<'py>(&self, py: Python<'py>, overrides: Vec<String>) -> PyResult<Bound<'py, PyDict>> {
        let (fresh, sim) = self.settings(&overrides).map_err(|e| model_error(&e))?;
        refuse_placed(&sim)?;
        let mechanism = fresh.as_ref().unwrap_or(&self.mechanism);
        let (config, _) = mstar::run::config(&sim)
            .map_err(|e| ModelError::new_err(format!("{}: {e}", self.origin)))?;
        let redundant = sim.redundant.unwrap_or_default();
        let report =
            py.detach(|| mstar::run::check(mstar::run::lookup(mechanism), &config, redundant));
        // A KKT solver that does not fit the model, as `mstar check` says.
        let config_refusal = mstar::placed::kkt_refusal(&report, &sim, &self.origin);
        // As `mstar check`'s refusal (the violation first when the pose is
        // far from a joint; drivers that contradict the others).
        let sys = mstar::run::lookup(mechanism);
        let refused = (!report.redundant.is_empty() && !report.minimum_norm).then(|| {
            let e = RunError::redundant_at(report.redundant.clone(), sys, &sys.initial_position());
            format!("{}: {e}", self.origin)
        });
        check_dict(py, &report, refused.or(config_refusal))
    }

    /// Runs the model with the settings `overrides`, GIL released: a dict of
    /// arrays and `stats`. On a failure or Ctrl-C, the exception carries the
    /// samples so far as `partial` (such a dict).
    #[pyo3(signature = (overrides, sensitivities = Vec::new()))]
    fn run<'py>(
        &self,
        py: Python<'py>,
        overrides: Vec<String>,
        sensitivities: Vec<String>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let (fresh, sim) = self.settings(&overrides).map_err(|e| model_error(&e))?;
        refuse_placed(&sim)?;
        let params = self.parameters(&overrides, &sensitivities)?;
        let mechanism = fresh.as_ref().unwrap_or(&self.mechanism);
        let sys = mechanism.system();
        let mut collect = Collect::new(sys.n_coords(), sys.n_constraints());
        if let Some(rows) = expected_rows(&sim) {
            collect.reserve(rows);
        }
        let mut raised = None;
        // (Checked here, made again where the run is: not `Sync`.)
        extra_columns(mechanism, &self.sensors)
            .map_err(|e| ModelError::new_err(format!("{}: {e}", self.origin)))?;
        let sensors = &self.sensors;
        // The start's notes about the state given (`mstar run` prints them).
        let mut notes = Vec::new();
        let (outcome, extra_names) = py.detach(|| {
            let mut poll = Poll {
                last: Instant::now(),
                raised: &mut raised,
            };
            // (The reactions alone never: checked above.)
            let columns = extra_columns(mechanism, sensors)
                .unwrap_or_else(|_| Box::new(ReactionColumns::new(mstar::run::lookup(mechanism))));
            let sys = mstar::run::lookup(mechanism);
            let sens_columns = SensitivityColumns::new(sys, &sensitivities);
            let chained = Chained(Some(&*columns), &sens_columns);
            let mut observer = Extra {
                collect: &mut collect,
                columns: &chained,
            };
            let outcome = if params.is_empty() {
                mstar::run::simulate_noting(
                    sys,
                    &sim,
                    &mut observer,
                    &mut || poll.stop(),
                    &mut notes,
                )
            } else {
                let refs: Vec<&dyn Parameterized> =
                    params.iter().map(|p| p as &dyn Parameterized).collect();
                mstar::sensitivity::simulate_until(
                    sys,
                    &sim,
                    &refs,
                    &sens_columns,
                    &mut observer,
                    &mut || poll.stop(),
                    &mut notes,
                )
            };
            (outcome, chained.names())
        });
        let wall = collect.wall();
        let names = |d: &Bound<'py, PyDict>| -> PyResult<()> {
            d.set_item("coords", mstar::model::coord_names(sys))?;
            d.set_item("constraints", constraint_names(sys))?;
            // The standard columns' names as `mstar run --out` writes them.
            d.set_item("header", mstar::csv::header(sys))
        };
        let samples = collect.into_dict(py, extra_names)?;
        names(&samples)?;
        samples.set_item("notes", notes)?;
        let error = match outcome {
            Ok(stats) => {
                let stats_py = stats_dict(py, Some(&stats), wall)?;
                stats_py.set_item("warning", accuracy_warning(sys, &sim, &stats))?;
                samples.set_item("stats", stats_py)?;
                return Ok(samples);
            }
            Err(RunError::Settings(e)) => return Err(ModelError::new_err(e.to_string())),
            Err(RunError::Stopped { .. }) => raised.unwrap_or_else(|| {
                pyo3::exceptions::PyKeyboardInterrupt::new_err("the run was stopped")
            }),
            // The refusal of redundant constraints names the file, as
            // `mstar run`'s.
            Err(
                e @ (RunError::Redundant(_)
                | RunError::RedundantLarge(_)
                | RunError::RedundantDrivers(_)
                | RunError::RedundantAtViolatedPose { .. }),
            ) => IntegrationError::new_err(format!("{}: {}", self.origin, crate::message(&e))),
            Err(e) => IntegrationError::new_err(crate::message(&e)),
        };
        samples.set_item("stats", stats_dict(py, None, wall)?)?;
        error.value(py).setattr("partial", samples)?;
        Err(error)
    }

    /// The static equilibrium from the initial pose with `overrides`
    /// applied, as `mstar equilibrium` finds it: a one-sample run's dict
    /// with `equilibrium` (see `crate::equilibrium::solve`).
    fn equilibrium<'py>(
        &self,
        py: Python<'py>,
        overrides: Vec<String>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let (fresh, _) = self.settings(&overrides).map_err(|e| model_error(&e))?;
        let mechanism = fresh.as_ref().unwrap_or(&self.mechanism);
        crate::equilibrium::solve(py, mechanism, &self.sensors, &self.origin)
    }

    /// The lowest vibration modes about the state `about` names, with
    /// `overrides` applied, as `mstar modes` finds them (see
    /// `crate::modes::solve`).
    #[pyo3(signature = (overrides, count, about, method))]
    fn modes<'py>(
        &self,
        py: Python<'py>,
        overrides: Vec<String>,
        count: Option<usize>,
        about: &str,
        method: &str,
    ) -> PyResult<Bound<'py, PyDict>> {
        let (fresh, _) = self.settings(&overrides).map_err(|e| model_error(&e))?;
        let mechanism = fresh.as_ref().unwrap_or(&self.mechanism);
        crate::modes::solve(py, mechanism, &self.origin, count, about, method)
    }

    /// The gradient of `objective` (`final:COLUMN`, `sum:COLUMN` or
    /// `fit:COLUMN` with `measured`, one value per sample) over a run with
    /// respect to the model-file keys `params`, by the discrete adjoint
    /// (`mstar run --objective … --gradient …`), GIL released: `value`,
    /// `gradient` (key → dΨ/dp), `times`, `steps`.
    #[pyo3(signature = (overrides, objective, params, measured = None))]
    fn gradient<'py>(
        &self,
        py: Python<'py>,
        overrides: Vec<String>,
        objective: &str,
        params: Vec<String>,
        measured: Option<Vec<f64>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let (fresh, sim) = self.settings(&overrides).map_err(|e| model_error(&e))?;
        let mechanism = fresh.as_ref().unwrap_or(&self.mechanism);
        if params.is_empty() {
            return Err(ModelError::new_err(
                "gradient: give at least one key in params",
            ));
        }
        let parameters = self.parameters(&overrides, &params)?;
        let sys = mstar::run::lookup(mechanism);
        let objective = objective_of(sys, objective, measured)?;
        let found = py.detach(|| {
            let refs: Vec<&dyn Parameterized> =
                parameters.iter().map(|p| p as &dyn Parameterized).collect();
            mstar::sensitivity::gradient(sys, &sim, &refs, &objective, 1 << 30)
        });
        let g = found.map_err(|e| match e {
            RunError::Settings(e) => ModelError::new_err(format!("{}: {e}", self.origin)),
            e => IntegrationError::new_err(crate::message(&e)),
        })?;
        let d = PyDict::new(py);
        d.set_item("value", g.objective)?;
        let by_key = PyDict::new(py);
        for (k, v) in g.names.iter().zip(&g.values) {
            by_key.set_item(k, v)?;
        }
        d.set_item("gradient", by_key)?;
        d.set_item("times", g.times.clone())?;
        d.set_item("steps", g.steps)?;
        Ok(d)
    }

    /// The linear state-space model of the model file about the state
    /// `about` names (`mstar linearize`): its JSON text (the file `mstar
    /// linearize --out` writes) and the warnings on the way.
    #[pyo3(signature = (overrides, inputs, outputs, about))]
    fn linearize(
        &self,
        py: Python<'_>,
        overrides: Vec<String>,
        inputs: Vec<String>,
        outputs: Vec<String>,
        about: &str,
    ) -> PyResult<(String, Vec<String>)> {
        let about = match about {
            "equilibrium" => mstar::modes::About::Equilibrium,
            "initial" => mstar::modes::About::Initial,
            other => {
                return Err(pyo3::exceptions::PyValueError::new_err(format!(
                    "about: expected \"equilibrium\" or \"initial\", got {other:?}"
                )));
            }
        };
        let Source::Path(path) = &self.source else {
            return Err(ModelError::new_err(format!(
                "{}: a state-space model's inputs are keys of a model file; save the text to a .toml file and load that",
                self.origin
            )));
        };
        let request = mstar::linear::Request {
            about,
            inputs: &inputs,
            outputs: &outputs,
            overrides: &overrides,
        };
        let formed = py.detach(|| mstar::linear::from_file(path, &request));
        match formed {
            Ok(f) => Ok((f.model.to_json(), f.warnings)),
            Err(e @ mstar::linear::LinearError::NoEquilibrium(_)) => {
                Err(crate::EquilibriumError::new_err(format!(
                    "{}: {}",
                    self.origin,
                    crate::message(&e)
                )))
            }
            Err(e) => Err(ModelError::new_err(format!(
                "{}: {}",
                self.origin,
                crate::message(&e)
            ))),
        }
    }

    /// The model file's TOML text with the pose `u` as its initial pose,
    /// checked to be the same mechanism (`mstar equilibrium
    /// --write-model`).
    fn text_with_pose(&self, u: Vec<f64>) -> PyResult<String> {
        let text = match &self.source {
            Source::Text(text) => text.clone(),
            Source::Path(path) if is_toml(path) => std::fs::read_to_string(path)
                .map_err(|e| ModelError::new_err(format!("cannot read {}: {e}", path.display())))?,
            Source::Path(path) => {
                return Err(ModelError::new_err(format!(
                    "{}: only a TOML model file can be rewritten (a URDF with `mstar convert` first)",
                    path.display()
                )));
            }
            Source::Built => {
                return Err(ModelError::new_err(
                    "a builder's model has no model file to rewrite",
                ));
            }
        };
        crate::equilibrium::model_text(&self.mechanism, &text, &self.origin, &u)
    }
}

/// The objective `spec` (`final:COLUMN`, `sum:COLUMN`, `fit:COLUMN` with
/// `measured`) of `sys`.
///
/// # Errors
/// `ValueError` for a malformed objective or `measured` given or missing
/// wrongly; `ModelError` for a column that is not a state column.
fn objective_of(
    sys: &dyn System,
    spec: &str,
    measured: Option<Vec<f64>>,
) -> PyResult<mstar::newmark::Objective> {
    use mstar::newmark::Objective;
    let bad = || {
        pyo3::exceptions::PyValueError::new_err(format!(
            "objective: expected \"final:COLUMN\", \"sum:COLUMN\" or \"fit:COLUMN\" (with measured=), got {spec:?}"
        ))
    };
    let (kind, name) = spec.split_once(':').ok_or_else(bad)?;
    let name = name.trim();
    let column = mstar::sensitivity::state_column(sys, name).ok_or_else(|| {
        ModelError::new_err(format!(
            "objective: '{name}' is not a state column of this model: give a u:, v:, a: or lambda: column (e.g. u:{})",
            mstar::model::coord_names(sys).first().map_or("body.x", String::as_str)
        ))
    })?;
    match (kind.trim(), measured) {
        ("final", None) => Ok(Objective::Final(column)),
        ("sum", None) => Ok(Objective::Sum(column)),
        ("fit", Some(measured)) => Ok(Objective::Fit { column, measured }),
        ("fit", None) => Err(pyo3::exceptions::PyValueError::new_err(
            "objective: \"fit:…\" needs measured=, one value per sample of the run (its start and every step)",
        )),
        ("final" | "sum", Some(_)) => Err(pyo3::exceptions::PyValueError::new_err(
            "measured: only a \"fit:…\" objective takes measured values",
        )),
        _ => Err(bad()),
    }
}

/// Whether `path` names a TOML file (by its extension).
fn is_toml(path: &std::path::Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("toml"))
}

/// Settings the integrator refuses, blamed on the key that gives them as
/// `mstar run` blames them ([`mstar::placed::config`]); those no key is to
/// blame for are left to the run's own error.
fn refuse_placed(sim: &Simulation) -> PyResult<()> {
    match mstar::placed::config(sim) {
        Err(mstar::placed::Refusal::Placed(e)) => Err(model_error(&e)),
        _ => Ok(()),
    }
}

/// The warning `mstar run` prints (and exits 3 for) when a run's steps went
/// beyond the error tolerance or its energy drifted beyond it: one line
/// each, after `warning: ` (`None`: within the tolerance).
fn accuracy_warning(sys: &dyn System, sim: &Simulation, stats: &mstar::RunStats) -> Option<String> {
    let (config, _) = mstar::run::config(sim).ok()?;
    mstar::accuracy::warning(stats, &config, &|i| sys.coord_name(i), true)
}

/// The samples of a run with a fixed step size (`None` with adaptive steps,
/// or when there would be more than 10⁸).
fn expected_rows(sim: &Simulation) -> Option<usize> {
    let (config, t_end) = mstar::run::config(sim).ok()?;
    if config.error.mode == mstar::newmark::StepMode::Adaptive {
        return None;
    }
    let rows = (t_end / config.h).ceil() + 2.0;
    (rows.is_finite() && rows < 1e8).then_some(rows as usize)
}

/// [`CheckReport`] as a dict; `report`: the text `mstar check` prints;
/// `error`: the refusal of redundant constraints, else of a KKT solver
/// that does not fit the model (placed at its key), as `mstar check` says.
fn check_dict<'py>(
    py: Python<'py>,
    r: &CheckReport,
    error: Option<String>,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("coordinates", r.coordinates)?;
    d.set_item("constraints", r.constraints)?;
    d.set_item("rank", r.rank)?;
    d.set_item("degrees_of_freedom", r.degrees_of_freedom())?;
    d.set_item("redundant_constraints", &r.redundant)?;
    d.set_item("minimum_norm", r.minimum_norm)?;
    d.set_item("position_violation", r.position_violation.clone())?;
    d.set_item("velocity_violation", r.velocity_violation.clone())?;
    let projection = r.projection.clone().map(|[position, velocity]| {
        let d = PyDict::new(py);
        d.set_item("position", position)?;
        d.set_item("velocity", velocity)?;
        Ok::<_, PyErr>(d)
    });
    d.set_item("projection", projection.transpose()?)?;
    d.set_item("start_error", r.start_error.clone())?;
    d.set_item("can_run", r.can_run())?;
    d.set_item("error", error)?;
    d.set_item("report", r.to_string())?;
    Ok(d)
}
