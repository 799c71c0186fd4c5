//! [`PlanarBuilder`]: a planar mechanism assembled element by element, with
//! named parameters, and checked as a whole by [`PlanarBuilder::build`].

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

use super::geometry::Anchor;
use super::joints::{Constraint, Distance, Driver, JointElement, Prismatic, Revolute, Weld};
use super::loads::{Force, LoadElement, PointForce, RotationalSpring, Spring, Torque};
use super::{At, Body, BodyId, Coordinate, ModelError, PlanarSystem, TimeFunction};
use crate::dims::{self, Dimension, Planar};

/// A rigid body: mass, inertia about the centre of mass, initial pose and
/// velocity.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RigidBody {
    /// Mass, kg (> 0).
    pub mass: f64,
    /// Inertia about the centre of mass, kg m² (> 0, or 0 when a joint fixes
    /// the angle: see [`PlanarBuilder::rigid_body`]).
    pub inertia: f64,
    /// Centre of mass `x`, `y` (m) and angle `θ` (rad) of the body's x axis.
    pub pose: [f64; 3],
    /// `ẋ`, `ẏ`, `θ̇` (default: at rest).
    pub velocity: [f64; 3],
}

/// A point mass in `(x, y)`: mass, initial position and velocity.
pub type PointMass = crate::dims::PointMass<2>;

/// A linear spring-damper: tension `stiffness (ℓ − rest_length) + damping ℓ̇`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpringDamper {
    /// N/m (≥ 0).
    pub stiffness: f64,
    /// N s/m (≥ 0).
    pub damping: f64,
    /// m (≥ 0).
    pub rest_length: f64,
}

/// A rotational spring-damper: torque `−stiffness (θ_b − θ_a − θ₀) − damping
/// (θ̇_b − θ̇_a)` on body b, `θ₀` the initial relative angle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RotationalSpringDamper {
    /// N m/rad (≥ 0).
    pub stiffness: f64,
    /// N m s/rad (≥ 0).
    pub damping: f64,
}

/// Distinguishes builders, so that a handle from one is refused by another.
static BUILDERS: AtomicU64 = AtomicU64::new(1);

/// Builds a [`PlanarSystem`] element by element.
///
/// ```
/// use mstar_model::planar::{At, PlanarBuilder, RigidBody};
///
/// // A slender bar hinged to the ground at one end.
/// let mut b = PlanarBuilder::new();
/// let bar = b.rigid_body("bar", RigidBody { mass: 1.0, inertia: 1.0 / 12.0, pose: [0.5, 0.0, 0.0], velocity: [0.0; 3] });
/// b.revolute("hinge", At::Ground([0.0, 0.0]), At::Body(bar, [-0.5, 0.0]));
/// let sys = b.build()?;
/// # use mstar_model::System;
/// assert_eq!(sys.n_coords(), 3);
/// assert_eq!(sys.n_constraints(), 2);
/// assert_eq!(sys.body("bar").map(|b| b.theta), Some(Some(2)));
/// # Ok::<(), mstar_model::planar::ModelError>(())
/// ```
#[derive(Clone, Debug)]
pub struct PlanarBuilder {
    id: u64,
    gravity: [f64; 2],
    bodies: Vec<Body>,
    joints: Vec<(String, Arc<dyn JointElement>, [At; 2])>,
    drivers: Vec<(String, BodyId, Coordinate, TimeFunction)>,
    forces: Vec<(String, Arc<dyn LoadElement>, [At; 2])>,
    /// Misuse found while adding (e.g. a handle from another builder),
    /// reported by `build`.
    problems: Vec<ModelError>,
    n: usize,
}

impl Default for PlanarBuilder {
    fn default() -> Self {
        Self::new()
    }
}

impl PlanarBuilder {
    /// An empty model with gravity `(0, −9.81)` m/s².
    #[must_use]
    pub fn new() -> Self {
        Self {
            id: BUILDERS.fetch_add(1, Ordering::Relaxed),
            gravity: [0.0, -9.81],
            bodies: Vec::new(),
            joints: Vec::new(),
            drivers: Vec::new(),
            forces: Vec::new(),
            problems: Vec::new(),
            n: 0,
        }
    }

