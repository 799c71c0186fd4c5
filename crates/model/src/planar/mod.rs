//! Planar multibody systems: rigid bodies in `(x, y, θ)`, point masses in
//! `(x, y)`, joints, drivers and forces, assembled into a [`System`].
//!
//! Coordinates of a body named `b` are `b.x`, `b.y` (centre of mass) and
//! `b.theta` (angle of the body's x axis from the global x axis, counter-
//! clockwise). Local points are given in the body frame relative to the centre
//! of mass. Every element has analytic first and second derivatives, checked
//! against finite differences in the tests.

mod chains;
mod elements;
mod geometry;
mod time;

pub use chains::{Bar, bar_chain, bar_chain_of, point_mass_chain};
pub use time::TimeFunction;

use elements::{Constraint, Force, Joint, Load, RevoluteKernel};
use geometry::{Anchor, Slots};

use rayon::prelude::*;

use crate::{Pattern, System};

/// Handle of a body in a [`PlanarBuilder`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct BodyId(usize);

/// Where an element attaches: a fixed ground point or a point of a body
/// (local coordinates, relative to the centre of mass).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum At {
    /// A fixed point `[x, y]` of the ground.
    Ground([f64; 2]),
    /// The point at local offset `[sx, sy]` of a body (`[0, 0]` for a point mass).
    Body(BodyId, [f64; 2]),
}

/// Which coordinate of a body a driver prescribes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Coordinate {
    /// The centre of mass `x`.
    X,
    /// The centre of mass `y`.
    Y,
    /// The angle `θ` (rigid bodies only).
    Theta,
}

/// Errors in a planar model.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ModelError {
    /// Two bodies or two elements share a name.
    #[error("the name '{0}' is used twice")]
    DuplicateName(String),
    /// A parameter is out of range.
    #[error("{element}: {what}")]
    Invalid {
        /// The element's name.
        element: String,
        /// What is wrong.
        what: String,
    },
}

#[derive(Clone, Debug)]
struct Body {
    name: String,
    mass: f64,
    /// `None` for a point mass.
    inertia: Option<f64>,
    /// Index of the body's `x` coordinate.
    x: usize,
    pose: [f64; 3],
    velocity: [f64; 3],
}

