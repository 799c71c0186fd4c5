//! A URDF robot written as the `mstar.spatial/1` document it means: each
//! link with mass a body at its centre of mass, placed by forward
//! kinematics through the tree at the given joint positions (and moving at
//! the given joint velocities), each joint a revolute, prismatic or weld
//! joint at its global point and axis.

use std::collections::HashMap;
use std::fmt::Write as _;

use super::robot::{Inertial, Kind, Origin, Robot, V3};
use crate::FileError;
use mstar_model::spatial::rotation_matrix;

/// Euler parameters.
type Q = [f64; 4];

/// A joint's position and velocity at the start (rad and rad/s, or m and m/s).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct JointState {
    pub(crate) position: f64,
    pub(crate) velocity: f64,
}

/// A link frame at the start: origin, orientation (frame to global), the
/// velocity of its origin and its angular velocity (global).
#[derive(Clone, Copy, Debug)]
struct Frame {
    p: V3,
    q: Q,
    v: V3,
    w: V3,
}

/// What carries a link in the mstar model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Carrier {
    /// The ground (a massless root, or massless links fixed to it).
    Ground,
    /// The body of the link with this index (the link itself, its parent's
    /// for a massless link fixed to it, or for a massless link moved by a
    /// joint the first link with mass welded to it).
    Body(usize),
    /// Nothing: a massless leaf moved by a joint, left out with its joint.
    Dropped,
}

/// The robot's mstar model: each link's frame and carrier, and the notes
/// about links left out.
pub(crate) struct Placement {
    frames: Vec<Frame>,
    carriers: Vec<Carrier>,
    pub(crate) notes: Vec<String>,
}

/// The name of the weld that holds a root link with mass to the ground.
pub(crate) fn root_weld(root: &str) -> String {
    format!("{root}_to_ground")
}

/// Places every link of `robot` with the joints at `initial` (by joint name;
/// absent joints at 0, at rest) and decides what carries it.
///
/// # Errors
/// A massless link moved by a joint that has children of its own.
pub(crate) fn place(
    robot: &Robot,
    initial: &HashMap<String, JointState>,
) -> Result<Placement, FileError> {
    let n = robot.links.len();
    let rest = Frame {
        p: [0.0; 3],
        q: [1.0, 0.0, 0.0, 0.0],
        v: [0.0; 3],
        w: [0.0; 3],
    };
    let mut frames = vec![rest; n];
    let mut carriers = vec![Carrier::Ground; n];
    let mut notes = Vec::new();
    let root = robot.root;
    if robot.links[root].inertial.is_some() {
        carriers[root] = Carrier::Body(root);
    }
    // Breadth first from the root: each link placed after its parent.
    let mut order = vec![root];
    let mut k = 0;
    while let Some(&l) = order.get(k) {
        k += 1;
        for &j in &robot.children[l] {
            let joint = &robot.joints[j];
            let state = initial.get(&joint.name).copied().unwrap_or_default();
            frames[joint.child] =
                child_frame(&frames[l], joint.kind, &joint.origin, joint.axis, state);
            carriers[joint.child] = carrier(robot, j, carriers[l], &mut notes)?;
            order.push(joint.child);
        }
    }
    Ok(Placement {
        frames,
        carriers,
        notes,
    })
}

/// What carries the child of joint `j`, whose parent is carried by `parent`.
fn carrier(
    robot: &Robot,
    j: usize,
    parent: Carrier,
    notes: &mut Vec<String>,
) -> Result<Carrier, FileError> {
    let joint = &robot.joints[j];
    let child = &robot.links[joint.child];
    if child.inertial.is_some() {
        return Ok(Carrier::Body(joint.child));
    }
    if joint.kind == Kind::Fixed {
        // A massless frame fixed to its parent: the parent's body carries it.
        return Ok(parent);
    }
    // A massless frame moved by the joint, with a link of mass welded to
    // it (through fixed joints): that link's body carries it.
    if let Some(body) = fixed_body(robot, joint.child) {
        return Ok(Carrier::Body(body));
    }
    let (line, column) = joint.place;
    if robot.children[joint.child].is_empty() {
        notes.push(format!(
            "{}:{line}:{column}: joint '{}': left out with its child link '{}', which has no mass (no <inertial>, or mass 0) and nothing attached: it would move nothing",
            robot.origin,
            joint.name.escape_debug(),
            child.name.escape_debug()
        ));
        return Ok(Carrier::Dropped);
    }
    Err(FileError {
        origin: robot.origin.clone(),
        place: Some((line, column)),
        message: format!(
            "joint '{}': its child link '{}' has no mass (no <inertial>, or mass 0) and carries further joints, none of them fixed to a link with mass: a {} joint between massless links cannot be merged into a body; give '{}' an <inertial> with a mass, or make the joint fixed",
            joint.name.escape_debug(),
            child.name.escape_debug(),
            if joint.kind == Kind::Revolute {
                "revolute"
            } else {
                "prismatic"
            },
            child.name.escape_debug()
        ),
        in_override: false,
    })
}

