//! A URDF document read into links and joints, every value checked where
//! it is written (`FILE:LINE:COLUMN`), and its tree checked: one root, no
//! cycle, every joint's links known.

use std::collections::{HashMap, HashSet};

use crate::FileError;

/// A 3-vector.
pub(crate) type V3 = [f64; 3];

/// A place in the URDF file: line and column, from 1.
pub(crate) type Place = (usize, usize);

/// An `<origin xyz rpy>`: a translation and URDF's fixed-axis roll, pitch,
/// yaw, `R = Rz(yaw) Ry(pitch) Rx(roll)`.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Origin {
    pub(crate) xyz: V3,
    pub(crate) rpy: V3,
}

/// A link's `<inertial>`: its mass, the frame of its centre of mass and
/// its inertia tensor about the centre of mass, in that frame.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Inertial {
    pub(crate) mass: f64,
    pub(crate) origin: Origin,
    pub(crate) tensor: [V3; 3],
}

/// A `<link>`.
#[derive(Clone, Debug)]
pub(crate) struct Link {
    pub(crate) name: String,
    /// `None`: no `<inertial>`, or a mass of 0 (a massless frame).
    pub(crate) inertial: Option<Inertial>,
    pub(crate) place: Place,
}

/// The joint types mstar imports.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Kind {
    /// `revolute` and `continuous`.
    Revolute,
    /// `prismatic`.
    Prismatic,
    /// `fixed`: a weld, or a massless link merged into its parent.
    Fixed,
}

/// A `<joint>`.
#[derive(Clone, Debug)]
pub(crate) struct Joint {
    pub(crate) name: String,
    pub(crate) kind: Kind,
    pub(crate) parent: usize,
    pub(crate) child: usize,
    /// The joint frame in the parent link's frame.
    pub(crate) origin: Origin,
    /// The unit axis in the joint frame (default x).
    pub(crate) axis: V3,
    pub(crate) place: Place,
}

/// A URDF robot: its links and joints in file order, as a tree.
#[derive(Clone, Debug)]
pub(crate) struct Robot {
    /// The URDF file, for messages.
    pub(crate) origin: String,
    pub(crate) links: Vec<Link>,
    pub(crate) joints: Vec<Joint>,
    /// The one link that is no joint's child.
    pub(crate) root: usize,
    /// For each link, the joints whose parent it is, in file order.
    pub(crate) children: Vec<Vec<usize>>,
    /// One note for each kind of element read and ignored.
    pub(crate) notes: Vec<String>,
}

/// What an ignored element is, and why it does not matter to mstar.
const IGNORED: [(&str, &str); 8] = [
    (
        "limit",
        "joint limits are not modelled: the joint moves freely",
    ),
    (
        "dynamics",
        "joint damping and friction are not modelled (a [[force]] of type rotational-spring-damper adds them in a mstar.spatial/1 file)",
    ),
    (
        "mimic",
        "the joint moves on its own: mimic couplings are not modelled",
    ),
    ("safety_controller", "safety controllers are not modelled"),
    ("calibration", "calibration is not used"),
    (
        "transmission",
        "actuators are not modelled (a [[driver]] prescribes a joint's motion in a mstar.spatial/1 file)",
    ),
    ("visual", "geometry is not used: the inertials are"),
    ("collision", "geometry is not used: the inertials are"),
];

/// The document being read: the file's name and text, and the notes so far.
struct Reader<'t> {
    origin: &'t str,
    doc: &'t roxmltree::Document<'t>,
    noted: HashSet<String>,
    /// The notes, with their places (sorted by place at the end).
    notes: Vec<(Place, String)>,
}

type XNode<'a, 't> = roxmltree::Node<'a, 't>;

