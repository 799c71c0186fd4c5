//! The adjoint gradient's transposed solves with each KKT backend
//! (`Integrator::gradient` factors `Aᵀ` with the forward run's backend):
//! against the forward sensitivities' `Σ w_nᵀ S_n` made with the same
//! backend, on a planar slider-crank and a spatial chain of bodies in Euler
//! parameters, each with a symmetric and an unsymmetric iteration matrix;
//! and the fallback to the sparse LU when the backend refuses `Aᵀ`'s pattern.

mod common;

use common::{Model, Param, column_of};
use mstar_kkt::{Backend, Csc, KktBackend, KktError, KktOptions, Registration, Structure};
use mstar_model::planar::{
    At, PlanarBuilder, PointMass, RigidBody, RotationalSpringDamper, SpringDamper, TimeFunction,
};
use mstar_model::spatial::{
    Attach, JointSpec, JointType, SpatialBody, SpatialBuilder, SpatialInertia, SpatialSystem,
};
use mstar_model::{Pattern, System};
use mstar_newmark::{Column, Config, Integrator, Memory, Newton, Objective, Parameterized, Scheme};

/// A slider-crank driven by a constant torque, with a spring from a point
/// above the mechanism to the coupler and a rotational damper at the crank.
/// `p` = crank mass, coupler mass, spring stiffness, spring damping: the
/// spring's damping makes `∂g/∂u` and so `J` unsymmetric, in both directions
/// of the plane; without it `J` is symmetric (the rotational damper's `C_T`
/// is diagonal). Every body interacts with the others through joints
/// only, so `S` is block-diagonal and the Schur backends take it.
fn slider_crank(p: &[f64]) -> Model {
    let (r, l, theta) = (0.5, 1.5, 0.3_f64);
    let (ax, ay) = (r * theta.cos(), r * theta.sin());
    let bx = ax + (l * l - ay * ay).sqrt();
    let phi = (-ay).atan2(bx - ax);
    let mut b = PlanarBuilder::new();
    b.gravity(0.0, -9.81);
    let body = |mass: f64, length: f64, pose| RigidBody {
        mass,
        inertia: mass * length * length / 12.0,
        pose,
        velocity: [0.0; 3],
    };
    let crank = b.rigid_body("crank", body(p[0], r, [0.5 * ax, 0.5 * ay, theta]));
    let coupler = b.rigid_body("coupler", body(p[1], l, [0.5 * (ax + bx), 0.5 * ay, phi]));
    let slider = b.point_mass(
        "slider",
        PointMass {
            mass: 0.8,
            position: [bx, 0.0],
            velocity: [0.0; 2],
        },
    );
    let hinge = At::Body(crank, [-0.5 * r, 0.0]);
    b.revolute("hinge", At::Ground([0.0, 0.0]), hinge);
    let pin = [
        At::Body(crank, [0.5 * r, 0.0]),
        At::Body(coupler, [-0.5 * l, 0.0]),
    ];
    b.revolute("pin", pin[0], pin[1]);
    let wrist = [
        At::Body(coupler, [0.5 * l, 0.0]),
        At::Body(slider, [0.0; 2]),
    ];
    b.revolute("wrist", wrist[0], wrist[1]);
    let rail = At::Body(slider, [0.0; 2]);
    b.prismatic("rail", At::Ground([0.0, 0.0]), [1.0, 0.0], rail);
    b.torque("motor", crank, TimeFunction::Constant(3.0));
    let spring = SpringDamper {
        stiffness: p[2],
        damping: p[3],
        rest_length: 1.0,
    };
    let anchor = At::Ground([1.5, 1.0]);
    b.spring("buffer", anchor, At::Body(coupler, [0.3, 0.0]), spring);
    let damper = RotationalSpringDamper {
        stiffness: 0.0,
        damping: 0.4,
    };
    b.rotational_spring("bearing", None, crank, damper);
    let sys = b.build().expect("a valid slider-crank");
    let (u0, v0) = (sys.initial_position(), sys.initial_velocity());
    Model {
        sys: Box::new(sys),
        u0,
        v0,
    }
}