/// Builds a [`PlanarSystem`] element by element.
///
/// ```
/// use mstar_model::planar::{At, PlanarBuilder};
///
/// // A slender bar hinged to the ground at one end.
/// let mut b = PlanarBuilder::new();
/// let bar = b.rigid_body("bar", 1.0, 1.0 / 12.0, [0.5, 0.0, 0.0]);
/// b.revolute("hinge", At::Ground([0.0, 0.0]), At::Body(bar, [-0.5, 0.0]));
/// let sys = b.build()?;
/// # use mstar_model::System;
/// assert_eq!(sys.n_coords(), 3);
/// assert_eq!(sys.n_constraints(), 2);
/// # Ok::<(), mstar_model::planar::ModelError>(())
/// ```
#[derive(Clone, Debug)]
pub struct PlanarBuilder {
    gravity: [f64; 2],
    bodies: Vec<Body>,
    joints: Vec<(String, Joint, [At; 2])>,
    drivers: Vec<(String, BodyId, Coordinate, TimeFunction)>,
    forces: Vec<(String, Load, [At; 2])>,
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
            gravity: [0.0, -9.81],
            bodies: Vec::new(),
            joints: Vec::new(),
            drivers: Vec::new(),
            forces: Vec::new(),
            n: 0,
        }
    }

    /// Sets the gravitational acceleration (default `(0, −9.81)` m/s²).
    pub fn gravity(&mut self, gx: f64, gy: f64) -> &mut Self {
        self.gravity = [gx, gy];
        self
    }

    /// Adds a rigid body of mass `m` and inertia `j` about its centre of mass at
    /// the initial pose `[x, y, θ]` (at rest; see [`PlanarBuilder::velocity`]).
    pub fn rigid_body(&mut self, name: &str, m: f64, j: f64, pose: [f64; 3]) -> BodyId {
        self.add_body(name, m, Some(j), pose)
    }

    /// Adds a point mass at `[x, y]` (at rest).
    pub fn point_mass(&mut self, name: &str, m: f64, position: [f64; 2]) -> BodyId {
        self.add_body(name, m, None, [position[0], position[1], 0.0])
    }

    fn add_body(&mut self, name: &str, mass: f64, inertia: Option<f64>, pose: [f64; 3]) -> BodyId {
        let x = self.n;
        self.n += if inertia.is_some() { 3 } else { 2 };
        self.bodies.push(Body {
            name: name.to_string(),
            mass,
            inertia,
            x,
            pose,
            velocity: [0.0; 3],
        });
        BodyId(self.bodies.len() - 1)
    }

    /// Sets a body's initial velocity `[ẋ, ẏ, θ̇]` (θ̇ ignored for point masses).
    pub fn velocity(&mut self, body: BodyId, velocity: [f64; 3]) -> &mut Self {
        if let Some(b) = self.bodies.get_mut(body.0) {
            b.velocity = velocity;
        }
        self
    }

    /// A revolute joint: the two points coincide (2 equations).
    pub fn revolute(&mut self, name: &str, a: At, b: At) -> &mut Self {
        self.joints.push((name.into(), Joint::Revolute, [a, b]));
        self
    }

    /// A distance joint (massless rod): the two points stay `length` apart.
    pub fn distance(&mut self, name: &str, a: At, b: At, length: f64) -> &mut Self {
        self.joints
            .push((name.into(), Joint::Distance { length }, [a, b]));
        self
    }

    /// A weld: the points coincide and `θ_b − θ_a` stays at its initial value.
    pub fn weld(&mut self, name: &str, a: At, b: At) -> &mut Self {
        let angle = self.angle(b) - self.angle(a);
        self.joints
            .push((name.into(), Joint::Weld { angle }, [a, b]));
        self
    }

    /// A prismatic joint: point `b` slides along the line through point `a` with
    /// direction `axis` (in `a`'s body frame, or global for the ground); a rigid
    /// body `b` keeps its initial angle relative to `a`.
    pub fn prismatic(&mut self, name: &str, a: At, axis: [f64; 2], b: At) -> &mut Self {
        let len = (axis[0] * axis[0] + axis[1] * axis[1]).sqrt();
        let normal = if len > 0.0 {
            [-axis[1] / len, axis[0] / len]
        } else {
            [f64::NAN, f64::NAN]
        };
        let angle = self.angle(b) - self.angle(a);
        self.joints
            .push((name.into(), Joint::Prismatic { normal, angle }, [a, b]));
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
        self.forces.push((
            name.into(),
            Load::PointForce { fx, fy },
            [at, At::Ground([0.0; 2])],
        ));
        self
    }

    /// A torque `τ(t)` on a rigid body.
    pub fn torque(&mut self, name: &str, body: BodyId, tau: TimeFunction) -> &mut Self {
        self.forces.push((
            name.into(),
            Load::Torque { tau },
            [At::Body(body, [0.0; 2]), At::Ground([0.0; 2])],
        ));
        self
    }

    /// A linear spring-damper between two points: tension `k(ℓ − ℓ₀) + c ℓ̇`.
    pub fn spring(&mut self, name: &str, a: At, b: At, k: f64, c: f64, rest: f64) -> &mut Self {
        self.forces
            .push((name.into(), Load::Spring { k, c, rest }, [a, b]));
        self
    }

    /// A rotational spring-damper between body `a` (or the ground) and body `b`:
    /// torque `−k(θ_b − θ_a − θ₀) − c(θ̇_b − θ̇_a)` on `b`, `θ₀` the initial
    /// relative angle.
    pub fn rotational_spring(
        &mut self,
        name: &str,
        a: Option<BodyId>,
        b: BodyId,
        k: f64,
        c: f64,
    ) -> &mut Self {
        let at_a = a.map_or(At::Ground([0.0; 2]), |id| At::Body(id, [0.0; 2]));
        let at_b = At::Body(b, [0.0; 2]);
        let angle = self.angle(at_b) - self.angle(at_a);
        self.forces.push((
            name.into(),
            Load::RotationalSpring { k, c, angle },
            [at_a, at_b],
        ));
        self
    }

    fn angle(&self, at: At) -> f64 {
        match at {
            At::Body(id, _) => self
                .bodies
                .get(id.0)
                .filter(|b| b.inertia.is_some())
                .map_or(0.0, |b| b.pose[2]),
            At::Ground(_) => 0.0,
        }
    }

    fn anchor(&self, element: &str, at: At) -> Result<Anchor, ModelError> {
        let invalid = |what: String| ModelError::Invalid {
            element: element.to_string(),
            what,
        };
        match at {
            At::Ground(p) => Ok(Anchor::Ground(p)),
            At::Body(id, s) => {
                let b = self
                    .bodies
                    .get(id.0)
                    .ok_or_else(|| invalid(format!("unknown body #{}", id.0)))?;
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
    /// [`ModelError`] for duplicate names, non-positive masses or inertias,
    /// non-finite values, a zero prismatic axis, a non-positive rod length, a
    /// driver of `θ` on a point mass, or an element attached to the ground twice.
    pub fn build(&self) -> Result<PlanarSystem, ModelError> {
        self.check_names()?;
        self.check_bodies()?;
        let mut constraints = Vec::new();
        let mut row = 0;
        for (name, joint, [a, b]) in &self.joints {
            let c = Constraint::new(
                name.clone(),
                joint.clone(),
                self.joint_anchors(name, joint, [*a, *b])?,
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
            .map(|(name, load, [a, b])| self.force_element(name, load, [*a, *b]))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(PlanarSystem::assemble(self, constraints, forces, row))
    }

    /// Every body and element has its own name.
    fn check_names(&self) -> Result<(), ModelError> {
        let mut names = std::collections::HashSet::new();
        let all_names = self
            .bodies
            .iter()
            .map(|b| &b.name)
            .chain(self.joints.iter().map(|j| &j.0))
            .chain(self.drivers.iter().map(|d| &d.0))
            .chain(self.forces.iter().map(|f| &f.0));
        for name in all_names {
            if !names.insert(name.clone()) {
                return Err(ModelError::DuplicateName(name.clone()));
            }
        }
        Ok(())
    }

    /// Positive masses and inertias, finite poses and velocities.
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
                && !(j > 0.0 && j.is_finite())
            {
                return Err(invalid("the inertia must be positive"));
            }
            if !b.pose.iter().chain(&b.velocity).all(|x| x.is_finite()) {
                return Err(invalid("the initial pose and velocity must be finite"));
            }
        }
        Ok(())
    }

    /// A joint's anchors, checked with its parameters.
    fn joint_anchors(
        &self,
        name: &str,
        joint: &Joint,
        at: [At; 2],
    ) -> Result<[Anchor; 2], ModelError> {
        let invalid = |what: &str| ModelError::Invalid {
            element: name.to_string(),
            what: what.to_string(),
        };
        let anchors = [self.anchor(name, at[0])?, self.anchor(name, at[1])?];
        if matches!(anchors, [Anchor::Ground(_), Anchor::Ground(_)]) {
            return Err(invalid("both ends are on the ground"));
        }
        match joint {
            Joint::Distance { length } if !(*length > 0.0 && length.is_finite()) => {
                Err(invalid("the rod length must be positive"))
            }
            Joint::Prismatic { normal, .. } if !normal.iter().all(|x| x.is_finite()) => {
                Err(invalid("the prismatic axis must be a non-zero vector"))
            }
            Joint::Prismatic { .. } if matches!(anchors[1], Anchor::Ground(_)) => {
                Err(invalid("the sliding side (b) must be a body"))
            }
            _ => Ok(anchors),
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
            .bodies
            .get(body.0)
            .ok_or_else(|| invalid("unknown body"))?;
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
        Ok(Constraint::new(
            name.to_string(),
            Joint::Driver { f: f.clone() },
            [Anchor::Point { x }, Anchor::Ground([0.0; 2])],
            row,
        ))
    }

    /// A force element, its parameters checked.
    fn force_element(&self, name: &str, load: &Load, at: [At; 2]) -> Result<Force, ModelError> {
        let anchors = [self.anchor(name, at[0])?, self.anchor(name, at[1])?];
        let function = match load {
            Load::PointForce { fx, fy } => fx.problem().or_else(|| fy.problem()),
            Load::Torque { tau } => tau.problem(),
            _ => None,
        };
        if let Some(problem) = function {
            return Err(ModelError::Invalid {
                element: name.to_string(),
                what: format!("the load function: {problem}"),
            });
        }
        let finite = match load {
            Load::PointForce { .. } | Load::Torque { .. } => true,
            Load::Spring { k, c, rest } => {
                k.is_finite() && c.is_finite() && rest.is_finite() && *rest >= 0.0
            }
            Load::RotationalSpring { k, c, .. } => k.is_finite() && c.is_finite(),
        };
        if !finite {
            return Err(ModelError::Invalid {
                element: name.to_string(),
                what: "parameters must be finite (and a rest length non-negative)".into(),
            });
        }
        Ok(Force::new(load.clone(), anchors))
    }
}

/// A planar multibody system assembled by [`PlanarBuilder`].
#[derive(Clone, Debug)]
pub struct PlanarSystem {
    gravity: [f64; 2],
    bodies: Vec<Body>,
    constraints: Vec<Constraint>,
    forces: Vec<Force>,
    n: usize,
    m: usize,
    coord_names: Vec<String>,
    constraint_names: Vec<String>,
    mass_pattern: Pattern,
    b_pattern: Pattern,
    hessian_pattern: Pattern,
    g_u_pattern: Pattern,
    g_v_pattern: Pattern,
    /// Offsets of each constraint's entries in the B and Hessian value buffers.
    b_offsets: Vec<usize>,
    h_offsets: Vec<usize>,
    /// Revolute joints (the bulk of chains), evaluated without slot tables.
    revolutes: Vec<RevoluteKernel>,
    /// Indices of the other constraints.
    others: Vec<usize>,
    /// Global indices of the rigid bodies' angles.
    angles: Vec<usize>,
    g_u_offsets: Vec<usize>,
    g_v_offsets: Vec<usize>,
}

fn global_pairs<'a>(
    slots: &'a Slots,
    local: &'a [(usize, usize)],
) -> impl Iterator<Item = (usize, usize)> + 'a {
    local
        .iter()
        .map(|&(a, b)| (slots.global[a], slots.global[b]))
}

/// A chunk of revolute joints and where its output starts: global row, B
/// value, Hessian value.
type Part<'a> = (&'a [RevoluteKernel], (usize, usize, usize));