impl Reader<'_> {
    fn place(&self, at: usize) -> Place {
        let p = self.doc.text_pos_at(at);
        (p.row as usize, p.col as usize)
    }

    /// An error at the element `node`.
    fn error(&self, node: XNode<'_, '_>, message: String) -> FileError {
        let place = self.place(node.range().start);
        FileError {
            origin: self.origin.to_string(),
            place: Some(place),
            message,
            in_override: false,
        }
    }

    /// An error at the value of the attribute `key` of `node` (at the
    /// element when it has no such attribute).
    fn attribute_error(&self, node: XNode<'_, '_>, key: &str, message: String) -> FileError {
        let at = node
            .attribute_node(key)
            .map_or(node.range().start, |a| a.range_value().start);
        FileError {
            origin: self.origin.to_string(),
            place: Some(self.place(at)),
            message,
            in_override: false,
        }
    }

    /// One note for the first element called `tag` read and ignored.
    fn ignore(&mut self, node: XNode<'_, '_>) {
        let tag = node.tag_name().name();
        if !self.noted.insert(tag.to_string()) {
            return;
        }
        let why = IGNORED.iter().find(|(t, _)| *t == tag).map_or(
            "not part of what mstar reads (links, inertials, joints)",
            |(_, w)| *w,
        );
        let (line, column) = self.place(node.range().start);
        self.notes.push((
            (line, column),
            format!(
                "{}:{line}:{column}: <{tag}>: ignored (each one in the file): {why}",
                self.origin
            ),
        ));
    }

    /// The attribute `key` of `node`, required.
    fn required<'a>(
        &self,
        node: XNode<'a, '_>,
        what: &str,
        key: &str,
    ) -> Result<&'a str, FileError> {
        node.attribute(key)
            .ok_or_else(|| self.error(node, format!("{what}: the attribute '{key}' is missing")))
    }

    /// The attribute `key` of `node` as numbers, `N` of them separated by
    /// blanks; `default` when absent.
    fn numbers<const N: usize>(
        &self,
        node: XNode<'_, '_>,
        what: &str,
        key: &str,
        default: [f64; N],
    ) -> Result<[f64; N], FileError> {
        let Some(text) = node.attribute(key) else {
            return Ok(default);
        };
        let words: Vec<&str> = text.split_whitespace().collect();
        let parsed: Option<Vec<f64>> = words.iter().map(|w| finite(w)).collect();
        match parsed {
            Some(v) if v.len() == N => Ok(std::array::from_fn(|k| v[k])),
            _ => Err(self.attribute_error(
                node,
                key,
                format!(
                    "{what}: {key}: expected {N} finite number{} separated by blanks, found '{}'",
                    if N == 1 { "" } else { "s" },
                    text.escape_debug()
                ),
            )),
        }
    }

    /// The `<origin>` child of `node`, if any (zero otherwise).
    fn origin(&self, node: XNode<'_, '_>, what: &str) -> Result<Origin, FileError> {
        let Some(o) = child(node, "origin") else {
            return Ok(Origin::default());
        };
        let what = format!("{what}: origin");
        Ok(Origin {
            xyz: self.numbers(o, &what, "xyz", [0.0; 3])?,
            rpy: self.numbers(o, &what, "rpy", [0.0; 3])?,
        })
    }
}

/// A finite number of magnitude at most [`crate::MAX_MAGNITUDE`].
fn finite(word: &str) -> Option<f64> {
    word.parse::<f64>()
        .ok()
        .filter(|x| x.abs() <= crate::MAX_MAGNITUDE)
}

/// The first child element of `node` called `tag`.
fn child<'a, 't>(node: XNode<'a, 't>, tag: &str) -> Option<XNode<'a, 't>> {
    node.children()
        .find(|c| c.is_element() && c.tag_name().name() == tag)
}

/// `name 'x'` as messages write it.
fn described(kind: &str, name: &str) -> String {
    format!("{kind} '{}'", name.escape_debug())
}

