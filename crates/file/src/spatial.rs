//! The `mstar.spatial/1` schema: rigid bodies in Euler parameters, point
//! masses, joints, drivers and forces read into a [`SpatialBuilder`], every
//! value checked where it is written (`docs/model-format.md`, "Spatial
//! models").

use std::collections::HashMap;

use super::FileError;
use super::bodies::{self, Given, Reader, Spring};
use super::fields::{Doc, Fields, choice, list, number, number_in, numbers, string};
use super::node::{Node, Value};
use mstar_model::planar::TimeFunction;
use mstar_model::sensor::Sensor;
use mstar_model::spatial::{
    Attach, Axes, DriverKind, JointSpec, JointType, RotationalMass, RotationalSpringDamper,
    SpatialBody, SpatialBodyId, SpatialBuilder, SpatialInertia, SpatialSystem, SpringDamper,
    rotation_matrix,
};

/// The format version of spatial model files.
pub const FORMAT: &str = "mstar.spatial/1";

/// How far from 1 the norm of a given orientation may be without a warning.
const NORM_WARNING: f64 = 1e-12;

/// Where a body is at the start.
#[derive(Clone, Copy, Debug)]
struct Pose {
    position: [f64; 3],
    /// Unit Euler parameters (identity for a point mass).
    orientation: [f64; 4],
}

/// The force types of the format.
const FORCES: [&str; 4] = [
    "force",
    "torque",
    "spring-damper",
    "rotational-spring-damper",
];

/// A named body of the model, as joints and forces refer to it.
type Placed = bodies::Placed<SpatialBodyId, Pose>;

/// One side of a joint or force: the ground or a body.
type Side = bodies::Side<Placed>;

impl Side {
    fn attach(self) -> Attach {
        match self {
            Self::Ground => Attach::Ground,
            Self::Body(b) => Attach::Body(b.id),
        }
    }

    /// The global point of the local point `s` at the initial pose.
    fn global(self, s: [f64; 3]) -> [f64; 3] {
        match self {
            Self::Ground => s,
            Self::Body(b) => add(
                b.pose.position,
                mul(&rotation_matrix(b.pose.orientation), s),
            ),
        }
    }

    /// The local point of the global point `g` at the initial pose.
    fn local(self, g: [f64; 3]) -> [f64; 3] {
        match self {
            Self::Ground => g,
            Self::Body(b) if !b.rigid => [0.0; 3],
            Self::Body(b) => mul_t(
                &rotation_matrix(b.pose.orientation),
                sub(g, b.pose.position),
            ),
        }
    }

    /// The global direction `g` in the side's axes at the initial pose.
    fn local_axis(self, g: [f64; 3]) -> [f64; 3] {
        match self {
            Self::Ground => g,
            Self::Body(b) => mul_t(&rotation_matrix(b.pose.orientation), g),
        }
    }
}

/// The model being read.
struct Model<'a> {
    builder: SpatialBuilder,
    r: Reader<'a, Placed>,
    /// The joints (not drivers) by name, with their type.
    joints: HashMap<String, JointType>,
    warnings: Vec<String>,
    sensors: Vec<Sensor>,
}

/// Reads a whole document: the system and the warnings about it (each
/// `FILE:LINE:COLUMN: element: key: what`).
pub(crate) fn read<'a>(
    doc: Doc<'a>,
    root: &'a Node,
    rotational_mass: RotationalMass,
) -> Result<(SpatialSystem, Vec<String>, Vec<Sensor>), FileError> {
    let known = format!("'{FORMAT}'");
    let (r, mut top, gravity) = Reader::open(doc, root, FORMAT, &known, [0.0, 0.0, -9.81])?;
    let mut m = Model {
        builder: SpatialBuilder::new(),
        r,
        joints: HashMap::new(),
        warnings: Vec::new(),
        sensors: Vec::new(),
    };
    m.builder.gravity(gravity);
    m.builder.rotational_mass(rotational_mass);
    // ([simulation] and [output] are the caller's: settings, not the mechanism.)
    bodies::read_elements(&mut top, &mut m)?;
    let system = m.builder.build().map_err(|e| m.r.located(&e))?;
    Ok((system, m.warnings, m.sensors))
}

