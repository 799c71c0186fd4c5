//! The initial sensitivities `S₀` (`Integrator::sensitivities`, through
//! the start's own linear systems) against central differences of whole
//! starts (`Integrator::new` at `p ± δ`, `p ± 2δ`, extrapolated), which
//! share nothing with them but the start itself: a planar slider-crank
//! (a mass, a length that moves the given pose off the constraints, a
//! constant torque) and a spatial chain of spinning bars (a mass, an axial
//! inertia, the spin rate that sets the given velocities).

mod common;

use common::{Model, Param};
use mstar_kkt::{Backend, KktOptions};
use mstar_model::planar::{
    At, BodyId, PlanarBuilder, PointMass, RigidBody, SpringDamper, TimeFunction,
};
use mstar_model::spatial::{
    Attach, JointSpec, JointType, SpatialBody, SpatialBuilder, SpatialInertia,
};
use mstar_newmark::{Config, Integrator, Newton, Parameterized, Scheme};

/// A slider-crank under gravity, its crank of mass `mass` given an angular
/// velocity `spin` (everything else at rest), the coupler `length` long
/// (the pose is laid out for 1.5 m, so any other length moves the given
/// positions off the constraints and the start projects them): the
/// builder and the crank's and coupler's ids.
fn slider_crank_parts(mass: f64, length: f64, spin: f64) -> (PlanarBuilder, [BodyId; 2]) {
    let (r, l, theta) = (0.5, 1.5, 0.3_f64);
    let (ax, ay) = (r * theta.cos(), r * theta.sin());
    let bx = ax + (l * l - ay * ay).sqrt();
    let phi = (-ay).atan2(bx - ax);
    let mut b = PlanarBuilder::new();
    b.gravity(0.0, -9.81);
    let body = |mass: f64, length: f64, pose, spin| RigidBody {
        mass,
        inertia: mass * length * length / 12.0,
        pose,
        velocity: [0.0, 0.0, spin],
    };
    let crank = b.rigid_body("crank", body(mass, r, [0.5 * ax, 0.5 * ay, theta], spin));
    let coupler_pose = [0.5 * (ax + bx), 0.5 * ay, phi];
    let coupler = b.rigid_body("coupler", body(1.2, l, coupler_pose, 0.0));
    let slider = b.point_mass(
        "slider",
        PointMass {
            mass: 0.8,
            position: [bx, 0.0],
            velocity: [0.0; 2],
        },
    );
    b.revolute(
        "hinge",
        At::Ground([0.0, 0.0]),
        At::Body(crank, [-0.5 * r, 0.0]),
    );
    let pin = [
        At::Body(crank, [0.5 * r, 0.0]),
        At::Body(coupler, [-0.5 * length, 0.0]),
    ];
    b.revolute("pin", pin[0], pin[1]);
    let wrist = [
        At::Body(coupler, [0.5 * length, 0.0]),
        At::Body(slider, [0.0; 2]),
    ];
    b.revolute("wrist", wrist[0], wrist[1]);
    b.prismatic(
        "rail",
        At::Ground([0.0, 0.0]),
        [1.0, 0.0],
        At::Body(slider, [0.0; 2]),
    );
    (b, [crank, coupler])
}

/// The model `b` builds, with its initial state.
fn model_of(b: &PlanarBuilder) -> Model {
    let sys = b.build().expect("a valid slider-crank");
    let (u0, v0) = (sys.initial_position(), sys.initial_velocity());
    Model {
        sys: Box::new(sys),
        u0,
        v0,
    }
}

/// [`slider_crank_parts`] at rest, driven by a torque `p[2]`, with a
/// spring to the coupler; `p[0]` the crank mass, `p[1]` the coupler length.
fn slider_crank(p: &[f64]) -> Model {
    let (mut b, [crank, coupler]) = slider_crank_parts(p[0], p[1], 0.0);
    b.torque("motor", crank, TimeFunction::Constant(p[2]));
    let spring = SpringDamper {
        stiffness: 40.0,
        damping: 0.0,
        rest_length: 1.0,
    };
    b.spring(
        "buffer",
        At::Ground([1.5, 1.0]),
        At::Body(coupler, [0.3, 0.0]),
        spring,
    );
    model_of(&b)
}