/// Revolute joints per parallel task.
const PARALLEL_CHUNK: usize = 2048;

/// Splits `x` into consecutive parts starting at `bases` (the first part at 0
/// whatever the first base says; bases ascending).
fn split_at_bases(x: &mut [f64], bases: impl Iterator<Item = usize>) -> Vec<&mut [f64]> {
    let mut parts = Vec::new();
    let (mut rest, mut at) = (x, 0);
    for base in bases.skip(1) {
        let (head, tail) = rest.split_at_mut(base - at);
        parts.push(head);
        (rest, at) = (tail, base);
    }
    parts.push(rest);
    parts
}

impl PlanarSystem {
    /// The revolute joints in chunks for rayon, each with the global row, B
    /// value and Hessian value at which its output part starts (0 for the
    /// first chunk); empty when the work is sequential: fewer than two
    /// chunks' worth of joints, or one thread in rayon's current pool.
    fn parallel_parts(&self) -> Vec<Part<'_>> {
        let threads = rayon::current_num_threads();
        if threads < 2 || self.revolutes.len() < 2 * PARALLEL_CHUNK {
            return Vec::new();
        }
        let size = self
            .revolutes
            .len()
            .div_ceil(4 * threads)
            .max(PARALLEL_CHUNK);
        self.revolutes
            .chunks(size)
            .enumerate()
            .map(|(i, ks)| (ks, if i == 0 { (0, 0, 0) } else { ks[0].offsets() }))
            .collect()
    }

    fn assemble(
        builder: &PlanarBuilder,
        constraints: Vec<Constraint>,
        forces: Vec<Force>,
        m: usize,
    ) -> Self {
        let n = builder.n;
        let mut coord_names = Vec::with_capacity(n);
        let mut mass_entries = Vec::with_capacity(n);
        for b in &builder.bodies {
            let count = if b.inertia.is_some() { 3 } else { 2 };
            for (k, c) in ["x", "y", "theta"].iter().take(count).enumerate() {
                coord_names.push(format!("{}.{c}", b.name));
                mass_entries.push((b.x + k, b.x + k));
            }
        }
        let mut constraint_names = Vec::with_capacity(m);
        let (mut b_entries, mut h_entries) = (Vec::new(), Vec::new());
        let (mut b_offsets, mut h_offsets) = (Vec::new(), Vec::new());
        for c in &constraints {
            constraint_names.extend(c.row_names.iter().map(|s| format!("{}{s}", c.name)));
            b_offsets.push(b_entries.len());
            h_offsets.push(h_entries.len());
            b_entries.extend(c.grad.iter().map(|&(r, a)| (c.row0 + r, c.slots.global[a])));
            h_entries.extend(
                c.hess
                    .iter()
                    .map(|&(_, a, b)| (c.slots.global[a], c.slots.global[b])),
            );
        }
        let (mut gu, mut gv, mut gu_off, mut gv_off) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for f in &forces {
            gu_off.push(gu.len());
            gv_off.push(gv.len());
            gu.extend(global_pairs(&f.slots, &f.g_u));
            gv.extend(global_pairs(&f.slots, &f.g_v));
        }
        let angles: Vec<usize> = builder
            .bodies
            .iter()
            .filter(|b| b.inertia.is_some())
            .map(|b| b.x + 2)
            .collect();
        // Position of each angle's (sin θ, cos θ) in the workspace of phi_b_into.
        let mut trig_slot = vec![0u32; n];
        for (k, &x) in angles.iter().enumerate() {
            trig_slot[x] = u32::try_from(k).unwrap_or(u32::MAX);
        }
        let (mut revolutes, mut others) = (Vec::new(), Vec::new());
        for (i, c) in constraints.iter().enumerate() {
            match RevoluteKernel::of(c, b_offsets[i], h_offsets[i], |x| trig_slot[x]) {
                Some(k) => revolutes.push(k),
                None => others.push(i),
            }
        }
        Self {
            revolutes,
            others,
            angles,
            gravity: builder.gravity,
            bodies: builder.bodies.clone(),
            n,
            m,
            coord_names,
            constraint_names,
            mass_pattern: Pattern::from_entries(n, n, mass_entries),
            b_pattern: Pattern::from_entries(m, n, b_entries),
            hessian_pattern: Pattern::from_entries(n, n, h_entries),
            g_u_pattern: Pattern::from_entries(n, n, gu),
            g_v_pattern: Pattern::from_entries(n, n, gv),
            b_offsets,
            h_offsets,
            g_u_offsets: gu_off,
            g_v_offsets: gv_off,
            constraints,
            forces,
        }
    }

    /// Initial coordinates `u₀` (the poses given to the builder).
    #[must_use]
    pub fn initial_position(&self) -> Vec<f64> {
        self.initial(|b| b.pose)
    }

    /// Initial velocities `u̇₀` (given to the builder, zero by default).
    #[must_use]
    pub fn initial_velocity(&self) -> Vec<f64> {
        self.initial(|b| b.velocity)
    }

    fn initial(&self, f: impl Fn(&Body) -> [f64; 3]) -> Vec<f64> {
        let mut u = vec![0.0; self.n];
        for b in &self.bodies {
            let count = if b.inertia.is_some() { 3 } else { 2 };
            u[b.x..b.x + count].copy_from_slice(&f(b)[..count]);
        }
        u
    }

    /// Number of bodies.
    #[must_use]
    pub fn n_bodies(&self) -> usize {
        self.bodies.len()
    }

    /// Index of the `x` coordinate of the body called `name`.
    #[must_use]
    pub fn body_x(&self, name: &str) -> Option<usize> {
        self.bodies.iter().find(|b| b.name == name).map(|b| b.x)
    }

    /// The name of the joint or driver that owns constraint row `row`
    /// (`None` past the last row).
    #[must_use]
    pub fn constraint_owner(&self, row: usize) -> Option<&str> {
        self.constraints
            .iter()
            .find(|c| (c.row0..c.row0 + c.rows).contains(&row))
            .map(|c| c.name.as_str())
    }
}

