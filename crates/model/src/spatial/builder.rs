//! [`SpatialBuilder`]: bodies, joints, drivers and loads by name, checked and
//! assembled into a [`SpatialSystem`].

use std::sync::Arc;

use super::SpatialBodyId;
use super::body::Inertia;
use super::data::{BodyData, JointData, LoadData};
use super::joints::{
    AngleDriver, Cylindrical, Distance, Geometry, Prismatic, Revolute, SlideDriver, SpatialJoint,
    Spherical, Universal, Weld, triad, unit,
};
use super::loads::{PointForce, RotationalSpring, SpatialLoad, Spring, Torque};
use super::rotation::rotates_to_body;
use super::rotation::{normalized, rates_of_omega};
use super::system::SpatialSystem;
use crate::dims::{self, ModelError};
use crate::planar::TimeFunction;

/// How a rigid body's rotational mass block is formed (`docs/theory.md`,
/// "Spatial bodies").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum RotationalMass {
    /// `4 Gᵀ J' G`, singular (rank 3): the paper's case, handled by
    /// `M* = M + BᵀB`; backends that factor `M` block by block (`schur`,
    /// `schur-lu`) cannot take it.
    Singular,
    /// `4 Gᵀ J' G + κ p pᵀ` with `κ = 4 tr(J')/3`: regular, the same motion
    /// (only the normalization multiplier changes); every backend takes it
    /// (the default).
    #[default]
    Regularized,
}

/// Rotational inertia about the centre of mass, in body axes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SpatialInertia {
    /// Principal moments `[Jxx, Jyy, Jzz]` (body axes are principal axes).
    Principal([f64; 3]),
    /// The full symmetric tensor.
    Matrix([[f64; 3]; 3]),
}

impl SpatialInertia {
    /// The tensor.
    #[must_use]
    pub fn matrix(&self) -> [[f64; 3]; 3] {
        match *self {
            Self::Principal(j) => [[j[0], 0.0, 0.0], [0.0, j[1], 0.0], [0.0, 0.0, j[2]]],
            Self::Matrix(j) => j,
        }
    }
}

/// A rigid body: mass, inertia about the centre of mass, initial pose and
/// motion.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpatialBody {
    /// Mass, kg.
    pub mass: f64,
    /// Inertia about the centre of mass, body axes, kg m².
    pub inertia: SpatialInertia,
    /// Centre of mass, global, m.
    pub position: [f64; 3],
    /// Euler parameters `[e0, e1, e2, e3]` (body to global); normalized by
    /// the builder.
    pub orientation: [f64; 4],
    /// Velocity of the centre of mass, global, m/s.
    pub velocity: [f64; 3],
    /// Angular velocity, global axes, rad/s.
    pub angular_velocity: [f64; 3],
}

/// A point mass in `(x, y, z)`: mass, initial position and velocity.
pub type SpatialPointMass = crate::dims::PointMass<3>;

/// What an element attaches to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Attach {
    /// The fixed ground (its points are global points, its axes global axes).
    Ground,
    /// A body.
    Body(SpatialBodyId),
}

/// The kinds of joints.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum JointType {
    /// Points coincide (3 rows).
    Spherical,
    /// Points coincide, axes parallel (5 rows).
    Revolute,
    /// Axes parallel, B's point on A's axis line, no twist (5 rows).
    Prismatic,
    /// Axes parallel, B's point on A's axis line (4 rows).
    Cylindrical,
    /// Points coincide, the two cross axes perpendicular (4 rows).
    Universal,
    /// Points coincide, relative orientation frozen (6 rows).
    Weld,
    /// The points keep a distance (1 row).
    Distance,
}

impl JointType {
    /// Every joint type, in the order of the documentation.
    pub const ALL: [Self; 7] = [
        Self::Spherical,
        Self::Revolute,
        Self::Prismatic,
        Self::Cylindrical,
        Self::Universal,
        Self::Weld,
        Self::Distance,
    ];

