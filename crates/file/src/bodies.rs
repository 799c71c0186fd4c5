//! The bodies a model file has named so far, and how its elements name
//! them: the steps the planar and the spatial readers share.

use std::collections::HashMap;
use std::ops::Range;

use super::FileError;
use super::fields::{Doc, Fields, choice, list, number_in, numbers, string, two_names};
use super::node::Node;
use mstar_model::PointMass;
use mstar_model::planar::{ModelError, TimeFunction};

/// The fixed frame's name.
pub(crate) const GROUND: &str = "ground";

/// One side of a joint or force: the ground or a body as placed (`P`).
#[derive(Clone, Copy, Debug)]
pub(crate) enum Side<P> {
    /// The fixed frame.
    Ground,
    /// A body or point mass.
    Body(P),
}

/// The bodies and point masses read so far, by name.
#[derive(Debug)]
pub(crate) struct Bodies<P> {
    by_name: HashMap<String, P>,
}

impl<P: Copy> Bodies<P> {
    /// None yet, with room for `bodies` without growing.
    pub(crate) fn with_capacity(bodies: usize) -> Self {
        Self {
            by_name: HashMap::with_capacity(bodies),
        }
    }

    /// Adds `name` (the reader has checked that it is new).
    pub(crate) fn insert(&mut self, name: String, placed: P) {
        self.by_name.insert(name, placed);
    }

    /// The two sides of the key `bodies` of `f`: each `"ground"` or a known
    /// body, and not the same twice.
    pub(crate) fn sides(&self, f: &mut Fields<'_>) -> Result<[Side<P>; 2], FileError> {
        let names = f.required("bodies", two_names)?;
        let e = f.read_entry("bodies")?;
        let side = |name: &str| -> Result<Side<P>, FileError> {
            if name == GROUND {
                return Ok(Side::Ground);
            }
            self.by_name
                .get(name)
                .map(|&b| Side::Body(b))
                .ok_or_else(|| f.bad(e, self.unknown(name)))
        };
        let sides = [side(names[0])?, side(names[1])?];
        if names[0] == names[1] {
            return Err(f.bad(
                e,
                format!(
                    "both sides are '{}': an element joins two different bodies",
                    names[0].escape_debug()
                ),
            ));
        }
        Ok(sides)
    }

    /// The body named by the key `key` of `f` (not the ground).
    pub(crate) fn body_of(&self, f: &mut Fields<'_>, key: &str) -> Result<P, FileError> {
        let name = f.required(key, string)?;
        let e = f.read_entry(key)?;
        if name == GROUND {
            return Err(f.bad(e, "the ground cannot move: name a body"));
        }
        self.by_name
            .get(name)
            .copied()
            .ok_or_else(|| f.bad(e, self.unknown(name)))
    }

    /// The body or point mass `name`, if the file has one.
    pub(crate) fn get(&self, name: &str) -> Option<P> {
        self.by_name.get(name).copied()
    }

    /// The message for an unknown name, listing the known ones.
    pub(crate) fn unknown(&self, name: &str) -> String {
        let mut known: Vec<&str> = self.by_name.keys().map(String::as_str).collect();
        known.sort_unstable();
        format!(
            "no body or point mass is called '{}' (known: ground{}{})",
            name.escape_debug(),
            if known.is_empty() { "" } else { ", " },
            known.join(", ")
        )
    }
}