impl System for PlanarSystem {
    fn n_coords(&self) -> usize {
        self.n
    }

    fn n_constraints(&self) -> usize {
        self.m
    }

    fn coord_name(&self, i: usize) -> String {
        self.coord_names[i].clone()
    }

    fn constraint_name(&self, i: usize) -> String {
        self.constraint_names[i].clone()
    }

    fn mass_pattern(&self) -> Pattern {
        self.mass_pattern.clone()
    }

    fn mass_is_constant(&self) -> bool {
        true
    }

    fn mass_into(&self, _t: f64, _u: &[f64], mass: &mut [f64]) {
        let mut k = 0;
        for b in &self.bodies {
            mass[k] = b.mass;
            mass[k + 1] = b.mass;
            k += 2;
            if let Some(j) = b.inertia {
                mass[k] = j;
                k += 1;
            }
        }
    }

    fn forces_are_constant(&self) -> bool {
        // Gravity alone.
        self.forces.is_empty()
    }

    fn tangent_is_symmetric(&self) -> bool {
        // M is constant; only a spring's damping makes ∂g/∂u unsymmetric
        // (its tension's rate times the spring direction).
        self.forces.iter().all(Force::has_symmetric_jacobians)
    }

    fn forces_into(&self, t: f64, u: &[f64], v: &[f64], g: &mut [f64]) {
        // Every coordinate belongs to a body: gravity writes all of g.
        for b in &self.bodies {
            g[b.x] = b.mass * self.gravity[0];
            g[b.x + 1] = b.mass * self.gravity[1];
            if b.inertia.is_some() {
                g[b.x + 2] = 0.0;
            }
        }
        for f in &self.forces {
            f.add_forces(t, u, v, g);
        }
    }