    /// Sets the gravitational acceleration (default `(0, −9.81)` m/s²).
    pub fn gravity(&mut self, gx: f64, gy: f64) -> &mut Self {
        self.gravity = [gx, gy];
        self
    }

    /// Adds a rigid body. Its inertia may be 0 — a point mass that carries
    /// an angle coordinate, as the paper's pendulum in `u = [x, y, θ]` whose
    /// mass matrix is singular (`algorithm.md` §2) — when a joint fixes its
    /// angle; [`build`](Self::build) checks that.
    pub fn rigid_body(&mut self, name: &str, body: RigidBody) -> BodyId {
        self.add_body(
            name,
            body.mass,
            Some(body.inertia),
            body.pose,
            body.velocity,
        )
    }

    /// Adds a point mass.
    pub fn point_mass(&mut self, name: &str, point: PointMass) -> BodyId {
        let [x, y] = point.position;
        let [vx, vy] = point.velocity;
        self.add_body(name, point.mass, None, [x, y, 0.0], [vx, vy, 0.0])
    }

    fn add_body(
        &mut self,
        name: &str,
        mass: f64,
        inertia: Option<f64>,
        pose: [f64; 3],
        velocity: [f64; 3],
    ) -> BodyId {
        let x = self.n;
        self.n += Planar::count(inertia.is_some());
        self.bodies.push(Body {
            name: name.to_string(),
            mass,
            inertia,
            x,
            u0: pose,
            v0: velocity,
        });
        BodyId {
            builder: self.id,
            index: self.bodies.len() - 1,
        }
    }

    /// Sets a body's initial velocity `[ẋ, ẏ, θ̇]` (`θ̇` of a point mass
    /// must be 0).
    pub fn velocity(&mut self, body: BodyId, velocity: [f64; 3]) -> &mut Self {
        match self.own(body) {
            Some(i) => self.bodies[i].v0 = velocity,
            None => self.problems.push(self.foreign(body, "a velocity")),
        }
        self
    }

    /// A revolute joint: the two points coincide (2 equations).
    pub fn revolute(&mut self, name: &str, a: At, b: At) -> &mut Self {
        self.joints.push((name.into(), Arc::new(Revolute), [a, b]));
        self
    }

    /// A distance joint (massless rod): the two points stay `length` apart.
    pub fn distance(&mut self, name: &str, a: At, b: At, length: f64) -> &mut Self {
        self.joints
            .push((name.into(), Arc::new(Distance { length }), [a, b]));
        self
    }

    /// A weld: the points coincide and `θ_b − θ_a` stays at its initial value.
    pub fn weld(&mut self, name: &str, a: At, b: At) -> &mut Self {
        let angle = self.angle(b) - self.angle(a);
        self.joints
            .push((name.into(), Arc::new(Weld { angle }), [a, b]));
        self
    }

    /// A prismatic joint: point `b` slides along the line through point `a`
    /// with direction `axis` (in `a`'s body frame, or global for the ground);
    /// a rigid body `b` keeps its initial angle relative to `a`.
    pub fn prismatic(&mut self, name: &str, a: At, axis: [f64; 2], b: At) -> &mut Self {
        let len = axis[0].hypot(axis[1]);
        let normal = if len > 0.0 {
            [-axis[1] / len, axis[0] / len]
        } else {
            [f64::NAN, f64::NAN]
        };
        let angle = self.angle(b) - self.angle(a);
        self.joints
            .push((name.into(), Arc::new(Prismatic { normal, angle }), [a, b]));
        self
    }

    /// A driver: `coordinate(body) = f(t)`.
    pub fn driver(
        &mut self,
        name: &str,
        body: BodyId,
        coordinate: Coordinate,
        f: TimeFunction,
    ) -> &mut Self {
        self.drivers.push((name.into(), body, coordinate, f));
        self
    }

