//! A model file parsed once and read again at other values of its keys
//! ([`ModelDocument`]): what parameter sensitivities need (the model at
//! `p ± h_p` for each parameter, `docs/analysis.md`, "Parameter
//! sensitivities") without reading and parsing the file twice per
//! parameter, and the part of the model one key belongs to
//! ([`ModelDocument::element_model`]).

use std::path::Path;

use crate::fields::Doc;
use crate::node::{Node, Value};
use crate::{FileError, Format, MechanismFile, document, keys, read, settings};

/// A model file's document, parsed (a URDF expanded) with the command
/// line's overrides applied: read into a model as often as needed, with
/// further overrides, without touching the file again.
#[derive(Clone)]
pub struct ModelDocument {
    origin: String,
    text: String,
    root: Node,
    /// The overrides applied to `root` (errors name them).
    overrides: Vec<String>,
}

impl std::fmt::Debug for ModelDocument {
    /// The file's name and size, not its text.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ModelDocument")
            .field("origin", &self.origin)
            .field("bytes", &self.text.len())
            .finish_non_exhaustive()
    }
}

impl ModelDocument {
    /// Reads and parses the model file at `path` and applies `overrides`
    /// (`--set KEY=VALUE`). The model itself is not read: see
    /// [`read_with`](Self::read_with).
    ///
    /// # Errors
    /// [`FileError`] for a file that cannot be read, a syntax error, or a
    /// malformed override (as [`MechanismFile::load_with`]).
    pub fn load(path: &Path, overrides: &[String]) -> Result<Self, FileError> {
        let origin = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| {
            FileError::unplaced(&origin, format!("cannot read the model file: {e}"))
        })?;
        let (root, _, _) = document(&text, &origin, Format::of(path), overrides)?;
        Ok(Self {
            origin,
            text,
            root,
            overrides: overrides.to_vec(),
        })
    }

    /// The file's name, as errors give it.
    #[must_use]
    pub fn origin(&self) -> &str {
        &self.origin
    }

    /// The model parameter at the dotted key `key` (as
    /// [`MechanismFile::parameter`]).
    ///
    /// # Errors
    /// For a key that names nothing or a value that is not a number (with
    /// the closest numeric keys), or a key of `[simulation]` or `[output]`.
    pub fn parameter(&self, key: &str) -> Result<f64, FileError> {
        if let Some(table) = ["simulation", "output"]
            .into_iter()
            .find(|t| key.split('.').next().map(str::trim) == Some(*t))
        {
            return Err(FileError::unplaced(
                &self.origin,
                format!(
                    "'{key}' is a setting of the run ([{table}]), not a parameter of the \
                     model: give a key of a body, joint, force, driver or other element"
                ),
            )
            .of_override());
        }
        keys::number(&self.root, key)
            .map_err(|why| FileError::unplaced(&self.origin, why).of_override())
    }

    /// The model with `overrides` applied after the document's own: the
    /// model [`MechanismFile::load_with`] reads with both lists of
    /// overrides, bit for bit, without parsing the file again.
    ///
    /// # Errors
    /// As [`MechanismFile::load_with`].
    pub fn read_with(&self, overrides: &[String]) -> Result<MechanismFile, FileError> {
        let mut root = self.root.clone();
        self.read_overridden(&mut root, overrides)
    }

    /// The part of the model the key `key` (`body.rod.mass`,
    /// `joint.rod.length`, `force.spring.stiffness`) belongs to, with
    /// `overrides` applied: the element the key names, every element that
    /// refers to it by name (a body's joints, forces and drivers; a joint's
    /// drivers), and every element those refer to (their bodies), with the
    /// document's gravity and `[simulation]`; no sensors, no `[output]`.
    /// For a body's or a point mass's `mass` or `inertia`, which enter its
    /// own terms only (its mass matrix and weight), the element alone. A
    /// residual row of the whole model changes with the key only where one
    /// of these elements acts, and there the small model has the same
    /// terms that depend on the key (its coordinates and constraint rows
    /// carry the whole model's names). `None` for a key of no element
    /// (a global one), or when the small model cannot be read on its own
    /// (e.g. a body without rotational inertia whose angle the joints left
    /// out would fix).
    ///
    /// # Errors
    /// A malformed override.
    pub fn element_model(
        &self,
        key: &str,
        overrides: &[String],
    ) -> Result<Option<MechanismFile>, FileError> {
        let Some(mut root) = restrict(&self.root, key) else {
            return Ok(None);
        };
        match self.read_overridden(&mut root, overrides) {
            Ok(file) => Ok(Some(file)),
            Err(e) if e.in_override => Err(e),
            Err(_) => Ok(None),
        }
    }

    /// Applies `overrides` to `root` and reads the model.
    fn read_overridden(
        &self,
        root: &mut Node,
        overrides: &[String],
    ) -> Result<MechanismFile, FileError> {
        // Numbered after the document's own, as their values' spans are.
        let all: Vec<String> = self.overrides.iter().chain(overrides).cloned().collect();
        let first = self.overrides.len();
        for (k, o) in overrides.iter().enumerate() {
            settings::apply_override(root, o, first + k).map_err(|why| {
                FileError::unplaced(&self.origin, format!("--set {o}: {why}")).of_override()
            })?;
        }
        let doc = Doc {
            origin: &self.origin,
            text: &self.text,
            overrides: &all,
        };
        read(doc, root)
    }
}

