//! `[simulation]` and `[output]`: how to integrate a model and what to write,
//! every key optional and checked where it is written, and the command
//! line's overrides of them.

use super::FileError;
use super::fields::{Doc, Fields, choice, count, number_in, string};
use super::node::{Entry, Node, Value};

/// The integration scheme of `[simulation] integrator`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IntegratorChoice {
    /// `"generalized-alpha"` (default): generalized-α with `rho`.
    GeneralizedAlpha,
    /// `"hht"`: Hilber-Hughes-Taylor with `alpha`.
    Hht,
    /// `"newmark"`: Newmark with `beta`, `gamma` (the paper's scheme).
    Newmark,
}

/// The Newton variant of `[simulation] newton`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum NewtonChoice {
    /// `"modified"`: reuse the factorization while it contracts.
    Modified,
    /// `"full"`: refactor at every iteration.
    Full,
    /// `"per-step"`: refactor at each step's first iteration, reuse within
    /// the step while it contracts.
    PerStep,
    /// `"auto"` (the default): `mstar_newmark::Newton::Automatic` (once per
    /// step with the Schur backends on a large model with cheap Jacobians,
    /// else modified).
    Auto,
}

/// What to do with redundant constraints, `[simulation] redundant`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum RedundantChoice {
    /// `"refuse"` (default): a model whose constraint equations are linearly
    /// dependent does not run; the error names the joints.
    #[default]
    Refuse,
    /// `"minimum-norm"`: the dependent rows are left out of the solve and the
    /// multipliers of all rows are the minimum-norm ones that give the same
    /// constraint forces.
    MinimumNorm,
}

/// What `[simulation] error_control` does with the local error estimate.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ErrorControlChoice {
    /// `"monitor"` (default): fixed step size `h`; a warning when the
    /// estimate exceeds the tolerance.
    #[default]
    Monitor,
    /// `"strict"`: fixed step size; a step beyond the tolerance is an error.
    Strict,
    /// `"adaptive"`: the step size follows the estimate (`h` is the first).
    Adaptive,
}

/// `[simulation]`: every key optional (defaults in `docs/model-format.md`,
/// applied by the program that runs the model).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Simulation {
    /// `t_end`, s (> 0).
    pub t_end: Option<f64>,
    /// `h`, the step size, s (> 0).
    pub h: Option<f64>,
    /// `h_min`, the smallest step size step control may take, s (in (0, h]).
    pub h_min: Option<f64>,
    /// `integrator`.
    pub integrator: Option<IntegratorChoice>,
    /// `rho`, generalized-α's spectral radius at infinite frequency, in [0, 1].
    pub rho: Option<f64>,
    /// `alpha`, HHT's α, in [−1/3, 0].
    pub alpha: Option<f64>,
    /// `beta`, Newmark's β (> 0).
    pub beta: Option<f64>,
    /// `gamma`, Newmark's γ (≥ ½).
    pub gamma: Option<f64>,
    /// `tol`, the relative Newton tolerance, in (0, 1).
    pub tol: Option<f64>,
    /// `max_iterations`, Newton iterations per step attempt (≥ 1).
    pub max_iterations: Option<usize>,
    /// `newton`.
    pub newton: Option<NewtonChoice>,
    /// `kkt`, the KKT solver by name (`auto`, `dense`, `lu`, `ldlt`, `schur`;
    /// checked by the program that runs the model).
    pub kkt: Option<String>,
    /// `redundant`.
    pub redundant: Option<RedundantChoice>,
    /// `rtol`, the local error estimate's relative tolerance (≥ 0).
    pub rtol: Option<f64>,
    /// `atol`, its absolute tolerance, m or rad (≥ 0).
    pub atol: Option<f64>,
    /// `error_control`.
    pub error_control: Option<ErrorControlChoice>,
    /// `h_max`, the largest step size of adaptive steps, s (≥ h).
    pub h_max: Option<f64>,
    /// `rotational_mass`, how a spatial model's rigid bodies form their
    /// rotational mass block (`"singular"`, the default, or
    /// `"regularized"`); spatial models only.
    pub rotational_mass: Option<mstar_model::spatial::RotationalMass>,
    /// Where each key given is written (a line of the file or a `--set`),
    /// for the errors found after reading: [`Simulation::error_at`].
    pub places: SettingPlaces,
}