/// Every name a file has given so far, with what carries it and where: a
/// name may be used once in a file.
#[derive(Debug, Default)]
pub(crate) struct Names {
    /// Where the name is given and the kind of what carries it (described
    /// as `<kind> '<name>'` when a message needs it, not stored: 10⁵-body
    /// files have 2.5·10⁵ names).
    by_name: HashMap<String, (Option<Range<usize>>, &'static str)>,
    /// The key of an element whose value only the builder checks in full
    /// (a spatial body's `inertia`), and where it is: a builder error about
    /// the element is placed there.
    checked: HashMap<String, (&'static str, Option<Range<usize>>)>,
}

impl Names {
    /// None yet, with room for `names` without growing.
    pub(crate) fn with_capacity(names: usize) -> Self {
        Self {
            by_name: HashMap::with_capacity(names),
            checked: HashMap::new(),
        }
    }

    /// The fields of the element table `node` (described as `what` until its
    /// name is known, then as `<kind> '<name>'`) and its name: non-empty,
    /// without control characters, new, and not `ground` (the fixed frame's,
    /// for every kind of element).
    pub(crate) fn named<'a>(
        &mut self,
        doc: Doc<'a>,
        node: &'a Node,
        what: String,
        kind: &'static str,
    ) -> Result<(Fields<'a>, String), FileError> {
        let mut f = Fields::of(doc, node, what)?;
        let name = f.required("name", string)?.to_string();
        let span = f.entry("name").and_then(|e| e.node.span.clone());
        // Escaped: a newline in a name must not split the message.
        f.what = described(kind, &name);
        if name.is_empty() || name.chars().any(|c| c.is_control()) {
            return Err(doc.error(
                span.as_ref(),
                format!(
                    "{}: a name must be non-empty and without control characters",
                    f.what
                ),
            ));
        }
        if let Some((at, other_kind)) = self.by_name.get(&name) {
            let other = described(other_kind, &name);
            let line = doc
                .line(at.as_ref())
                .map(|l| format!(" (line {l})"))
                .unwrap_or_default();
            return Err(doc.error(
                span.as_ref(),
                format!("the name '{name}' is used twice: by {other}{line} and by this {kind}"),
            ));
        }
        // One name space: a joint or a force called `ground` would be
        // confused with the fixed frame in `bodies` and in column names.
        if name == GROUND {
            return Err(doc.error(
                span.as_ref(),
                format!("a {kind} may not be called 'ground': that is the fixed frame"),
            ));
        }
        self.by_name.insert(name.clone(), (span, kind));
        Ok((f, name))
    }

    /// Notes that the builder checks the value of `key` of the element
    /// `name` (at `span`) beyond what the reader does: its errors about the
    /// element are placed there ([`located`](Self::located)).
    pub(crate) fn checked_by_builder(
        &mut self,
        name: &str,
        key: &'static str,
        span: Option<Range<usize>>,
    ) {
        self.checked.insert(name.to_string(), (key, span));
    }

    /// The kind of element (`body`, `joint`, `driver`, …) called `name`.
    pub(crate) fn kind_of(&self, name: &str) -> Option<&'static str> {
        self.by_name.get(name).map(|&(_, kind)| kind)
    }

    /// The names of the elements of the `kinds`, sorted.
    pub(crate) fn names_of(&self, kinds: &[&str]) -> Vec<&str> {
        let mut names: Vec<&str> = self
            .by_name
            .iter()
            .filter(|(_, (_, kind))| kinds.contains(kind))
            .map(|(name, _)| name.as_str())
            .collect();
        names.sort_unstable();
        names
    }

    /// A builder error, placed at the element it names when it can be.
    pub(crate) fn located(&self, doc: Doc<'_>, e: &ModelError) -> FileError {
        let (element, message) = match e {
            ModelError::Invalid { element, what } => (element.clone(), what.clone()),
            ModelError::DuplicateName(name) => (name.clone(), e.to_string()),
            // (ModelError is #[non_exhaustive]: a kind added later is
            // reported without a place.)
            _ => (String::new(), e.to_string()),
        };
        match (self.by_name.get(&element), self.checked.get(&element)) {
            (Some((_, kind)), Some((key, span))) => doc.error(
                span.as_ref(),
                format!("{}: {key}: {message}", described(kind, &element)),
            ),
            (Some((span, kind)), None) => doc.error(
                span.as_ref(),
                format!("{}: {message}", described(kind, &element)),
            ),
            (None, _) => doc.error(None, format!("{element}: {message}")),
        }
    }
}

/// `<kind> '<name>'`, the name escaped as `escape_debug` does (a newline
/// must not split a message), without the formatting machinery for a
/// name that needs no escape (10⁵-body files have 2.5·10⁵ names).
fn described(kind: &str, name: &str) -> String {
    let plain = name
        .bytes()
        .all(|b| (b.is_ascii_graphic() || b == b' ') && !matches!(b, b'\\' | b'\'' | b'"'));
    if !plain {
        return format!("{kind} '{}'", name.escape_debug());
    }
    let mut what = String::with_capacity(kind.len() + name.len() + 3);
    what.push_str(kind);
    what.push_str(" '");
    what.push_str(name);
    what.push('\'');
    what
}

/// A named body of a model file, as joints and forces refer to it: its
/// handle `I`, whether it is rigid, and its initial pose `P`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Placed<I, P> {
    pub(crate) id: I,
    pub(crate) rigid: bool,
    pub(crate) pose: P,
}

impl<I, P> Placed<I, P> {
    /// A rigid body.
    pub(crate) fn rigid(id: I, pose: P) -> Self {
        Self {
            id,
            rigid: true,
            pose,
        }
    }

