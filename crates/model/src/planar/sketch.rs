//! What a picture of a planar model needs: its bodies, and every joint and
//! load with the points it attaches to, for `mstar animate` and other
//! drawings. Positions follow from a state `u` with [`Sketch::position`].

use super::PlanarSystem;
use super::geometry::Anchor;

/// Where an element attaches: a ground point or a point of a body.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Attachment {
    /// A fixed point `[x, y]` of the ground, m.
    Ground([f64; 2]),
    /// The point at local offset `local` (body frame, relative to the centre
    /// of mass, m) of the `body`-th body of [`Sketch::bodies`].
    Body {
        /// Index into [`Sketch::bodies`].
        body: usize,
        /// Local offset, m (`[0, 0]` for a point mass).
        local: [f64; 2],
    },
}

/// A body as drawn.
#[derive(Clone, Debug, PartialEq)]
pub struct SketchBody {
    /// Its name.
    pub name: String,
    /// Index of its `x` coordinate in `u` (`y` follows, then `θ` if rigid).
    pub x: usize,
    /// A rigid body (else a point mass).
    pub rigid: bool,
    /// The local points where joints and loads attach to it (each once).
    pub points: Vec<[f64; 2]>,
}

/// A joint, driver or load as drawn.
#[derive(Clone, Debug, PartialEq)]
pub struct SketchElement {
    /// Its name.
    pub name: String,
    /// Its kind, as in model files: `revolute`, `weld`, `distance`,
    /// `prismatic`, `driver`, `force`, `torque`, `spring-damper`,
    /// `rotational-spring-damper`.
    pub kind: &'static str,
    /// Its two attachments (a one-body element — driver, force, torque —
    /// has the ground as its second).
    pub ends: [Attachment; 2],
    /// A prismatic joint's sliding direction, unit, in the frame of its first
    /// attachment's body (global for the ground); `None` for other kinds.
    pub axis: Option<[f64; 2]>,
}

/// The bodies and elements of a [`PlanarSystem`], for drawing.
#[derive(Clone, Debug, PartialEq)]
pub struct Sketch {
    /// The bodies, in the model's order.
    pub bodies: Vec<SketchBody>,
    /// The joints and drivers (in row order), then the loads.
    pub elements: Vec<SketchElement>,
}

impl Sketch {
    /// The global position of an attachment at the state `u`.
    #[must_use]
    pub fn position(&self, at: &Attachment, u: &[f64]) -> [f64; 2] {
        match *at {
            Attachment::Ground(p) => p,
            Attachment::Body { body, local } => {
                let b = &self.bodies[body];
                let theta = if b.rigid { u[b.x + 2] } else { 0.0 };
                let (s, c) = theta.sin_cos();
                [
                    u[b.x] + c * local[0] - s * local[1],
                    u[b.x + 1] + s * local[0] + c * local[1],
                ]
            }
        }
    }
}

impl PlanarSystem {
    /// The model's bodies and elements for a drawing.
    #[must_use]
    pub fn sketch(&self) -> Sketch {
        let mut bodies: Vec<SketchBody> = self
            .bodies
            .iter()
            .map(|b| SketchBody {
                name: b.name.clone(),
                x: b.x,
                rigid: b.inertia.is_some(),
                points: Vec::new(),
            })
            .collect();
        let joints = self.constraints.iter().map(|c| {
            // A driver's first anchor names the driven coordinate: its body.
            let anchors = if c.element.is_driver() {
                let x = c.slots.global[0];
                let b = self.body_of(x).map_or(0, |b| b.x);
                [Anchor::Point { x: b }, c.anchors[1]]
            } else {
                c.anchors
            };
            let points = c.element.uses_points();
            (
                c.name.clone(),
                c.element.kind(),
                anchors,
                points,
                c.element.axis(),
            )
        });
        let loads = self.forces.iter().map(|f| {
            let points = f.element.uses_points();
            (f.name.clone(), f.element.kind(), f.anchors, points, None)
        });
        let elements = joints
            .chain(loads)
            .map(|(name, kind, anchors, points, axis)| SketchElement {
                name,
                kind,
                ends: anchors.map(|a| self.attachment(a, points.then_some(&mut bodies[..]))),
                axis,
            })
            .collect();
        Sketch { bodies, elements }
    }

    /// The attachment of an anchor, its point recorded on its body when
    /// `bodies` is given (an element that acts on a body as a whole — a
    /// driver, a torque — has no point of it).
    fn attachment(&self, a: Anchor, bodies: Option<&mut [SketchBody]>) -> Attachment {
        let (x, local) = match a {
            Anchor::Ground(p) => return Attachment::Ground(p),
            Anchor::Point { x } => (x, [0.0; 2]),
            Anchor::Rigid { x, s } => (x, s),
        };
        let body = self.bodies.partition_point(|b| b.x < x);
        if let Some(b) = bodies.and_then(|b| b.get_mut(body))
            && !b.points.contains(&local)
        {
            b.points.push(local);
        }
        Attachment::Body { body, local }
    }
}

#[cfg(test)]
mod tests {
    use super::Attachment;
    use crate::planar::{At, PlanarBuilder, PointMass, RigidBody, SpringDamper};

    #[test]
    fn a_sketch_places_every_attachment_where_the_model_has_it() {
        let mut b = PlanarBuilder::new();
        let bar = b.rigid_body(
            "bar",
            RigidBody {
                mass: 1.0,
                inertia: 0.1,
                pose: [0.5, 0.0, std::f64::consts::FRAC_PI_2],
                velocity: [0.0; 3],
            },
        );
        let bob = b.point_mass(
            "bob",
            PointMass {
                mass: 1.0,
                position: [0.5, 1.5],
                velocity: [0.0; 2],
            },
        );
        b.revolute("hinge", At::Ground([0.5, -0.5]), At::Body(bar, [-0.5, 0.0]));
        b.distance(
            "rod",
            At::Body(bar, [0.5, 0.0]),
            At::Body(bob, [0.0, 0.0]),
            1.0,
        );
        let spring = SpringDamper {
            stiffness: 1.0,
            damping: 0.0,
            rest_length: 1.0,
        };
        b.spring(
            "spring",
            At::Body(bob, [0.0, 0.0]),
            At::Ground([2.0, 1.5]),
            spring,
        );
        let sys = b.build().expect("valid");
        let sketch = sys.sketch();
        let u = sys.initial_position();
        let kinds: Vec<&str> = sketch.elements.iter().map(|e| e.kind).collect();
        assert_eq!(kinds, ["revolute", "distance", "spring-damper"]);
        assert_eq!(sketch.bodies[0].points, [[-0.5, 0.0], [0.5, 0.0]]);
        assert_eq!(sketch.bodies[1].points, [[0.0, 0.0]]);
        // The bar stands up: its local (-0.5, 0) is at the hinge, (0.5, 0) at the top.
        let [hinge_ground, hinge_bar] = sketch.elements[0].ends;
        assert_eq!(hinge_ground, Attachment::Ground([0.5, -0.5]));
        let p = sketch.position(&hinge_bar, &u);
        assert!(
            (p[0] - 0.5).abs() < 1e-15 && (p[1] + 0.5).abs() < 1e-15,
            "{p:?}"
        );
        let top = sketch.position(&sketch.elements[1].ends[0], &u);
        assert!(
            (top[0] - 0.5).abs() < 1e-15 && (top[1] - 0.5).abs() < 1e-15,
            "{top:?}"
        );
        assert_eq!(sketch.position(&sketch.elements[2].ends[0], &u), [0.5, 1.5]);
    }
}