    fn forces_du_pattern(&self) -> Pattern {
        self.g_u_pattern.clone()
    }

    fn forces_du_into(&self, t: f64, u: &[f64], v: &[f64], g_u: &mut [f64]) {
        for (f, &off) in self.forces.iter().zip(&self.g_u_offsets) {
            f.jacobian(t, u, v, false, &mut g_u[off..off + f.g_u.len()]);
        }
    }

    fn forces_dv_pattern(&self) -> Pattern {
        self.g_v_pattern.clone()
    }

    fn forces_dv_into(&self, t: f64, u: &[f64], v: &[f64], g_v: &mut [f64]) {
        for (f, &off) in self.forces.iter().zip(&self.g_v_offsets) {
            f.jacobian(t, u, v, true, &mut g_v[off..off + f.g_v.len()]);
        }
    }

    fn phi_into(&self, t: f64, u: &[f64], phi: &mut [f64]) {
        for c in &self.constraints {
            c.phi(t, u, &mut phi[c.row0..c.row0 + c.rows]);
        }
    }

    fn b_pattern(&self) -> Pattern {
        self.b_pattern.clone()
    }

    fn b_into(&self, _t: f64, u: &[f64], b: &mut [f64]) {
        for (c, &off) in self.constraints.iter().zip(&self.b_offsets) {
            c.grad_values(u, &mut b[off..off + c.grad.len()]);
        }
    }