/// The first link with mass (breadth first) welded to the massless link `l`
/// through fixed joints and massless links, if any.
fn fixed_body(robot: &Robot, l: usize) -> Option<usize> {
    let mut queue = std::collections::VecDeque::from([l]);
    while let Some(link) = queue.pop_front() {
        for &j in &robot.children[link] {
            let joint = &robot.joints[j];
            if joint.kind != Kind::Fixed {
                continue;
            }
            if robot.links[joint.child].inertial.is_some() {
                return Some(joint.child);
            }
            queue.push_back(joint.child);
        }
    }
    None
}

/// The frame of a joint's child link: the parent frame, moved by the
/// joint's origin, then by its motion at `state` about or along `axis`
/// (unit, in the joint frame).
fn child_frame(parent: &Frame, kind: Kind, origin: &Origin, axis: V3, state: JointState) -> Frame {
    let p_joint = add(parent.p, rotate(parent.q, origin.xyz));
    let v_joint = add(parent.v, cross(parent.w, sub(p_joint, parent.p)));
    let q_joint = mul(parent.q, rpy(origin.rpy));
    let a = rotate(q_joint, axis);
    match kind {
        Kind::Fixed => Frame {
            p: p_joint,
            q: q_joint,
            v: v_joint,
            w: parent.w,
        },
        Kind::Revolute => Frame {
            p: p_joint,
            q: mul(q_joint, about(axis, state.position)),
            v: v_joint,
            w: add(parent.w, scale(a, state.velocity)),
        },
        Kind::Prismatic => {
            let d = scale(a, state.position);
            Frame {
                p: add(p_joint, d),
                q: q_joint,
                v: add(add(v_joint, cross(parent.w, d)), scale(a, state.velocity)),
                w: parent.w,
            }
        }
    }
}

/// Euler parameters of URDF's roll, pitch, yaw: `Rz(yaw) Ry(pitch) Rx(roll)`.
fn rpy(rpy: V3) -> Q {
    let [r, p, y] = rpy;
    mul(
        about([0.0, 0.0, 1.0], y),
        mul(about([0.0, 1.0, 0.0], p), about([1.0, 0.0, 0.0], r)),
    )
}

/// Euler parameters of a rotation by `angle` about the unit axis `n`.
fn about(n: V3, angle: f64) -> Q {
    let (s, c) = (angle / 2.0).sin_cos();
    [c, s * n[0], s * n[1], s * n[2]]
}

/// The quaternion product `a b` (rotation `b` first, then `a`).
fn mul(a: Q, b: Q) -> Q {
    [
        a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
        a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
        a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
        a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
    ]
}

fn rotate(q: Q, s: V3) -> V3 {
    let a = rotation_matrix(q);
    std::array::from_fn(|i| a[i][0] * s[0] + a[i][1] * s[1] + a[i][2] * s[2])
}

fn add(a: V3, b: V3) -> V3 {
    std::array::from_fn(|i| a[i] + b[i])
}

fn sub(a: V3, b: V3) -> V3 {
    std::array::from_fn(|i| a[i] - b[i])
}

fn scale(a: V3, s: f64) -> V3 {
    a.map(|x| x * s)
}

fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// `x` as TOML writes a float that reads back to the same bits (Rust's
/// shortest round trip: `1.0`, `0.25`, `1e-7`).
fn num(x: f64) -> String {
    // -0 reads back as -0 too, but a plain 0 is clearer.
    format!("{:?}", if x == 0.0 { 0.0 } else { x })
}

fn nums(v: &[f64]) -> String {
    let items: Vec<String> = v.iter().map(|&x| num(x)).collect();
    format!("[{}]", items.join(", "))
}