/// Where the keys of a `[simulation]` are given: each key with an error
/// placed there whose message is what precedes the key's own (empty, or
/// `--set KEY=VALUE: ` for an override).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SettingPlaces(Vec<(String, FileError)>);

impl Simulation {
    /// An error about the value of `[simulation] key` found after reading
    /// (the integrator refuses it, a KKT solver of that name does not
    /// exist): `FILE:LINE:COLUMN: [simulation]: KEY: why`, or with the
    /// override that gave it; `None` when the key is not given.
    #[must_use]
    pub fn error_at(&self, key: &str, why: impl std::fmt::Display) -> Option<FileError> {
        let (_, at) = self.places.0.iter().find(|(k, _)| k == key)?;
        Some(FileError {
            message: format!("{}[simulation]: {key}: {why}", at.message),
            ..at.clone()
        })
    }

    /// Whether `[simulation] key` is given.
    #[must_use]
    pub fn is_given(&self, key: &str) -> bool {
        self.places.0.iter().any(|(k, _)| k == key)
    }
}

/// `[output]`, and the `[[sensor]]`s whose columns it writes.
#[derive(Clone, Debug, PartialEq)]
pub struct Output {
    /// `every`: write every n-th step (≥ 1; default 1).
    pub every: usize,
    /// `every_time`: write the state every this many seconds instead,
    /// interpolated within the steps (> 0).
    pub every_time: Option<f64>,
    /// `columns`: the columns to write, by name with `*` globs (`None`:
    /// every column).
    pub columns: Option<Vec<String>>,
    /// The `[[sensor]]`s, in file order.
    pub sensors: Vec<mstar_model::sensor::Sensor>,
    /// Where `columns` is in the file (an error with an empty message).
    columns_at: Option<FileError>,
}

impl Default for Output {
    fn default() -> Self {
        Self {
            every: 1,
            every_time: None,
            columns: None,
            sensors: Vec::new(),
            columns_at: None,
        }
    }
}

impl Output {
    /// An error about `[output] columns` found after reading (an entry names
    /// no column of the model): `FILE:LINE:COLUMN: [output]: columns: why`
    /// (or the override that gave it); `None` when the file does not give
    /// `columns`.
    #[must_use]
    pub fn columns_error(&self, why: impl std::fmt::Display) -> Option<FileError> {
        let at = self.columns_at.as_ref()?;
        Some(FileError {
            message: format!("{}[output]: columns: {why}", at.message),
            ..at.clone()
        })
    }
}

/// The keys of `[simulation]` (the last, `rotational_mass`, for spatial
/// files only).
const SIMULATION_KEYS: [&str; 18] = [
    "t_end",
    "h",
    "h_min",
    "integrator",
    "rho",
    "alpha",
    "beta",
    "gamma",
    "tol",
    "max_iterations",
    "newton",
    "kkt",
    "redundant",
    "rtol",
    "atol",
    "error_control",
    "h_max",
    "rotational_mass",
];

/// Reads `[simulation]` and `[output]` of the document `root`.
/// (`spatial`: the document is a spatial model, the only kind that takes
/// `rotational_mass`.)
pub(crate) fn read(
    doc: Doc<'_>,
    root: &Node,
    spatial: bool,
) -> Result<(Simulation, Output), FileError> {
    let Value::Table(entries) = &root.value else {
        return Ok((Simulation::default(), Output::default()));
    };
    let find = |key: &str| entries.iter().find(|e| e.key == key);
    let simulation = match find("simulation") {
        Some(e) => simulation(
            Fields::of(doc, &e.node, "[simulation]".to_string())?,
            spatial,
        )?,
        None => Simulation::default(),
    };
    let output = match find("output") {
        Some(e) => {
            let mut f = Fields::of(doc, &e.node, "[output]".to_string())?;
            let every = f.optional("every", count(1))?;
            let every_time = f.optional("every_time", number_in(|x| x > 0.0, "positive, in s"))?;
            if let (Some(_), Some(entry)) = (every, f.entry("every_time")) {
                return Err(f.bad(entry, "give either every (steps) or every_time (seconds)"));
            }
            let columns = f.optional("columns", column_patterns)?;
            let columns_at = f
                .places()
                .into_iter()
                .find_map(|(key, at)| (key == "columns").then_some(at));
            f.finish(&["every", "every_time", "columns"])?;
            Output {
                every: every.unwrap_or(1),
                every_time,
                columns,
                sensors: Vec::new(),
                columns_at,
            }
        }
        None => Output::default(),
    };
    Ok((simulation, output))
}