/// Three bars (1 m, masses `p[0..3]`, axial inertia `p[3]`) on spherical
/// joints, the first to the ground, along +x, spinning about their axes at
/// 5 rad/s and falling under gravity: the exact iteration matrix, whose
/// gyroscopic 4 × 4 blocks (Euler parameters) are not symmetric.
fn spatial_chain(p: &[f64]) -> SpatialSystem {
    let mut b = SpatialBuilder::new();
    b.gravity([0.0, 0.0, -9.81]);
    let mut previous = Attach::Ground;
    for k in 0..3 {
        let id = b.body(
            &format!("bar{}", k + 1),
            SpatialBody {
                mass: p[k],
                inertia: SpatialInertia::Principal([p[3], 0.085, 0.083]),
                position: [k as f64 + 0.5, 0.0, 0.0],
                orientation: [1.0, 0.0, 0.0, 0.0],
                velocity: [0.0; 3],
                angular_velocity: [5.0, 0.0, 0.0],
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
    b.build().expect("a valid spatial chain")
}

fn spatial_model(sys: SpatialSystem) -> Model {
    let (u0, v0) = (sys.initial_position(), sys.initial_velocity());
    Model {
        sys: Box::new(sys),
        u0,
        v0,
    }
}

/// [`spatial_chain`] with its exact, unsymmetric iteration matrix.
fn spatial_exact(p: &[f64]) -> Model {
    spatial_model(spatial_chain(p))
}

/// [`spatial_chain`] with the gyroscopic blocks symmetrized
/// (`SpatialSystem::with_symmetric_tangent`), for the symmetric backends.
fn spatial_symmetric(p: &[f64]) -> Model {
    spatial_model(spatial_chain(p).with_symmetric_tangent())
}

/// Parameter `k` of a model family `make` at the values `nominal`.
/// `∂Ψ/∂y_n` of sample `n` of `last` (the objectives' definitions written
/// out independently of the library; no fits here).
fn weight(objective: &Objective, n: usize, last: usize) -> f64 {
    match objective {
        Objective::Final(_) => f64::from(u8::from(n == last)),
        Objective::Sum(_) | Objective::Fit { .. } => 1.0,
    }
}

/// `Σ_n w_nᵀ S_n` from the forward sensitivities (the integrator's own
/// factorization of `J`), with the backend the run used.
fn forward_gradient(
    model: &Model,
    config: &Config,
    t_end: f64,
    params: &[&dyn Parameterized],
    objective: &Objective,
    steps: usize,
) -> (Vec<f64>, Backend) {
    let sys = model.sys.as_ref();
    let mut integ = Integrator::new(sys, config.clone(), 0.0, &model.u0, &model.v0)
        .expect("the integrator starts");
    let mut sens = integ
        .sensitivities(params)
        .expect("the sensitivities start");
    let c = objective.column();
    let mut grad = vec![0.0; params.len()];
    for n in 0..=steps {
        if n > 0 {
            integ
                .step_with(t_end, &mut sens)
                .expect("the step succeeds");
        }
        let w = weight(objective, n, steps);
        for (k, g) in grad.iter_mut().enumerate() {
            *g += w * column_of(sens.u(k), sens.v(k), sens.a(k), sens.lambda(k), c);
        }
    }
    assert!(integ.reached(t_end), "the forward run took {steps} steps");
    (grad, integ.backend())
}

/// Newmark-type settings with the KKT backend `backend`.
fn config(backend: Backend) -> Config {
    Config {
        h: 0.01,
        tol: 1e-12,
        newton: Newton::Full,
        scheme: Scheme::GeneralizedAlpha { rho_inf: 0.8 },
        kkt: KktOptions {
            backend,
            ..KktOptions::default()
        },
        ..Config::default()
    }
}

/// For each backend: the adjoint gradient of `objective` over a run to
/// `t_end` with respect to the parameters `varied` of `make` at `nominal`,
/// its transposed solves made by that backend, against the forward
/// sensitivities made by the same backend. Both recurrences solve with the
/// KKT matrix factored at each converged state, each solve backward stable
/// to about `ε κ` relative, below `1e-12` for these small scaled KKT
/// matrices; over `N` steps `N · 1e-12` relative to the largest entry.
fn check_backends(
    make: fn(&[f64]) -> Model,
    (nominal, varied): (&[f64], &[usize]),
    backends: &[Backend],
    objective: &Objective,
    t_end: f64,
) {
    let ps: Vec<Param> = varied
        .iter()
        .map(|&k| Param {
            make,
            nominal: nominal.to_vec(),
            k,
        })
        .collect();
    let refs: Vec<&dyn Parameterized> = ps.iter().map(|p| p as &dyn Parameterized).collect();
    let model = make(nominal);
    for &backend in backends {
        let config = config(backend);
        let sys = model.sys.as_ref();
        let mut integ = Integrator::new(sys, config.clone(), 0.0, &model.u0, &model.v0)
            .expect("the integrator starts");
        let g = integ
            .gradient(t_end, &refs, objective, Memory::Store)
            .expect("the gradient is computed");
        assert_eq!(g.backend, backend, "the backend of the transposed solves");
        let (f, forward) = forward_gradient(&model, &config, t_end, &refs, objective, g.steps);
        assert_eq!(forward, backend, "the backend of the forward run");
        let scale = f
            .iter()
            .chain(&g.values)
            .fold(0.0_f64, |a, b| a.max(b.abs()));
        let tolerance = g.steps as f64 * 1e-12 * scale.max(f64::MIN_POSITIVE);
        for (k, (a, f)) in g.values.iter().zip(&f).enumerate() {
            assert!(
                (a - f).abs() <= tolerance,
                "{backend}, {objective:?}, parameter {k}: adjoint {a} against forward {f} \
                 (tolerance {tolerance:.1e})"
            );
        }
    }
}

const EVERY_BACKEND: [Backend; 4] = [
    Backend::SPARSE_LU,
    Backend::SCHUR,
    Backend::SCHUR_LU,
    Backend::SPARSE_LDLT,
];

/// The backends that take an unsymmetric matrix.
const UNSYMMETRIC_BACKENDS: [Backend; 2] = [Backend::SPARSE_LU, Backend::SCHUR_LU];

#[test]
fn planar_symmetric_adjoint_matches_forward_with_every_backend() {
    let nominal = [2.0, 1.5, 30.0, 0.0];
    assert!(slider_crank(&nominal).sys.tangent_is_symmetric());
    // (A damping of 0 is not varied: the model refuses a negative one.)
    let varied = [0, 1, 2];
    for objective in [
        Objective::Final(Column::Position(6)),
        Objective::Sum(Column::Multiplier(0)),
    ] {
        check_backends(
            slider_crank,
            (&nominal, &varied),
            &EVERY_BACKEND,
            &objective,
            0.5,
        );
    }
}

#[test]
fn planar_damped_adjoint_matches_forward_with_unsymmetric_backends() {
    let nominal = [2.0, 1.5, 30.0, 4.0];
    assert!(!slider_crank(&nominal).sys.tangent_is_symmetric());
    for objective in [
        Objective::Final(Column::Velocity(2)),
        Objective::Sum(Column::Multiplier(3)),
    ] {
        check_backends(
            slider_crank,
            (&nominal, &[0, 1, 2, 3]),
            &UNSYMMETRIC_BACKENDS,
            &objective,
            0.5,
        );
    }
}

#[test]
fn spatial_exact_adjoint_matches_forward_with_unsymmetric_backends() {
    let nominal = [1.0, 1.2, 0.8, 0.004];
    assert!(!spatial_exact(&nominal).sys.tangent_is_symmetric());
    // Bar 3's z and its first Euler parameter's rate; joint 1's x reaction.
    for objective in [
        Objective::Final(Column::Position(16)),
        Objective::Sum(Column::Velocity(17)),
        Objective::Sum(Column::Multiplier(0)),
    ] {
        check_backends(
            spatial_exact,
            (&nominal, &[0, 1, 2, 3]),
            &UNSYMMETRIC_BACKENDS,
            &objective,
            0.3,
        );
    }
}

#[test]
fn spatial_symmetrized_adjoint_matches_forward_with_every_backend() {
    let nominal = [1.0, 1.2, 0.8, 0.004];
    assert!(spatial_symmetric(&nominal).sys.tangent_is_symmetric());
    for objective in [
        Objective::Final(Column::Position(16)),
        Objective::Sum(Column::Multiplier(0)),
    ] {
        check_backends(
            spatial_symmetric,
            (&nominal, &[0, 1, 2, 3]),
            &EVERY_BACKEND,
            &objective,
            0.3,
        );
    }
}

/// A point mass `m` (`p[0]`) in the plane on a rod of length 1 to the
/// origin, `Φ = (x² + y² − 1)/2`, under gravity and a force `k y` along x
/// (`k = p[1]`): `∂g/∂u` has the entry `(x, y)` and not `(y, x)`, and the
/// Hessian `μ I` is diagonal, so `S` (without `BᵀB`) is structurally
/// unsymmetric and `Aᵀ`'s pattern is not `A`'s.
struct CrossForced {
    m: f64,
    k: f64,
}

impl System for CrossForced {
    fn n_coords(&self) -> usize {
        2
    }
    fn n_constraints(&self) -> usize {
        1
    }
    fn mass_pattern(&self) -> Pattern {
        Pattern::diagonal(2)
    }
    fn mass_into(&self, _t: f64, _u: &[f64], mass: &mut [f64]) {
        mass.fill(self.m);
    }
    fn mass_is_constant(&self) -> bool {
        true
    }
    fn forces_into(&self, _t: f64, u: &[f64], _v: &[f64], g: &mut [f64]) {
        g[0] = self.k * u[1];
        g[1] = -9.81 * self.m;
    }
    fn forces_du_pattern(&self) -> Pattern {
        Pattern::from_entries(2, 2, vec![(0, 1)])
    }
    fn forces_du_into(&self, _t: f64, _u: &[f64], _v: &[f64], g_u: &mut [f64]) {
        g_u[0] = self.k;
    }
    fn forces_dv_pattern(&self) -> Pattern {
        Pattern::new(2, 2)
    }
    fn phi_into(&self, _t: f64, u: &[f64], phi: &mut [f64]) {
        phi[0] = 0.5 * (u[0] * u[0] + u[1] * u[1] - 1.0);
    }
    fn b_pattern(&self) -> Pattern {
        Pattern::from_entries(1, 2, vec![(0, 0), (0, 1)])
    }
    fn b_into(&self, _t: f64, u: &[f64], b: &mut [f64]) {
        b.copy_from_slice(u);
    }
    fn hessian_pattern(&self) -> Pattern {
        Pattern::diagonal(2)
    }
    fn hessian_into(&self, _t: f64, _u: &[f64], mu: &[f64], out: &mut [f64]) {
        out.fill(mu[0]);
    }
}

/// [`CrossForced`] released at rest 0.6 rad from the vertical.
fn cross_forced(p: &[f64]) -> Model {
    let (s, c) = 0.6_f64.sin_cos();
    Model {
        sys: Box::new(CrossForced { m: p[0], k: p[1] }),
        u0: vec![s, -c],
        v0: vec![0.0; 2],
    }
}

/// A backend that factors the whole matrix `[S Bᵀ; B 0]` (without `BᵀB`)
/// densely and refuses a pattern with the entry (row 1, column 0): it takes
/// [`CrossForced`]'s `A` and not its `Aᵀ`.
const REFUSES_TRANSPOSE: Backend = Backend::new("test-refuses-transpose");

fn refuses_transpose(a: &Csc, options: &KktOptions) -> Result<Box<dyn KktBackend>, KktError> {
    if a.position(1, 0).is_some() {
        return Err(KktError::Structure("the entry (1, 0)".into()));
    }
    let dense = Backend::DENSE
        .registration()
        .ok_or_else(|| KktError::Structure("no dense backend".into()))?;
    (dense.analyse)(a, options)
}

#[test]
fn a_backend_that_refuses_the_transposed_pattern_falls_back_to_sparse_lu() {
    mstar_kkt::register(Registration {
        backend: REFUSES_TRANSPOSE,
        summary: "dense LU that refuses the entry (1, 0) (a test)",
        structure: Structure {
            augmented: false,
            transpose: true,
        },
        symmetric: false,
        analyse: refuses_transpose,
        automatic: None,
        needs_n_primal: false,
    })
    .expect("the test backend registers");
    let nominal = [1.5, 2.0];
    let ps: Vec<Param> = (0..2)
        .map(|k| Param {
            make: cross_forced,
            nominal: nominal.to_vec(),
            k,
        })
        .collect();
    let refs: Vec<&dyn Parameterized> = ps.iter().map(|p| p as &dyn Parameterized).collect();
    let model = cross_forced(&nominal);
    let config = config(REFUSES_TRANSPOSE);
    let objective = Objective::Sum(Column::Position(0));
    let sys = model.sys.as_ref();
    let mut integ = Integrator::new(sys, config.clone(), 0.0, &model.u0, &model.v0)
        .expect("the integrator starts");
    let g = integ
        .gradient(0.5, &refs, &objective, Memory::Store)
        .expect("the gradient is computed");
    assert_eq!(g.backend, Backend::SPARSE_LU);
    let (f, forward) = forward_gradient(&model, &config, 0.5, &refs, &objective, g.steps);
    assert_eq!(forward, REFUSES_TRANSPOSE);
    // As in `check_backends`: N · 1e-12 relative to the largest entry.
    let scale = f
        .iter()
        .chain(&g.values)
        .fold(0.0_f64, |a, b| a.max(b.abs()));
    let tolerance = g.steps as f64 * 1e-12 * scale;
    for (k, (a, f)) in g.values.iter().zip(&f).enumerate() {
        assert!(
            (a - f).abs() <= tolerance,
            "parameter {k}: adjoint {a} against forward {f} (tolerance {tolerance:.1e})"
        );
    }
}
