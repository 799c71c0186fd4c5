//! The `mstar.planar/1` schema: bodies, point masses, joints, drivers and
//! forces read into a [`PlanarBuilder`], every value checked where it is
//! written (`docs/model-format.md`).

use super::FileError;
use super::bodies::{self, Given, Reader, Spring};
use super::fields::{Doc, Fields, choice, number_in, numbers, two_points};
use super::node::Node;
use mstar_model::planar::{
    At, BodyId, Coordinate, PlanarBuilder, PlanarSystem, RigidBody, RotationalSpringDamper,
    SpringDamper, TimeFunction,
};
use mstar_model::sensor::Sensor;

/// The one format version this reader knows.
pub const FORMAT: &str = "mstar.planar/1";

/// The joint types of the format.
const JOINTS: [&str; 4] = ["revolute", "prismatic", "distance", "weld"];

/// The force types of the format.
const FORCES: [&str; 4] = [
    "spring-damper",
    "rotational-spring-damper",
    "torque",
    "force",
];

/// A named body of the model, as joints and forces refer to it (its pose
/// `[x, y, θ]`).
type Placed = bodies::Placed<BodyId, [f64; 3]>;

/// One side of a joint or force: the ground or a body.
type Side = bodies::Side<Placed>;

/// The model being read.
struct Model<'a> {
    builder: PlanarBuilder,
    r: Reader<'a, Placed>,
    sensors: Vec<Sensor>,
}

/// Reads a whole document.
pub(crate) fn read<'a>(
    doc: Doc<'a>,
    root: &'a Node,
) -> Result<(PlanarSystem, Vec<Sensor>), FileError> {
    let known = format!("'{FORMAT}' and '{}'", super::spatial::FORMAT);
    let (r, mut top, gravity) = Reader::open(doc, root, FORMAT, &known, [0.0, -9.81])?;
    let mut m = Model {
        builder: PlanarBuilder::new(),
        r,
        sensors: Vec::new(),
    };
    m.builder.gravity(gravity[0], gravity[1]);
    // ([simulation] and [output] are the caller's: settings, not the mechanism.)
    bodies::read_elements(&mut top, &mut m)?;
    let system = m.builder.build().map_err(|e| m.r.located(&e))?;
    Ok((system, m.sensors))
}