/// Parses the URDF document `text` (the file `origin`).
///
/// # Errors
/// Malformed XML (`FILE:LINE:COLUMN`), a missing or malformed attribute, an
/// unsupported joint type, a joint naming an unknown link, a link that is
/// the child of two joints, a cycle, no root or two roots.
pub(crate) fn parse(text: &str, origin: &str) -> Result<Robot, FileError> {
    let opts = roxmltree::ParsingOptions {
        allow_dtd: true,
        ..roxmltree::ParsingOptions::default()
    };
    let doc = roxmltree::Document::parse_with_options(text, opts).map_err(|e| {
        let pos = e.pos();
        let message = e.to_string().replace(&format!(" at {pos}"), "");
        FileError {
            origin: origin.to_string(),
            place: Some((pos.row as usize, pos.col as usize)),
            message: format!("XML syntax: {message}"),
            in_override: false,
        }
    })?;
    let mut r = Reader {
        origin,
        doc: &doc,
        noted: HashSet::new(),
        notes: Vec::new(),
    };
    let top = doc.root_element();
    if top.tag_name().name() != "robot" {
        return Err(r.error(
            top,
            format!(
                "expected a URDF document, whose root element is <robot>, found <{}>",
                top.tag_name().name()
            ),
        ));
    }
    let (links, joint_nodes) = read_links(&mut r, top)?;
    let index: HashMap<&str, usize> = links
        .iter()
        .enumerate()
        .map(|(k, l)| (l.name.as_str(), k))
        .collect();
    let mut joints = Vec::with_capacity(joint_nodes.len());
    let mut names = HashSet::new();
    for node in joint_nodes {
        let joint = read_joint(&mut r, node, &index, &links)?;
        if !names.insert(joint.name.clone()) {
            return Err(r.error(
                node,
                format!(
                    "{}: a second joint of this name",
                    described("joint", &joint.name)
                ),
            ));
        }
        joints.push(joint);
    }
    let (root, children) = tree(&r, top, &links, &joints)?;
    // In the order of the file (joints are read after the links).
    r.notes.sort_by_key(|(place, _)| *place);
    Ok(Robot {
        origin: origin.to_string(),
        links,
        joints,
        root,
        children,
        notes: r.notes.into_iter().map(|(_, note)| note).collect(),
    })
}

/// The links of `<robot>` (every other element noted and ignored), and
/// its joint elements, read once the links are known.
fn read_links<'a, 't>(
    r: &mut Reader<'_>,
    top: XNode<'a, 't>,
) -> Result<(Vec<Link>, Vec<XNode<'a, 't>>), FileError> {
    let mut links: Vec<Link> = Vec::new();
    let mut names = HashSet::new();
    let mut joints = Vec::new();
    for node in top.children().filter(XNode::is_element) {
        match node.tag_name().name() {
            "link" => {
                let name = r.required(node, "<link>", "name")?.to_string();
                let what = described("link", &name);
                if !names.insert(name.clone()) {
                    return Err(r.error(node, format!("{what}: a second link of this name")));
                }
                let inertial = match child(node, "inertial") {
                    Some(i) => read_inertial(r, i, &what)?,
                    None => None,
                };
                for c in node.children().filter(XNode::is_element) {
                    if c.tag_name().name() != "inertial" {
                        r.ignore(c);
                    }
                }
                let place = r.place(node.range().start);
                links.push(Link {
                    name,
                    inertial,
                    place,
                });
            }
            "joint" => joints.push(node),
            _ => r.ignore(node),
        }
    }
    Ok((links, joints))
}

/// A link's `<inertial>`: `None` for a mass of 0.
fn read_inertial(
    r: &Reader<'_>,
    node: XNode<'_, '_>,
    what: &str,
) -> Result<Option<Inertial>, FileError> {
    let origin = r.origin(node, what)?;
    let mass_node = child(node, "mass").ok_or_else(|| {
        r.error(
            node,
            format!("{what}: inertial: the element <mass value=\"..\"/> is missing"),
        )
    })?;
    let what_mass = format!("{what}: mass");
    let [mass] = r.numbers::<1>(mass_node, &what_mass, "value", [f64::NAN])?;
    if mass.is_nan() || mass < 0.0 {
        return Err(r.attribute_error(
            mass_node,
            "value",
            format!("{what_mass}: value: must be a number >= 0, in kg (0: a massless frame, merged into its parent)"),
        ));
    }
    if mass == 0.0 {
        return Ok(None);
    }
    let i_node = child(node, "inertia").ok_or_else(|| {
        r.error(
            node,
            format!("{what}: inertial: the element <inertia ixx=\"..\" .. izz=\"..\"/> is missing"),
        )
    })?;
    let what_i = format!("{what}: inertia");
    let get = |key: &str| -> Result<f64, FileError> {
        if i_node.attribute(key).is_none() {
            return Err(r.error(
                i_node,
                format!("{what_i}: the attribute '{key}' is missing"),
            ));
        }
        Ok(r.numbers::<1>(i_node, &what_i, key, [0.0])?[0])
    };
    let [ixx, ixy, ixz, iyy, iyz, izz] = [
        get("ixx")?,
        get("ixy")?,
        get("ixz")?,
        get("iyy")?,
        get("iyz")?,
        get("izz")?,
    ];
    Ok(Some(Inertial {
        mass,
        origin,
        tensor: [[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]],
    }))
}

