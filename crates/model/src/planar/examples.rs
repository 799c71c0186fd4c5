//! One small model per registered element kind and anchor combination, for
//! tests that must cover every element without a hand-kept list (the
//! derivative checks of `mstar_linearize`).

use super::builder::{PlanarBuilder, PointMass, RigidBody};
use super::{At, BodyId, Coordinate, PlanarSystem, joints, loads};

/// The kinds of anchor an element can join.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Side {
    Ground,
    Rigid,
    Point,
}

const SIDES: [Side; 3] = [Side::Ground, Side::Rigid, Side::Point];

/// Every registered joint, driver and load between every pair of anchor
/// kinds it accepts, each in a model of its own: `(description, model)`.
/// `p` (at least 24 values in `[-1, 1)`) places the bodies and sets the
/// elements' parameters.
///
/// # Panics
/// If `p` has fewer than 24 values.
#[must_use]
pub fn element_examples(p: &[f64]) -> Vec<(String, PlanarSystem)> {
    assert!(p.len() >= 24, "element_examples needs 24 parameters");
    let mut out = Vec::new();
    for kind in joints::KINDS.iter().filter(|k| k.name != "driver") {
        for (a, b) in pairs() {
            let mut builder = PlanarBuilder::new();
            let at = [
                place(&mut builder, a, &p[0..6], 0),
                place(&mut builder, b, &p[6..12], 1),
            ];
            builder.joint_element("element", (kind.example)(&p[12..]), at[0], at[1]);
            push(&mut out, format!("{} {a:?}–{b:?}", kind.name), &builder);
        }
    }
    for (side, coordinate) in [
        (Side::Rigid, Coordinate::X),
        (Side::Rigid, Coordinate::Theta),
        (Side::Point, Coordinate::Y),
    ] {
        let mut builder = PlanarBuilder::new();
        let body = body(&mut builder, side, &p[0..6], 0);
        builder.driver("element", body, coordinate, driver_function(&p[12..]));
        push(
            &mut out,
            format!("driver {side:?} {coordinate:?}"),
            &builder,
        );
    }
    for kind in loads::KINDS {
        for (a, b) in pairs() {
            if (!kind.two_sided && b != Side::Ground) || a == Side::Ground {
                continue;
            }
            let mut builder = PlanarBuilder::new();
            let at = [
                place(&mut builder, a, &p[0..6], 0),
                place(&mut builder, b, &p[6..12], 1),
            ];
            builder.load_element("element", (kind.example)(&p[12..]), at[0], at[1]);
            push(&mut out, format!("{} {a:?}–{b:?}", kind.name), &builder);
        }
    }
    out
}

/// The pairs of anchor kinds, not both the ground.
fn pairs() -> impl Iterator<Item = (Side, Side)> {
    SIDES
        .iter()
        .flat_map(|&a| SIDES.iter().map(move |&b| (a, b)))
        .filter(|&(a, b)| !(a == Side::Ground && b == Side::Ground))
}

/// Adds the model if its elements accept their anchors (kinds that refuse a
/// combination, e.g. a torque on a point mass, are skipped).
fn push(out: &mut Vec<(String, PlanarSystem)>, what: String, builder: &PlanarBuilder) {
    if let Ok(sys) = builder.build() {
        out.push((what, sys));
    }
}

/// A body of the given kind (or the ground) with an attachment point.
fn place(b: &mut PlanarBuilder, side: Side, p: &[f64], k: usize) -> At {
    match side {
        Side::Ground => At::Ground([p[0], p[1]]),
        Side::Rigid => At::Body(body(b, side, p, k), [0.3 + 0.2 * p[3], p[4]]),
        Side::Point => At::Body(body(b, side, p, k), [0.0, 0.0]),
    }
}

fn body(b: &mut PlanarBuilder, side: Side, p: &[f64], k: usize) -> BodyId {
    let name = format!("body{k}");
    match side {
        Side::Point => b.point_mass(
            &name,
            PointMass {
                mass: 1.0 + 0.5 * p[5],
                position: [p[0] + k as f64, p[1]],
                velocity: [0.0; 2],
            },
        ),
        _ => b.rigid_body(
            &name,
            RigidBody {
                mass: 1.0 + 0.5 * p[5],
                inertia: 0.2 + 0.1 * p[3],
                pose: [p[0] + k as f64, p[1], 2.0 * p[2]],
                velocity: [0.0; 3],
            },
        ),
    }
}

fn driver_function(p: &[f64]) -> super::TimeFunction {
    super::TimeFunction::Sine {
        offset: p[0],
        amplitude: 0.5,
        omega: 2.0,
        phase: p[1],
    }
}

#[cfg(test)]
mod tests {
    use super::{element_examples, joints, loads};

    #[test]
    fn every_registered_kind_has_an_example() {
        let p: Vec<f64> = (0..24).map(|i| 0.37 * f64::from(i) % 1.0 - 0.5).collect();
        let examples = element_examples(&p);
        let names = joints::KINDS.iter().map(|k| k.name);
        for name in names.chain(loads::KINDS.iter().map(|k| k.name)) {
            let count = examples
                .iter()
                .filter(|(what, _)| what.starts_with(&format!("{name} ")))
                .count();
            assert!(count > 0, "no example of '{name}'");
        }
        // Joints join any two anchors but two grounds: 8 pairs each.
        let revolutes = examples
            .iter()
            .filter(|(w, _)| w.starts_with("revolute "))
            .count();
        assert_eq!(revolutes, 8);
    }
}