    fn workspace_len(&self) -> usize {
        2 * self.angles.len()
    }

    fn phi_b_into(&self, t: f64, u: &[f64], phi: &mut [f64], b: &mut [f64], work: &mut [f64]) {
        // The workspace holds each body's (sin θ, cos θ), computed once, not
        // once per joint it takes part in, in a table of the angles alone (no
        // gaps: on a long chain it is written and read through memory).
        let Some(trig) = work.get_mut(..2 * self.angles.len()) else {
            self.phi_into(t, u, phi);
            self.b_into(t, u, b);
            return;
        };
        for (t, &x) in trig.chunks_exact_mut(2).zip(&self.angles) {
            (t[0], t[1]) = u[x].sin_cos();
        }
        let trig: &[f64] = trig;
        let revolutes = |ks: &[RevoluteKernel], phi: &mut [f64], b: &mut [f64], base| {
            for k in ks {
                k.phi_b(u, trig, phi, b, base);
            }
        };
        let parts = self.parallel_parts();
        if parts.is_empty() {
            revolutes(&self.revolutes, phi, b, (0, 0));
        } else {
            let phi_parts = split_at_bases(phi, parts.iter().map(|p| p.1.0));
            let b_parts = split_at_bases(b, parts.iter().map(|p| p.1.1));
            parts
                .into_par_iter()
                .zip(phi_parts)
                .zip(b_parts)
                .for_each(|(((ks, base), phi), b)| revolutes(ks, phi, b, (base.0, base.1)));
        }
        for &i in &self.others {
            let (c, off) = (&self.constraints[i], self.b_offsets[i]);
            c.phi_grad(
                t,
                u,
                &mut phi[c.row0..c.row0 + c.rows],
                &mut b[off..off + c.grad.len()],
            );
        }
    }