/// The arrays of elements that enter the residual (sensors only read it).
const ELEMENTS: [&str; 5] = ["body", "point_mass", "joint", "driver", "force"];

/// One element of the document: where it is, its name, and the strings it
/// holds (other than its name and type): the names it refers to.
struct Element<'n> {
    kind: usize,
    index: usize,
    name: Option<&'n str>,
    refs: Vec<&'n str>,
}

/// The document restricted to the elements `key` touches (see
/// [`ModelDocument::element_model`]); `None` when `key` names no element.
fn restrict(root: &Node, key: &str) -> Option<Node> {
    let mut parts = key.split('.').map(str::trim);
    let (kind, name, field) = (parts.next()?, parts.next()?, parts.next()?);
    let Value::Table(entries) = &root.value else {
        return None;
    };
    let elements = elements(entries);
    // A body's mass and inertia enter its own terms only (its mass matrix
    // and its weight), not those of the elements that name it.
    let inertial = matches!(kind, "body" | "point_mass") && matches!(field, "mass" | "inertia");
    let kind = ELEMENTS.iter().position(|k| *k == kind)?;
    let own = elements
        .iter()
        .position(|e| e.kind == kind && e.name == Some(name))?;
    let kept = if inertial {
        (0..elements.len()).map(|i| i == own).collect()
    } else {
        touched(&elements, own)
    };
    // keep[kind][index]: whether the element stays.
    let mut keep: Vec<Vec<bool>> = vec![Vec::new(); ELEMENTS.len()];
    for (e, kept) in elements.iter().zip(kept) {
        let row = &mut keep[e.kind];
        if row.len() <= e.index {
            row.resize(e.index + 1, false);
        }
        row[e.index] = kept;
    }
    let mut out = Vec::with_capacity(entries.len());
    for entry in entries {
        if entry.key == "sensor" || entry.key == "output" {
            continue;
        }
        let (Some(k), Value::List(items)) = (
            ELEMENTS.iter().position(|x| *x == entry.key),
            &entry.node.value,
        ) else {
            out.push(entry.clone());
            continue;
        };
        // Only the kept elements are copied.
        let items = items
            .iter()
            .enumerate()
            .filter(|(i, _)| keep[k].get(*i).copied().unwrap_or(false))
            .map(|(_, item)| item.clone())
            .collect();
        let entry = crate::node::Entry {
            key: entry.key.clone(),
            key_span: entry.key_span.clone(),
            node: Node {
                value: Value::List(items),
                span: entry.node.span.clone(),
            },
            created: entry.created,
        };
        out.push(entry);
    }
    Some(Node {
        value: Value::Table(out),
        span: root.span.clone(),
    })
}