/// `[output] columns`: a non-empty array of non-empty names or globs.
fn column_patterns(node: &Node) -> Result<Vec<String>, String> {
    let items = super::fields::list(node)?;
    if items.is_empty() {
        return Err(
            "an empty list selects no column: leave `columns` out to write them all".into(),
        );
    }
    items
        .iter()
        .map(|item| match super::fields::string(item)? {
            "" => Err("a column name must not be empty".to_string()),
            name => Ok(name.to_string()),
        })
        .collect()
}

fn simulation(mut f: Fields<'_>, spatial: bool) -> Result<Simulation, FileError> {
    let positive = |unit: &'static str| number_in(|x| x > 0.0, unit);
    let s = Simulation {
        t_end: f.optional("t_end", positive("positive, in s"))?,
        h: f.optional("h", positive("positive, in s"))?,
        h_min: f.optional("h_min", positive("positive, in s"))?,
        integrator: f
            .optional(
                "integrator",
                choice(&["generalized-alpha", "hht", "newmark"]),
            )?
            .map(|c| match c {
                "hht" => IntegratorChoice::Hht,
                "newmark" => IntegratorChoice::Newmark,
                _ => IntegratorChoice::GeneralizedAlpha,
            }),
        rho: f.optional("rho", number_in(|x| (0.0..=1.0).contains(&x), "in [0, 1]"))?,
        alpha: f.optional(
            "alpha",
            number_in(|x| (-1.0 / 3.0..=0.0).contains(&x), "in [−1/3, 0]"),
        )?,
        beta: f.optional("beta", positive("positive"))?,
        gamma: f.optional(
            "gamma",
            number_in(|x| x >= 0.5, "at least 1/2 (below, Newmark is unstable)"),
        )?,
        tol: f.optional("tol", number_in(|x| x > 0.0 && x < 1.0, "in (0, 1)"))?,
        max_iterations: f.optional("max_iterations", count(1))?,
        newton: f
            .optional("newton", choice(&["auto", "modified", "full", "per-step"]))?
            .map(|c| match c {
                "full" => NewtonChoice::Full,
                "per-step" => NewtonChoice::PerStep,
                "modified" => NewtonChoice::Modified,
                _ => NewtonChoice::Auto,
            }),
        kkt: f.optional("kkt", string)?.map(str::to_string),
        redundant: f
            .optional("redundant", choice(&["refuse", "minimum-norm"]))?
            .map(|c| match c {
                "minimum-norm" => RedundantChoice::MinimumNorm,
                _ => RedundantChoice::Refuse,
            }),
        rtol: f.optional("rtol", number_in(|x| x >= 0.0, "at least 0"))?,
        atol: f.optional("atol", number_in(|x| x >= 0.0, "at least 0, in m or rad"))?,
        error_control: f
            .optional("error_control", choice(&["monitor", "strict", "adaptive"]))?
            .map(|c| match c {
                "strict" => ErrorControlChoice::Strict,
                "adaptive" => ErrorControlChoice::Adaptive,
                _ => ErrorControlChoice::Monitor,
            }),
        h_max: f.optional("h_max", positive("positive, in s"))?,
        rotational_mass: f
            .optional("rotational_mass", choice(&["singular", "regularized"]))?
            .map(|c| match c {
                "regularized" => mstar_model::spatial::RotationalMass::Regularized,
                _ => mstar_model::spatial::RotationalMass::Singular,
            }),
        places: SettingPlaces(f.places()),
    };
    if !spatial && let Some(e) = f.entry("rotational_mass") {
        return Err(f.bad(
            e,
            "applies to spatial models (format = \"mstar.spatial/1\"): a planar body's mass matrix is regular",
        ));
    }
    consistent(&mut f, &s)?;
    // (A planar file's list of keys leaves out the spatial one.)
    let keys = if spatial {
        &SIMULATION_KEYS[..]
    } else {
        &SIMULATION_KEYS[..SIMULATION_KEYS.len() - 1]
    };
    f.finish(keys)?;
    Ok(s)
}