impl<'a> bodies::Elements<'a> for Model<'a> {
    /// A `[[sensor]]`.
    fn sensor(&mut self, node: &'a Node, what: String) -> Result<(), FileError> {
        let sensor = self.r.sensor::<3>(node, what)?;
        self.sensors.push(sensor);
        Ok(())
    }

    /// A `[[body]]`: a rigid body.
    fn body(&mut self, node: &'a Node, what: String) -> Result<(), FileError> {
        let (mut f, name) = self.r.named(node, what, "body")?;
        let mass = bodies::mass(&mut f)?;
        let inertia = f.required("inertia", inertia)?;
        // Whether a rigid body can have the inertia, the builder checks.
        let at = f.read_entry("inertia")?;
        let span = at.node.span.clone().or_else(|| at.key_span.clone());
        self.r.checked_by_builder(&name, "inertia", span);
        let position = f.required("position", numbers::<3>)?;
        let given = f.required("orientation", numbers::<4>)?;
        let velocity = f.optional("velocity", numbers::<3>)?.unwrap_or([0.0; 3]);
        let angular_velocity = f
            .optional("angular_velocity", numbers::<3>)?
            .unwrap_or([0.0; 3]);
        f.finish(&[
            "name",
            "mass",
            "inertia",
            "position",
            "orientation",
            "velocity",
            "angular_velocity",
        ])?;
        let e = f.read_entry("orientation")?;
        // (Scaled by the largest, so that tiny parameters do not underflow.)
        let largest = given.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        let norm = largest
            * given
                .iter()
                .map(|x| (x / largest).powi(2))
                .sum::<f64>()
                .sqrt();
        if !(norm > 0.0 && norm.is_finite()) {
            return Err(f.bad(
                e,
                "must not be zero: Euler parameters [e0, e1, e2, e3] of a rotation ([1, 0, 0, 0]: body axes = global axes)",
            ));
        }
        if (norm - 1.0).abs() > NORM_WARNING {
            let message = format!(
                "{}: orientation: normalized: its norm was {norm:.15} (Euler parameters have norm 1)",
                f.what
            );
            let span = e.node.span.as_ref().or(e.key_span.as_ref());
            self.warnings
                .push(self.r.doc.error(span, message).to_string());
        }
        let orientation = given.map(|x| x / norm);
        let id = self.builder.body(
            &name,
            SpatialBody {
                mass,
                inertia,
                position,
                orientation,
                velocity,
                angular_velocity,
            },
        );
        let pose = Pose {
            position,
            orientation,
        };
        self.r.place(name, Placed::rigid(id, pose))
    }

    /// A `[[point_mass]]`.
    fn point_mass(&mut self, node: &'a Node, what: String) -> Result<(), FileError> {
        self.r.point_mass(node, what, |name, point| {
            let pose = Pose {
                position: point.position,
                orientation: [1.0, 0.0, 0.0, 0.0],
            };
            Placed::point(self.builder.point_mass(name, point), pose)
        })
    }

    /// A `[[joint]]`.
    fn joint(&mut self, node: &'a Node, what: String) -> Result<(), FileError> {
        let names = JointType::ALL.map(JointType::name);
        let (mut f, name, kind) = self.r.typed(node, what, "joint", &names)?;
        let kind = JointType::ALL[names.iter().position(|n| *n == kind).expect("a choice")];
        let sides = self.r.bodies.sides(&mut f)?;
        let points = self.anchors(&mut f, sides)?;
        let mut known = vec!["name", "type", "bodies", "points", "at"];
        for s in sides {
            if let Side::Body(b) = s
                && !b.rigid
                && (kind.uses_axes() || kind == JointType::Weld)
            {
                let e = f.read_entry("type")?;
                return Err(f.bad(
                    e,
                    format!(
                        "a {} joint needs orientations, and one of its bodies is a point mass (use spherical or distance)",
                        kind.name()
                    ),
                ));
            }
        }
        let axes = if kind.uses_axes() {
            known.extend(["axes", "axis"]);
            self.joint_axes(&mut f, kind, sides)?
        } else {
            for key in ["axes", "axis"] {
                if let Some(e) = f.entry(key) {
                    return Err(f.bad(
                        e,
                        format!(
                            "a {} joint has no axis: '{key}' belongs to revolute, prismatic, cylindrical and universal joints",
                            kind.name()
                        ),
                    ));
                }
            }
            [[0.0, 0.0, 1.0]; 2]
        };
        let mut length = None;
        if kind == JointType::Distance {
            known.push("length");
            length = f.optional("length", number_in(|x| x > 0.0, "positive, in m"))?;
            let initial = distance(sides[0].global(points[0]), sides[1].global(points[1]));
            if length.is_none() && (initial.is_nan() || initial <= 0.0) {
                return Err(self.r.doc.error(
                    f.span(),
                    format!(
                        "{}: the two points coincide at the initial pose: give 'length'",
                        f.what
                    ),
                ));
            }
        }
        f.finish(&known)?;
        self.builder.joint(
            &name,
            JointSpec {
                kind,
                bodies: sides.map(Side::attach),
                points,
                axes,
                length,
            },
        );
        self.joints.insert(name, kind);
        Ok(())
    }

    /// A `[[driver]]`: a joint's angle or translation prescribed in time.
    fn driver(&mut self, node: &'a Node, what: String) -> Result<(), FileError> {
        let (mut f, name) = self.r.named(node, what, "driver")?;
        let joint = f.required("joint", string)?;
        let e = f.read_entry("joint")?;
        let Some(&kind) = self.joints.get(joint) else {
            let mut known: Vec<&str> = self.joints.keys().map(String::as_str).collect();
            known.sort_unstable();
            return Err(f.bad(
                e,
                format!(
                    "no joint is called '{}' (known: {})",
                    joint.escape_debug(),
                    if known.is_empty() {
                        "none".to_string()
                    } else {
                        known.join(", ")
                    }
                ),
            ));
        };
        let motion = f.required("motion", choice(&["angle", "translation"]))?;
        let motion_kind = if motion == "angle" {
            DriverKind::Angle
        } else {
            DriverKind::Translation
        };
        let fits = match motion_kind {
            DriverKind::Angle => matches!(kind, JointType::Revolute | JointType::Cylindrical),
            DriverKind::Translation => {
                matches!(kind, JointType::Prismatic | JointType::Cylindrical)
            }
        };
        if !fits {
            let e = f.read_entry("motion")?;
            return Err(f.bad(
                e,
                format!(
                    "joint '{}' is {}, which has no free {motion} (angle: revolute, cylindrical; translation: prismatic, cylindrical)",
                    joint.escape_debug(),
                    kind.name()
                ),
            ));
        }
        let function = self
            .r
            .function(&mut f, "function")?
            .ok_or_else(|| f.missing("function"))?;
        f.finish(&["name", "joint", "motion", "function"])?;
        self.builder.driver(&name, joint, motion_kind, function);
        Ok(())
    }

    /// A `[[force]]`.
    fn force(&mut self, node: &'a Node, what: String) -> Result<(), FileError> {
        let (mut f, name, kind) = self.r.typed(node, what, "force", &FORCES)?;
        match kind {
            "force" | "torque" => self.point_load(&mut f, &name, kind == "torque"),
            "spring-damper" => self.spring_damper(&mut f, &name),
            _ => self.rotational_spring_damper(&mut f, &name),
        }
    }
}

