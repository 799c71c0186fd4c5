//! What a picture of a spatial model needs: its bodies, and every joint,
//! driver and load with the points it attaches to (in body axes), for
//! `mstar animate` and other drawings. Global positions follow from a state
//! `u` with [`SpatialSketch::position`]; projecting them onto a picture is
//! the drawing's business.

use super::rotation_matrix;
use super::system::SpatialSystem;

/// Where an element attaches: a ground point or a point of a body.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SpatialAttachment {
    /// A fixed point `[x, y, z]` of the ground, m.
    Ground([f64; 3]),
    /// The point at `local` (body axes, relative to the centre of mass, m)
    /// of the `body`-th body of [`SpatialSketch::bodies`].
    Body {
        /// Index into [`SpatialSketch::bodies`].
        body: usize,
        /// Local offset, m (`[0, 0, 0]` for a point mass).
        local: [f64; 3],
    },
}

/// A body as drawn.
#[derive(Clone, Debug, PartialEq)]
pub struct SpatialSketchBody {
    /// Its name.
    pub name: String,
    /// Index of its `x` coordinate in `u` (`y`, `z` follow, then the Euler
    /// parameters `e0 … e3` if rigid).
    pub x: usize,
    /// A rigid body (else a point mass).
    pub rigid: bool,
}

/// A joint, driver or load as drawn.
#[derive(Clone, Debug, PartialEq)]
pub struct SpatialSketchElement {
    /// Its name.
    pub name: String,
    /// Its type, as [`SpatialSystem::joint_kind`] and
    /// [`SpatialSystem::loads`] name it (`spherical`, `revolute`,
    /// `angle driver`, `spring-damper`, …).
    pub kind: &'static str,
    /// Whether it is a driver.
    pub driver: bool,
    /// Its two attachments (a point force's second is the ground's origin;
    /// a torque's are both at the centres of mass).
    pub ends: [SpatialAttachment; 2],
}

/// The bodies and elements of a [`SpatialSystem`], for drawing.
#[derive(Clone, Debug, PartialEq)]
pub struct SpatialSketch {
    /// The bodies, in the model's order.
    pub bodies: Vec<SpatialSketchBody>,
    /// The joints and drivers, then the loads, each in the model's order.
    pub elements: Vec<SpatialSketchElement>,
}

impl SpatialSketch {
    /// The global position of an attachment at the state `u`: `r + A(p) s`.
    #[must_use]
    pub fn position(&self, at: &SpatialAttachment, u: &[f64]) -> [f64; 3] {
        match *at {
            SpatialAttachment::Ground(p) => p,
            SpatialAttachment::Body { body, local } => {
                let b = &self.bodies[body];
                let r = [u[b.x], u[b.x + 1], u[b.x + 2]];
                if !b.rigid {
                    return r;
                }
                let p = [u[b.x + 3], u[b.x + 4], u[b.x + 5], u[b.x + 6]];
                let a = rotation_matrix(p);
                std::array::from_fn(|i| r[i] + (0..3).map(|j| a[i][j] * local[j]).sum::<f64>())
            }
        }
    }
}

impl SpatialSystem {
    /// The model's bodies and elements for a drawing.
    #[must_use]
    pub fn sketch(&self) -> SpatialSketch {
        let bodies = self
            .bodies
            .iter()
            .map(|b| SpatialSketchBody {
                name: b.name.clone(),
                x: b.x,
                rigid: b.is_rigid(),
            })
            .collect();
        let joints = self.joints.iter().map(|j| SpatialSketchElement {
            name: j.name.clone(),
            kind: j.element.kind(),
            driver: j.element.is_driver(),
            ends: ends(j.sides, j.element.points()),
        });
        let loads = self.load_list().iter().map(|l| SpatialSketchElement {
            name: l.name.clone(),
            kind: l.element.kind(),
            driver: false,
            ends: ends(l.sides, l.element.points()),
        });
        SpatialSketch {
            bodies,
            elements: joints.chain(loads).collect(),
        }
    }
}

/// The attachments of an element on `sides` (`None`: the ground) at
/// `points`.
fn ends(sides: [Option<usize>; 2], points: [[f64; 3]; 2]) -> [SpatialAttachment; 2] {
    std::array::from_fn(|k| match sides[k] {
        None => SpatialAttachment::Ground(points[k]),
        Some(body) => SpatialAttachment::Body {
            body,
            local: points[k],
        },
    })
}

#[cfg(test)]
mod tests {
    use super::SpatialAttachment;
    use crate::spatial::{
        Attach, JointSpec, JointType, SpatialBody, SpatialBuilder, SpatialInertia, euler_parameters,
    };

    #[test]
    fn a_sketch_places_joint_points_by_the_bodies_orientation() {
        let mut b = SpatialBuilder::new();
        // A rod along its body x axis, turned by 90° about global z: its
        // body x axis points along global y.
        let rod = b.body(
            "rod",
            SpatialBody {
                mass: 1.0,
                inertia: SpatialInertia::Principal([0.01, 0.1, 0.1]),
                position: [1.0, 2.0, 3.0],
                orientation: euler_parameters([0.0, 0.0, 1.0], std::f64::consts::FRAC_PI_2),
                velocity: [0.0; 3],
                angular_velocity: [0.0; 3],
            },
        );
        b.joint(
            "ball",
            JointSpec {
                kind: JointType::Spherical,
                bodies: [Attach::Ground, Attach::Body(rod)],
                points: [[1.0, 1.5, 3.0], [-0.5, 0.0, 0.0]],
                axes: [[0.0, 0.0, 1.0]; 2],
                length: None,
            },
        );
        let sys = b.build().expect("valid");
        let sketch = sys.sketch();
        let u = sys.initial_position();
        assert_eq!(sketch.bodies.len(), 1);
        assert!(sketch.bodies[0].rigid);
        let [ground, on_rod] = sketch.elements[0].ends;
        assert_eq!(ground, SpatialAttachment::Ground([1.0, 1.5, 3.0]));
        assert_eq!(
            on_rod,
            SpatialAttachment::Body {
                body: 0,
                local: [-0.5, 0.0, 0.0]
            }
        );
        let p = sketch.position(&on_rod, &u);
        let expected = [1.0, 1.5, 3.0];
        assert!(
            p.iter().zip(expected).all(|(a, b)| (a - b).abs() < 1e-12),
            "{p:?}"
        );
    }
}