    /// The name model files use.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Spherical => "spherical",
            Self::Revolute => "revolute",
            Self::Prismatic => "prismatic",
            Self::Cylindrical => "cylindrical",
            Self::Universal => "universal",
            Self::Weld => "weld",
            Self::Distance => "distance",
        }
    }

    /// Whether the joint reads `axes`.
    #[must_use]
    pub fn uses_axes(self) -> bool {
        !matches!(self, Self::Spherical | Self::Weld | Self::Distance)
    }
}

/// A joint between two attachments.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointSpec {
    /// Its kind.
    pub kind: JointType,
    /// Body A and body B.
    pub bodies: [Attach; 2],
    /// The joint point on each side: body axes relative to the centre of
    /// mass, or a global point on the ground.
    pub points: [[f64; 3]; 2],
    /// The joint axis in each side's axes (revolute, prismatic, cylindrical:
    /// the same physical axis; universal: the two cross axes).
    pub axes: [[f64; 3]; 2],
    /// The distance joint's length, m (`None`: the initial distance).
    pub length: Option<f64>,
}

/// What a driver prescribes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DriverKind {
    /// The rotation about the joint axis, rad, from the initial pose
    /// (revolute, cylindrical).
    Angle,
    /// The translation along A's joint axis from A's point to B's point, m
    /// (prismatic, cylindrical).
    Translation,
}

/// A linear spring-damper: tension `stiffness (ℓ − rest_length) + damping ℓ̇ +
/// preload` (the planar [`SpringDamper`](crate::planar::SpringDamper) with a
/// preload, and a rest length that defaults to the initial one).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpringDamper {
    /// N/m (≥ 0).
    pub stiffness: f64,
    /// N s/m (≥ 0).
    pub damping: f64,
    /// m (≥ 0; `None`: the initial length).
    pub rest_length: Option<f64>,
    /// Tension at the rest length, N (default: 0).
    pub preload: f64,
}

/// A rotational spring-damper about a joint axis: torque `−stiffness (θ −
/// angle) − damping θ̇`, `θ` the rotation from the initial pose (the planar
/// [`RotationalSpringDamper`](crate::planar::RotationalSpringDamper) with a
/// rest angle).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RotationalSpringDamper {
    /// N m/rad (≥ 0).
    pub stiffness: f64,
    /// N m s/rad (≥ 0).
    pub damping: f64,
    /// The rest angle from the initial pose, rad (default: 0).
    pub angle: f64,
}

/// The axes in which a force's or torque's components are given.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Axes {
    /// The global axes: the load keeps its direction (the default).
    #[default]
    Global,
    /// The body's axes: the load turns with the body (rigid bodies only).
    Body,
}

#[derive(Clone, Debug)]
enum Pending {
    Joint(JointSpec),
    Driver {
        joint: String,
        kind: DriverKind,
        f: TimeFunction,
    },
}

/// Builds a [`SpatialSystem`].
///
/// ```
/// use mstar_model::spatial::{Attach, JointSpec, JointType, SpatialBody, SpatialBuilder, SpatialInertia};
/// use mstar_model::System;
///
/// let mut b = SpatialBuilder::new();
/// let top = b.body("top", SpatialBody {
///     mass: 2.0,
///     inertia: SpatialInertia::Principal([0.05, 0.05, 0.08]),
///     position: [0.0, 0.0, 0.25],
///     orientation: [1.0, 0.0, 0.0, 0.0],
///     velocity: [0.0; 3],
///     angular_velocity: [0.0, 0.0, 30.0],
/// });
/// b.joint("tip", JointSpec {
///     kind: JointType::Spherical,
///     bodies: [Attach::Ground, Attach::Body(top)],
///     points: [[0.0; 3], [0.0, 0.0, -0.25]],
///     axes: [[0.0, 0.0, 1.0]; 2],
///     length: None,
/// });
/// let sys = b.build().unwrap();
/// assert_eq!((sys.n_coords(), sys.n_constraints()), (7, 4));
/// assert_eq!(sys.coord_name(3), "top.e0");
/// ```
#[derive(Clone, Debug)]
pub struct SpatialBuilder {
    gravity: [f64; 3],
    rotational_mass: RotationalMass,
    bodies: Vec<(String, Option<SpatialInertia>, SpatialBody)>,
    joints: Vec<(String, Pending)>,
    loads: Vec<(String, [Attach; 2], Arc<dyn SpatialLoad>)>,
    errors: Vec<ModelError>,
    /// Whether joint axes are checked at the initial pose
    /// ([`check_axes`](Self::check_axes); off for the derivative checks'
    /// examples, whose axes are arbitrary).
    axes_checked: bool,
}

