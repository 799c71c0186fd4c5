//! Spatial rigid bodies in Euler parameters through the whole DAE path
//! (linearization, KKT, generalized-α) against the index-1 RK4 reference
//! (`mstar_rk4::Index1Rk4`, which shares no code with that path): second
//! order in positions, velocities and joint multipliers; the singular and the
//! regularized rotational mass give the same motion.

use mstar::model::spatial::{
    Attach, JointSpec, JointType, RotationalMass, SpatialBody, SpatialBuilder, SpatialInertia,
    SpatialSystem, euler_parameters,
};
use mstar::rk4::Index1Rk4;
use mstar::{Config, Integrator, SampleRef, System};

/// Two bars (1 kg and 0.8 kg) on spherical joints, the first along +x from
/// the ground at the origin, the second along +y from its end, at rest under
/// gravity −z, the lower one spinning about its own axis at 3 rad/s: the
/// motion is fully three-dimensional.
fn double_pendulum(mode: RotationalMass) -> SpatialSystem {
    let mut b = SpatialBuilder::new();
    b.rotational_mass(mode);
    let bar = |mass: f64, position, orientation, spin| SpatialBody {
        mass,
        inertia: SpatialInertia::Principal([1e-3 * mass, mass / 12.0, mass / 12.0]),
        position,
        orientation,
        velocity: [0.0; 3],
        angular_velocity: spin,
    };
    let first = b.body(
        "upper",
        bar(1.0, [0.5, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0], [0.0; 3]),
    );
    let quarter = euler_parameters([0.0, 0.0, 1.0], std::f64::consts::FRAC_PI_2);
    let second = b.body("lower", bar(0.8, [1.0, 0.5, 0.0], quarter, [0.0, 3.0, 0.0]));
    let joint = |bodies, points| JointSpec {
        kind: JointType::Spherical,
        bodies,
        points,
        axes: [[0.0, 0.0, 1.0]; 2],
        length: None,
    };
    b.joint(
        "base",
        joint(
            [Attach::Ground, Attach::Body(first)],
            [[0.0; 3], [-0.5, 0.0, 0.0]],
        ),
    );
    b.joint(
        "elbow",
        joint(
            [Attach::Body(first), Attach::Body(second)],
            [[0.5, 0.0, 0.0], [-0.5, 0.0, 0.0]],
        ),
    );
    b.build().expect("a valid model")
}

/// `(u, v, λ)` at `t_end` from generalized-α with step `h`.
fn dae(sys: &SpatialSystem, h: f64, t_end: f64) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let config = Config {
        h,
        tol: 1e-12,
        ..Config::default()
    };
    let (u0, v0) = (sys.initial_position(), sys.initial_velocity());
    let mut integ = Integrator::new(sys, config, 0.0, &u0, &v0).expect("start");
    let mut last = None;
    integ
        .run(t_end, &mut |s: &SampleRef<'_>| {
            last = Some((s.u.to_vec(), s.v.to_vec(), s.lambda.to_vec()));
        })
        .expect("integration");
    last.expect("samples")
}

fn max_diff(a: &[f64], b: &[f64], keep: impl Fn(usize) -> bool) -> f64 {
    a.iter()
        .zip(b)
        .enumerate()
        .filter(|(i, _)| keep(*i))
        .map(|(_, (x, y))| (x - y).abs())
        .fold(0.0, f64::max)
}

#[test]
fn the_spatial_double_pendulum_converges_at_second_order_to_the_index1_reference() {
    let sys = double_pendulum(RotationalMass::Singular);
    let t_end = 0.5;
    let oracle = Index1Rk4::new(&sys);
    let reference = oracle
        .solve(&sys.initial_position(), &sys.initial_velocity(), &[t_end])
        .expect("reference");
    let (u_ref, v_ref) = &reference[0];
    let lambda_ref = oracle
        .multipliers(t_end, u_ref, v_ref)
        .expect("a regular KKT matrix");
    // Joint rows only: the normalization multipliers depend on how the
    // singular direction of M is filled.
    let joints = |i: usize| !sys.constraint_name(i).ends_with(".norm");
    let errors = |h: f64| {
        let (u, v, lambda) = dae(&sys, h, t_end);
        [
            max_diff(&u, u_ref, |_| true),
            max_diff(&v, v_ref, |_| true),
            max_diff(&lambda, &lambda_ref, joints),
        ]
    };
    let (coarse, fine) = (errors(1e-3), errors(5e-4));
    for (k, what) in ["positions", "velocities", "multipliers"]
        .iter()
        .enumerate()
    {
        let order = (coarse[k] / fine[k]).log2();
        assert!(
            (order - 2.0).abs() <= 0.1,
            "{what}: error {:.3e} at h = 1e-3, {:.3e} at 5e-4, order {order:.3}",
            coarse[k],
            fine[k]
        );
    }
}

#[test]
fn singular_and_regularized_rotational_mass_give_the_same_motion() {
    let t_end = 0.3;
    let a = dae(&double_pendulum(RotationalMass::Singular), 1e-3, t_end);
    let sys = double_pendulum(RotationalMass::Regularized);
    let b = dae(&sys, 1e-3, t_end);
    let joints = |i: usize| !sys.constraint_name(i).ends_with(".norm");
    // Both solve the same discrete equations to the Newton tolerance 1e-12
    // (scaled): the trajectories agree to round-off, far below the step's
    // own error (about 1e-6 here).
    assert!(max_diff(&a.0, &b.0, |_| true) < 1e-10, "u");
    assert!(max_diff(&a.1, &b.1, |_| true) < 1e-8, "v");
    assert!(max_diff(&a.2, &b.2, joints) < 1e-7, "λ");
}
