//! The planar builder refuses what it cannot honour: a body handle from
//! another builder, and loads on angles (a torque, a rotational spring) of a
//! point mass, which has no angle to act on. Each is an error naming the
//! element and the body, never a silently ignored call.

use mstar_model::planar::{
    At, PlanarBuilder, PointMass, RigidBody, RotationalSpringDamper, TimeFunction,
};

fn bar() -> RigidBody {
    RigidBody {
        mass: 1.0,
        inertia: 1.0 / 12.0,
        pose: [0.5, 0.0, 0.0],
        velocity: [0.0; 3],
    }
}

fn bead() -> PointMass {
    PointMass {
        mass: 1.0,
        position: [1.0, 0.0],
        velocity: [0.0; 2],
    }
}

/// A model that builds on its own: a bar hinged to the ground.
fn hinged_bar(b: &mut PlanarBuilder) {
    let bar = b.rigid_body("bar", bar());
    b.revolute("hinge", At::Ground([0.0, 0.0]), At::Body(bar, [-0.5, 0.0]));
}

#[test]
fn a_velocity_for_another_builders_body_is_an_error() {
    let mut other = PlanarBuilder::new();
    let foreign = other.rigid_body("elsewhere", bar());
    let mut b = PlanarBuilder::new();
    hinged_bar(&mut b);
    assert!(b.build().is_ok(), "the model alone builds");
    b.velocity(foreign, [0.0, 1.0, 2.0]);
    let e = b.build().err().map(|e| e.to_string()).unwrap_or_default();
    assert!(e.contains("another PlanarBuilder"), "{e:?}");
    assert!(e.contains("velocity"), "{e:?}");
}

#[test]
fn a_velocity_for_an_own_body_is_kept() {
    let mut b = PlanarBuilder::new();
    let bar = b.rigid_body("bar", bar());
    b.revolute("hinge", At::Ground([0.0, 0.0]), At::Body(bar, [-0.5, 0.0]));
    b.velocity(bar, [0.0, 1.0, 2.0]);
    let sys = b.build().map_err(|e| e.to_string());
    assert_eq!(
        sys.map(|s| s.initial_velocity()),
        Ok(vec![0.0, 1.0, 2.0]),
        "the velocity given for the builder's own body"
    );
}

#[test]
fn a_torque_on_a_point_mass_is_an_error_naming_it() {
    let mut b = PlanarBuilder::new();
    hinged_bar(&mut b);
    let slider = b.point_mass("slider", bead());
    b.torque("motor-torque", slider, TimeFunction::Constant(1.0));
    let e = b.build().err().map(|e| e.to_string()).unwrap_or_default();
    assert!(e.starts_with("motor-torque:"), "names the element: {e:?}");
    assert!(
        e.contains("'slider' is a point mass"),
        "names the body: {e:?}"
    );
}

#[test]
fn a_rotational_spring_on_a_point_mass_is_an_error_naming_it() {
    let spring = RotationalSpringDamper {
        stiffness: 10.0,
        damping: 0.0,
    };
    let mut b = PlanarBuilder::new();
    hinged_bar(&mut b);
    let slider = b.point_mass("slider", bead());
    b.rotational_spring("coil", None, slider, spring);
    let e = b.build().err().map(|e| e.to_string()).unwrap_or_default();
    assert!(e.starts_with("coil:"), "names the element: {e:?}");
    assert!(
        e.contains("'slider' is a point mass"),
        "names the body: {e:?}"
    );
    // On a rigid body the same spring is accepted.
    let mut b = PlanarBuilder::new();
    let bar = b.rigid_body("bar", bar());
    b.revolute("hinge", At::Ground([0.0, 0.0]), At::Body(bar, [-0.5, 0.0]));
    b.rotational_spring("coil", None, bar, spring);
    assert!(b.build().is_ok());
}

/// A spatial joint's axes are checked at the initial pose as a model file's
/// are: a revolute joint whose two axes are not parallel there (a bar
/// rotated 90° about z, the same local axis on both sides) and a universal
/// joint whose cross axes are not perpendicular are refused, naming the
/// joint; parallel (and opposite) and perpendicular axes are taken.
#[test]
fn spatial_joint_axes_are_checked_at_the_initial_pose() {
    use mstar_model::spatial::{
        Attach, JointSpec, JointType, SpatialBody, SpatialBuilder, SpatialInertia,
    };
    let build = |kind: JointType, axes: [[f64; 3]; 2], turned: bool| {
        let mut b = SpatialBuilder::new();
        let (s, c) = (
            std::f64::consts::FRAC_PI_4.sin(),
            std::f64::consts::FRAC_PI_4.cos(),
        );
        let bar = b.body(
            "bar",
            SpatialBody {
                mass: 1.0,
                inertia: SpatialInertia::Principal([0.08, 0.08, 0.002]),
                position: [0.0, 0.0, -0.5],
                // 90° about z when `turned`.
                orientation: if turned {
                    [c, 0.0, 0.0, s]
                } else {
                    [1.0, 0.0, 0.0, 0.0]
                },
                velocity: [0.0; 3],
                angular_velocity: [0.0; 3],
            },
        );
        b.joint(
            "h",
            JointSpec {
                kind,
                bodies: [Attach::Ground, Attach::Body(bar)],
                points: [[0.0; 3], [0.0, 0.0, 0.5]],
                axes,
                length: None,
            },
        );
        b.build().map(|_| ()).map_err(|e| e.to_string())
    };
    let x = [1.0, 0.0, 0.0];
    assert_eq!(build(JointType::Revolute, [x, x], false), Ok(()));
    assert_eq!(
        build(JointType::Revolute, [x, [-1.0, 0.0, 0.0]], false),
        Ok(())
    );
    // Turned 90° about z, the bar's local x is the global y.
    assert_eq!(
        build(JointType::Revolute, [[0.0, 1.0, 0.0], x], true),
        Ok(())
    );
    let e = build(JointType::Revolute, [x, x], true).expect_err("not parallel");
    assert!(
        e.contains("h") && e.contains("must be parallel at the initial pose"),
        "{e}"
    );
    let y = [0.0, 1.0, 0.0];
    assert_eq!(build(JointType::Universal, [x, y], false), Ok(()));
    let e =
        build(JointType::Universal, [x, [0.1, 1.0, 0.0]], false).expect_err("not perpendicular");
    assert!(
        e.contains("must be perpendicular at the initial pose"),
        "{e}"
    );
}
