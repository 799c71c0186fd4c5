//! URDF robots (`.urdf`): read into the `mstar.spatial/1` document they
//! mean, which the spatial reader then reads as it reads a file, so a URDF
//! and its conversion (`mstar convert`) give the same model bit for bit; and
//! the `urdf = "robot.urdf"` key of a spatial file, which starts the file
//! from a URDF (`docs/model-format.md`, "URDF robots").

mod robot;
mod write;

use std::collections::{HashMap, HashSet};
use std::ops::Range;
use std::path::Path;

use self::robot::{Kind, Robot};
use self::write::{JointState, Placement};
use crate::FileError;
use crate::fields::{Doc, Fields, list, number, string};
use crate::node::{self, Entry, Node, Value};

/// A URDF read as a tree: the tree, the notes, and where the URDF defines
/// each of its bodies and joints.
pub(crate) struct Read {
    pub(crate) root: Node,
    pub(crate) notes: Vec<String>,
    pub(crate) places: Places,
}

/// Where a URDF defines the bodies and joints of its model, for errors the
/// spatial reader finds in them (the tree has no places of its own).
pub(crate) struct Places {
    origin: String,
    by_name: Vec<(String, (usize, usize))>,
}

impl Places {
    /// `e` placed at the URDF element it is about, when it has no place and
    /// is about a body or joint of the URDF (`body 'upper_arm': …`).
    pub(crate) fn locate(&self, e: FileError) -> FileError {
        if e.place.is_some() || e.in_override {
            return e;
        }
        let about = |name: &str| {
            ["body", "joint"].iter().any(|kind| {
                e.message
                    .starts_with(&format!("{kind} '{}':", name.escape_debug()))
            })
        };
        match self.by_name.iter().find(|(name, _)| about(name)) {
            Some((_, place)) => FileError {
                origin: self.origin.clone(),
                place: Some(*place),
                // (A URDF link has no [[point_mass]] to be instead.)
                message: e.message.replace(
                    "a body without rotational inertia is a [[point_mass]]",
                    "give the link's <inertia> positive moments ixx, iyy, izz",
                ),
                ..e
            },
            None => e,
        }
    }
}

/// The `mstar.spatial/1` document of the URDF `text` (the file `origin`),
/// all joints at 0 and at rest, and one note for each kind of element read
/// and ignored (and each massless link left out).
///
/// # Errors
/// As [`robot::parse`], and for a massless link between moving joints or a
/// name that is both a link's and a joint's.
pub(crate) fn convert(text: &str, origin: &str) -> Result<(String, Vec<String>), FileError> {
    let (document, notes, _) = converted(text, origin)?;
    Ok((document, notes))
}

/// [`convert`], and where the URDF defines each body and joint.
fn converted(text: &str, origin: &str) -> Result<(String, Vec<String>, Places), FileError> {
    let robot = robot::parse(text, origin)?;
    let placement = write::place(&robot, &HashMap::new())?;
    check_names(&robot, &placement)?;
    let document = placement.document(&robot, origin, true);
    let places = Places {
        origin: origin.to_string(),
        by_name: placement.names(&robot),
    };
    let mut notes = robot.notes;
    notes.extend(placement.notes);
    Ok((document, notes, places))
}

/// The tree of the URDF `text` as [`convert`] writes it, without places
/// (they would be the converted text's), the notes and the places of the
/// bodies and joints in the URDF.
///
/// # Errors
/// As [`convert`].
pub(crate) fn read(text: &str, origin: &str) -> Result<Read, FileError> {
    let (document, notes, places) = converted(text, origin)?;
    Ok(Read {
        root: tree(&document, origin)?,
        notes,
        places,
    })
}

/// The tree of a converted `document`, without places.
fn tree(document: &str, origin: &str) -> Result<Node, FileError> {
    let mut root =
        node::parse_toml(document, origin).map_err(|e| FileError { place: None, ..e })?;
    unplace(&mut root);
    Ok(root)
}

/// Takes the places out of `node` and everything in it.
fn unplace(node: &mut Node) {
    node.span = None;
    match &mut node.value {
        Value::List(items) => items.iter_mut().for_each(unplace),
        Value::Table(entries) => {
            for e in entries {
                e.key_span = None;
                unplace(&mut e.node);
            }
        }
        _ => {}
    }
}

/// Refuses a URDF whose model would give one name twice (a link and a
/// joint of the same name, or a link called `ground`): mstar's bodies and
/// joints share one name space.
fn check_names(robot: &Robot, placement: &Placement) -> Result<(), FileError> {
    let mut seen = HashSet::new();
    for (name, place) in placement.names(robot) {
        let why = if name == "ground" {
            "'ground' is mstar's name for the fixed frame: rename the link".to_string()
        } else if !seen.insert(name.clone()) {
            "a link and a joint (or the root's weld) share this name, and mstar's bodies and joints share one name space: rename one of them".to_string()
        } else {
            continue;
        };
        return Err(FileError {
            origin: robot.origin.clone(),
            place: Some(place),
            message: format!("'{}': {why}", name.escape_debug()),
            in_override: false,
        });
    }
    Ok(())
}