impl Default for SpatialBuilder {
    fn default() -> Self {
        Self::new()
    }
}

impl SpatialBuilder {
    /// An empty model with gravity `[0, 0, −9.81]`.
    #[must_use]
    pub fn new() -> Self {
        Self {
            gravity: [0.0, 0.0, -9.81],
            rotational_mass: RotationalMass::Regularized,
            bodies: Vec::new(),
            joints: Vec::new(),
            loads: Vec::new(),
            errors: Vec::new(),
            axes_checked: true,
        }
    }

    /// Sets gravity, m/s².
    pub fn gravity(&mut self, g: [f64; 3]) -> &mut Self {
        self.gravity = g;
        self
    }

    /// Sets how rotational mass blocks are formed.
    pub fn rotational_mass(&mut self, r: RotationalMass) -> &mut Self {
        self.rotational_mass = r;
        self
    }

    /// Adds a rigid body.
    pub fn body(&mut self, name: &str, body: SpatialBody) -> SpatialBodyId {
        self.bodies
            .push((name.to_string(), Some(body.inertia), body));
        SpatialBodyId(self.bodies.len() - 1)
    }

    /// Adds a point mass.
    pub fn point_mass(&mut self, name: &str, point: SpatialPointMass) -> SpatialBodyId {
        let body = SpatialBody {
            mass: point.mass,
            inertia: SpatialInertia::Principal([0.0; 3]),
            position: point.position,
            orientation: [1.0, 0.0, 0.0, 0.0],
            velocity: point.velocity,
            angular_velocity: [0.0; 3],
        };
        self.bodies.push((name.to_string(), None, body));
        SpatialBodyId(self.bodies.len() - 1)
    }

    /// Adds a joint.
    pub fn joint(&mut self, name: &str, spec: JointSpec) -> &mut Self {
        self.joints.push((name.to_string(), Pending::Joint(spec)));
        self
    }

    /// Adds a driver of the joint `joint`'s angle or translation.
    pub fn driver(
        &mut self,
        name: &str,
        joint: &str,
        kind: DriverKind,
        f: TimeFunction,
    ) -> &mut Self {
        let joint = joint.to_string();
        self.joints
            .push((name.to_string(), Pending::Driver { joint, kind, f }));
        self
    }

    /// Adds a force `f` on the point `point` of `body`, its components in
    /// `axes` ([`Axes::Body`]: it turns with the body).
    pub fn force(
        &mut self,
        name: &str,
        body: SpatialBodyId,
        point: [f64; 3],
        f: [TimeFunction; 3],
        axes: Axes,
    ) -> &mut Self {
        let body_axes = axes == Axes::Body;
        self.body_load(
            name,
            body,
            Arc::new(PointForce {
                point,
                f,
                body_axes,
            }),
        )
    }

    /// Adds a torque `n` on `body`, its components in `axes`.
    pub fn torque(
        &mut self,
        name: &str,
        body: SpatialBodyId,
        n: [TimeFunction; 3],
        axes: Axes,
    ) -> &mut Self {
        let body_axes = axes == Axes::Body;
        self.body_load(name, body, Arc::new(Torque { n, body_axes }))
    }