    fn phi_t_into(&self, t: f64, _u: &[f64], phi_t: &mut [f64]) {
        let mut tt = [0.0; 3];
        for c in &self.constraints {
            c.phi_t(t, &mut phi_t[c.row0..c.row0 + c.rows], &mut tt[..c.rows]);
        }
    }

    fn hessian_pattern(&self) -> Pattern {
        self.hessian_pattern.clone()
    }

    fn hessian_into(&self, _t: f64, u: &[f64], mu: &[f64], out: &mut [f64]) {
        let parts = self.parallel_parts();
        if parts.is_empty() {
            for k in &self.revolutes {
                k.hessian(u, mu, out, 0);
            }
        } else {
            let out_parts = split_at_bases(out, parts.iter().map(|p| p.1.2));
            parts
                .into_par_iter()
                .zip(out_parts)
                .for_each(|((ks, base), out)| {
                    for k in ks {
                        k.hessian(u, mu, out, base.2);
                    }
                });
        }
        for &i in &self.others {
            let (c, off) = (&self.constraints[i], self.h_offsets[i]);
            let vals = &mut out[off..off + c.hess.len()];
            c.hess_values(u, vals);
            for (v, &(r, _, _)) in vals.iter_mut().zip(&c.hess) {
                *v *= mu[c.row0 + r];
            }
        }
    }

    fn accel_rhs_into(&self, t: f64, u: &[f64], v: &[f64], out: &mut [f64]) {
        // c = −vᵀ (∂²Φ/∂q²) v − Φ_tt (no element has a B_t). An element
        // has at most two bodies (6 slots): its Hessian at most 3 × 6 × 6
        // values, on the stack.
        let mut buffer = [0.0; elements::MAX_HESSIAN];
        let (mut t1, mut tt) = ([0.0; 3], [0.0; 3]);
        for c in &self.constraints {
            c.phi_t(t, &mut t1[..c.rows], &mut tt[..c.rows]);
            let rows = &mut out[c.row0..c.row0 + c.rows];
            for (o, &x) in rows.iter_mut().zip(&tt) {
                *o = -x;
            }
            let hess = &mut buffer[..c.hess.len()];
            c.hess_values(u, hess);
            for (h, &(r, a, b)) in hess.iter().zip(&c.hess) {
                rows[r] -= h * v[c.slots.global[a]] * v[c.slots.global[b]];
            }
        }
    }

    fn potential_energy(&self, _t: f64, u: &[f64]) -> f64 {
        let gravity: f64 = self
            .bodies
            .iter()
            .map(|b| -b.mass * (self.gravity[0] * u[b.x] + self.gravity[1] * u[b.x + 1]))
            .sum();
        gravity + self.forces.iter().map(|f| f.potential(u)).sum::<f64>()
    }
}