/// The scheme's parameters belong to the scheme chosen, and `h_min ≤ h`.
fn consistent(f: &mut Fields<'_>, s: &Simulation) -> Result<(), FileError> {
    let integrator = s.integrator.unwrap_or(IntegratorChoice::GeneralizedAlpha);
    let belongs = [
        (
            "rho",
            s.rho.is_some(),
            IntegratorChoice::GeneralizedAlpha,
            "generalized-alpha",
        ),
        ("alpha", s.alpha.is_some(), IntegratorChoice::Hht, "hht"),
        (
            "beta",
            s.beta.is_some(),
            IntegratorChoice::Newmark,
            "newmark",
        ),
        (
            "gamma",
            s.gamma.is_some(),
            IntegratorChoice::Newmark,
            "newmark",
        ),
    ];
    for (key, given, owner, name) in belongs {
        if given && integrator != owner {
            let e: &Entry = f.read_entry(key)?;
            return Err(f.bad(
                e,
                format!("applies to integrator = \"{name}\", and this model uses another"),
            ));
        }
    }
    if let (Some(h_min), Some(h)) = (s.h_min, s.h)
        && h_min > h
    {
        let e: &Entry = f.read_entry("h_min")?;
        return Err(f.bad(e, format!("must not exceed h = {h}")));
    }
    if let (Some(h_max), Some(h)) = (s.h_max, s.h)
        && h_max < h
    {
        let e: &Entry = f.read_entry("h_max")?;
        return Err(f.bad(e, format!("must be at least h = {h}")));
    }
    if s.rtol == Some(0.0)
        && s.atol == Some(0.0)
        && let Some(e) = f.entry("atol")
    {
        return Err(f.bad(e, "rtol and atol cannot both be 0"));
    }
    Ok(())
}

/// The tables an override may add when the file has none: the settings,
/// every key of which is optional.
const OPTIONAL_TABLES: [&str; 2] = ["simulation", "output"];

/// Applies the override `path=value` to the document `root`. The path is
/// dotted: a key of a table, or in an array of named tables (`[[body]]`,
/// `[[joint]]`, `[[force]]`, …) the `name` of an element
/// (`body.upper.mass`, `force.drive.function.constant`). The value is in TOML
/// syntax, or a bare word taken as a string.
///
/// Every step but the last must exist (but `[simulation]` and `[output]`,
/// which it adds); the last key may be new, marked as added, and the reader
/// then refuses it if the table has no such key. The value's spans number
/// the override as `k` ([`crate::node::override_span`]), so that an error
/// about it names the override.
pub(crate) fn apply_override(root: &mut Node, assignment: &str, k: usize) -> Result<(), String> {
    let (path, text) = assignment
        .split_once('=')
        .ok_or("expected key=value, e.g. simulation.h=1e-4")?;
    let keys: Vec<&str> = path.trim().split('.').map(str::trim).collect();
    if keys.iter().any(|k| k.is_empty()) {
        return Err(format!("'{path}' is not a dotted path of keys"));
    }
    let mut value = override_value(text.trim());
    super::node::respan(&mut value, &super::node::override_span(k));
    let Some((last, through)) = keys.split_last() else {
        return Err(format!("'{path}' is not a dotted path of keys"));
    };
    let mut node = root;
    for (k, key) in through.iter().enumerate() {
        node = step(node, &keys[..k], key)?;
    }
    let Value::Table(entries) = &mut node.value else {
        return Err(not_a_table(node, through));
    };
    if keys == ["simulation", "integrator"]
        && let Value::Str(scheme) = &value.value
    {
        drop_other_schemes(entries, scheme);
    }
    // The command line wins over the file: rows every n steps replace rows
    // every Δt, and the other way round (the file may hold one only). Both
    // on the command line are refused, as both in the file are.
    if let ["output", key @ ("every" | "every_time")] = keys[..] {
        let other = if key == "every" {
            "every_time"
        } else {
            "every"
        };
        let by_override = |e: &Entry| {
            e.created
                || e.node
                    .span
                    .as_ref()
                    .is_some_and(|s| s.start >= super::node::OVERRIDES_FROM)
        };
        if entries.iter().any(|e| e.key == other && by_override(e)) {
            return Err(format!(
                "give either every (steps) or every_time (seconds): --set output.{other} is given too"
            ));
        }
        entries.retain(|e| e.key != other);
    }
    match entries.iter().position(|e| e.key == *last) {
        Some(at) => entries[at].node = value,
        None => entries.push(Entry {
            key: (*last).to_string(),
            key_span: None,
            node: value,
            created: true,
        }),
    }
    Ok(())
}

