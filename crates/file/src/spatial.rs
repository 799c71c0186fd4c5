//! The `mstar.spatial/1` schema: rigid bodies in Euler parameters, point
//! masses, joints, drivers and forces read into a [`SpatialBuilder`], every
//! value checked where it is written (`docs/model-format.md`, "Spatial
//! models").

use std::collections::HashMap;

use super::FileError;
use super::bodies::{self, Bodies, Names};
use super::fields::{Doc, Fields, choice, list, number, number_in, numbers, string};
use super::node::{Node, Value};
use mstar_model::planar::{ModelError, TimeFunction};
use mstar_model::spatial::{
    Attach, DriverKind, JointSpec, JointType, RotationalMass, SpatialBody, SpatialBodyId,
    SpatialBuilder, SpatialInertia, SpatialPointMass, SpatialSystem, SpringSpec, rotation_matrix,
};

/// The format version of spatial model files.
pub const FORMAT: &str = "mstar.spatial/1";

/// How far from 1 the norm of a given orientation may be without a warning.
const NORM_WARNING: f64 = 1e-12;

/// A named body of the model, as joints and forces refer to it.
#[derive(Clone, Copy, Debug)]
struct Placed {
    id: SpatialBodyId,
    rigid: bool,
    position: [f64; 3],
    /// Unit Euler parameters (identity for a point mass).
    orientation: [f64; 4],
}

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
            Self::Body(b) => add(b.position, mul(&rotation_matrix(b.orientation), s)),
        }
    }

    /// The local point of the global point `g` at the initial pose.
    fn local(self, g: [f64; 3]) -> [f64; 3] {
        match self {
            Self::Ground => g,
            Self::Body(b) if !b.rigid => [0.0; 3],
            Self::Body(b) => mul_t(&rotation_matrix(b.orientation), sub(g, b.position)),
        }
    }

    /// The global direction `g` in the side's axes at the initial pose.
    fn local_axis(self, g: [f64; 3]) -> [f64; 3] {
        match self {
            Self::Ground => g,
            Self::Body(b) => mul_t(&rotation_matrix(b.orientation), g),
        }
    }
}

/// The model being read.
struct Model<'a> {
    doc: Doc<'a>,
    builder: SpatialBuilder,
    bodies: Bodies<Placed>,
    /// The joints (not drivers) by name, with their type.
    joints: HashMap<String, JointType>,
    /// Every name with what carries it and where, for duplicates.
    names: Names,
    warnings: Vec<String>,
}

/// Reads a whole document: the system and the warnings about it (each
/// `FILE:LINE:COLUMN: element: key: what`).
pub(crate) fn read<'a>(
    doc: Doc<'a>,
    root: &'a Node,
    rotational_mass: RotationalMass,
) -> Result<(SpatialSystem, Vec<String>), FileError> {
    let mut top = Fields::of(doc, root, "the model".to_string())?;
    let format = top.required("format", string)?;
    if format != FORMAT {
        let e = top.entry("format").map(|e| e.node.span.clone());
        return Err(doc.error(
            e.flatten().as_ref(),
            format!("unknown format '{format}': this version of mstar reads '{FORMAT}'"),
        ));
    }
    let gravity = top
        .optional("gravity", numbers::<3>)?
        .unwrap_or([0.0, 0.0, -9.81]);
    let counts = bodies::element_counts(&top);
    let mut m = Model {
        doc,
        builder: SpatialBuilder::new(),
        bodies: Bodies::with_capacity(counts.1),
        joints: HashMap::new(),
        names: Names::with_capacity(counts.0),
        warnings: Vec::new(),
    };
    m.builder.gravity(gravity);
    m.builder.rotational_mass(rotational_mass);
    // ([simulation] and [output] are the caller's: settings, not the mechanism.)
    bodies::read_elements(
        &mut top,
        &mut m,
        [
            Model::body,
            Model::point_mass,
            Model::joint,
            Model::driver,
            Model::force,
        ],
    )?;
    let system = m.builder.build().map_err(|e| m.located(e))?;
    Ok((system, m.warnings))
}

impl<'a> Model<'a> {
    /// The element's fields and its name, the name claimed
    /// ([`Names::named`]).
    fn named(
        &mut self,
        node: &'a Node,
        what: String,
        kind: &str,
    ) -> Result<(Fields<'a>, String), FileError> {
        self.names.named(self.doc, node, what, kind)
    }

    /// A `[[body]]`: a rigid body.
    fn body(&mut self, node: &'a Node, what: String) -> Result<(), FileError> {
        let (mut f, name) = self.named(node, what, "body")?;
        let mass = f.required("mass", number_in(|x| x > 0.0, "positive, in kg"))?;
        let inertia = f.required("inertia", inertia)?;
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
                .push(self.doc.error(span, message).to_string());
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
        self.bodies.insert(
            name,
            Placed {
                id,
                rigid: true,
                position,
                orientation,
            },
        );
        Ok(())
    }

    /// A `[[point_mass]]`.
    fn point_mass(&mut self, node: &'a Node, what: String) -> Result<(), FileError> {
        let (mut f, name) = self.named(node, what, "point mass")?;
        let mass = f.required("mass", number_in(|x| x > 0.0, "positive, in kg"))?;
        let position = f.required("position", numbers::<3>)?;
        let velocity = f.optional("velocity", numbers::<3>)?.unwrap_or([0.0; 3]);
        f.finish(&["name", "mass", "position", "velocity"])?;
        let id = self.builder.point_mass(
            &name,
            SpatialPointMass {
                mass,
                position,
                velocity,
            },
        );
        self.bodies.insert(
            name,
            Placed {
                id,
                rigid: false,
                position,
                orientation: [1.0, 0.0, 0.0, 0.0],
            },
        );
        Ok(())
    }