    /// A force `(f_x(t), f_y(t))` in global directions at a point.
    pub fn force(&mut self, name: &str, at: At, fx: TimeFunction, fy: TimeFunction) -> &mut Self {
        let ground = At::Ground([0.0; 2]);
        self.forces
            .push((name.into(), Arc::new(PointForce { fx, fy }), [at, ground]));
        self
    }

    /// A torque `τ(t)` on a rigid body (counter-clockwise positive).
    pub fn torque(&mut self, name: &str, body: BodyId, tau: TimeFunction) -> &mut Self {
        let at = [At::Body(body, [0.0; 2]), At::Ground([0.0; 2])];
        self.forces
            .push((name.into(), Arc::new(Torque { tau }), at));
        self
    }

    /// A linear spring-damper between two points.
    pub fn spring(&mut self, name: &str, a: At, b: At, spring: SpringDamper) -> &mut Self {
        let element = Spring {
            k: spring.stiffness,
            c: spring.damping,
            rest: spring.rest_length,
        };
        self.forces.push((name.into(), Arc::new(element), [a, b]));
        self
    }

    /// A rotational spring-damper between body `a` (or the ground) and rigid
    /// body `b`, at rest at their initial relative angle.
    pub fn rotational_spring(
        &mut self,
        name: &str,
        a: Option<BodyId>,
        b: BodyId,
        spring: RotationalSpringDamper,
    ) -> &mut Self {
        self.rotational_spring_at(name, a, b, spring, None)
    }

    /// [`rotational_spring`](Self::rotational_spring) at rest at the
    /// relative angle `rest` (`θ_b − θ_a`, rad) when given, else at the
    /// initial one.
    pub fn rotational_spring_at(
        &mut self,
        name: &str,
        a: Option<BodyId>,
        b: BodyId,
        spring: RotationalSpringDamper,
        rest: Option<f64>,
    ) -> &mut Self {
        let at_a = a.map_or(At::Ground([0.0; 2]), |id| At::Body(id, [0.0; 2]));
        let at_b = At::Body(b, [0.0; 2]);
        let element = RotationalSpring {
            k: spring.stiffness,
            c: spring.damping,
            angle: rest.unwrap_or_else(|| self.angle(at_b) - self.angle(at_a)),
        };
        self.forces
            .push((name.into(), Arc::new(element), [at_a, at_b]));
        self
    }

    /// Any joint element between two points (the registered kinds'
    /// examples).
    pub(crate) fn joint_element(
        &mut self,
        name: &str,
        element: Arc<dyn JointElement>,
        a: At,
        b: At,
    ) -> &mut Self {
        self.joints.push((name.into(), element, [a, b]));
        self
    }

    /// Any load element between two points (the registered kinds' examples).
    pub(crate) fn load_element(
        &mut self,
        name: &str,
        element: Arc<dyn LoadElement>,
        a: At,
        b: At,
    ) -> &mut Self {
        self.forces.push((name.into(), element, [a, b]));
        self
    }

    /// The index of `body` if it is one of this builder's.
    fn own(&self, body: BodyId) -> Option<usize> {
        (body.builder == self.id && body.index < self.bodies.len()).then_some(body.index)
    }

    fn foreign(&self, body: BodyId, what: &str) -> ModelError {
        ModelError::Invalid {
            element: format!("body #{}", body.index),
            what: format!("{what} for a body handle that another PlanarBuilder made"),
        }
    }

    /// " ('a' is a point mass)" for the point masses an element is attached
    /// to (empty when there are none): which body a torque or a rotational
    /// spring must not act on.
    fn point_masses_among(&self, at: [At; 2]) -> String {
        let names: Vec<String> = at
            .iter()
            .filter_map(|a| match a {
                At::Body(id, _) => self.own(*id).map(|i| &self.bodies[i]),
                At::Ground(_) => None,
            })
            .filter(|b| b.inertia.is_none())
            .map(|b| format!("'{}' is a point mass", b.name))
            .collect();
        if names.is_empty() {
            String::new()
        } else {
            format!(" ({})", names.join(", "))
        }
    }