/// [`slider_crank_parts`] with its crank given the angular velocity `p[2]`
/// and everything else at rest: inconsistent velocities, which the start's
/// projection moves (the mechanism keeps one degree of freedom, so the
/// projection's direction matters), and the coupler length `p[1]` turns
/// that direction with `B`.
fn spun_slider_crank(p: &[f64]) -> Model {
    model_of(&slider_crank_parts(p[0], p[1], p[2]).0)
}

/// Three bars (1 m, the first of mass `p[0]`, axial inertia `p[1]`) on
/// spherical joints along +x, spinning about their axes at `p[2]` rad/s
/// (consistent with the joints at every rate) and falling under gravity.
fn spinning_chain(p: &[f64]) -> Model {
    let mut b = SpatialBuilder::new();
    b.gravity([0.0, 0.0, -9.81]);
    let mut previous = Attach::Ground;
    for k in 0..3 {
        let id = b.body(
            &format!("bar{}", k + 1),
            SpatialBody {
                mass: if k == 0 { p[0] } else { 1.0 },
                inertia: SpatialInertia::Principal([p[1], 0.085, 0.083]),
                position: [k as f64 + 0.5, 0.0, 0.0],
                orientation: [1.0, 0.0, 0.0, 0.0],
                velocity: [0.0; 3],
                angular_velocity: [p[2], 0.0, 0.0],
            },
        );
        let first = if k == 0 { [0.0; 3] } else { [0.5, 0.0, 0.0] };
        b.joint(
            &format!("joint{}", k + 1),
            JointSpec {
                kind: JointType::Spherical,
                bodies: [previous, Attach::Body(id)],
                points: [first, [-0.5, 0.0, 0.0]],
                axes: [[0.0, 0.0, 1.0]; 2],
                length: None,
            },
        );
        previous = Attach::Body(id);
    }
    let sys = b.build().expect("a valid spatial chain");
    let (u0, v0) = (sys.initial_position(), sys.initial_velocity());
    Model {
        sys: Box::new(sys),
        u0,
        v0,
    }
}

fn config(corrected_start: bool) -> Config {
    Config {
        h: 0.01,
        tol: 1e-12,
        newton: Newton::Full,
        scheme: Scheme::GeneralizedAlpha { rho_inf: 0.8 },
        corrected_start,
        ..Config::default()
    }
}

/// The start's `[u; u̇; ü; λ]` of `make` at `p`.
fn start(make: fn(&[f64]) -> Model, p: &[f64], config: &Config) -> Vec<f64> {
    let model = make(p);
    let integ = Integrator::new(
        model.sys.as_ref(),
        config.clone(),
        0.0,
        &model.u0,
        &model.v0,
    )
    .expect("the model starts");
    let s = integ.view();
    [s.u, s.v, s.a, s.lambda].concat()
}