    /// Adds a load that acts on `body` alone.
    fn body_load(
        &mut self,
        name: &str,
        body: SpatialBodyId,
        load: Arc<dyn SpatialLoad>,
    ) -> &mut Self {
        let sides = [Attach::Body(body), Attach::Ground];
        self.loads.push((name.to_string(), sides, load));
        self
    }

    /// Adds a spring-damper between two points.
    pub fn spring(
        &mut self,
        name: &str,
        bodies: [Attach; 2],
        points: [[f64; 3]; 2],
        spring: SpringDamper,
    ) -> &mut Self {
        let length = spring
            .rest_length
            .unwrap_or_else(|| self.initial_distance(bodies, points));
        let load = Spring {
            points,
            stiffness: spring.stiffness,
            damping: spring.damping,
            length,
            preload: spring.preload,
        };
        self.loads.push((name.to_string(), bodies, Arc::new(load)));
        self
    }

    /// Adds a rotational spring-damper about the axis `axes[0]` of A (B's
    /// `axes[1]` is the same physical axis), see [`RotationalSpringDamper`].
    pub fn rotational_spring(
        &mut self,
        name: &str,
        bodies: [Attach; 2],
        axes: [[f64; 3]; 2],
        spring: RotationalSpringDamper,
    ) -> &mut Self {
        let RotationalSpringDamper {
            stiffness,
            damping,
            angle,
        } = spring;
        match self.geometry(name, bodies, [[0.0; 3]; 2], axes) {
            Ok((geometry, a_in_b)) => {
                let load = RotationalSpring {
                    geometry,
                    f_b0: a_in_b(geometry.axes[0][0]),
                    stiffness,
                    damping,
                    angle,
                };
                self.loads.push((name.to_string(), bodies, Arc::new(load)));
            }
            Err(e) => self.errors.push(e),
        }
        self
    }

    fn initial_distance(&self, bodies: [Attach; 2], points: [[f64; 3]; 2]) -> f64 {
        let x = |k: usize| self.initial_point(bodies[k], points[k]);
        let (a, b) = (x(0), x(1));
        ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
    }

    fn initial_orientation(&self, at: Attach) -> [f64; 4] {
        match at {
            Attach::Body(SpatialBodyId(i)) if i < self.bodies.len() => {
                normalized(self.bodies[i].2.orientation)
            }
            _ => [1.0, 0.0, 0.0, 0.0],
        }
    }

    fn initial_point(&self, at: Attach, s: [f64; 3]) -> [f64; 3] {
        match at {
            Attach::Body(SpatialBodyId(i)) if i < self.bodies.len() => {
                let b = &self.bodies[i].2;
                let a = super::rotation::rotate(&normalized(b.orientation), s);
                [
                    b.position[0] + a[0],
                    b.position[1] + a[1],
                    b.position[2] + a[2],
                ]
            }
            _ => s,
        }
    }

    /// The joint geometry (unit axes, triads) and a map of A's body vectors
    /// to B's body axes in the initial pose.
    #[allow(clippy::type_complexity)]
    fn geometry(
        &self,
        name: &str,
        bodies: [Attach; 2],
        points: [[f64; 3]; 2],
        axes: [[f64; 3]; 2],
    ) -> Result<(Geometry, impl Fn([f64; 3]) -> [f64; 3] + use<>), ModelError> {
        let invalid = |what: String| ModelError::Invalid {
            element: name.to_string(),
            what,
        };
        let mut triads = [[[0.0; 3]; 3]; 2];
        for k in 0..2 {
            let h = unit(axes[k]).ok_or_else(|| {
                invalid(format!(
                    "axis {} is zero or not finite: {:?}",
                    k + 1,
                    axes[k]
                ))
            })?;
            triads[k] = triad(h);
        }
        let (pa, pb) = (
            self.initial_orientation(bodies[0]),
            self.initial_orientation(bodies[1]),
        );
        let geometry = Geometry {
            points,
            axes: triads,
        };
        Ok((geometry, move |v: [f64; 3]| {
            rotates_to_body(&pb, super::rotation::rotate(&pa, v))
        }))
    }