    /// A point mass.
    pub(crate) fn point(id: I, pose: P) -> Self {
        Self {
            id,
            rigid: false,
            pose,
        }
    }
}

/// Where an element's points are given: `points`, one local point per
/// side, or `at`, one global point at the initial pose.
pub(crate) enum Given<const D: usize> {
    /// `points = [[..], [..]]`.
    Points([[f64; D]; 2]),
    /// `at = [..]`.
    At([f64; D]),
}

/// What the reader of either dimension holds beside its builder: the
/// document, the bodies read so far (placed as `P`) and every name given.
pub(crate) struct Reader<'a, P> {
    pub(crate) doc: Doc<'a>,
    pub(crate) bodies: Bodies<P>,
    names: Names,
}

impl<'a, P: Copy> Reader<'a, P> {
    /// Opens the document `root`: its `format` must be `format` (`known`
    /// says, in the message, which formats this version reads); its
    /// `gravity` defaults to `gravity`. Returns the reader, sized for the
    /// element arrays, the top-level fields and the gravity.
    pub(crate) fn open<const D: usize>(
        doc: Doc<'a>,
        root: &'a Node,
        format: &str,
        known: &str,
        gravity: [f64; D],
    ) -> Result<(Self, Fields<'a>, [f64; D]), FileError> {
        let mut top = Fields::of(doc, root, "the model".to_string())?;
        let found = top.required("format", string)?;
        if found != format {
            let e = top.entry("format").map(|e| e.node.span.clone());
            return Err(doc.error(
                e.flatten().as_ref(),
                format!("unknown format '{found}': this version of mstar reads {known}"),
            ));
        }
        let gravity = top.optional("gravity", numbers::<D>)?.unwrap_or(gravity);
        let (elements, bodies) = element_counts(&top);
        let reader = Self {
            doc,
            bodies: Bodies::with_capacity(bodies),
            names: Names::with_capacity(elements),
        };
        Ok((reader, top, gravity))
    }

    /// The element's fields and its name, the name claimed
    /// ([`Names::named`]).
    pub(crate) fn named(
        &mut self,
        node: &'a Node,
        what: String,
        kind: &'static str,
    ) -> Result<(Fields<'a>, String), FileError> {
        self.names.named(self.doc, node, what, kind)
    }

    /// Notes the key the builder checks ([`Names::checked_by_builder`]).
    pub(crate) fn checked_by_builder(
        &mut self,
        name: &str,
        key: &'static str,
        span: Option<Range<usize>>,
    ) {
        self.names.checked_by_builder(name, key, span);
    }

    /// The kind of element called `name` ([`Names::kind_of`]).
    pub(crate) fn kind_of(&self, name: &str) -> Option<&'static str> {
        self.names.kind_of(name)
    }

    /// The names of the elements of the `kinds` ([`Names::names_of`]).
    pub(crate) fn names_of(&self, kinds: &[&str]) -> Vec<&str> {
        self.names.names_of(kinds)
    }

    /// The element's fields, its name (claimed, as [`named`](Self::named))
    /// and its `type`, one of `types`.
    pub(crate) fn typed<'c>(
        &mut self,
        node: &'a Node,
        what: String,
        kind: &'static str,
        types: &'c [&'c str],
    ) -> Result<(Fields<'a>, String, &'c str), FileError> {
        let (mut f, name) = self.named(node, what, kind)?;
        let found = f.required("type", choice(types))?;
        Ok((f, name, found))
    }

    /// A `[[point_mass]]`: its name, mass, position and velocity (at rest
    /// by default), no other key, added by `add` (to the builder, which
    /// says where the point mass is placed).
    pub(crate) fn point_mass<const D: usize>(
        &mut self,
        node: &'a Node,
        what: String,
        add: impl FnOnce(&str, PointMass<D>) -> P,
    ) -> Result<(), FileError> {
        let (mut f, name) = self.named(node, what, "point mass")?;
        let mass = mass(&mut f)?;
        let position = f.required("position", numbers::<D>)?;
        let velocity = f.optional("velocity", numbers::<D>)?.unwrap_or([0.0; D]);
        f.finish(&["name", "mass", "position", "velocity"])?;
        let point = PointMass {
            mass,
            position,
            velocity,
        };
        let placed = add(&name, point);
        self.place(name, placed)
    }

    /// Adds the body `name` (the reader has checked that it is new): the
    /// last step of reading a body, which cannot fail.
    #[allow(clippy::unnecessary_wraps)]
    pub(crate) fn place(&mut self, name: String, placed: P) -> Result<(), FileError> {
        self.bodies.insert(name, placed);
        Ok(())
    }

    /// The attachment points as given: `points` (`two` reads them, one per
    /// side, local) or `at` (one global point), exactly one of them.
    pub(crate) fn given<const D: usize>(
        &self,
        f: &mut Fields<'a>,
        two: fn(&Node) -> Result<[[f64; D]; 2], String>,
    ) -> Result<Given<D>, FileError> {
        let points = f.optional("points", two)?;
        let at = f.optional("at", numbers::<D>)?;
        match (points, at) {
            (Some(p), None) => Ok(Given::Points(p)),
            (None, Some(g)) => Ok(Given::At(g)),
            (Some(_), Some(_)) => Err(self.doc.error(
                f.span(),
                format!("{}: give 'points' or 'at', not both", f.what),
            )),
            (None, None) => Err(f.typo_of(&["points", "at"]).unwrap_or_else(|| {
                self.doc.error(
                    f.span(),
                    format!("{}: the key 'points' (or 'at') is missing", f.what),
                )
            })),
        }
    }

    /// The time function of `key`, if present.
    pub(crate) fn function(
        &self,
        f: &mut Fields<'a>,
        key: &str,
    ) -> Result<Option<TimeFunction>, FileError> {
        let Some(e) = f.entry(key) else {
            return Ok(None);
        };
        let what = format!("{}: {key}", f.what);
        super::functions::read(self.doc, &e.node, what).map(Some)
    }

    /// A builder error, placed at the element it names when it can be.
    pub(crate) fn located(&self, e: &ModelError) -> FileError {
        self.names.located(self.doc, e)
    }
}