    fn angle(&self, at: At) -> f64 {
        match at {
            At::Body(id, _) => self
                .own(id)
                .map(|i| &self.bodies[i])
                .filter(|b| b.inertia.is_some())
                .map_or(0.0, |b| b.u0[2]),
            At::Ground(_) => 0.0,
        }
    }

    fn anchor(&self, element: &str, at: At) -> Result<Anchor, ModelError> {
        let invalid = |what: String| ModelError::Invalid {
            element: element.to_string(),
            what,
        };
        match at {
            At::Ground(p) if p.iter().all(|x| x.is_finite()) => Ok(Anchor::Ground(p)),
            At::Ground(p) => Err(invalid(format!("non-finite ground point {p:?}"))),
            At::Body(id, s) => {
                let b = self.own(id).map(|i| &self.bodies[i]).ok_or_else(|| {
                    invalid("a body handle that another PlanarBuilder made".to_string())
                })?;
                if !s.iter().all(|x| x.is_finite()) {
                    return Err(invalid(format!(
                        "non-finite attachment point on '{}'",
                        b.name
                    )));
                }
                match b.inertia {
                    Some(_) => Ok(Anchor::Rigid { x: b.x, s }),
                    None if s == [0.0, 0.0] => Ok(Anchor::Point { x: b.x }),
                    None => Err(invalid(format!(
                        "'{}' is a point mass: attach at [0, 0], not {s:?}",
                        b.name
                    ))),
                }
            }
        }
    }

    /// Checks the model and assembles the [`PlanarSystem`].
    ///
    /// # Errors
    /// [`ModelError`] for a model without bodies, duplicate names, non-positive masses or inertias,
    /// non-finite values, a body handle from another builder, an element
    /// whose parameters are out of range (a zero prismatic axis, a
    /// non-positive rod length, a negative stiffness), a driver of `θ`, a
    /// torque or a rotational spring on a point mass, or an element attached
    /// to the ground twice.
    pub fn build(&self) -> Result<PlanarSystem, ModelError> {
        dims::check_start(&self.problems, self.bodies.len())?;
        self.check_names()?;
        self.check_bodies()?;
        let mut constraints = Vec::new();
        let mut row = 0;
        for (name, element, [a, b]) in &self.joints {
            let c = Constraint::new(
                name.clone(),
                element.clone(),
                self.joint_anchors(name, element.as_ref(), [*a, *b])?,
                row,
            );
            row += c.rows;
            constraints.push(c);
        }
        for (name, body, coordinate, f) in &self.drivers {
            let c = self.driver_constraint(name, *body, *coordinate, f, row)?;
            row += c.rows;
            constraints.push(c);
        }
        let forces = self
            .forces
            .iter()
            .map(|(name, element, [a, b])| self.force_element(name, element, [*a, *b]))
            .collect::<Result<Vec<_>, _>>()?;
        let sys =
            PlanarSystem::assemble(self.gravity, &self.bodies, self.n, constraints, forces, row);
        check_massless_angles(&sys)?;
        Ok(sys)
    }

    /// Every body and element has its own name.
    fn check_names(&self) -> Result<(), ModelError> {
        let count = self.bodies.len() + self.joints.len() + self.drivers.len() + self.forces.len();
        let all_names = self
            .bodies
            .iter()
            .map(|b| &b.name)
            .chain(self.joints.iter().map(|j| &j.0))
            .chain(self.drivers.iter().map(|d| &d.0))
            .chain(self.forces.iter().map(|f| &f.0));
        dims::check_names(all_names, count, None)
    }

    /// Positive masses, inertias ≥ 0, finite poses and velocities, no angular
    /// velocity on a point mass.
    fn check_bodies(&self) -> Result<(), ModelError> {
        for b in &self.bodies {
            let invalid = |what: &str| ModelError::Invalid {
                element: b.name.clone(),
                what: what.to_string(),
            };
            if !(b.mass > 0.0 && b.mass.is_finite()) {
                return Err(invalid("the mass must be positive"));
            }
            if let Some(j) = b.inertia
                && !(j >= 0.0 && j.is_finite())
            {
                return Err(invalid(
                    "the inertia must be positive (or 0, see PlanarBuilder::rigid_body)",
                ));
            }
            if !b.u0.iter().chain(&b.v0).all(|x| x.is_finite()) {
                return Err(invalid("the initial pose and velocity must be finite"));
            }
            if b.inertia.is_none() && b.v0[2] != 0.0 {
                return Err(invalid("a point mass has no angle: its θ̇ must be 0"));
            }
        }
        Ok(())
    }