/// The node the dotted `path` (as in [`apply_override`]) names in `root`;
/// every step must exist.
pub(crate) fn lookup<'n>(root: &'n mut Node, path: &str) -> Result<&'n Node, String> {
    let keys: Vec<&str> = path.trim().split('.').map(str::trim).collect();
    if keys.iter().any(|k| k.is_empty()) {
        return Err(format!("'{path}' is not a dotted path of keys"));
    }
    let mut node = root;
    for (k, key) in keys.iter().enumerate() {
        if k == 0 && OPTIONAL_TABLES.contains(key) {
            // (`step` would add an empty settings table the file does not have.)
            if let Value::Table(entries) = &node.value
                && !entries.iter().any(|e| e.key == *key)
            {
                return Err(format!("the file has no [{key}] table"));
            }
        }
        node = step(node, &keys[..k], key)?;
    }
    Ok(node)
}

/// The scheme parameters that belong to each integrator.
const SCHEME_PARAMETERS: [(&str, &[&str]); 3] = [
    ("generalized-alpha", &["rho"]),
    ("hht", &["alpha"]),
    ("newmark", &["beta", "gamma"]),
];

/// An override of `integrator` takes out the parameters of the other schemes
/// that the file (or an earlier override) set (`rho` of a file's
/// generalized-α under `--set simulation.integrator=hht`), which would
/// otherwise contradict it: the new scheme runs with its own defaults, or
/// with its parameters set by later overrides.
fn drop_other_schemes(entries: &mut Vec<Entry>, scheme: &str) {
    let own: &[&str] = SCHEME_PARAMETERS
        .iter()
        .find(|(name, _)| *name == scheme)
        .map_or(&[], |(_, keys)| *keys);
    let foreign = |key: &str| {
        SCHEME_PARAMETERS
            .iter()
            .any(|(_, keys)| keys.contains(&key))
            && !own.contains(&key)
    };
    entries.retain(|e| !foreign(&e.key));
}

/// The node `key` names inside `node` (at the path `before`): a key of a
/// table or the element of an array whose `name` it is.
fn step<'n>(node: &'n mut Node, before: &[&str], key: &str) -> Result<&'n mut Node, String> {
    let error = match &node.value {
        Value::List(_) | Value::Table(_) => None,
        _ => Some(not_a_table(node, before)),
    };
    match &mut node.value {
        Value::List(items) => element(items, before, key),
        Value::Table(entries) => table_entry(entries, before, key),
        _ => Err(error.unwrap_or_default()),
    }
}

/// The value of `key` in the table `entries` (at the path `before`);
/// `[simulation]` or `[output]` added empty when the file has none.
fn table_entry<'n>(
    entries: &'n mut Vec<Entry>,
    before: &[&str],
    key: &str,
) -> Result<&'n mut Node, String> {
    if let Some(at) = entries.iter().position(|e| e.key == key) {
        return Ok(&mut entries[at].node);
    }
    if before.is_empty() && OPTIONAL_TABLES.contains(&key) {
        entries.push(Entry {
            key: key.to_string(),
            key_span: None,
            node: Node {
                value: Value::Table(Vec::new()),
                span: None,
            },
            created: true,
        });
        let at = entries.len() - 1;
        return Ok(&mut entries[at].node);
    }
    let known: Vec<&str> = entries.iter().map(|e| e.key.as_str()).collect();
    let place = if before.is_empty() {
        "the file".to_string()
    } else {
        format!("'{}'", before.join("."))
    };
    Err(format!(
        "{place} has no key '{key}'; its keys are: {}",
        known.join(", ")
    ))
}