    /// Builds the system.
    ///
    /// # Errors
    /// [`ModelError`] for a duplicate name, an unknown or repeated body, a
    /// non-positive mass, an inertia that is not positive definite, a zero
    /// axis, an axis joint on a point mass, or a driver of a joint that has
    /// no such motion.
    pub fn build(&self) -> Result<SpatialSystem, ModelError> {
        dims::check_start(&self.errors, self.bodies.len())?;
        self.check_names()?;
        let bodies = self.bodies_data()?;
        let mut joints = Vec::new();
        for (name, pending) in &self.joints {
            joints.push(self.joint_data(name, pending, &bodies)?);
        }
        let loads = self
            .loads
            .iter()
            .map(|(name, at, load)| {
                let sides = self.sides(name, *at, &bodies)?;
                point_mass_points(name, sides, load.points(), &bodies)?;
                Ok(LoadData {
                    name: name.clone(),
                    sides,
                    element: load.clone(),
                })
            })
            .collect::<Result<Vec<_>, ModelError>>()?;
        Ok(SpatialSystem::assemble(self.gravity, bodies, joints, loads))
    }

    /// Every body and element has its own name, and none is `ground`.
    fn check_names(&self) -> Result<(), ModelError> {
        let count = self.bodies.len() + self.joints.len() + self.loads.len();
        let names = self.bodies.iter().map(|b| &b.0);
        let names = names
            .chain(self.joints.iter().map(|j| &j.0))
            .chain(self.loads.iter().map(|l| &l.0));
        dims::check_names(names, count, Some("ground"))
    }

    fn bodies_data(&self) -> Result<Vec<BodyData>, ModelError> {
        let mut x = 0;
        let mut out = Vec::new();
        for (name, inertia, b) in &self.bodies {
            let invalid = |what: String| ModelError::Invalid {
                element: name.clone(),
                what,
            };
            if !(b.mass > 0.0 && b.mass.is_finite()) {
                return Err(invalid(format!(
                    "mass must be positive and finite, got {}",
                    b.mass
                )));
            }
            let inertia = match inertia {
                Some(j) => {
                    Some(checked_inertia(j.matrix(), self.rotational_mass).map_err(invalid)?)
                }
                None => None,
            };
            let norm = b.orientation.iter().map(|e| e * e).sum::<f64>().sqrt();
            if inertia.is_some() && !(norm > 0.0 && norm.is_finite()) {
                return Err(invalid(
                    "orientation must be a non-zero quaternion".to_string(),
                ));
            }
            let data = body_data(name.clone(), b, inertia, x);
            x += data.count();
            out.push(data);
        }
        Ok(out)
    }

    fn sides(
        &self,
        name: &str,
        at: [Attach; 2],
        bodies: &[BodyData],
    ) -> Result<[Option<usize>; 2], ModelError> {
        let side = |a: Attach| match a {
            Attach::Ground => Ok(None),
            Attach::Body(SpatialBodyId(i)) if i < bodies.len() => Ok(Some(i)),
            Attach::Body(_) => Err(ModelError::Invalid {
                element: name.to_string(),
                what: "attaches to a body of another builder".to_string(),
            }),
        };
        let sides = [side(at[0])?, side(at[1])?];
        if sides[0] == sides[1] {
            return Err(ModelError::Invalid {
                element: name.to_string(),
                what: "connects a body (or the ground) to itself".to_string(),
            });
        }
        Ok(sides)
    }