/// A `<joint>` of the types mstar imports, its links looked up in `index`.
fn read_joint(
    r: &mut Reader<'_>,
    node: XNode<'_, '_>,
    index: &HashMap<&str, usize>,
    links: &[Link],
) -> Result<Joint, FileError> {
    let name = r.required(node, "<joint>", "name")?.to_string();
    let what = described("joint", &name);
    let kind = match r.required(node, &what, "type")? {
        "revolute" | "continuous" => Kind::Revolute,
        "prismatic" => Kind::Prismatic,
        "fixed" => Kind::Fixed,
        other => return Err(r.attribute_error(node, "type", unsupported(&what, other))),
    };
    let link = |tag: &str| -> Result<usize, FileError> {
        let Some(c) = child(node, tag) else {
            return Err(r.error(
                node,
                format!("{what}: the element <{tag} link=\"..\"/> is missing"),
            ));
        };
        let wanted = r.required(c, &format!("{what}: {tag}"), "link")?;
        index.get(wanted).copied().ok_or_else(|| {
            let mut known: Vec<&str> = links.iter().map(|l| l.name.as_str()).collect();
            known.sort_unstable();
            r.attribute_error(
                c,
                "link",
                format!(
                    "{what}: {tag}: no link is called '{}' (known: {})",
                    wanted.escape_debug(),
                    if known.is_empty() {
                        "none".to_string()
                    } else {
                        known.join(", ")
                    }
                ),
            )
        })
    };
    let parent = link("parent")?;
    let child_link = link("child")?;
    let origin = r.origin(node, &what)?;
    let axis = match child(node, "axis") {
        Some(a) => unit_axis(r, a, &what)?,
        None => [1.0, 0.0, 0.0],
    };
    for c in node.children().filter(XNode::is_element) {
        if !["parent", "child", "origin", "axis"].contains(&c.tag_name().name()) {
            r.ignore(c);
        }
    }
    Ok(Joint {
        name,
        kind,
        parent,
        child: child_link,
        origin,
        axis,
        place: r.place(node.range().start),
    })
}

/// The message for a joint type mstar does not import.
fn unsupported(what: &str, kind: &str) -> String {
    let hint = match kind {
        "floating" => {
            "for a fixed base make the joint fixed (a weld); a free body is a [[body]] without joints in a mstar.spatial/1 file"
        }
        "planar" => "model it as two prismatic joints and a revolute joint through links with mass",
        _ => "URDF's joint types are revolute, continuous, prismatic, fixed, floating and planar",
    };
    format!(
        "{what}: type: '{}' is not supported: mstar imports revolute, continuous, prismatic and fixed joints; {hint}",
        kind.escape_debug()
    )
}

/// The `<axis xyz>` of a joint, normalized; an error for a zero axis.
fn unit_axis(r: &Reader<'_>, node: XNode<'_, '_>, what: &str) -> Result<V3, FileError> {
    let what = format!("{what}: axis");
    let a = r.numbers(node, &what, "xyz", [1.0, 0.0, 0.0])?;
    let norm = a.iter().map(|x| x * x).sum::<f64>().sqrt();
    if !(norm > 0.0 && norm.is_finite()) {
        return Err(r.attribute_error(
            node,
            "xyz",
            format!("{what}: xyz: must not be zero: a direction in the joint frame"),
        ));
    }
    Ok(a.map(|x| x / norm))
}