/// The element named `name` of the array `items` (at the path `before`).
fn element<'n>(items: &'n mut [Node], before: &[&str], name: &str) -> Result<&'n mut Node, String> {
    let name_of = |n: &Node| match &n.value {
        Value::Table(entries) => {
            entries
                .iter()
                .find(|e| e.key == "name")
                .and_then(|e| match &e.node.value {
                    Value::Str(s) => Some(s.clone()),
                    _ => None,
                })
        }
        _ => None,
    };
    let array = before.join(".");
    match items
        .iter()
        .position(|n| name_of(n).as_deref() == Some(name))
    {
        Some(at) => Ok(&mut items[at]),
        None => {
            let names: Vec<String> = items.iter().filter_map(name_of).collect();
            if names.is_empty() {
                return Err(format!(
                    "'{array}' is an array without named elements: no element is named '{name}'"
                ));
            }
            Err(format!(
                "no element of '{array}' is named '{name}'; the names are: {}",
                names.join(", ")
            ))
        }
    }
}

/// The error for a path through `node` (at `path`), which is not a table.
fn not_a_table(node: &Node, path: &[&str]) -> String {
    let path = path.join(".");
    match node.value {
        Value::List(_) => format!(
            "'{path}' is an array: the next key is the name of one of its elements, then a key of it (e.g. body.upper.mass)"
        ),
        ref v => format!("'{path}' is {}, not a table", v.kind()),
    }
}