impl<'a> Model<'a> {
    /// The axes of a joint: `axes = [[..], [..]]` in each body's axes, or
    /// `axis = [..]` global at the initial pose (not for universal joints).
    fn joint_axes(
        &self,
        f: &mut Fields<'a>,
        kind: JointType,
        sides: [Side; 2],
    ) -> Result<[[f64; 3]; 2], FileError> {
        let axes = f.optional("axes", two_vectors)?;
        let axis = f.optional("axis", numbers::<3>)?;
        let axes = match (axes, axis) {
            (Some(a), None) => a,
            (None, Some(g)) if kind != JointType::Universal => {
                [sides[0].local_axis(g), sides[1].local_axis(g)]
            }
            (None, Some(_)) => {
                let e = f.read_entry("axis")?;
                return Err(f.bad(
                    e,
                    "a universal joint has two cross axes, one per body: give 'axes = [[..], [..]]'",
                ));
            }
            (Some(_), Some(_)) => {
                return Err(self.r.doc.error(
                    f.span(),
                    format!("{}: give 'axes' or 'axis', not both", f.what),
                ));
            }
            (None, None) => {
                if let Some(typo) = f.typo_of(&["axes", "axis"]) {
                    return Err(typo);
                }
                return Err(self.r.doc.error(
                    f.span(),
                    format!(
                        "{}: the key 'axes' is missing: a {} joint needs {} (or 'axis = [x, y, z]', global{})",
                        f.what,
                        kind.name(),
                        if kind == JointType::Universal {
                            "its two cross axes, 'axes = [[..], [..]]' in each body's axes"
                        } else {
                            "its axis in each body's axes, 'axes = [[..], [..]]'"
                        },
                        if kind == JointType::Universal {
                            ", not for a universal joint"
                        } else {
                            ""
                        }
                    ),
                ));
            }
        };
        for (k, a) in axes.iter().enumerate() {
            if a.iter().all(|x| *x == 0.0) {
                let key = if axis.is_some() { "axis" } else { "axes" };
                let e = f.read_entry(key)?;
                let which = if axis.is_some() {
                    "the axis".to_string()
                } else {
                    format!(
                        "axis {} (the {} body's)",
                        k + 1,
                        if k == 0 { "first" } else { "second" }
                    )
                };
                return Err(f.bad(e, format!("{which} must not be zero")));
            }
        }
        let g = [sides[0].global(axes[0]), sides[1].global(axes[1])];
        let g = [
            sub(g[0], sides[0].global([0.0; 3])),
            sub(g[1], sides[1].global([0.0; 3])),
        ];
        let c = dot(g[0], g[1]) / (dot(g[0], g[0]) * dot(g[1], g[1])).sqrt();
        let parallel = matches!(
            kind,
            JointType::Revolute | JointType::Prismatic | JointType::Cylindrical
        );
        // The joint keeps its axes as they are at the start: axes that are
        // not parallel there would make its rows contradict the start
        // (reported as redundant, with advice that fails). The same bound as
        // the universal joint's: 1e-6 rad.
        let apart = (1.0 - c * c).max(0.0).sqrt().asin();
        if parallel && axis.is_none() && (apart.is_nan() || apart > 1e-6) {
            let e = f.read_entry("axes")?;
            return Err(f.bad(
                e,
                format!(
                    "the two axes must be parallel at the initial pose (to 1e-6 rad): in global axes \
                     they are [{}] and [{}], {:.3e} rad apart; give each body's axis so that both \
                     point along the joint axis at the start, or write 'axis = [x, y, z]' (global) \
                     instead",
                    global_text(g[0]),
                    global_text(g[1]),
                    apart
                ),
            ));
        }
        if kind == JointType::Universal && c.abs() > 1e-6 {
            let e = f.read_entry("axes")?;
            return Err(f.bad(
                e,
                format!(
                    "the two cross axes must be perpendicular at the initial pose (to 1e-6): in global axes they are [{}] and [{}], the cosine of their angle {c:.3e}; give each body's cross axis so that they are perpendicular at the start",
                    global_text(g[0]),
                    global_text(g[1])
                ),
            ));
        }
        Ok(axes)
    }

