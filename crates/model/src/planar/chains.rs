//! Generators of chains: uniform bars and point masses for the benchmarks,
//! and bars of any size at any angle and rate for property tests and the
//! test catalogue.

use super::{At, ModelError, PlanarBuilder, PlanarSystem, PointMass, RigidBody};

/// One bar of [`bar_chain_of`]: a uniform slender bar hinged at its start.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bar {
    /// Length, m.
    pub length: f64,
    /// Mass, kg (inertia about the centre `m l²/12`).
    pub mass: f64,
    /// Initial angle from `+x`, counter-clockwise, rad.
    pub angle: f64,
    /// Initial angular velocity, rad/s.
    pub rate: f64,
}

/// A chain of uniform slender bars on revolute joints, the first hinged to
/// the ground at the origin, each at its given angle and angular velocity
/// with centre velocities consistent with the joints; gravity `−9.81 ŷ`.
/// Bodies are named `link1` … `linkN` from the ground outwards, joints
/// `joint1` … `jointN`.
///
/// # Errors
/// [`ModelError`] for a non-positive mass or a non-finite value.
pub fn bar_chain_of(bars: &[Bar]) -> Result<PlanarSystem, ModelError> {
    let mut b = PlanarBuilder::new();
    let mut previous = At::Ground([0.0, 0.0]);
    let (mut joint, mut joint_velocity) = ([0.0, 0.0], [0.0, 0.0]);
    for (k, bar) in bars.iter().enumerate() {
        let (l, w) = (bar.length, bar.rate);
        let (s, c) = bar.angle.sin_cos();
        let centre = [joint[0] + 0.5 * l * c, joint[1] + 0.5 * l * s];
        let centre_velocity = [
            joint_velocity[0] - 0.5 * l * s * w,
            joint_velocity[1] + 0.5 * l * c * w,
        ];
        let body = b.rigid_body(
            &format!("link{}", k + 1),
            RigidBody {
                mass: bar.mass,
                inertia: bar.mass * l * l / 12.0,
                pose: [centre[0], centre[1], bar.angle],
                velocity: [centre_velocity[0], centre_velocity[1], w],
            },
        );
        b.revolute(
            &format!("joint{}", k + 1),
            previous,
            At::Body(body, [-0.5 * l, 0.0]),
        );
        previous = At::Body(body, [0.5 * l, 0.0]);
        joint = [joint[0] + l * c, joint[1] + l * s];
        joint_velocity = [joint_velocity[0] - l * s * w, joint_velocity[1] + l * c * w];
    }
    b.build()
}

/// An `n`-link chain of uniform slender bars (1 kg, 1 m, inertia `m l²/12`)
/// joined by revolute joints, the first hinged to the ground at the origin, all
/// links horizontal along `+x` at rest, gravity `−9.81 ŷ`. Bodies are named
/// `link1` … `linkN` from the ground outwards; joints `joint1` … `jointN`.
/// `n = 0` gives an empty system.
#[must_use]
pub fn bar_chain(n: usize) -> PlanarSystem {
    let bar = Bar {
        length: 1.0,
        mass: 1.0,
        angle: 0.0,
        rate: 0.0,
    };
    bar_chain_of(&vec![bar; n]).expect("the bar chain is valid by construction")
}

/// An `n`-link chain of 1 kg point masses on massless 1 m rods (distance
/// joints), the first rod from the ground at the origin, masses at `(k, 0)` at
/// rest, gravity `−9.81 ŷ`. Masses are named `link1` … `linkN`; rods `rod1` …
/// `rodN`.
#[must_use]
pub fn point_mass_chain(n: usize) -> PlanarSystem {
    let mut b = PlanarBuilder::new();
    let mut previous = At::Ground([0.0, 0.0]);
    for k in 1..=n {
        let point = PointMass {
            mass: 1.0,
            position: [k as f64, 0.0],
            velocity: [0.0; 2],
        };
        let body = b.point_mass(&format!("link{k}"), point);
        b.distance(
            &format!("rod{k}"),
            previous,
            At::Body(body, [0.0, 0.0]),
            1.0,
        );
        previous = At::Body(body, [0.0, 0.0]);
    }
    b.build()
        .expect("the point-mass chain is valid by construction")
}