/// The root of the tree and each link's child joints; errors for a link
/// that is the child of two joints, for no root or two roots, and for a
/// cycle.
fn tree(
    r: &Reader<'_>,
    top: XNode<'_, '_>,
    links: &[Link],
    joints: &[Joint],
) -> Result<(usize, Vec<Vec<usize>>), FileError> {
    let at = |place: Place| FileError {
        origin: r.origin.to_string(),
        place: Some(place),
        message: String::new(),
        in_override: false,
    };
    let mut parent_joint: Vec<Option<usize>> = vec![None; links.len()];
    let mut children = vec![Vec::new(); links.len()];
    for (k, j) in joints.iter().enumerate() {
        if let Some(before) = parent_joint[j.child] {
            return Err(FileError {
                message: format!(
                    "{}: child: link '{}' is already the child of joint '{}': a URDF is a tree (close a loop with a [[joint]] in a mstar.spatial/1 file that starts from the URDF, urdf = \"..\")",
                    described("joint", &j.name),
                    links[j.child].name.escape_debug(),
                    joints[before].name.escape_debug()
                ),
                ..at(j.place)
            });
        }
        parent_joint[j.child] = Some(k);
        children[j.parent].push(k);
    }
    let roots: Vec<usize> = (0..links.len())
        .filter(|&l| parent_joint[l].is_none())
        .collect();
    match roots.as_slice() {
        [root] => match unreached(joints, &children, links.len(), *root) {
            Some(start) => Err(cycle(r, links, joints, &parent_joint, start)),
            None => Ok((*root, children)),
        },
        [] if links.is_empty() => Err(r.error(top, "the robot has no <link>".to_string())),
        // Every link has a parent: the walk up from any one goes round a cycle.
        [] => Err(cycle(r, links, joints, &parent_joint, 0)),
        [first, second, ..] => Err(FileError {
            message: format!(
                "two root links, '{}' and '{}' (no joint has either as its child): a URDF robot is one tree; join them with a joint",
                links[*first].name.escape_debug(),
                links[*second].name.escape_debug()
            ),
            ..at(links[*second].place)
        }),
    }
}

/// A link not reached from `root` through the joints, if any.
fn unreached(joints: &[Joint], children: &[Vec<usize>], n: usize, root: usize) -> Option<usize> {
    let mut reached = vec![false; n];
    let mut stack = vec![root];
    while let Some(l) = stack.pop() {
        if std::mem::replace(&mut reached[l], true) {
            continue;
        }
        stack.extend(children[l].iter().map(|&j| joints[j].child));
    }
    (0..n).find(|&l| !reached[l])
}

/// The error naming the cycle of joints above `start`, a link that the
/// root does not reach (or any link, when there is no root).
fn cycle(
    r: &Reader<'_>,
    links: &[Link],
    joints: &[Joint],
    parent_joint: &[Option<usize>],
    start: usize,
) -> FileError {
    // Up the parents from a link not reached: every link has one, so the
    // walk comes back to a link it passed, and the links from there on are
    // the cycle.
    let mut path = vec![start];
    let mut l = start;
    while let Some(j) = parent_joint[l] {
        l = joints[j].parent;
        if let Some(k) = path.iter().position(|&p| p == l) {
            path.drain(..k);
            break;
        }
        path.push(l);
    }
    path.reverse();
    let names: Vec<String> = path
        .iter()
        .map(|&l| format!("'{}'", links[l].name.escape_debug()))
        .collect();
    let first = parent_joint[path[0]].map_or(links[path[0]].place, |j| joints[j].place);
    FileError {
        origin: r.origin.to_string(),
        place: Some(first),
        message: format!(
            "the joints form a cycle through the links {} (back to {}): a URDF is a tree (close a loop with a [[joint]] in a mstar.spatial/1 file that starts from the URDF, urdf = \"..\")",
            names.join(" → "),
            names[0]
        ),
        in_override: false,
    }
}
