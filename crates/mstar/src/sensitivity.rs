//! Parameter sensitivities of a model file's run (`docs/analysis.md`,
//! "Parameter sensitivities"): a numeric key of the file as a parameter
//! ([`FileParameter`], the file read again with `--set KEY=VALUE` at
//! `p ± h_p`), and the output columns `d(<column>)/d(<key>)`
//! ([`SensitivityColumns`]). The sensitivities themselves are
//! [`mstar_newmark::Sensitivities`].

use std::cell::RefCell;
use std::path::Path;
use std::sync::Arc;

use mstar_file::{FileError, Mechanism, ModelDocument};
use mstar_model::{SampleRef, System};
use mstar_newmark::{Parameterized, Sensitivities, Variant};

use crate::columns::Columns;

/// A numeric key of a model file as a parameter of its model.
#[derive(Clone, Debug)]
pub struct FileParameter {
    document: Arc<ModelDocument>,
    key: String,
    value: f64,
}

impl FileParameter {
    /// The key `key` of the model file at `path` with `overrides` (`--set`
    /// assignments) applied, its value read from the file. For several
    /// keys of one file, [`in_document`](Self::in_document) reads the file
    /// once.
    ///
    /// # Errors
    /// [`FileError`] for a file that cannot be read, a key that names no
    /// number (with the closest numeric keys), or a key of `[simulation]`
    /// or `[output]` ([`mstar_file::MechanismFile::parameter`]).
    pub fn new(path: &Path, overrides: &[String], key: &str) -> Result<Self, FileError> {
        let document = Arc::new(ModelDocument::load(path, overrides)?);
        Self::in_document(&document, key)
    }

    /// The key `key` of a model file already parsed (with its overrides):
    /// the parameters of one run share the document, and their models at
    /// `p ± h_p` are read from it without parsing the file again.
    ///
    /// # Errors
    /// As [`new`](Self::new), but for the document's reading.
    pub fn in_document(document: &Arc<ModelDocument>, key: &str) -> Result<Self, FileError> {
        let key = key.trim();
        let value = document.parameter(key)?;
        Ok(Self {
            document: Arc::clone(document),
            key: key.to_string(),
            value,
        })
    }

    /// The override that sets the key to `value`; `{:?}` writes the
    /// shortest decimal that reads back as `value`.
    fn set(&self, value: f64) -> [String; 1] {
        [format!("{}={value:?}", self.key)]
    }
}

/// The parameters of one model file, sharing its document: the file is
/// read and parsed at the first [`parameter`](Self::parameter), once for
/// all of them (what `mstar run --sensitivity`/`--gradient` with many keys
/// does).
#[derive(Debug)]
pub struct FileParameters {
    path: std::path::PathBuf,
    overrides: Vec<String>,
    document: Option<Arc<ModelDocument>>,
}

impl FileParameters {
    /// The parameters of the model file at `path` with `overrides`.
    #[must_use]
    pub fn new(path: &Path, overrides: &[String]) -> Self {
        Self {
            path: path.to_path_buf(),
            overrides: overrides.to_vec(),
            document: None,
        }
    }

    /// The key `key` as a parameter ([`FileParameter::new`]).
    ///
    /// # Errors
    /// As [`FileParameter::new`].
    pub fn parameter(&mut self, key: &str) -> Result<FileParameter, FileError> {
        let document = match &self.document {
            Some(d) => d,
            None => self
                .document
                .insert(Arc::new(ModelDocument::load(&self.path, &self.overrides)?)),
        };
        FileParameter::in_document(document, key)
    }
}

/// A model file read at one value of a parameter.
struct FileVariant {
    mechanism: Mechanism,
    u0: Vec<f64>,
    v0: Vec<f64>,
}

impl Variant for FileVariant {
    fn system(&self) -> &dyn System {
        self.mechanism.system()
    }
    fn initial_position(&self) -> &[f64] {
        &self.u0
    }
    fn initial_velocity(&self) -> &[f64] {
        &self.v0
    }
}

impl Parameterized for FileParameter {
    fn name(&self) -> String {
        self.key.clone()
    }

    fn value(&self) -> f64 {
        self.value
    }

    fn at(&self, value: f64) -> Result<Box<dyn Variant>, String> {
        let file = self
            .document
            .read_with(&self.set(value))
            .map_err(|e| format!("the model at {} = {value:?}: {e}", self.key))?;
        let sys = crate::run::lookup(&file.mechanism);
        let (u0, v0) = (sys.initial_position(), sys.initial_velocity());
        Ok(Box::new(FileVariant {
            mechanism: file.mechanism,
            u0,
            v0,
        }))
    }

