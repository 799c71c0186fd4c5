//! One small model per spatial element and pair of attachments, for the
//! finite-difference check of every element's derivatives (the tests of
//! `mstar-linearize` run them all).

use super::builder::{
    Attach, Axes, DriverKind, JointSpec, JointType, RotationalMass, RotationalSpringDamper,
    SpatialBuilder, SpringDamper,
};
use super::{SpatialBody, SpatialInertia, SpatialPointMass, SpatialSystem, euler_parameters};
use crate::planar::TimeFunction;

/// Every joint, driver and load of the spatial layer between two rigid
/// bodies, the ground and a rigid body, and (where it takes points only) a
/// rigid body and a point mass; with singular and regularized rotational
/// mass. `params` (at least 24 values in `[−1, 1]`) set the geometry.
#[must_use]
pub fn element_examples(params: &[f64]) -> Vec<(String, SpatialSystem)> {
    let p = |k: usize| params.get(k).copied().unwrap_or(0.3);
    let v3 = |k: usize| [p(k), p(k + 1), p(k + 2)];
    let mut out = Vec::new();
    for mode in [RotationalMass::Singular, RotationalMass::Regularized] {
        for pair in 0..3 {
            let add = |what: &str, f: &dyn Fn(&mut SpatialBuilder, [Attach; 2])| {
                let mut b = SpatialBuilder::new();
                b.rotational_mass(mode).unchecked_axes();
                let a = b.body("a", body(&v3(0), p(3), 0.0));
                let second = match pair {
                    0 => Attach::Body(b.body("b", body(&v3(4), p(7), 1.0))),
                    1 => Attach::Ground,
                    _ => Attach::Body(b.point_mass(
                        "b",
                        SpatialPointMass {
                            mass: 1.5,
                            position: v3(4),
                            velocity: v3(8),
                        },
                    )),
                };
                let at = if pair == 1 {
                    [second, Attach::Body(a)]
                } else {
                    [Attach::Body(a), second]
                };
                f(&mut b, at);
                match b.build() {
                    Ok(s) => Some((format!("{what} ({mode:?}, pair {pair})"), s)),
                    Err(e) => {
                        eprintln!("{what} {pair}: {e}");
                        None
                    }
                }
            };
            // A point mass attaches at its own position.
            let points = [v3(12), if pair == 2 { [0.0; 3] } else { v3(15) }];
            // Axes away from zero (a zero axis is an error).
            let axes = [v3(18), v3(21)].map(|a| [a[0] + 1.5, a[1], a[2]]);
            for kind in JointType::ALL {
                if pair == 2 && (kind.uses_axes() || kind == JointType::Weld) {
                    continue;
                }
                let spec = |bodies| JointSpec {
                    kind,
                    bodies,
                    points,
                    axes,
                    length: None,
                };
                out.extend(add(kind.name(), &|b, at| _ = b.joint("j", spec(at))));
                let drivers: &[DriverKind] = match kind {
                    JointType::Revolute => &[DriverKind::Angle],
                    JointType::Prismatic => &[DriverKind::Translation],
                    JointType::Cylindrical => &[DriverKind::Angle, DriverKind::Translation],
                    _ => &[],
                };
                for &d in drivers {
                    let f = TimeFunction::Sine {
                        offset: 0.1,
                        amplitude: 0.4,
                        omega: 2.0,
                        phase: p(9),
                    };
                    out.extend(add(&format!("{} {d:?} driver", kind.name()), &|b, at| {
                        b.joint("j", spec(at)).driver("d", "j", d, f.clone());
                    }));
                }
            }
            let spring = SpringDamper {
                stiffness: 30.0,
                damping: 0.7,
                rest_length: Some(0.4),
                preload: 2.0,
            };
            out.extend(add("spring", &|b, at| {
                _ = b.spring("s", at, points, spring)
            }));
            if pair != 2 {
                out.extend(add("rotational spring", &|b, at| {
                    let spring = RotationalSpringDamper {
                        stiffness: 5.0,
                        damping: 0.3,
                        angle: 0.2,
                    };
                    _ = b.rotational_spring("r", at, axes, spring);
                }));
            }
            let f = || {
                [
                    TimeFunction::Constant(1.0),
                    TimeFunction::Linear {
                        value: 0.5,
                        rate: -1.0,
                    },
                    TimeFunction::Constant(-2.0),
                ]
            };
            for axes in [Axes::Global, Axes::Body] {
                out.extend(add("force", &|b, _| {
                    _ = b.force("f", super::SpatialBodyId(0), v3(12), f(), axes);
                }));
                out.extend(add("torque", &|b, _| {
                    _ = b.torque("n", super::SpatialBodyId(0), f(), axes);
                }));
            }
        }
    }
    out
}

fn body(position: &[f64; 3], angle: f64, spin: f64) -> SpatialBody {
    SpatialBody {
        mass: 2.0,
        inertia: SpatialInertia::Matrix([
            [0.3, 0.02, -0.01],
            [0.02, 0.4, 0.03],
            [-0.01, 0.03, 0.5],
        ]),
        position: *position,
        orientation: euler_parameters([0.3, -0.5, 0.8], 1.0 + angle),
        velocity: [0.1, -0.2, 0.3],
        angular_velocity: [1.0, spin, -0.5],
    }
}