    fn joint_data(
        &self,
        name: &str,
        pending: &Pending,
        bodies: &[BodyData],
    ) -> Result<JointData, ModelError> {
        let invalid = |what: String| ModelError::Invalid {
            element: name.to_string(),
            what,
        };
        let (spec, element) = match pending {
            Pending::Joint(spec) => (*spec, self.joint_element(name, spec)?),
            Pending::Driver { joint, kind, f } => {
                let Some((_, Pending::Joint(spec))) = self.joints.iter().find(|j| &j.0 == joint)
                else {
                    return Err(invalid(format!(
                        "drives '{joint}', which is not a joint of the model"
                    )));
                };
                (*spec, self.driver_element(name, spec, *kind, f.clone())?)
            }
        };
        let sides = self.sides(name, spec.bodies, bodies)?;
        point_mass_points(name, sides, spec.points, bodies)?;
        if spec.kind.uses_axes() || matches!(spec.kind, JointType::Weld) {
            for s in sides.iter().flatten() {
                if !bodies[*s].is_rigid() {
                    return Err(invalid(format!(
                        "a {} joint needs orientations, and '{}' is a point mass",
                        spec.kind.name(),
                        bodies[*s].name
                    )));
                }
            }
        }
        Ok(JointData::new(name.to_string(), sides, element))
    }

    /// Joints whose axes are not parallel (or perpendicular) at the start
    /// are taken as given: for the derivative checks' examples
    /// (`examples.rs`), whose constraints need not hold.
    pub(crate) fn unchecked_axes(&mut self) -> &mut Self {
        self.axes_checked = false;
        self
    }

    /// A joint's axes at the initial pose, as a model file's are checked:
    /// parallel (or opposite) for a revolute, prismatic or cylindrical joint,
    /// perpendicular for a universal one, to 1e-6 rad. The joint keeps its
    /// axes as they are at the start: axes that are not so there would make
    /// its rows contradict the start.
    fn check_axes(&self, name: &str, spec: &JointSpec) -> Result<(), ModelError> {
        if !self.axes_checked {
            return Ok(());
        }
        let global = |k: usize| {
            let h = unit(spec.axes[k])?;
            Some(super::rotation::rotate(
                &self.initial_orientation(spec.bodies[k]),
                h,
            ))
        };
        // (A zero axis is `geometry`'s error.)
        let (Some(a), Some(b)) = (global(0), global(1)) else {
            return Ok(());
        };
        let c = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let text = |v: [f64; 3]| format!("[{:.9}, {:.9}, {:.9}]", v[0], v[1], v[2]);
        let why = match spec.kind {
            JointType::Revolute | JointType::Prismatic | JointType::Cylindrical => {
                let apart = (1.0 - c * c).max(0.0).sqrt().asin();
                if apart.is_nan() || apart > 1e-6 {
                    Some(format!(
                        "the two axes must be parallel at the initial pose: in global axes they are {} and {}, {apart:.3e} rad apart; give each body's axis so that both point along the joint axis at the start",
                        text(a),
                        text(b)
                    ))
                } else {
                    None
                }
            }
            JointType::Universal if c.is_nan() || c.abs() > 1e-6 => Some(format!(
                "the two cross axes must be perpendicular at the initial pose: in global axes they are {} and {} (the cosine of their angle is {c:.3e}); give each body's cross axis so that they are perpendicular at the start",
                text(a),
                text(b)
            )),
            _ => None,
        };
        why.map_or(Ok(()), |what| {
            Err(ModelError::Invalid {
                element: name.to_string(),
                what,
            })
        })
    }