/// `s` as a TOML basic string.
pub(crate) fn quoted(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            c if c.is_control() => {
                let _ = write!(out, "\\u{:04X}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

impl Placement {
    /// The name of what carries link `l` in the model.
    fn carrier_name<'r>(&self, robot: &'r Robot, l: usize) -> &'r str {
        match self.carriers[l] {
            Carrier::Body(b) => &robot.links[b].name,
            Carrier::Ground | Carrier::Dropped => "ground",
        }
    }

    /// The `mstar.spatial/1` document: a comment naming `source`, then
    /// `format` and `gravity` (when `header`), the `[[body]]`s in the
    /// URDF's link order, the root's weld and the `[[joint]]`s in its joint
    /// order.
    pub(crate) fn document(&self, robot: &Robot, source: &str, header: bool) -> String {
        let mut out = String::new();
        if header {
            let _ = writeln!(
                out,
                "# The URDF robot {source} as a mstar.spatial/1 model (mstar convert):\n\
                 # each link with mass a body at its centre of mass, massless links merged\n\
                 # into their parents, joint positions 0 at t = 0, the root link the ground\n\
                 # (massless) or welded to it.\n\
                 format = \"mstar.spatial/1\"\n\
                 gravity = [0.0, 0.0, -9.81]"
            );
        }
        for (l, link) in robot.links.iter().enumerate() {
            if let (Carrier::Body(_), Some(i)) = (self.carriers[l], &link.inertial) {
                self.write_body(&mut out, &link.name, &self.frames[l], i);
            }
        }
        let root = robot.root;
        if self.carriers[root] == Carrier::Body(root) {
            let name = &robot.links[root].name;
            let _ = write!(
                out,
                "\n[[joint]]\nname = {}\ntype = \"weld\"\nbodies = [\"ground\", {}]\nat = {}\n",
                quoted(&root_weld(name)),
                quoted(name),
                nums(&self.frames[root].p)
            );
        }
        for joint in &robot.joints {
            if let Some(text) = self.joint(robot, joint) {
                out.push_str(&text);
            }
        }
        out
    }

    /// A `[[body]]`: the link's centre of mass, the orientation of its
    /// inertial frame and the inertia tensor in that frame.
    fn write_body(&self, out: &mut String, name: &str, frame: &Frame, i: &Inertial) {
        let position = add(frame.p, rotate(frame.q, i.origin.xyz));
        let orientation = mul(frame.q, rpy(i.origin.rpy));
        let velocity = add(frame.v, cross(frame.w, sub(position, frame.p)));
        let t = i.tensor;
        let inertia = if t[0][1] == 0.0 && t[0][2] == 0.0 && t[1][2] == 0.0 {
            nums(&[t[0][0], t[1][1], t[2][2]])
        } else {
            format!("[{}, {}, {}]", nums(&t[0]), nums(&t[1]), nums(&t[2]))
        };
        let _ = write!(
            out,
            "\n[[body]]\nname = {}\nmass = {}\ninertia = {inertia}\nposition = {}\norientation = {}\n",
            quoted(name),
            num(i.mass),
            nums(&position),
            nums(&orientation)
        );
        if velocity != [0.0; 3] {
            let _ = writeln!(out, "velocity = {}", nums(&velocity));
        }
        if frame.w != [0.0; 3] {
            let _ = writeln!(out, "angular_velocity = {}", nums(&frame.w));
        }
    }

    /// The `[[joint]]` of a URDF joint, or `None` for a joint inside a body
    /// (a massless link fixed to its parent) or left out.
    fn joint(&self, robot: &Robot, joint: &super::robot::Joint) -> Option<String> {
        if !self.has(joint) {
            return None;
        }
        let frame = &self.frames[joint.child];
        let parent = self.carrier_name(robot, joint.parent);
        let child = self.carrier_name(robot, joint.child);
        let mut text = format!(
            "\n[[joint]]\nname = {}\ntype = \"{}\"\nbodies = [{}, {}]\nat = {}\n",
            quoted(&joint.name),
            match joint.kind {
                Kind::Revolute => "revolute",
                Kind::Prismatic => "prismatic",
                Kind::Fixed => "weld",
            },
            quoted(parent),
            quoted(child),
            nums(&frame.p)
        );
        if joint.kind != Kind::Fixed {
            // The axis turns with the child: its global direction now.
            let _ = writeln!(text, "axis = {}", nums(&rotate(frame.q, joint.axis)));
        }
        Some(text)
    }

    /// Whether joint `j` is in the model (not inside a body, not left out).
    pub(crate) fn has_joint(&self, robot: &Robot, j: usize) -> bool {
        self.has(&robot.joints[j])
    }

    /// Whether `joint` joins two bodies of the model: its child is carried
    /// by a body (its own, or that of a link with mass welded to it), not
    /// the one that carries its parent (a massless link fixed to its
    /// parent, a link with mass welded to the massless link it carries),
    /// and not left out.
    fn has(&self, joint: &super::robot::Joint) -> bool {
        let child = self.carriers[joint.child];
        matches!(child, Carrier::Body(_)) && child != self.carriers[joint.parent]
    }

    /// The names the model gives bodies and joints, each with where the URDF
    /// defines it: the links with mass, the root's weld and the joints kept.
    pub(crate) fn names(&self, robot: &Robot) -> Vec<(String, (usize, usize))> {
        let mut names = Vec::new();
        for (l, link) in robot.links.iter().enumerate() {
            if self.carriers[l] == Carrier::Body(l) {
                names.push((link.name.clone(), link.place));
            }
        }
        if self.carriers[robot.root] == Carrier::Body(robot.root) {
            let root = &robot.links[robot.root];
            names.push((root_weld(&root.name), root.place));
        }
        for (j, joint) in robot.joints.iter().enumerate() {
            if self.has_joint(robot, j) {
                names.push((joint.name.clone(), joint.place));
            }
        }
        names
    }
}
