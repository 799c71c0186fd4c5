//! Sensors: quantities a model file asks to have written beside the state
//! (`docs/model-format.md`, "`[[sensor]]`"), and the body frames they are
//! measured from.
//!
//! A body's frame at a state is its centre of mass `r`, its rotation `A`
//! (body to global axes) and their rates. A point `s` fixed in the body (body
//! axes, from the centre of mass) is at `r + A s` and moves with
//! `ṙ + ω × (A s)` and `r̈ + α × (A s) + ω × (ω × (A s))` (rigid-body
//! kinematics; Haug 1989, §9.1). A planar body is a spatial one in the
//! `x`–`y` plane turning about `z`: `A = Rz(θ)`, `ω = (0, 0, θ̇)`. A spatial
//! body's `ω = 2 E(p) ṗ` and `α = 2 E(p) p̈` (global axes: `Ė ṗ = 0`;
//! `spatial/rotation.rs`).

use crate::StateRef;
use crate::spatial::rotation::{cross, omega_global, rotate};

/// A named sensor as a model file gives it: the elements it measures are
/// named, and checked when its columns are made.
#[derive(Clone, Debug, PartialEq)]
pub struct Sensor {
    /// Its name: its columns are `sensor:<name>` and `sensor:<name>.<component>`.
    pub name: String,
    /// What it measures.
    pub kind: SensorKind,
}

/// What a [`Sensor`] measures.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum SensorKind {
    /// A body point's position, velocity or acceleration (global axes).
    Point {
        /// Which of the three.
        motion: Motion,
        /// The point.
        at: BodyPoint,
    },
    /// A body's angular velocity (global axes).
    AngularVelocity {
        /// The body.
        body: String,
    },
    /// A body's orientation: the planar angle, or the spatial rotation's
    /// Cardan angles ([`cardan_angles`]).
    Orientation {
        /// The body.
        body: String,
    },
    /// The distance between two points (either may be on the ground).
    Distance {
        /// The first point.
        a: BodyPoint,
        /// The second point.
        b: BodyPoint,
    },
    /// The reaction of a joint or driver (as its `reaction:` columns).
    Reaction {
        /// The joint or driver.
        joint: String,
    },
    /// The effort of a driver (as its `effort:` column).
    Effort {
        /// The driver.
        driver: String,
    },
}

/// A point's position, velocity or acceleration.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Motion {
    /// Position, m.
    Position,
    /// Velocity, m/s.
    Velocity,
    /// Acceleration, m/s².
    Acceleration,
}

/// A point fixed in a body (or in the ground: then global).
#[derive(Clone, Debug, PartialEq)]
pub struct BodyPoint {
    /// The body's name, or `ground`.
    pub body: String,
    /// The point in body axes from the centre of mass (global for the
    /// ground), m; a planar point's `z` is 0.
    pub point: [f64; 3],
}

/// A body's frame at a state: centre of mass, rotation and their rates, all
/// in global axes (a planar body's in the `x`–`y` plane).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// Centre of mass, m.
    pub r: [f64; 3],
    /// Its velocity, m/s.
    pub v: [f64; 3],
    /// Its acceleration, m/s².
    pub a: [f64; 3],
    /// Rotation matrix, body to global axes (rows).
    pub rotation: [[f64; 3]; 3],
    /// Angular velocity, rad/s.
    pub omega: [f64; 3],
    /// Angular acceleration, rad/s².
    pub alpha: [f64; 3],
}

impl Frame {
    /// The ground's frame: at rest at the origin.
    pub const GROUND: Self = Self {
        r: [0.0; 3],
        v: [0.0; 3],
        a: [0.0; 3],
        rotation: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        omega: [0.0; 3],
        alpha: [0.0; 3],
    };

    /// `A s`: the body vector `s` in global axes.
    #[must_use]
    pub fn to_global(&self, s: [f64; 3]) -> [f64; 3] {
        let m = &self.rotation;
        [0, 1, 2].map(|i| m[i][0] * s[0] + m[i][1] * s[1] + m[i][2] * s[2])
    }

    /// The position, velocity or acceleration of the body point `s`.
    #[must_use]
    pub fn point(&self, motion: Motion, s: [f64; 3]) -> [f64; 3] {
        let d = self.to_global(s);
        let add = |x: [f64; 3], y: [f64; 3]| [x[0] + y[0], x[1] + y[1], x[2] + y[2]];
        match motion {
            Motion::Position => add(self.r, d),
            Motion::Velocity => add(self.v, cross(self.omega, d)),
            Motion::Acceleration => {
                let centripetal = cross(self.omega, cross(self.omega, d));
                add(self.a, add(cross(self.alpha, d), centripetal))
            }
        }
    }
}

/// The frame of a planar body whose `x, y (, θ)` are at `u[x..]` (`rigid`:
/// it has `θ`; a point mass does not turn).
#[must_use]
pub fn planar_frame(x: usize, rigid: bool, s: &StateRef<'_>) -> Frame {
    let three = |w: &[f64]| [w[x], w[x + 1], 0.0];
    let (theta, w, dw) = if rigid {
        (s.u[x + 2], s.v[x + 2], s.a[x + 2])
    } else {
        (0.0, 0.0, 0.0)
    };
    let (sin, cos) = theta.sin_cos();
    Frame {
        r: three(s.u),
        v: three(s.v),
        a: three(s.a),
        rotation: [[cos, -sin, 0.0], [sin, cos, 0.0], [0.0, 0.0, 1.0]],
        omega: [0.0, 0.0, w],
        alpha: [0.0, 0.0, dw],
    }
}