    /// A body's or point mass's `mass` and `inertia`, and every key of a
    /// joint, driver or force: the initial state is the bodies' own keys
    /// (`pose`, `velocity`, …), which these do not change.
    fn keeps_initial_state(&self) -> bool {
        let mut parts = self.key.split('.').map(str::trim);
        let (kind, field) = (parts.next(), parts.nth(1));
        match kind {
            Some("body" | "point_mass") => matches!(field, Some("mass" | "inertia")),
            Some("joint" | "driver" | "force") => true,
            _ => false,
        }
    }

    /// The key's element, the elements that refer to it and the bodies
    /// they act on ([`ModelDocument::element_model`]); `None` for a key of
    /// no element.
    fn local_at(&self, value: f64) -> Result<Option<Box<dyn Variant>>, String> {
        let file = self
            .document
            .element_model(&self.key, &self.set(value))
            .map_err(|e| format!("the model at {} = {value:?}: {e}", self.key))?;
        Ok(file.map(|file| {
            Box::new(FileVariant {
                mechanism: file.mechanism,
                u0: Vec::new(),
                v0: Vec::new(),
            }) as Box<dyn Variant>
        }))
    }
}

/// The columns `d(<column>)/d(<key>)` of every parameter, for the state's
/// columns `u:…`, `v:…`, `a:…` and `lambda:…` (in the order of
/// [`crate::csv::header`]). The values are the sensitivities last
/// [`set`](Self::set): a run sets them after every step, before the
/// sample is observed.
#[derive(Debug)]
pub struct SensitivityColumns {
    names: Vec<String>,
    values: RefCell<Vec<f64>>,
}

impl SensitivityColumns {
    /// The columns of `sys`'s state for the parameters `keys`.
    #[must_use]
    pub fn new<S: System + ?Sized>(sys: &S, keys: &[String]) -> Self {
        let header = crate::csv::header(sys);
        let state = &header[1..1 + 3 * sys.n_coords() + sys.n_constraints()];
        let names = keys
            .iter()
            .flat_map(|k| state.iter().map(move |c| format!("d({c})/d({k})")))
            .collect();
        Self {
            names,
            values: RefCell::new(Vec::new()),
        }
    }

    /// Takes the current sensitivities.
    pub fn set(&self, sens: &Sensitivities) {
        let mut values = self.values.borrow_mut();
        values.clear();
        for k in 0..sens.len() {
            for part in [sens.u(k), sens.v(k), sens.a(k), sens.lambda(k)] {
                values.extend_from_slice(part);
            }
        }
    }
}

impl Columns for SensitivityColumns {
    fn names(&self) -> Vec<String> {
        self.names.clone()
    }

    fn count(&self) -> usize {
        self.names.len()
    }

    /// The sensitivities last set (NaN before any).
    fn values(&self, _s: &SampleRef<'_>, out: &mut Vec<f64>) {
        let values = self.values.borrow();
        if values.len() == self.names.len() {
            out.extend_from_slice(&values);
        } else {
            out.extend(std::iter::repeat_n(f64::NAN, self.names.len()));
        }
    }
}

/// Two sets of columns, one after the other (a model's reactions and
/// sensors, then sensitivities).
pub struct Chained<'a>(pub Option<&'a dyn Columns>, pub &'a dyn Columns);

impl Columns for Chained<'_> {
    fn names(&self) -> Vec<String> {
        let mut names = self.0.map(Columns::names).unwrap_or_default();
        names.extend(self.1.names());
        names
    }

    fn count(&self) -> usize {
        self.0.map_or(0, Columns::count) + self.1.count()
    }

    fn values(&self, s: &SampleRef<'_>, out: &mut Vec<f64>) {
        if let Some(first) = self.0 {
            first.values(s, out);
        }
        self.1.values(s, out);
    }

    fn values_wanted(&self, s: &SampleRef<'_>, wanted: &[bool], out: &mut Vec<f64>) {
        let first = self.0.map_or(0, Columns::count);
        let (a, b) = wanted.split_at(first.min(wanted.len()));
        if let Some(c) = self.0 {
            c.values_wanted(s, a, out);
        }
        self.1.values_wanted(s, b, out);
    }
}