impl<'a> bodies::Elements<'a> for Model<'a> {
    /// A `[[sensor]]`.
    fn sensor(&mut self, node: &'a Node, what: String) -> Result<(), FileError> {
        let sensor = self.r.sensor::<2>(node, what)?;
        self.sensors.push(sensor);
        Ok(())
    }

    /// A `[[body]]`: a rigid body.
    fn body(&mut self, node: &'a Node, what: String) -> Result<(), FileError> {
        let (mut f, name) = self.r.named(node, what, "body")?;
        let mass = bodies::mass(&mut f)?;
        let inertia = f.required(
            "inertia",
            number_in(
                |x| x >= 0.0,
                "positive (or 0 for a body whose angle a joint fixes), in kg m²",
            ),
        )?;
        let pose = f.required("pose", numbers::<3>)?;
        let velocity = f.optional("velocity", numbers::<3>)?.unwrap_or([0.0; 3]);
        f.finish(&["name", "mass", "inertia", "pose", "velocity"])?;
        let id = self.builder.rigid_body(
            &name,
            RigidBody {
                mass,
                inertia,
                pose,
                velocity,
            },
        );
        self.r.place(name, Placed::rigid(id, pose))
    }

    /// A `[[point_mass]]`.
    fn point_mass(&mut self, node: &'a Node, what: String) -> Result<(), FileError> {
        self.r.point_mass(node, what, |name, point| {
            let [x, y] = point.position;
            Placed::point(self.builder.point_mass(name, point), [x, y, 0.0])
        })
    }

    /// A `[[joint]]`: revolute, prismatic, distance or weld.
    fn joint(&mut self, node: &'a Node, what: String) -> Result<(), FileError> {
        let (mut f, name, kind) = self.r.typed(node, what, "joint", &JOINTS)?;
        let sides = self.r.bodies.sides(&mut f)?;
        let at = self.anchors(&mut f, sides)?;
        match kind {
            "revolute" => {
                f.finish(&["name", "type", "bodies", "points", "at"])?;
                self.builder.revolute(&name, at[0], at[1]);
            }
            "weld" => {
                f.finish(&["name", "type", "bodies", "points", "at"])?;
                self.builder.weld(&name, at[0], at[1]);
            }
            "distance" => {
                let initial = distance(self.global(sides[0], at[0]), self.global(sides[1], at[1]));
                let length = f.optional("length", number_in(|x| x > 0.0, "positive, in m"))?;
                f.finish(&["name", "type", "bodies", "points", "at", "length"])?;
                let length = length.unwrap_or(initial);
                if length.is_nan() || length <= 0.0 {
                    return Err(self.r.doc.error(
                        f.span(),
                        format!(
                            "{}: the two points coincide at the initial pose: give 'length'",
                            f.what
                        ),
                    ));
                }
                self.builder.distance(&name, at[0], at[1], length);
            }
            _ => {
                let axis = f.required("axis", numbers::<2>)?;
                if axis == [0.0, 0.0] {
                    let e = f.read_entry("axis")?;
                    return Err(f.bad(e, "must not be zero: it is the sliding direction"));
                }
                if matches!(sides[1], Side::Ground) {
                    return Err(self.r.doc.error(
                        f.span(),
                        format!(
                            "{}: the sliding side (the second of 'bodies') must be a body",
                            f.what
                        ),
                    ));
                }
                f.finish(&["name", "type", "bodies", "points", "at", "axis"])?;
                self.builder.prismatic(&name, at[0], axis, at[1]);
            }
        }
        Ok(())
    }

    /// A `[[driver]]`: a coordinate of a body prescribed in time.
    fn driver(&mut self, node: &'a Node, what: String) -> Result<(), FileError> {
        let (mut f, name) = self.r.named(node, what, "driver")?;
        let body = self.r.bodies.body_of(&mut f, "body")?;
        let coordinate = f.required("coordinate", choice(&["x", "y", "theta"]))?;
        if coordinate == "theta" && !body.rigid {
            let e = f.read_entry("coordinate")?;
            return Err(f.bad(e, "a point mass has no angle: drive x or y"));
        }
        let function = self
            .r
            .function(&mut f, "function")?
            .ok_or_else(|| f.missing("function"))?;
        f.finish(&["name", "body", "coordinate", "function"])?;
        let coordinate = match coordinate {
            "x" => Coordinate::X,
            "y" => Coordinate::Y,
            _ => Coordinate::Theta,
        };
        self.builder.driver(&name, body.id, coordinate, function);
        Ok(())
    }

    /// A `[[force]]`: spring-damper, rotational spring-damper, torque or force.
    fn force(&mut self, node: &'a Node, what: String) -> Result<(), FileError> {
        let (mut f, name, kind) = self.r.typed(node, what, "force", &FORCES)?;
        match kind {
            "spring-damper" => self.spring(&mut f, &name)?,
            "rotational-spring-damper" => self.rotational_spring(&mut f, &name)?,
            "torque" => {
                let body = self.r.bodies.body_of(&mut f, "body")?;
                if !body.rigid {
                    return Err(self.r.doc.error(
                        f.span(),
                        format!("{}: a torque needs a rigid body, not a point mass", f.what),
                    ));
                }
                let tau = self
                    .r
                    .function(&mut f, "function")?
                    .ok_or_else(|| f.missing("function"))?;
                f.finish(&["name", "type", "body", "function"])?;
                self.builder.torque(&name, body.id, tau);
            }
            _ => {
                let body = self.r.bodies.body_of(&mut f, "body")?;
                let point = f.optional("point", numbers::<2>)?.unwrap_or([0.0; 2]);
                let fx = self
                    .r
                    .function(&mut f, "fx")?
                    .unwrap_or(TimeFunction::Constant(0.0));
                let fy = self
                    .r
                    .function(&mut f, "fy")?
                    .unwrap_or(TimeFunction::Constant(0.0));
                f.finish(&["name", "type", "body", "point", "fx", "fy"])?;
                self.check_point(&f, "point", Side::Body(body), point)?;
                self.builder.force(&name, At::Body(body.id, point), fx, fy);
            }
        }
        Ok(())
    }
}