/// Every element of the document's arrays.
fn elements(entries: &[crate::node::Entry]) -> Vec<Element<'_>> {
    let mut out = Vec::new();
    for entry in entries {
        let Some(kind) = ELEMENTS.iter().position(|k| *k == entry.key) else {
            continue;
        };
        let Value::List(items) = &entry.node.value else {
            continue;
        };
        for (index, item) in items.iter().enumerate() {
            let Value::Table(fields) = &item.value else {
                continue;
            };
            let mut name = None;
            let mut refs = Vec::new();
            for f in fields {
                match (f.key.as_str(), &f.node.value) {
                    ("name", Value::Str(s)) => name = Some(s.as_str()),
                    ("type", _) => {}
                    _ => strings(&f.node, &mut refs),
                }
            }
            out.push(Element {
                kind,
                index,
                name,
                refs,
            });
        }
    }
    out
}

/// Every string in `node`, recursively.
fn strings<'n>(node: &'n Node, out: &mut Vec<&'n str>) {
    match &node.value {
        Value::Str(s) => out.push(s),
        Value::List(items) => items.iter().for_each(|n| strings(n, out)),
        Value::Table(entries) => entries.iter().for_each(|e| strings(&e.node, out)),
        _ => {}
    }
}

/// Which elements the one at `own` touches: itself and, transitively,
/// those that refer to it (whose terms may depend on its values), then,
/// transitively, those any of them refer to (which they need to be read).
fn touched(elements: &[Element<'_>], own: usize) -> Vec<bool> {
    let mut kept = vec![false; elements.len()];
    kept[own] = true;
    // Upward: elements that name a kept one.
    let mut up: Vec<&str> = elements[own].name.into_iter().collect();
    loop {
        let before = up.len();
        for (e, k) in elements.iter().zip(kept.iter_mut()) {
            if !*k && e.refs.iter().any(|r| up.contains(r)) {
                *k = true;
                up.extend(e.name);
            }
        }
        if up.len() == before {
            break;
        }
    }
    // Downward: elements a kept one names.
    loop {
        let wanted: Vec<&str> = elements
            .iter()
            .zip(&kept)
            .filter(|(_, k)| **k)
            .flat_map(|(e, _)| e.refs.iter().copied())
            .collect();
        let mut changed = false;
        for (e, k) in elements.iter().zip(kept.iter_mut()) {
            if !*k && e.name.is_some_and(|n| wanted.contains(&n)) {
                *k = true;
                changed = true;
            }
        }
        if !changed {
            return kept;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A chain `ground – a – b – c` on revolute joints, a spring from `c`
    /// to the ground, a driver on `a`, a sensor on `b`.
    const TEXT: &str = r#"
format = "mstar.planar/1"
[[body]]
name = "a"
mass = 1.0
inertia = 0.1
pose = [0.5, 0.0, 0.0]
[[body]]
name = "b"
mass = 1.0
inertia = 0.1
pose = [1.5, 0.0, 0.0]
[[body]]
name = "c"
mass = 1.0
inertia = 0.1
pose = [2.5, 0.0, 0.0]
[[joint]]
name = "j1"
type = "revolute"
bodies = ["ground", "a"]
at = [0.0, 0.0]
[[joint]]
name = "j2"
type = "revolute"
bodies = ["a", "b"]
at = [1.0, 0.0]
[[joint]]
name = "j3"
type = "revolute"
bodies = ["b", "c"]
at = [2.0, 0.0]
[[driver]]
name = "motor"
body = "a"
coordinate = "theta"
function = { linear = { value = 0.0, rate = 1.0 } }
[[force]]
name = "spring"
type = "spring-damper"
bodies = ["c", "ground"]
points = [[0.5, 0.0], [3.0, 1.0]]
stiffness = 10.0
[[sensor]]
name = "where"
type = "position"
body = "b"
[output]
columns = ["t", "sensor:*"]
"#;

    /// The names of the elements `key`'s small document keeps, by array.
    fn kept(key: &str) -> Option<Vec<String>> {
        let root = crate::node::parse_toml(TEXT, "t.toml").expect("the document parses");
        let small = restrict(&root, key)?;
        let Value::Table(entries) = &small.value else {
            return None;
        };
        let mut names = Vec::new();
        for e in entries {
            if let Value::List(items) = &e.node.value {
                for item in items {
                    let Value::Table(fields) = &item.value else {
                        return None;
                    };
                    let name = fields.iter().find(|f| f.key == "name").and_then(|f| {
                        match &f.node.value {
                            Value::Str(s) => Some(s.clone()),
                            _ => None,
                        }
                    })?;
                    names.push(format!("{}.{name}", e.key));
                }
            } else {
                names.push(e.key.clone());
            }
        }
        names.sort();
        Some(names)
    }

    #[test]
    fn a_body_keeps_what_names_it_and_what_that_names() {
        // b's joints j2, j3 name it; they name a and c; nothing else.
        assert_eq!(
            kept("body.b.pose").expect("an element's key"),
            [
                "body.a", "body.b", "body.c", "format", "joint.j2", "joint.j3"
            ]
        );
        // a's joints and its driver; b through j2.
        assert_eq!(
            kept("body.a.velocity").expect("an element's key"),
            [
                "body.a",
                "body.b",
                "driver.motor",
                "format",
                "joint.j1",
                "joint.j2"
            ]
        );
    }

    #[test]
    fn a_body_s_mass_or_inertia_keeps_the_body_alone() {
        // The joints, the driver and the spring that name a, b or c do not
        // read their masses or inertias.
        for key in ["body.b.mass", "body.a.inertia", "body.c.mass"] {
            let body = key.rsplit_once('.').map(|(b, _)| b).expect("a field");
            assert_eq!(
                kept(key).expect("an element's key"),
                [body, "format"],
                "{key}"
            );
        }
    }

    #[test]
    fn a_force_or_a_driver_keeps_itself_and_its_bodies() {
        assert_eq!(
            kept("force.spring.stiffness").expect("an element's key"),
            ["body.c", "force.spring", "format"]
        );
        assert_eq!(
            kept("driver.motor.function.linear.rate").expect("an element's key"),
            ["body.a", "driver.motor", "format"]
        );
        assert_eq!(
            kept("joint.j3.at").expect("an element's key"),
            ["body.b", "body.c", "format", "joint.j3"]
        );
    }

    #[test]
    fn keys_of_no_element_have_no_small_model() {
        for key in [
            "gravity",
            "body.b",
            "body.nobody.mass",
            "sensor.where.x",
            "output.every",
        ] {
            assert_eq!(kept(key), None, "{key}");
        }
    }

    /// The small model reads and keeps the whole model's names.
    #[test]
    fn the_small_model_reads_with_the_whole_models_names() {
        let dir = std::env::temp_dir().join(format!("mstar-file-document-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("a scratch directory");
        let path = dir.join("chain.toml");
        std::fs::write(&path, TEXT).expect("written");
        let doc = ModelDocument::load(&path, &[]).expect("the file reads");
        let small = doc
            .element_model("joint.j3.at", &["body.b.mass=2.5".into()])
            .expect("the override applies")
            .expect("a small model");
        let sys = small.mechanism.system();
        let names: Vec<String> = (0..sys.n_coords()).map(|i| sys.coord_name(i)).collect();
        assert_eq!(names[..3], ["b.x", "b.y", "b.theta"]);
        let rows: Vec<String> = (0..sys.n_constraints())
            .map(|j| sys.constraint_name(j))
            .collect();
        assert_eq!(rows, ["j3.x", "j3.y"]);
        let whole = doc.read_with(&[]).expect("the whole model");
        assert_eq!(whole.mechanism.system().n_coords(), 9);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