    /// A `[[force]]` of type `force` (at a point) or `torque`.
    fn point_load(
        &mut self,
        f: &mut Fields<'a>,
        name: &str,
        torque: bool,
    ) -> Result<(), FileError> {
        let body = self.r.bodies.body_of(f, "body")?;
        if torque && !body.rigid {
            let e = f.read_entry("body")?;
            return Err(f.bad(e, "a torque needs a rigid body, not a point mass"));
        }
        let point = if torque {
            [0.0; 3]
        } else {
            f.optional("point", numbers::<3>)?.unwrap_or([0.0; 3])
        };
        if !body.rigid && point != [0.0; 3] {
            let e = f.read_entry("point")?;
            return Err(f.bad(e, "a point mass has no extent: its point is [0, 0, 0]"));
        }
        let keys = if torque {
            ["tx", "ty", "tz"]
        } else {
            ["fx", "fy", "fz"]
        };
        let mut c: [TimeFunction; 3] = std::array::from_fn(|_| TimeFunction::Constant(0.0));
        for (c, key) in c.iter_mut().zip(keys) {
            if let Some(function) = self.r.function(f, key)? {
                *c = function;
            }
        }
        let axes = f
            .optional("axes", choice(&["global", "body"]))?
            .unwrap_or("global");
        if axes == "body" && !body.rigid {
            let e = f.read_entry("axes")?;
            return Err(f.bad(e, "a point mass has no axes: use \"global\""));
        }
        let mut known = vec!["name", "type", "body", "axes"];
        known.extend(keys);
        if !torque {
            known.push("point");
        }
        f.finish(&known)?;
        let axes = if axes == "body" {
            Axes::Body
        } else {
            Axes::Global
        };
        if torque {
            self.builder.torque(name, body.id, c, axes);
        } else {
            self.builder.force(name, body.id, point, c, axes);
        }
        Ok(())
    }

    /// A `[[force]]` of type `spring-damper`.
    fn spring_damper(&mut self, f: &mut Fields<'a>, name: &str) -> Result<(), FileError> {
        let sides = self.r.bodies.sides(f)?;
        let points = self.anchors(f, sides)?;
        let (stiffness, damping) = bodies::stiffness_damping(f, Spring::Linear)?;
        let length = f.optional("length", number_in(|x| x >= 0.0, "non-negative, in m"))?;
        let preload = f.optional("preload", number)?.unwrap_or(0.0);
        f.finish(&[
            "name",
            "type",
            "bodies",
            "points",
            "at",
            "stiffness",
            "damping",
            "length",
            "preload",
        ])?;
        self.builder.spring(
            name,
            sides.map(Side::attach),
            points,
            SpringDamper {
                stiffness,
                damping,
                rest_length: length,
                preload,
            },
        );
        Ok(())
    }