    fn joint_element(
        &self,
        name: &str,
        spec: &JointSpec,
    ) -> Result<Arc<dyn SpatialJoint>, ModelError> {
        self.check_axes(name, spec)?;
        let (g, a_in_b) = self.geometry(name, spec.bodies, spec.points, spec.axes)?;
        Ok(match spec.kind {
            JointType::Spherical => Arc::new(Spherical(g)),
            JointType::Revolute => Arc::new(Revolute(g)),
            JointType::Cylindrical => Arc::new(Cylindrical(g)),
            JointType::Universal => Arc::new(Universal(g)),
            JointType::Prismatic => Arc::new(Prismatic {
                geometry: g,
                g_b0: a_in_b(g.axes[0][1]),
            }),
            JointType::Weld => Arc::new(Weld {
                geometry: g,
                a_in_b: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]].map(&a_in_b),
            }),
            JointType::Distance => {
                let length = spec
                    .length
                    .unwrap_or_else(|| self.initial_distance(spec.bodies, spec.points));
                if !(length >= 0.0 && length.is_finite()) {
                    return Err(ModelError::Invalid {
                        element: name.to_string(),
                        what: format!("length must be non-negative and finite, got {length}"),
                    });
                }
                Arc::new(Distance {
                    geometry: g,
                    length,
                })
            }
        })
    }

    fn driver_element(
        &self,
        name: &str,
        spec: &JointSpec,
        kind: DriverKind,
        f: TimeFunction,
    ) -> Result<Arc<dyn SpatialJoint>, ModelError> {
        use JointType::{Cylindrical as C, Prismatic as P, Revolute as R};
        let (g, a_in_b) = self.geometry(name, spec.bodies, spec.points, spec.axes)?;
        match (kind, spec.kind) {
            (DriverKind::Angle, R | C) => Ok(Arc::new(AngleDriver {
                geometry: g,
                f_b0: a_in_b(g.axes[0][0]),
                f,
            })),
            (DriverKind::Translation, P | C) => Ok(Arc::new(SlideDriver { geometry: g, f })),
            _ => Err(ModelError::Invalid {
                element: name.to_string(),
                what: format!(
                    "a {} joint has no free {} to drive (angle: revolute, cylindrical; \
                     translation: prismatic, cylindrical)",
                    spec.kind.name(),
                    match kind {
                        DriverKind::Angle => "angle",
                        DriverKind::Translation => "translation",
                    }
                ),
            }),
        }
    }
}

/// A point mass has no extent: its attachment point must be `[0, 0, 0]`.
fn point_mass_points(
    name: &str,
    sides: [Option<usize>; 2],
    points: [[f64; 3]; 2],
    bodies: &[BodyData],
) -> Result<(), ModelError> {
    for (k, side) in sides.iter().enumerate() {
        if let Some(&i) = side.as_ref()
            && !bodies[i].is_rigid()
            && points[k] != [0.0; 3]
        {
            return Err(ModelError::Invalid {
                element: name.to_string(),
                what: format!(
                    "'{}' is a point mass: its point must be [0, 0, 0], got {:?}",
                    bodies[i].name, points[k]
                ),
            });
        }
    }
    Ok(())
}

/// A body as assembled, its first coordinate `x`; unit Euler parameters
/// and their rates from the given orientation and angular velocity.
fn body_data(name: String, b: &SpatialBody, inertia: Option<Inertia>, x: usize) -> BodyData {
    let p = normalized(b.orientation);
    let pd = rates_of_omega(&p, b.angular_velocity);
    let [x0, y0, z0] = b.position;
    let [vx, vy, vz] = b.velocity;
    BodyData {
        name,
        mass: b.mass,
        inertia,
        x,
        u0: [x0, y0, z0, p[0], p[1], p[2], p[3]],
        v0: [vx, vy, vz, pd[0], pd[1], pd[2], pd[3]],
    }
}