/// A value written on the command line: TOML syntax, or else a string.
fn override_value(text: &str) -> Node {
    let parsed = super::node::parse_toml(&format!("v = {text}"), "--set").ok();
    let value = parsed.and_then(|n| match n.value {
        Value::Table(mut e) if e.len() == 1 => e.pop().map(|e| e.node.value),
        _ => None,
    });
    Node {
        value: value.unwrap_or_else(|| Value::Str(text.to_string())),
        span: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn overrides_set_and_create_keys() {
        let mut root =
            super::super::node::parse_toml("[simulation]\nh = 0.01\n", "m").expect("valid");
        apply_override(&mut root, "simulation.h=1e-4", 0).expect("set");
        apply_override(&mut root, "simulation.integrator=hht", 0).expect("a bare word");
        apply_override(&mut root, "output.every=5", 0).expect("a new table");
        let doc = Doc {
            origin: "m",
            text: "",
            overrides: &[],
        };
        let (s, o) = read(doc, &root, false).expect("valid");
        assert_eq!(s.h, Some(1e-4));
        assert_eq!(s.integrator, Some(IntegratorChoice::Hht));
        assert_eq!(o.every, 5);
        assert!(apply_override(&mut root, "simulation.h", 0).is_err());
        assert!(apply_override(&mut root, "simulation.h.x=1", 0).is_err());
    }

    /// Issue 21 (24): `--set simulation.integrator=hht` on a file that sets
    /// `rho` always failed, with no way to unset `rho`.
    #[test]
    fn an_integrator_override_takes_the_file_s_other_scheme_parameters_out() {
        let doc = Doc {
            origin: "m",
            text: "",
            overrides: &[],
        };
        let file = "[simulation]\nintegrator = \"generalized-alpha\"\nrho = 0.9\n";
        let mut root = super::super::node::parse_toml(file, "m").expect("valid");
        apply_override(&mut root, "simulation.integrator=hht", 0).expect("set");
        let (s, _) = read(doc, &root, false).expect("rho is taken out");
        assert_eq!((s.integrator, s.rho), (Some(IntegratorChoice::Hht), None));
        // A parameter of another scheme set after it contradicts it, as before.
        let mut root = super::super::node::parse_toml(file, "m").expect("valid");
        apply_override(&mut root, "simulation.integrator=hht", 0).expect("set");
        apply_override(&mut root, "simulation.rho=0.5", 0).expect("set");
        assert!(read(doc, &root, false).is_err());
        // The new scheme's own parameter, set after it, is kept.
        let mut root = super::super::node::parse_toml(file, "m").expect("valid");
        apply_override(&mut root, "simulation.integrator=hht", 0).expect("set");
        apply_override(&mut root, "simulation.alpha=-0.2", 0).expect("set");
        let (s, _) = read(doc, &root, false).expect("valid");
        assert_eq!(s.alpha, Some(-0.2));
    }

    #[test]
    fn overrides_find_array_elements_by_name() {
        let text = "[[body]]\nname = \"upper\"\nmass = 1.0\n[[body]]\nname = \"lower\"\nmass = 2.0\n\
                    [[force]]\nname = \"drive\"\nfunction = { constant = 0.2 }\n";
        let mut root = super::super::node::parse_toml(text, "m").expect("valid");
        apply_override(&mut root, "body.lower.mass=3", 0).expect("by name");
        apply_override(&mut root, "force.drive.function.constant=0.5", 0).expect("nested");
        let Value::Table(top) = &root.value else {
            panic!("a table")
        };
        let Value::List(bodies) = &top[0].node.value else {
            panic!("an array")
        };
        let mass = |body: &Node| match &body.value {
            Value::Table(e) => e
                .iter()
                .find(|e| e.key == "mass")
                .map(|e| e.node.value.clone()),
            _ => None,
        };
        let num = |value: f64, integer: bool| Some(Value::Num { value, integer });
        assert_eq!(mass(&bodies[1]), num(3.0, true));
        assert_eq!(mass(&bodies[0]), num(1.0, false));
        let e = apply_override(&mut root, "body.uper.mass=3", 0).expect_err("no such body");
        assert_eq!(
            e,
            "no element of 'body' is named 'uper'; the names are: upper, lower"
        );
        let e = apply_override(&mut root, "joint.hinge.at=1", 0).expect_err("no joints");
        assert!(e.starts_with("the file has no key 'joint'"), "{e}");
        let e = apply_override(&mut root, "force.drive.functon.constant=1", 0).expect_err("typo");
        assert!(e.starts_with("'force.drive' has no key 'functon'"), "{e}");
        let e = apply_override(&mut root, "body.mass=1", 0).expect_err("an array");
        assert!(e.contains("'body' is an array"), "{e}");
    }

    #[test]
    fn unknown_keys_of_overrides_are_the_override_s_error() {
        use super::super::{Format, MechanismFile};
        let text = "format = \"mstar.planar/1\"\n[[body]]\nname = \"upper\"\nmass = 1.0\n\
                    inertia = 0.1\npose = [0.0, 0.0, 0.0]\n\
                    [[force]]\nname = \"drive\"\ntype = \"torque\"\nbody = \"upper\"\n\
                    function = { constant = 0.2 }\n";
        let parse =
            |set: &str| MechanismFile::parse_with(text, "m.toml", Format::Toml, &[set.to_string()]);
        assert!(parse("body.upper.mass=2").is_ok());
        let e = parse("body.upper.mas=2").expect_err("a typo");
        assert!(e.in_override, "{e}");
        assert!(
            e.message
                .contains("unknown key 'mas' (given by --set) (did you mean 'mass'?)"),
            "{e}"
        );
        let e = parse("force.drive.function.constnt=2").expect_err("a typo");
        assert!(e.in_override, "{e}");
        let e = parse("simulation.hh=2").expect_err("a typo");
        assert!(e.in_override, "{e}");
        let e = parse("body.lower.mass=2").expect_err("no such body");
        assert!(e.in_override, "{e}");
        // A value out of range is the model's error.
        let e = parse("body.upper.mass=-2").expect_err("negative");
        assert!(!e.in_override, "{e}");
        assert!(e.message.contains("mass: must be positive"), "{e}");
    }

    /// A whole number written with a fraction (`2.0`; in JSON 2.0 and 2
    /// are the same number) counts; 2.5 and 0 do not, with the same message.
    #[test]
    fn whole_numbers_written_as_floats_count() {
        use super::super::node::{parse_json, parse_toml};
        let doc = Doc {
            origin: "m",
            text: "",
            overrides: &[],
        };
        let root = parse_toml(
            "[simulation]\nmax_iterations = 5.0\n[output]\nevery = 2.0\n",
            "m",
        )
        .expect("valid");
        let (s, o) = read(doc, &root, false).expect("whole numbers");
        assert_eq!((s.max_iterations, o.every), (Some(5), 2));
        let root = parse_json(r#"{"output": {"every": 2.0}}"#, "m").expect("valid");
        assert_eq!(read(doc, &root, false).expect("JSON's 2.0").1.every, 2);
        for (text, got) in [
            ("every = 2.5", "2.5"),
            ("every = 0.0", "0"),
            ("every = 0", "0"),
        ] {
            let root = parse_toml(&format!("[output]\n{text}\n"), "m").expect("valid");
            let e = read(doc, &root, false).expect_err(text);
            assert_eq!(
                e.message,
                format!("[output]: every: must be a whole number of at least 1 (got {got})"),
                "{text}"
            );
        }
        let root = parse_toml("[simulation]\nmax_iterations = 5.5\n", "m").expect("valid");
        let e = read(doc, &root, false).expect_err("5.5");
        assert!(
            e.message
                .ends_with("max_iterations: must be a whole number of at least 1 (got 5.5)"),
            "{e}"
        );
    }

    /// An override of `every` replaces the file's `every_time`, and the
    /// other way round: the command line wins (the file may hold one only).
    #[test]
    fn an_override_of_every_or_every_time_replaces_the_other() {
        let doc = Doc {
            origin: "m",
            text: "",
            overrides: &[],
        };
        let file = |key: &str| {
            super::super::node::parse_toml(&format!("[output]\n{key}\n"), "m").expect("valid")
        };
        let mut root = file("every_time = 0.25");
        apply_override(&mut root, "output.every=3", 0).expect("set");
        let (_, o) = read(doc, &root, false).expect("every replaces every_time");
        assert_eq!((o.every, o.every_time), (3, None));
        let mut root = file("every = 5");
        apply_override(&mut root, "output.every_time=0.1", 0).expect("set");
        let (_, o) = read(doc, &root, false).expect("every_time replaces every");
        assert_eq!((o.every, o.every_time), (1, Some(0.1)));
        // Both on the command line: refused, naming the other.
        let mut root = file("every = 5");
        apply_override(&mut root, "output.every_time=0.1", 0).expect("set");
        let e = apply_override(&mut root, "output.every=2", 1).expect_err("both");
        assert_eq!(
            e,
            "give either every (steps) or every_time (seconds): --set output.every_time is given too"
        );
        // Both in the file, as before: refused.
        let root = file("every = 5\nevery_time = 0.1");
        let e = read(doc, &root, false).expect_err("both");
        assert!(
            e.message
                .contains("give either every (steps) or every_time"),
            "{e}"
        );
    }

    /// A value an override gave that is out of range is blamed on the
    /// override, not on the line of the file's key (issue C), also inside
    /// a table the override gave; it stays the model's error.
    #[test]
    fn values_given_by_overrides_are_blamed_on_the_override() {
        use super::super::{Format, MechanismFile};
        let text = "format = \"mstar.planar/1\"\n[[point_mass]]\nname = \"m\"\nmass = 3.0\n\
                    position = [0.0, -1.0]\n[[force]]\nname = \"push\"\ntype = \"force\"\n\
                    body = \"m\"\nfy = { constant = 1.0 }\n";
        let parse = |set: &[&str]| {
            let set: Vec<String> = set.iter().map(|s| (*s).to_string()).collect();
            MechanismFile::parse_with(text, "m.toml", Format::Toml, &set)
        };
        for (set, says) in [
            (
                &["point_mass.m.mass=1e101"][..],
                "--set point_mass.m.mass=1e101: point mass 'm': mass: 1e101 is out of range",
            ),
            (
                &["simulation.h=1e-3", "simulation.alpha=-0.5"][..],
                "--set simulation.alpha=-0.5: [simulation]: alpha: must be in [−1/3, 0] (got -0.5)",
            ),
            (
                &["force.push.fy={ constant = 1e101 }"][..],
                "--set force.push.fy={ constant = 1e101 }: force 'push': fy",
            ),
        ] {
            let e = parse(set).expect_err(says);
            assert_eq!(e.place, None, "{e}");
            assert!(e.to_string().starts_with(&format!("m.toml: {says}")), "{e}");
            assert!(!e.in_override, "{e}");
        }
        // The file's own values keep their places.
        let e = parse(&["simulation.h=1e-3"]).map(|_| ());
        assert!(e.is_ok(), "{e:?}");
    }
}