impl<'a> Model<'a> {
    /// A linear spring-damper between two points.
    fn spring(&mut self, f: &mut Fields<'a>, name: &str) -> Result<(), FileError> {
        let sides = self.r.bodies.sides(f)?;
        let points = f.required("points", two_points)?;
        let at = [
            self.side_at(f, sides[0], points[0])?,
            self.side_at(f, sides[1], points[1])?,
        ];
        let (stiffness, damping) = bodies::stiffness_damping(f, Spring::Linear)?;
        let rest = f.optional("rest_length", number_in(|x| x >= 0.0, "non-negative, in m"))?;
        f.finish(&[
            "name",
            "type",
            "bodies",
            "points",
            "stiffness",
            "damping",
            "rest_length",
        ])?;
        let rest = rest.unwrap_or_else(|| {
            distance(self.global(sides[0], at[0]), self.global(sides[1], at[1]))
        });
        self.builder.spring(
            name,
            at[0],
            at[1],
            SpringDamper {
                stiffness,
                damping,
                rest_length: rest,
            },
        );
        Ok(())
    }

    /// A rotational spring-damper between two bodies (or the ground and a
    /// body), at rest at the initial relative angle.
    fn rotational_spring(&mut self, f: &mut Fields<'a>, name: &str) -> Result<(), FileError> {
        let sides = self.r.bodies.sides(f)?;
        let (stiffness, damping) = bodies::stiffness_damping(f, Spring::Rotational)?;
        let rest = f.optional("rest_angle", number_in(f64::is_finite, "finite, in rad"))?;
        f.finish(&[
            "name",
            "type",
            "bodies",
            "stiffness",
            "damping",
            "rest_angle",
        ])?;
        let rigid = |s: Side| match s {
            Side::Ground => Ok(None),
            Side::Body(b) if b.rigid => Ok(Some(b.id)),
            Side::Body(_) => Err(()),
        };
        let why = match (rigid(sides[0]), rigid(sides[1])) {
            (Ok(a), Ok(Some(b))) => {
                let spring = RotationalSpringDamper { stiffness, damping };
                self.builder.rotational_spring_at(name, a, b, spring, rest);
                return Ok(());
            }
            (_, Ok(None)) => {
                "the second body must be a rigid body: give the ground first (bodies = [\"ground\", \"<body>\"])"
            }
            _ => {
                "a rotational spring joins two rigid bodies (the first may be 'ground'); point masses have no angle"
            }
        };
        Err(f.bad_key("bodies", why))
    }

    /// The attachment points from `points` (local) or `at` (one global point
    /// at the initial pose).
    fn anchors(&self, f: &mut Fields<'a>, sides: [Side; 2]) -> Result<[At; 2], FileError> {
        Ok(match self.r.given(f, two_points)? {
            Given::Points(p) => [
                self.side_at(f, sides[0], p[0])?,
                self.side_at(f, sides[1], p[1])?,
            ],
            Given::At(g) => [local_at(sides[0], g), local_at(sides[1], g)],
        })
    }

    /// The point `local` of a side (global for the ground).
    fn side_at(&self, f: &Fields<'a>, side: Side, local: [f64; 2]) -> Result<At, FileError> {
        self.check_point(f, "points", side, local)?;
        Ok(match side {
            Side::Ground => At::Ground(local),
            Side::Body(b) => At::Body(b.id, local),
        })
    }

    /// A point mass has no extent: its point, given by `key`, is `[0, 0]`.
    fn check_point(
        &self,
        f: &Fields<'a>,
        key: &str,
        side: Side,
        local: [f64; 2],
    ) -> Result<(), FileError> {
        match side {
            Side::Body(b) if !b.rigid && local != [0.0, 0.0] => Err(f.bad_key(
                key,
                format!("a point mass has no extent: its point must be [0, 0], not {local:?}"),
            )),
            _ => Ok(()),
        }
    }

    /// The global position of an attachment at the initial pose.
    fn global(&self, side: Side, at: At) -> [f64; 2] {
        match (side, at) {
            (Side::Body(b), At::Body(_, s)) => {
                let (sn, cs) = b.pose[2].sin_cos();
                [
                    b.pose[0] + cs * s[0] - sn * s[1],
                    b.pose[1] + sn * s[0] + cs * s[1],
                ]
            }
            (_, At::Ground(p)) | (Side::Ground, At::Body(_, p)) => p,
        }
    }
}

/// The local point of a side for the global point `g` at the initial pose.
fn local_at(side: Side, g: [f64; 2]) -> At {
    match side {
        Side::Ground => At::Ground(g),
        Side::Body(b) if !b.rigid => At::Body(b.id, [0.0, 0.0]),
        Side::Body(b) => {
            let (sn, cs) = b.pose[2].sin_cos();
            let d = [g[0] - b.pose[0], g[1] - b.pose[1]];
            At::Body(b.id, [cs * d[0] + sn * d[1], -sn * d[0] + cs * d[1]])
        }
    }
}

fn distance(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}
