//! The bodies a model file has named so far, and how its elements name
//! them: the steps the planar and the spatial readers share.

use std::collections::HashMap;
use std::ops::Range;

use super::FileError;
use super::fields::{Doc, Fields, list, string, two_names};
use super::node::Node;
use mstar_model::planar::ModelError;

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

    /// The message for an unknown name, listing the known ones.
    fn unknown(&self, name: &str) -> String {
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
    by_name: HashMap<String, (String, Option<Range<usize>>)>,
}

impl Names {
    /// None yet, with room for `names` without growing.
    pub(crate) fn with_capacity(names: usize) -> Self {
        Self {
            by_name: HashMap::with_capacity(names),
        }
    }

    /// The fields of the element table `node` (described as `what` until its
    /// name is known, then as `<kind> '<name>'`) and its name: non-empty,
    /// without control characters, new, and not `ground` for a body.
    pub(crate) fn named<'a>(
        &mut self,
        doc: Doc<'a>,
        node: &'a Node,
        what: String,
        kind: &str,
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
        if let Some((other, at)) = self.by_name.get(&name) {
            let line = at
                .as_ref()
                .map(|s| format!(" (line {})", super::node::line_column(doc.text, s.start).0))
                .unwrap_or_default();
            return Err(doc.error(
                span.as_ref(),
                format!("the name '{name}' is used twice: by {other}{line} and by this {kind}"),
            ));
        }
        if name == GROUND && matches!(kind, "body" | "point mass") {
            return Err(doc.error(
                span.as_ref(),
                format!("a {kind} may not be called 'ground': that is the fixed frame"),
            ));
        }
        self.by_name.insert(name.clone(), (f.what.clone(), span));
        Ok((f, name))
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
        match self.by_name.get(&element) {
            Some((what, span)) => doc.error(span.as_ref(), format!("{what}: {message}")),
            None => doc.error(None, format!("{element}: {message}")),
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

/// Reads one element of the arrays of tables into a model `M`.
pub(crate) type Adder<'a, M> = fn(&mut M, &'a Node, String) -> Result<(), FileError>;

/// How many elements the arrays of [`read_elements`] hold, and how many of
/// them are bodies and point masses (to size the maps by name at once).
pub(crate) fn element_counts(top: &Fields<'_>) -> (usize, usize) {
    let count = |kind: &str| {
        top.peek(kind)
            .and_then(|n| list(n).ok())
            .map_or(0, <[Node]>::len)
    };
    let bodies = count("body") + count("point_mass");
    (
        bodies + count("joint") + count("driver") + count("force"),
        bodies,
    )
}

/// Reads the element arrays `body`, `point_mass`, `joint`, `driver` and
/// `force` of the document `top`, in that order (a joint names the bodies
/// before it), with `adders` in the same order, then checks that `top` has
/// no other keys than these, `format`, `gravity` and the caller's
/// `simulation` and `output`.
pub(crate) fn read_elements<'a, M>(
    top: &mut Fields<'a>,
    m: &mut M,
    adders: [Adder<'a, M>; 5],
) -> Result<(), FileError> {
    const ELEMENTS: [&str; 5] = ["body", "point_mass", "joint", "driver", "force"];
    for (kind, add) in ELEMENTS.into_iter().zip(adders) {
        for (k, node) in top.optional(kind, list)?.unwrap_or(&[]).iter().enumerate() {
            add(m, node, format!("{kind} #{}", k + 1))?;
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
}