/// A spatial document that starts from a URDF (`urdf = "arm.urdf"`, the
/// path relative to the document's directory) expanded: the URDF's bodies
/// and joints, placed at the joint positions and velocities of its
/// `[[initial]]` tables, come before the document's own; `urdf` and
/// `initial` are taken out. `None` for a document without `urdf`.
///
/// # Errors
/// A `urdf` that is not a string or cannot be read, the URDF's errors, and
/// an `[[initial]]` that names no moving joint of the URDF or is malformed.
pub(crate) fn expand(doc: Doc<'_>, root: &Node) -> Result<Option<Read>, FileError> {
    let Value::Table(entries) = &root.value else {
        return Ok(None);
    };
    let Some(entry) = entries.iter().find(|e| e.key == "urdf") else {
        return Ok(None);
    };
    let at = entry.node.span.as_ref().or(entry.key_span.as_ref());
    let Value::Str(file) = &entry.node.value else {
        return Err(doc.error(
            at,
            format!(
                "the model: urdf: expected a string, the path of a URDF file relative to this file, found {}",
                entry.node.value.kind()
            ),
        ));
    };
    let path = Path::new(doc.origin)
        .parent()
        .unwrap_or(Path::new(""))
        .join(file);
    let source = path.display().to_string();
    let text = std::fs::read_to_string(&path).map_err(|e| {
        doc.error(
            at,
            format!("the model: urdf: cannot read the URDF file {source}: {e}"),
        )
    })?;
    let robot = robot::parse(&text, &source)?;
    let initial = read_initial(doc, root)?;
    let states: HashMap<String, JointState> =
        initial.iter().map(|(n, s, _)| (n.clone(), *s)).collect();
    let placement = write::place(&robot, &states)?;
    check_names(&robot, &placement)?;
    for (name, _, span) in &initial {
        check_initial(doc, &robot, &placement, name, span.as_ref())?;
    }
    let urdf = tree(&placement.document(&robot, &source, false), &source)?;
    let places = Places {
        origin: source,
        by_name: placement.names(&robot),
    };
    let mut notes = robot.notes;
    notes.extend(placement.notes);
    Ok(Some(Read {
        root: merged(entries, urdf),
        notes,
        places,
    }))
}

/// The wrapper's `entries` without `urdf` and `initial`, with the URDF's
/// bodies and joints before its own.
fn merged(entries: &[Entry], urdf: Node) -> Node {
    let Value::Table(mut from_urdf) = urdf.value else {
        return urdf;
    };
    let mut out: Vec<Entry> = Vec::with_capacity(entries.len() + 2);
    for e in entries {
        if e.key == "urdf" || e.key == "initial" {
            continue;
        }
        let mut e = e.clone();
        if let Some(k) = from_urdf.iter().position(|u| u.key == e.key)
            && let (Value::List(first), Value::List(own)) =
                (from_urdf.remove(k).node.value, &mut e.node.value)
        {
            own.splice(0..0, first);
        }
        out.push(e);
    }
    // The URDF's elements the wrapper has none of.
    out.extend(from_urdf);
    Node {
        value: Value::Table(out),
        span: None,
    }
}

/// An `[[initial]]` table: the joint's name, its state, and where the name
/// is written.
type Initial = (String, JointState, Option<Range<usize>>);

/// The `[[initial]]` tables of a wrapper: joint name, state, and where the
/// name is written. Each has `joint`, `position` (default 0) and
/// `velocity` (default 0), and names its joint once.
fn read_initial(doc: Doc<'_>, root: &Node) -> Result<Vec<Initial>, FileError> {
    let mut top = Fields::of(doc, root, "the model".to_string())?;
    let items = top.optional("initial", list)?.unwrap_or(&[]);
    let mut out: Vec<Initial> = Vec::new();
    for (k, node) in items.iter().enumerate() {
        let mut f = Fields::of(doc, node, format!("initial #{}", k + 1))?;
        let joint = f.required("joint", string)?.to_string();
        let position = f.optional("position", number)?.unwrap_or(0.0);
        let velocity = f.optional("velocity", number)?.unwrap_or(0.0);
        f.finish(&["joint", "position", "velocity"])?;
        let e = f.read_entry("joint")?;
        if out.iter().any(|(n, _, _)| *n == joint) {
            return Err(f.bad(
                e,
                format!(
                    "joint '{}' has an [[initial]] already",
                    joint.escape_debug()
                ),
            ));
        }
        out.push((
            joint,
            JointState { position, velocity },
            e.node.span.clone(),
        ));
    }
    Ok(out)
}

/// Refuses an `[[initial]]` of a joint that is not a revolute, continuous
/// or prismatic joint of the model.
fn check_initial(
    doc: Doc<'_>,
    robot: &Robot,
    placement: &Placement,
    name: &str,
    at: Option<&Range<usize>>,
) -> Result<(), FileError> {
    let moving: Vec<&str> = robot
        .joints
        .iter()
        .enumerate()
        .filter(|(j, joint)| joint.kind != Kind::Fixed && placement.has_joint(robot, *j))
        .map(|(_, joint)| joint.name.as_str())
        .collect();
    if moving.contains(&name) {
        return Ok(());
    }
    let what = match robot.joints.iter().find(|j| j.name == name) {
        Some(j) if j.kind == Kind::Fixed => "is fixed",
        Some(_) => "moves a massless link and is left out",
        None => "is not a joint of the URDF",
    };
    Err(doc.error(
        at,
        format!(
            "initial: joint: '{}' {what}; [[initial]] sets the position of a revolute, continuous or prismatic joint of the URDF (here: {})",
            name.escape_debug(),
            if moving.is_empty() { "none".to_string() } else { moving.join(", ") }
        ),
    ))
}

#[cfg(test)]
mod tests;