/// Checks `S₀` of parameter `k` of `make` at `nominal` against whole
/// starts at `p ± δ`, `p ± 2δ` (δ = 1e-3 relative): `D₁`, `D₂` err by
/// `c δ²`, `4c δ²`, so `R = (4D₁ − D₂)/3` and `|D₁ − D₂|/3` bounds `D₁`'s
/// error. The starts' own errors (the projection's tolerance `1e-15`, the
/// solves' round-off, about `1e-14` of each part's largest value) enter
/// `R` as at most `1e-13` of that value over `δ` (ten times over); `S₀`'s
/// central differences (about `1e-10` relative, `DIFFERENCE_STEP³` and
/// round-off over it) stay below `1e-8` of each part's largest entry.
fn check(make: fn(&[f64]) -> Model, nominal: &[f64], k: usize, config: &Config) {
    let model = make(nominal);
    let integ = Integrator::new(
        model.sys.as_ref(),
        config.clone(),
        0.0,
        &model.u0,
        &model.v0,
    )
    .expect("the model starts");
    let param = Param {
        make,
        nominal: nominal.to_vec(),
        k,
    };
    let params: [&dyn Parameterized; 1] = [&param];
    let sens = integ
        .sensitivities(&params)
        .expect("the sensitivities start");
    let s0 = [sens.u(0), sens.v(0), sens.a(0), sens.lambda(0)].concat();
    let delta = 1e-3 * nominal[k].abs();
    let at = |c: f64| {
        let mut p = nominal.to_vec();
        p[k] += c * delta;
        start(make, &p, config)
    };
    let (p1, m1, p2, m2) = (at(1.0), at(-1.0), at(2.0), at(-2.0));
    let n = sens.u(0).len();
    let parts = [0..n, n..2 * n, 2 * n..3 * n, 3 * n..s0.len()];
    let nominal_start = start(make, nominal, config);
    let largest = |v: &[f64]| v.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    for (part, name) in parts.into_iter().zip(["u", "v", "a", "lambda"]) {
        let size = largest(&s0[part.clone()]);
        let rounding = 1e-13 * largest(&nominal_start[part.clone()]) / delta;
        for i in part {
            let d1 = (p1[i] - m1[i]) / (2.0 * delta);
            let d2 = (p2[i] - m2[i]) / (4.0 * delta);
            let r = (4.0 * d1 - d2) / 3.0;
            let bound = (d1 - d2).abs() / 3.0 + 1e-8 * size.max(1e-3) + rounding;
            let error = (s0[i] - r).abs();
            assert!(
                error <= bound,
                "parameter {k}, {name}[{i}]: S₀ {} against {r} (error {error:e} > {bound:e})",
                s0[i]
            );
        }
        assert!(size.is_finite(), "parameter {k}: {name} is not finite");
    }
}

/// [`check`] for every parameter of `make` at `nominal`.
fn check_each(make: fn(&[f64]) -> Model, nominal: &[f64], config: &Config) {
    for k in 0..nominal.len() {
        check(make, nominal, k, config);
    }
}

#[test]
fn slider_crank_initial_sensitivities_match_extrapolated_starts() {
    let nominal = [1.0, 1.5, 3.0];
    for corrected in [true, false] {
        check_each(slider_crank, &nominal, &config(corrected));
    }
}

/// The same with the sparse LU, whose KKT structure carries `BᵀB` (the
/// stages' right-hand sides augmented as the start's are).
#[test]
fn on_the_augmented_structure_the_sensitivities_match_extrapolated_starts() {
    let config = Config {
        kkt: KktOptions {
            backend: Backend::SPARSE_LU,
            ..KktOptions::default()
        },
        ..config(true)
    };
    check_each(slider_crank, &[1.0, 1.5, 3.0], &config);
    check_each(spun_slider_crank, &[1.0, 1.5, 4.0], &config);
}

#[test]
fn spun_slider_crank_moved_velocities_match_extrapolated_starts() {
    let nominal = [1.0, 1.5, 4.0];
    check_each(spun_slider_crank, &nominal, &config(true));
}

/// Given positions off the constraints (laid out for a coupler of 1.5 m,
/// the nominal one 1.52 m): the start projects them, and the initial
/// sensitivities are central differences of whole starts, which the
/// extrapolated starts check as well.
#[test]
fn moved_positions_match_extrapolated_starts() {
    let nominal = [1.0, 1.52, 3.0];
    check_each(slider_crank, &nominal, &config(true));
}

#[test]
fn spinning_chain_initial_sensitivities_match_extrapolated_starts() {
    let nominal = [1.0, 0.05, 5.0];
    check_each(spinning_chain, &nominal, &config(true));
}

/// A length that moves the given pose: `S₀` satisfies the differentiated
/// constraints `B δu₀ + Φ_p = 0` (here checked as `δu₀` nonzero in the
/// slider's x, which only the projection moves).
#[test]
fn a_length_moves_the_projected_pose() {
    let nominal = [1.0, 1.5, 3.0];
    let model = slider_crank(&nominal);
    let integ = Integrator::new(model.sys.as_ref(), config(true), 0.0, &model.u0, &model.v0)
        .expect("the model starts");
    let param = Param {
        make: slider_crank,
        nominal: nominal.to_vec(),
        k: 1,
    };
    let params: [&dyn Parameterized; 1] = [&param];
    let sens = integ
        .sensitivities(&params)
        .expect("the sensitivities start");
    let moved = sens.u(0).iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    assert!(moved > 0.1, "δu₀ of the coupler length: {moved}");
}