    /// A `[[joint]]`.
    fn joint(&mut self, node: &'a Node, what: String) -> Result<(), FileError> {
        let (mut f, name) = self.named(node, what, "joint")?;
        let kinds = JointType::ALL;
        let names = kinds.map(JointType::name);
        let kind = f.required("type", choice(&names))?;
        let kind = kinds[names.iter().position(|n| *n == kind).expect("a choice")];
        let sides = self.bodies.sides(&mut f)?;
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
                            "a {} joint has no axis: 'axes' belongs to revolute, prismatic, cylindrical and universal joints",
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
                return Err(self.doc.error(
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
                return Err(self.doc.error(
                    f.span(),
                    format!("{}: give 'axes' or 'axis', not both", f.what),
                ));
            }
            (None, None) => {
                return Err(self.doc.error(
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
                return Err(f.bad(e, format!("axis {} must not be zero", k + 1)));
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
                    "the two axes must be parallel at the initial pose: in global axes they are \
                     [{}] and [{}], {:.4}° apart; give each body's axis so that both point along the \
                     joint axis at the start, or write 'axis = [x, y, z]' (global) instead",
                    global_text(g[0]),
                    global_text(g[1]),
                    apart.to_degrees()
                ),
            ));
        }
        if kind == JointType::Universal && c.abs() > 1e-6 {
            let e = f.read_entry("axes")?;
            return Err(f.bad(
                e,
                format!(
                    "the two cross axes must be perpendicular at the initial pose (the cosine of their angle is {c:.3e})"
                ),
            ));
        }
        Ok(axes)
    }

    /// A `[[driver]]`: a joint's angle or translation prescribed in time.
    fn driver(&mut self, node: &'a Node, what: String) -> Result<(), FileError> {
        let (mut f, name) = self.named(node, what, "driver")?;
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
            .function(&mut f, "function")?
            .ok_or_else(|| f.missing("function"))?;
        f.finish(&["name", "joint", "motion", "function"])?;
        self.builder.driver(&name, joint, motion_kind, function);
        Ok(())
    }

    /// A `[[force]]`.
    fn force(&mut self, node: &'a Node, what: String) -> Result<(), FileError> {
        let (mut f, name) = self.named(node, what, "force")?;
        let kind = f.required(
            "type",
            choice(&[
                "force",
                "torque",
                "spring-damper",
                "rotational-spring-damper",
            ]),
        )?;
        match kind {
            "force" | "torque" => self.point_load(&mut f, &name, kind == "torque"),
            "spring-damper" => self.spring_damper(&mut f, &name),
            _ => self.rotational_spring_damper(&mut f, &name),
        }
    }

    /// A `[[force]]` of type `force` (at a point) or `torque`.
    fn point_load(
        &mut self,
        f: &mut Fields<'a>,
        name: &str,
        torque: bool,
    ) -> Result<(), FileError> {
        let body = self.bodies.body_of(f, "body")?;
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
            if let Some(function) = self.function(f, key)? {
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
        if torque {
            self.builder.torque(name, body.id, c, axes == "body");
        } else {
            self.builder.force(name, body.id, point, c, axes == "body");
        }
        Ok(())
    }

    /// A `[[force]]` of type `spring-damper`.
    fn spring_damper(&mut self, f: &mut Fields<'a>, name: &str) -> Result<(), FileError> {
        let sides = self.bodies.sides(f)?;
        let points = self.anchors(f, sides)?;
        let stiffness = f.required("stiffness", number_in(|x| x >= 0.0, "non-negative, in N/m"))?;
        let damping = f
            .optional("damping", number_in(|x| x >= 0.0, "non-negative, in N s/m"))?
            .unwrap_or(0.0);
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
            SpringSpec {
                stiffness,
                damping,
                length,
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
        let sides = self.bodies.sides(f)?;
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
        let stiffness = f.required(
            "stiffness",
            number_in(|x| x >= 0.0, "non-negative, in N m/rad"),
        )?;
        let damping = f
            .optional(
                "damping",
                number_in(|x| x >= 0.0, "non-negative, in N m s/rad"),
            )?
            .unwrap_or(0.0);
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
            [stiffness, damping, angle],
        );
        Ok(())
    }

    /// The attachment points from `points` (local) or `at` (one global point
    /// at the initial pose).
    fn anchors(&self, f: &mut Fields<'a>, sides: [Side; 2]) -> Result<[[f64; 3]; 2], FileError> {
        let points = f.optional("points", two_vectors)?;
        let at = f.optional("at", numbers::<3>)?;
        let points = match (points, at) {
            (Some(p), None) => p,
            (None, Some(g)) => [sides[0].local(g), sides[1].local(g)],
            (Some(_), Some(_)) => {
                return Err(self.doc.error(
                    f.span(),
                    format!("{}: give 'points' or 'at', not both", f.what),
                ));
            }
            (None, None) => {
                return Err(self.doc.error(
                    f.span(),
                    format!("{}: the key 'points' (or 'at') is missing", f.what),
                ));
            }
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

    /// The time function of `key`, if present.
    fn function(&self, f: &mut Fields<'a>, key: &str) -> Result<Option<TimeFunction>, FileError> {
        let Some(e) = f.entry(key) else {
            return Ok(None);
        };
        let what = format!("{}: {key}", f.what);
        super::functions::read(self.doc, &e.node, what).map(Some)
    }

    /// A builder error, placed at the element it names when it can be.
    fn located(&self, e: ModelError) -> FileError {
        self.names.located(self.doc, &e)
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
    a.map(|x| format!("{:.4}", x / n)).join(", ")
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