/// Runs `sys` with the settings `sim` as [`crate::run::simulate_until`]
/// does, carrying the forward sensitivities to `params` along
/// (`docs/analysis.md`, "Parameter sensitivities"): after every step
/// `columns` holds them, so an observer that reads `columns` (e.g. through
/// [`Chained`]) sees each sample's own. What `mstar run --sensitivity` and
/// Python's `model.run(sensitivities=…)` do. The start's notes about the
/// state given go to `notes`, as [`crate::run::simulate_noting`]'s.
///
/// # Errors
/// [`crate::run::RunError::Settings`] for adaptive steps (the step sizes would depend
/// on the parameters) or redundant constraints solved on a subset of rows;
/// otherwise as [`crate::run::simulate_until`].
pub fn simulate_until<S: crate::run::ModelLookup + ?Sized>(
    sys: &S,
    sim: &mstar_file::Simulation,
    params: &[&dyn Parameterized],
    columns: &SensitivityColumns,
    observer: &mut dyn mstar_newmark::Observer,
    stop: &mut dyn FnMut() -> bool,
    notes: &mut Vec<String>,
) -> Result<mstar_newmark::RunStats, crate::run::RunError> {
    use crate::run::{RunError, SettingsError};
    let refuse = |why: &str| {
        RunError::Settings(SettingsError::Refused(
            mstar_newmark::IntegrationError::Config(format!("sensitivities {why}")),
        ))
    };
    let (config, t_end) = crate::run::config(sim)?;
    if config.error.mode == mstar_newmark::StepMode::Adaptive {
        return Err(refuse(
            "need fixed steps: with adaptive steps the step sizes depend on the parameter; \
             use fixed steps (error_control = \"warn\" or \"strict\") and choose h",
        ));
    }
    let (u0, v0) = (sys.initial_position(), sys.initial_velocity());
    if crate::run::solve_rows(sys, &u0, sim.redundant.unwrap_or_default())?.is_some() {
        return Err(refuse(
            "do not handle redundant constraints solved on a subset of rows yet; remove the \
             redundant joints",
        ));
    }
    notes.extend(crate::run::far_start_note(sys));
    let mut integ = mstar_newmark::Integrator::new(sys, config, 0.0, &u0, &v0)?;
    notes.extend(crate::run::projection_notes(
        sys,
        integ.start_report(),
        &u0,
        &v0,
    ));
    let mut sens = integ.sensitivities(params)?;
    columns.set(&sens);
    observer.observe(&integ.view());
    if !t_end.is_finite() {
        return Err(refuse("need a finite t_end"));
    }
    while !integ.reached(t_end) {
        if stop() {
            return Err(RunError::Stopped { t: integ.time() });
        }
        integ.step_with(t_end, &mut sens)?;
        columns.set(&sens);
        observer.observe(&integ.view());
    }
    Ok(integ.stats())
}

/// The state column `name` of `sys` (`u:<coordinate>`, `v:…`, `a:…` or
/// `lambda:<row>`, as [`crate::csv::header`] names them) as an adjoint
/// objective's [`mstar_newmark::Column`]; `None` when `name` is no such
/// column.
#[must_use]
pub fn state_column<S: System + ?Sized>(sys: &S, name: &str) -> Option<mstar_newmark::Column> {
    use mstar_newmark::Column;
    let (n, m) = (sys.n_coords(), sys.n_constraints());
    let header = crate::csv::header(sys);
    let k = header[1..1 + 3 * n + m].iter().position(|c| c == name)?;
    Some(if k >= 3 * n {
        Column::Multiplier(k - 3 * n)
    } else if k >= 2 * n {
        Column::Acceleration(k - 2 * n)
    } else if k >= n {
        Column::Velocity(k - n)
    } else {
        Column::Position(k)
    })
}

/// The gradient of `objective` over a run of `sys` with the settings `sim`
/// with respect to `params`, by the discrete adjoint
/// ([`mstar_newmark::Integrator::gradient`]; `docs/analysis.md`, "Adjoint
/// gradients"), the states stored up to `memory_budget` bytes and
/// checkpointed beyond. What Python's `model.gradient(…)` runs.
///
/// # Errors
/// [`RunError::Settings`](crate::run::RunError::Settings) for adaptive
/// steps or redundant constraints solved on a subset of rows; the run's and
/// the adjoint's errors.
pub fn gradient<S: crate::run::ModelLookup + ?Sized>(
    sys: &S,
    sim: &mstar_file::Simulation,
    params: &[&dyn Parameterized],
    objective: &mstar_newmark::Objective,
    memory_budget: usize,
) -> Result<mstar_newmark::Gradient, crate::run::RunError> {
    use crate::run::{RunError, SettingsError};
    let refuse = |why: &str| {
        RunError::Settings(SettingsError::Refused(
            mstar_newmark::IntegrationError::Config(format!("the gradient {why}")),
        ))
    };
    let (config, t_end) = crate::run::config(sim)?;
    if config.error.mode == mstar_newmark::StepMode::Adaptive {
        return Err(refuse(
            "needs fixed steps: with adaptive steps the step sizes depend on the parameters; \
             use fixed steps (error_control = \"warn\" or \"strict\") and choose h",
        ));
    }
    let (u0, v0) = (sys.initial_position(), sys.initial_velocity());
    if crate::run::solve_rows(sys, &u0, sim.redundant.unwrap_or_default())?.is_some() {
        return Err(refuse(
            "does not handle redundant constraints solved on a subset of rows yet; remove the \
             redundant joints",
        ));
    }
    let mut integ = mstar_newmark::Integrator::new(sys, config, 0.0, &u0, &v0)?;
    let memory = mstar_newmark::Memory::Budget {
        bytes: memory_budget,
    };
    Ok(integ.gradient(t_end, params, objective, memory)?)
}