/// The frame of a spatial body whose `x, y, z (, e0, e1, e2, e3)` are at
/// `u[x..]` (`rigid`: it has Euler parameters).
#[must_use]
pub fn spatial_frame(x: usize, rigid: bool, s: &StateRef<'_>) -> Frame {
    let three = |w: &[f64]| [w[x], w[x + 1], w[x + 2]];
    let mut frame = Frame {
        r: three(s.u),
        v: three(s.v),
        a: three(s.a),
        ..Frame::GROUND
    };
    if rigid {
        let four = |w: &[f64]| [w[x + 3], w[x + 4], w[x + 5], w[x + 6]];
        let (p, pd, pdd) = (four(s.u), four(s.v), four(s.a));
        // Columns of A: the body axes in global axes.
        let columns = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]].map(|e| rotate(&p, e));
        frame.rotation = [0, 1, 2].map(|i| [columns[0][i], columns[1][i], columns[2][i]]);
        frame.omega = omega_global(&p, &pd);
        frame.alpha = omega_global(&p, &pdd);
    }
    frame
}

/// The Cardan angles `[roll, pitch, yaw]` of a rotation matrix `A` (body to
/// global): `A = Rz(yaw) Ry(pitch) Rx(roll)`, rotations about the fixed
/// global axes `x`, then `y`, then `z` (URDF's `rpy`). `pitch` is in
/// `[−π/2, π/2]`, `roll` and `yaw` in `(−π, π]`; at `pitch = ±π/2` (gimbal
/// lock) only `yaw ∓ roll` is defined, and `roll` is reported as 0.
#[must_use]
pub fn cardan_angles(a: &[[f64; 3]; 3]) -> [f64; 3] {
    let pitch = (-a[2][0]).clamp(-1.0, 1.0).asin();
    let locked = a[2][1].hypot(a[2][2]) < 1e-12;
    if locked {
        return [0.0, pitch, (-a[0][1]).atan2(a[1][1])];
    }
    [a[2][1].atan2(a[2][2]), pitch, a[1][0].atan2(a[0][0])]
}

/// A model whose bodies have [`Frame`]s: planar and spatial systems.
pub trait Frames {
    /// 2 (planar) or 3 (spatial).
    fn dimension(&self) -> usize;

    /// The body `name`: its first coordinate and whether it is rigid (has an
    /// orientation); `None` for no such body.
    fn body_coordinates(&self, name: &str) -> Option<(usize, bool)>;

    /// The frame of the body at `(x, rigid)` ([`body_coordinates`](Self::body_coordinates)).
    fn frame(&self, x: usize, rigid: bool, s: &StateRef<'_>) -> Frame;
}

impl Frames for crate::planar::PlanarSystem {
    fn dimension(&self) -> usize {
        2
    }
    fn body_coordinates(&self, name: &str) -> Option<(usize, bool)> {
        self.body(name).map(|b| (b.x, b.theta.is_some()))
    }
    fn frame(&self, x: usize, rigid: bool, s: &StateRef<'_>) -> Frame {
        planar_frame(x, rigid, s)
    }
}

impl Frames for crate::spatial::SpatialSystem {
    fn dimension(&self) -> usize {
        3
    }
    fn body_coordinates(&self, name: &str) -> Option<(usize, bool)> {
        self.body(name)
    }
    fn frame(&self, x: usize, rigid: bool, s: &StateRef<'_>) -> Frame {
        spatial_frame(x, rigid, s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `Rz(y) Ry(p) Rx(r)` written out (Craig, *Introduction to Robotics*,
    /// 3rd ed., eq. 2.64), and its angles read back.
    #[test]
    fn cardan_angles_read_back_a_written_out_rotation() {
        let (r, p, y) = (0.3_f64, -0.7_f64, 2.5_f64);
        let (sr, cr, sp, cp, sy, cy) = (r.sin(), r.cos(), p.sin(), p.cos(), y.sin(), y.cos());
        let a = [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ];
        let got = cardan_angles(&a);
        for (g, want) in got.iter().zip([r, p, y]) {
            assert!((g - want).abs() < 1e-14, "{got:?}");
        }
    }

    /// A planar bar turning at ω = 2 rad/s with α = 3 rad/s² about its
    /// centre: its end `s = (1, 0)` at θ = 0 moves with `(0, 2)` and
    /// accelerates with `(−ω², α) = (−4, 3)`.
    #[test]
    fn a_turning_bar_end_moves_as_circular_motion_says() {
        let (u, v, a) = ([0.0; 3], [0.0, 0.0, 2.0], [0.0, 0.0, 3.0]);
        let s = StateRef {
            t: 0.0,
            u: &u,
            v: &v,
            a: &a,
            lambda: &[],
        };
        let f = planar_frame(0, true, &s);
        assert_eq!(f.point(Motion::Velocity, [1.0, 0.0, 0.0]), [0.0, 2.0, 0.0]);
        assert_eq!(
            f.point(Motion::Acceleration, [1.0, 0.0, 0.0]),
            [-4.0, 3.0, 0.0]
        );
    }
}