    /// A joint's anchors, checked with its parameters.
    fn joint_anchors(
        &self,
        name: &str,
        element: &dyn JointElement,
        at: [At; 2],
    ) -> Result<[Anchor; 2], ModelError> {
        let invalid = |what: String| ModelError::Invalid {
            element: name.to_string(),
            what,
        };
        let anchors = [self.anchor(name, at[0])?, self.anchor(name, at[1])?];
        if matches!(anchors, [Anchor::Ground(_), Anchor::Ground(_)]) {
            return Err(invalid("both ends are on the ground".to_string()));
        }
        match element.problem(&anchors) {
            Some(why) => Err(invalid(why)),
            None => Ok(anchors),
        }
    }

    /// The constraint of a driver, `coordinate(body) = f(t)`, from row `row`.
    fn driver_constraint(
        &self,
        name: &str,
        body: BodyId,
        coordinate: Coordinate,
        f: &TimeFunction,
        row: usize,
    ) -> Result<Constraint, ModelError> {
        let invalid = |what: &str| ModelError::Invalid {
            element: name.to_string(),
            what: what.to_string(),
        };
        let b = self
            .own(body)
            .map(|i| &self.bodies[i])
            .ok_or_else(|| invalid("a body handle that another PlanarBuilder made"))?;
        if let Some(problem) = f.problem() {
            return Err(invalid(&format!("the driver function: {problem}")));
        }
        let x = match (coordinate, b.inertia) {
            (Coordinate::X, _) => b.x,
            (Coordinate::Y, _) => b.x + 1,
            (Coordinate::Theta, Some(_)) => b.x + 2,
            (Coordinate::Theta, None) => {
                return Err(invalid("a point mass has no angle to drive"));
            }
        };
        let element = Arc::new(Driver { f: f.clone() });
        let anchors = [Anchor::Point { x }, Anchor::Ground([0.0; 2])];
        Ok(Constraint::new(name.to_string(), element, anchors, row))
    }

    /// A force element, its parameters checked.
    fn force_element(
        &self,
        name: &str,
        element: &Arc<dyn LoadElement>,
        at: [At; 2],
    ) -> Result<Force, ModelError> {
        let anchors = [self.anchor(name, at[0])?, self.anchor(name, at[1])?];
        if let Some(why) = element.problem(&anchors) {
            return Err(ModelError::Invalid {
                element: name.to_string(),
                what: format!("{why}{}", self.point_masses_among(at)),
            });
        }
        Ok(Force::new(name.to_string(), element.clone(), anchors))
    }
}

/// A rigid body with no inertia (the paper's pendulum: `M` singular in `θ`)
/// needs a joint that fixes its angle, or `M* = M + BᵀB` is singular too: a
/// non-zero entry in its `θ` column of `B` at the initial pose.
fn check_massless_angles(sys: &PlanarSystem) -> Result<(), ModelError> {
    let p = crate::System::b_pattern(sys);
    let mut b = vec![0.0; p.len()];
    crate::System::b_into(sys, 0.0, &sys.initial_position(), &mut b);
    for body in sys.bodies.iter().filter(|b| b.inertia == Some(0.0)) {
        let theta = body.x + 2;
        let fixed = p
            .entries
            .iter()
            .zip(&b)
            .any(|(&(_, c), &v)| c == theta && v != 0.0);
        if !fixed {
            return Err(ModelError::Invalid {
                element: body.name.clone(),
                what: "inertia 0 needs a joint that fixes the body's angle (a revolute or distance joint away from its centre of mass, a weld, a prismatic joint or a driver of theta); give it an inertia > 0 or a point mass instead".to_string(),
            });
        }
    }
    Ok(())
}
