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
#[derive(Clone, Debug)]
pub struct ModelDocument {
    origin: String,
    text: String,
    root: Node,
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
        Ok(Self { origin, text, root })
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
    /// document's gravity and `[simulation]`; no sensors, no `[output]`. A
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
        for o in overrides {
            settings::apply_override(root, o).map_err(|why| {
                FileError::unplaced(&self.origin, format!("--set {o}: {why}")).of_override()
            })?;
        }
        let doc = Doc {
            origin: &self.origin,
            text: &self.text,
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
    let (kind, name) = (parts.next()?, parts.next()?);
    parts.next()?;
    let Value::Table(entries) = &root.value else {
        return None;
    };
    let elements = elements(entries);
    let kind = ELEMENTS.iter().position(|k| *k == kind)?;
    let own = elements
        .iter()
        .position(|e| e.kind == kind && e.name == Some(name))?;
    // keep[kind][index]: whether the element stays.
    let mut keep: Vec<Vec<bool>> = vec![Vec::new(); ELEMENTS.len()];
    for (e, kept) in elements.iter().zip(touched(&elements, own)) {
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