/// The key `mass`: positive, in kg.
pub(crate) fn mass(f: &mut Fields<'_>) -> Result<f64, FileError> {
    f.required("mass", number_in(|x| x > 0.0, "positive, in kg"))
}

/// What a spring-damper resists: a change of length or of angle.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Spring {
    /// N/m and N s/m.
    Linear,
    /// N m/rad and N m s/rad.
    Rotational,
}

/// The keys `stiffness` (required) and `damping` (0 by default) of a
/// spring-damper, both non-negative.
pub(crate) fn stiffness_damping(
    f: &mut Fields<'_>,
    spring: Spring,
) -> Result<(f64, f64), FileError> {
    let (k, c) = match spring {
        Spring::Linear => ("non-negative, in N/m", "non-negative, in N s/m"),
        Spring::Rotational => ("non-negative, in N m/rad", "non-negative, in N m s/rad"),
    };
    let stiffness = f.required("stiffness", number_in(|x| x >= 0.0, k))?;
    let damping = f
        .optional("damping", number_in(|x| x >= 0.0, c))?
        .unwrap_or(0.0);
    Ok((stiffness, damping))
}

/// The element arrays of a model file, read in this order (a joint names
/// the bodies before it).
pub(crate) trait Elements<'a> {
    /// A `[[body]]`.
    fn body(&mut self, node: &'a Node, what: String) -> Result<(), FileError>;
    /// A `[[point_mass]]`.
    fn point_mass(&mut self, node: &'a Node, what: String) -> Result<(), FileError>;
    /// A `[[joint]]`.
    fn joint(&mut self, node: &'a Node, what: String) -> Result<(), FileError>;
    /// A `[[driver]]`.
    fn driver(&mut self, node: &'a Node, what: String) -> Result<(), FileError>;
    /// A `[[force]]`.
    fn force(&mut self, node: &'a Node, what: String) -> Result<(), FileError>;
    /// A `[[sensor]]` (read after every other element).
    fn sensor(&mut self, node: &'a Node, what: String) -> Result<(), FileError>;
}

/// How many elements the arrays of [`read_elements`] hold, and how many of
/// them are bodies and point masses (to size the maps by name at once).
fn element_counts(top: &Fields<'_>) -> (usize, usize) {
    let count = |kind: &str| {
        top.peek(kind)
            .and_then(|n| list(n).ok())
            .map_or(0, <[Node]>::len)
    };
    let bodies = count("body") + count("point_mass");
    (
        bodies + count("joint") + count("driver") + count("force") + count("sensor"),
        bodies,
    )
}

/// Reads the element arrays `body`, `point_mass`, `joint`, `driver`,
/// `force` and `sensor` of the document `top` into `m`, in that order (a
/// joint names the bodies before it, a sensor any element), then checks that `top` has no other keys than these,
/// `format`, `gravity` and the caller's `simulation` and `output`.
pub(crate) fn read_elements<'a, M: Elements<'a>>(
    top: &mut Fields<'a>,
    m: &mut M,
) -> Result<(), FileError> {
    const ELEMENTS: [&str; 6] = ["body", "point_mass", "joint", "driver", "force", "sensor"];
    for kind in ELEMENTS {
        for (k, node) in top.optional(kind, list)?.unwrap_or(&[]).iter().enumerate() {
            let what = format!("{kind} #{}", k + 1);
            match kind {
                "body" => m.body(node, what),
                "point_mass" => m.point_mass(node, what),
                "joint" => m.joint(node, what),
                "driver" => m.driver(node, what),
                "force" => m.force(node, what),
                _ => m.sensor(node, what),
            }?;
        }
    }
    let mut keys = vec!["format", "gravity", "simulation", "output"];
    keys.extend(ELEMENTS);
    top.finish(&keys)
}

#[cfg(test)]
mod tests {
    use super::described;

    /// The fast path writes what `escape_debug` would.
    #[test]
    fn names_are_described_as_escaped() {
        for name in [
            "crank",
            "B1-C2",
            "a b",
            "x'y",
            "q\"",
            "back\\slash",
            "new\nline",
            "é",
            "tab\t",
            "~!@#$%^&*()",
        ] {
            assert_eq!(
                described("joint", name),
                format!("joint '{}'", name.escape_debug()),
                "{name}"
            );
        }
    }

    /// `ground` is the fixed frame in the one name space: no element of
    /// any kind may carry it (a joint called so wrote `lambda:ground`).
    #[test]
    fn no_element_may_be_called_ground() {
        use crate::{Format, MechanismFile};
        let body = "format = \"mstar.planar/1\"\n[[body]]\nname = \"bar\"\nmass = 1.0\n\
                    inertia = 0.1\npose = [0.5, 0.0, 0.0]\n";
        for (kind, element) in [
            (
                "joint",
                "[[joint]]\nname = \"ground\"\ntype = \"revolute\"\nbodies = [\"ground\", \"bar\"]\nat = [0.0, 0.0]\n",
            ),
            (
                "force",
                "[[force]]\nname = \"ground\"\ntype = \"torque\"\nbody = \"bar\"\nfunction = { constant = 1.0 }\n",
            ),
            (
                "driver",
                "[[driver]]\nname = \"ground\"\nbody = \"bar\"\ncoordinate = \"x\"\nfunction = { constant = 0.5 }\n",
            ),
            (
                "sensor",
                "[[sensor]]\nname = \"ground\"\ntype = \"position\"\nbody = \"bar\"\n",
            ),
        ] {
            let text = format!("{body}{element}");
            let e = MechanismFile::parse(&text, "m.toml", Format::Toml).expect_err(kind);
            assert_eq!(
                e.to_string(),
                format!("m.toml:8:8: a {kind} may not be called 'ground': that is the fixed frame"),
                "{kind}"
            );
        }
    }

    /// An error about a key is placed at the key, not at the element's
    /// header: a force's `point` on a point mass, a joint's `points`.
    #[test]
    fn a_point_on_a_point_mass_is_placed_at_its_key() {
        use crate::{Format, MechanismFile};
        let mass = "format = \"mstar.planar/1\"\n[[point_mass]]\nname = \"m\"\nmass = 3.0\n\
                    position = [0.0, -1.0]\n";
        for (element, at, key) in [
            (
                "[[force]]\nname = \"f2\"\ntype = \"force\"\nbody = \"m\"\npoint = [0.1, 0.0]\n",
                "m.toml:10:9: force 'f2': point",
                "[0.1, 0.0]",
            ),
            (
                "[[joint]]\nname = \"pin\"\ntype = \"revolute\"\nbodies = [\"ground\", \"m\"]\n\
                 points = [[0.0, -1.0], [0.2, 0.0]]\n",
                "m.toml:10:10: joint 'pin': points",
                "[0.2, 0.0]",
            ),
        ] {
            let text = format!("{mass}{element}");
            let e = MechanismFile::parse(&text, "m.toml", Format::Toml).expect_err(at);
            assert_eq!(
                e.to_string(),
                format!("{at}: a point mass has no extent: its point must be [0, 0], not {key}"),
            );
        }
    }
}