    /// A `[[force]]` of type `rotational-spring-damper`.
    fn rotational_spring_damper(
        &mut self,
        f: &mut Fields<'a>,
        name: &str,
    ) -> Result<(), FileError> {
        let sides = self.r.bodies.sides(f)?;
        for s in sides {
            if let Side::Body(b) = s
                && !b.rigid
            {
                let e = f.read_entry("bodies")?;
                return Err(f.bad(
                    e,
                    "a rotational spring joins rigid bodies (or the ground); point masses have no orientation",
                ));
            }
        }
        let axes = self.joint_axes(f, JointType::Revolute, sides)?;
        let (stiffness, damping) = bodies::stiffness_damping(f, Spring::Rotational)?;
        let angle = f.optional("angle", number)?.unwrap_or(0.0);
        f.finish(&[
            "name",
            "type",
            "bodies",
            "axes",
            "axis",
            "stiffness",
            "damping",
            "angle",
        ])?;
        self.builder.rotational_spring(
            name,
            sides.map(Side::attach),
            axes,
            RotationalSpringDamper {
                stiffness,
                damping,
                angle,
            },
        );
        Ok(())
    }

    /// The attachment points from `points` (local) or `at` (one global point
    /// at the initial pose).
    fn anchors(&self, f: &mut Fields<'a>, sides: [Side; 2]) -> Result<[[f64; 3]; 2], FileError> {
        let points = match self.r.given(f, two_vectors)? {
            Given::Points(p) => p,
            Given::At(g) => [sides[0].local(g), sides[1].local(g)],
        };
        for (side, p) in sides.iter().zip(points) {
            if let Side::Body(b) = side
                && !b.rigid
                && p != [0.0; 3]
            {
                let e = f.entry("points").expect("given for a point off [0, 0, 0]");
                return Err(f.bad(
                    e,
                    format!("a point mass has no extent: its point must be [0, 0, 0], not {p:?}"),
                ));
            }
        }
        Ok(points)
    }
}

/// `inertia`: principal moments `[Jxx, Jyy, Jzz]` or a 3 × 3 matrix.
fn inertia(node: &Node) -> Result<SpatialInertia, String> {
    let items = list(node)?;
    if items.len() == 3 && items.iter().all(|i| matches!(i.value, Value::List(_))) {
        let rows = [
            numbers::<3>(&items[0]),
            numbers::<3>(&items[1]),
            numbers::<3>(&items[2]),
        ];
        let mut j = [[0.0; 3]; 3];
        for (r, row) in j.iter_mut().zip(rows) {
            *r = row.map_err(|why| format!("a 3 × 3 matrix has rows of 3 numbers: {why}"))?;
        }
        return Ok(SpatialInertia::Matrix(j));
    }
    let j = numbers::<3>(node).map_err(|why| {
        format!("expected the principal moments [Jxx, Jyy, Jzz] or a 3 × 3 matrix, in kg m²: {why}")
    })?;
    if j.iter().any(|x| *x <= 0.0) {
        return Err(format!(
            "the principal moments must be positive, in kg m² (got {j:?}); a body without rotational inertia is a [[point_mass]]"
        ));
    }
    Ok(SpatialInertia::Principal(j))
}

/// Two vectors `[[x, y, z], [x, y, z]]`.
fn two_vectors(node: &Node) -> Result<[[f64; 3]; 2], String> {
    let items = list(node)?;
    if items.len() != 2 {
        return Err(format!(
            "expected two vectors [[x, y, z], [x, y, z]], found {} items",
            items.len()
        ));
    }
    Ok([numbers::<3>(&items[0])?, numbers::<3>(&items[1])?])
}

fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// A direction for a message, unit length, 4 decimals.
fn global_text(a: [f64; 3]) -> String {
    let n = dot(a, a).sqrt();
    a.map(|x| format!("{:.9}", x / n)).join(", ")
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// `A s`.
fn mul(a: &[[f64; 3]; 3], s: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|i| dot(a[i], s))
}

/// `Aᵀ g`.
fn mul_t(a: &[[f64; 3]; 3], g: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|j| a[0][j] * g[0] + a[1][j] * g[1] + a[2][j] * g[2])
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    let d = sub(a, b);
    dot(d, d).sqrt()
}