/// The inertia tensor checked: finite, symmetric, positive definite and a
/// rigid body's (the principal moments satisfy the triangle inequality).
fn checked_inertia(j: [[f64; 3]; 3], mode: RotationalMass) -> Result<Inertia, String> {
    let flat = j.iter().flatten();
    if flat.clone().any(|x| !x.is_finite()) {
        return Err(format!("inertia has a value that is not finite: {j:?}"));
    }
    let scale = flat.fold(0.0f64, |a, x| a.max(x.abs()));
    for (r, c) in [(0, 1), (0, 2), (1, 2)] {
        if (j[r][c] - j[c][r]).abs() > 1e-12 * scale {
            return Err(format!("the inertia matrix is not symmetric: {j:?}"));
        }
    }
    let minors = [j[0][0], j[0][0] * j[1][1] - j[0][1] * j[1][0], det3(&j)];
    if minors.iter().any(|&d| d <= 0.0) {
        let m = principal_moments(&j);
        return Err(format!(
            "inertia must be positive definite: its principal moments (eigenvalues) are [{:.6e}, {:.6e}, {:.6e}], and each must be > 0; got {j:?}",
            m[0], m[1], m[2]
        ));
    }
    let (jxx, jyy, jzz) = (j[0][0], j[1][1], j[2][2]);
    let tol = 1e-12 * scale;
    if jxx + jyy < jzz - tol || jyy + jzz < jxx - tol || jzz + jxx < jyy - tol {
        return Err(format!(
            "no rigid body has this inertia: each moment must be at most the sum of the \
             other two (Jxx + Jyy >= Jzz and so on), got [{jxx}, {jyy}, {jzz}]"
        ));
    }
    let kappa = match mode {
        RotationalMass::Singular => 0.0,
        RotationalMass::Regularized => 4.0 * (jxx + jyy + jzz) / 3.0,
    };
    Ok(Inertia { j, kappa })
}

/// The eigenvalues of the symmetric `j`, ascending, in closed form (the
/// trigonometric solution of the characteristic cubic; O. K. Smith,
/// "Eigenvalues of a symmetric 3 × 3 matrix", Comm. ACM 4 (1961) 168).
fn principal_moments(j: &[[f64; 3]; 3]) -> [f64; 3] {
    let off = j[0][1] * j[0][1] + j[0][2] * j[0][2] + j[1][2] * j[1][2];
    let mut e = if off == 0.0 {
        [j[0][0], j[1][1], j[2][2]]
    } else {
        let q = (j[0][0] + j[1][1] + j[2][2]) / 3.0;
        let d = [j[0][0] - q, j[1][1] - q, j[2][2] - q];
        let p = ((d[0] * d[0] + d[1] * d[1] + d[2] * d[2] + 2.0 * off) / 6.0).sqrt();
        let mut b = *j;
        for (k, row) in b.iter_mut().enumerate() {
            row[k] -= q;
            row.iter_mut().for_each(|x| *x /= p);
        }
        let phi = (det3(&b) / 2.0).clamp(-1.0, 1.0).acos() / 3.0;
        let largest = q + 2.0 * p * phi.cos();
        let smallest = q + 2.0 * p * (phi + 2.0 * std::f64::consts::FRAC_PI_3).cos();
        [smallest, 3.0 * q - largest - smallest, largest]
    };
    e.sort_by(f64::total_cmp);
    e
}

fn det3(j: &[[f64; 3]; 3]) -> f64 {
    j[0][0] * (j[1][1] * j[2][2] - j[1][2] * j[2][1])
        - j[0][1] * (j[1][0] * j[2][2] - j[1][2] * j[2][0])
        + j[0][2] * (j[1][0] * j[2][1] - j[1][1] * j[2][0])
}

#[cfg(test)]
mod inertia_tests {
    use super::principal_moments;

    /// Against eigenvalues known in closed form: a diagonal matrix, and
    /// `[[a, b, 0], [b, a, 0], [0, 0, c]]` with `a ± b` and `c`.
    #[test]
    fn principal_moments_are_the_eigenvalues() {
        let d = principal_moments(&[[0.3, 0.0, 0.0], [0.0, 0.1, 0.0], [0.0, 0.0, 0.2]]);
        assert_eq!(d, [0.1, 0.2, 0.3]);
        let e = principal_moments(&[[0.1, 0.2, 0.0], [0.2, 0.1, 0.0], [0.0, 0.0, 0.1]]);
        for (got, want) in e.iter().zip([-0.1, 0.1, 0.3]) {
            assert!((got - want).abs() < 1e-15, "{e:?}");
        }
    }
}
