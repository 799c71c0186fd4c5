//! The discrete adjoint gradient (`Integrator::gradient`) against the
//! forward sensitivities' `Σ w_nᵀ S_n` (the same derivative computed by
//! another recurrence), against central differences of whole runs with
//! Richardson extrapolation, and its stored and checkpointed modes against
//! each other.

mod common;

use common::{Model, Param, column_of};
use mstar_model::PendulumChain;
use mstar_model::planar::{
    At, PlanarBuilder, PointMass, RigidBody, RotationalSpringDamper, SpringDamper, TimeFunction,
};
use mstar_newmark::{
    Column, Config, IntegrationError, Integrator, Memory, Newton, Objective, Parameterized, Scheme,
};

/// Newton tolerance of every run here (the finite differences divide the
/// runs' own errors by the difference step).
const TOL: f64 = 1e-12;

/// The paper's pendulum of mass `p[0]` and length `p[1]` (g = 9.81),
/// released at rest from θ₀ = 1 rad.
fn pendulum(p: &[f64]) -> Model {
    let sys = PendulumChain::paper(p[0], p[1], 9.81);
    let u0 = sys.position(&[1.0]);
    Model {
        sys: Box::new(sys),
        u0,
        v0: vec![0.0; 3],
    }
}

/// A slider-crank driven by a constant torque, with a damped spring on the
/// slider and a rotational damper at the crank (velocity-dependent forces:
/// `K_T` and so `J` unsymmetric). `p` = crank mass, coupler mass, spring
/// damping, spring stiffness.
fn slider_crank(p: &[f64]) -> Model {
    let (r, l, theta) = (0.5, 1.5, 0.3_f64);
    let (ax, ay) = (r * theta.cos(), r * theta.sin());
    let bx = ax + (l * l - ay * ay).sqrt();
    let phi = (-ay).atan2(bx - ax);
    let mut b = PlanarBuilder::new();
    b.gravity(0.0, -9.81);
    let crank = b.rigid_body(
        "crank",
        RigidBody {
            mass: p[0],
            inertia: p[0] * r * r / 12.0,
            pose: [0.5 * ax, 0.5 * ay, theta],
            velocity: [0.0; 3],
        },
    );
    let coupler = b.rigid_body(
        "coupler",
        RigidBody {
            mass: p[1],
            inertia: p[1] * l * l / 12.0,
            pose: [0.5 * (ax + bx), 0.5 * ay, phi],
            velocity: [0.0; 3],
        },
    );
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
    b.revolute(
        "pin",
        At::Body(crank, [0.5 * r, 0.0]),
        At::Body(coupler, [-0.5 * l, 0.0]),
    );
    b.revolute(
        "wrist",
        At::Body(coupler, [0.5 * l, 0.0]),
        At::Body(slider, [0.0, 0.0]),
    );
    b.prismatic(
        "rail",
        At::Ground([0.0, 0.0]),
        [1.0, 0.0],
        At::Body(slider, [0.0, 0.0]),
    );
    b.torque("motor", crank, TimeFunction::Constant(3.0));
    b.spring(
        "buffer",
        At::Ground([3.0, 0.0]),
        At::Body(slider, [0.0, 0.0]),
        SpringDamper {
            stiffness: p[3],
            damping: p[2],
            rest_length: 1.0,
        },
    );
    b.rotational_spring(
        "bearing",
        None,
        crank,
        RotationalSpringDamper {
            stiffness: 0.0,
            damping: 0.4,
        },
    );
    let sys = b.build().expect("a valid slider-crank");
    let (u0, v0) = (sys.initial_position(), sys.initial_velocity());
    Model {
        sys: Box::new(sys),
        u0,
        v0,
    }
}

/// Parameter `k` of a model family `make` at the values `nominal`.
fn params(make: fn(&[f64]) -> Model, nominal: &[f64]) -> Vec<Param> {
    (0..nominal.len())
        .map(|k| Param {
            make,
            nominal: nominal.to_vec(),
            k,
        })
        .collect()
}

fn config(newton: Newton, rho: f64) -> Config {
    Config {
        h: 0.01,
        tol: TOL,
        newton,
        scheme: Scheme::GeneralizedAlpha { rho_inf: rho },
        ..Config::default()
    }
}

/// `∂Ψ/∂y_n` of sample `n` of `last` with value `y` (the objective's own
/// definition, written out here independently of the library).
fn weight(objective: &Objective, n: usize, last: usize, y: f64) -> f64 {
    match objective {
        Objective::Final(_) => f64::from(u8::from(n == last)),
        Objective::Sum(_) => 1.0,
        Objective::Fit { measured, .. } => 2.0 * (y - measured[n]),
    }
}

/// `Σ_n w_nᵀ S_n` from the forward sensitivities of a run of `model` to
/// `t_end` with `steps` steps (the weights need the count for `Final`).
fn forward_gradient(
    model: &Model,
    config: &Config,
    t_end: f64,
    params: &[&dyn Parameterized],
    objective: &Objective,
    steps: usize,
) -> Vec<f64> {
    let mut integ = Integrator::new(
        model.sys.as_ref(),
        config.clone(),
        0.0,
        &model.u0,
        &model.v0,
    )
    .expect("the integrator starts");
    let mut sens = integ
        .sensitivities(params)
        .expect("the sensitivities start");
    let c = objective.column();
    let mut grad = vec![0.0; params.len()];
    let mut n = 0;
    loop {
        let s = integ.view();
        let w = weight(objective, n, steps, column_of(s.u, s.v, s.a, s.lambda, c));
        for (k, g) in grad.iter_mut().enumerate() {
            *g += w * column_of(sens.u(k), sens.v(k), sens.a(k), sens.lambda(k), c);
        }
        if integ.reached(t_end) {
            return grad;
        }
        integ
            .step_with(t_end, &mut sens)
            .expect("the step succeeds");
        n += 1;
    }
}

/// The adjoint gradient of a run of `model` to `t_end`.
fn adjoint(
    model: &Model,
    config: &Config,
    t_end: f64,
    params: &[&dyn Parameterized],
    objective: &Objective,
    memory: Memory,
) -> Result<mstar_newmark::Gradient, IntegrationError> {
    let mut integ = Integrator::new(
        model.sys.as_ref(),
        config.clone(),
        0.0,
        &model.u0,
        &model.v0,
    )
    .expect("the integrator starts");
    integ.gradient(t_end, params, objective, memory)
}

/// Both recurrences solve with the step's KKT matrix factored at the
/// converged state (forward `J`, backward `Jᵀ`), each solve backward
/// stable: a relative error of about `ε κ`, below `1e-12` for the scaled
/// KKT matrices of these small models (`κ ≲ 4e3`). Over `N` steps those
/// errors add up to at most `N · 1e-12` relative to the gradient's terms
/// (bounded by the larger of the two gradients' entries).
fn assert_agree(adjoint: &[f64], forward: &[f64], steps: usize, what: &str) {
    let scale = forward
        .iter()
        .chain(adjoint)
        .fold(0.0_f64, |a, b| a.max(b.abs()));
    let tolerance = steps as f64 * 1e-12 * scale.max(f64::MIN_POSITIVE);
    for (k, (a, f)) in adjoint.iter().zip(forward).enumerate() {
        assert!(
            (a - f).abs() <= tolerance,
            "{what}, parameter {k}: adjoint {a} against forward {f} (tolerance {tolerance:.1e})"
        );
    }
}

/// Measured values for a fit: a made-up signal near the column's range.
fn measured(samples: usize, amplitude: f64) -> Vec<f64> {
    (0..samples)
        .map(|n| amplitude * (0.05 * n as f64).cos())
        .collect()
}

#[test]
fn pendulum_adjoint_matches_forward_sensitivities() {
    let ps = params(pendulum, &[1.3, 0.9]);
    let refs: Vec<&dyn Parameterized> = ps.iter().map(|p| p as &dyn Parameterized).collect();
    let model = pendulum(&[1.3, 0.9]);
    let config = config(Newton::Full, 0.8);
    let t_end = 1.0;
    for objective in [
        Objective::Final(Column::Position(0)),
        Objective::Sum(Column::Multiplier(1)),
        Objective::Final(Column::Velocity(2)),
        Objective::Fit {
            column: Column::Position(1),
            measured: measured(101, -0.8),
        },
    ] {
        let g = adjoint(&model, &config, t_end, &refs, &objective, Memory::Store)
            .expect("the gradient is computed");
        assert_eq!(g.steps, 100);
        let f = forward_gradient(&model, &config, t_end, &refs, &objective, g.steps);
        assert_agree(&g.values, &f, g.steps, &format!("{objective:?}"));
    }
}

#[test]
fn damped_slider_crank_adjoint_matches_forward_sensitivities() {
    let nominal = [2.0, 1.5, 4.0, 30.0];
    let ps = params(slider_crank, &nominal);
    let refs: Vec<&dyn Parameterized> = ps.iter().map(|p| p as &dyn Parameterized).collect();
    let model = slider_crank(&nominal);
    assert!(!model.sys.tangent_is_symmetric());
    // A shortened last step (0.795 s is not a multiple of h) exercises the
    // predictor's rescaling.
    let (config, t_end) = (config(Newton::Full, 0.6), 0.795);
    for objective in [
        Objective::Final(Column::Position(6)),
        Objective::Sum(Column::Multiplier(0)),
        Objective::Final(Column::Acceleration(2)),
    ] {
        let g = adjoint(&model, &config, t_end, &refs, &objective, Memory::Store)
            .expect("the gradient is computed");
        let f = forward_gradient(&model, &config, t_end, &refs, &objective, g.steps);
        assert_agree(&g.values, &f, g.steps, &format!("{objective:?}"));
    }
}

/// Central differences of whole runs at `p ± δ`, `p ± 2δ` extrapolated
/// (Richardson): `D₁`, `D₂` have errors `c δ²`, `4 c δ²`, so `(4 D₁ − D₂)/3`
/// removes them and `|D₁ − D₂|/3` bounds what is left; the runs' own errors
/// `η` (Newton's tolerance on every sample, weighted by `|w_n|`) enter it
/// as at most `1.5 η / δ`. With modified Newton and checkpoints the
/// adjoint's run refactors at every checkpoint, and its solution differs
/// from the plain runs' within the same Newton tolerance.
fn check_against_differences(
    make: fn(&[f64]) -> Model,
    nominal: &[f64],
    objective: &Objective,
    (newton, memory): (Newton, Memory),
) {
    let config = config(newton, 0.8);
    let t_end = 0.6;
    let ps = params(make, nominal);
    let refs: Vec<&dyn Parameterized> = ps.iter().map(|p| p as &dyn Parameterized).collect();
    let g = adjoint(&make(nominal), &config, t_end, &refs, objective, memory)
        .expect("the gradient is computed");
    let psi = |p: &[f64]| -> (f64, f64) {
        let model = make(p);
        let mut integ = Integrator::new(
            model.sys.as_ref(),
            config.clone(),
            0.0,
            &model.u0,
            &model.v0,
        )
        .expect("the integrator starts");
        let (mut psi, mut eta, mut samples) = (0.0, 0.0, Vec::new());
        loop {
            let s = integ.view();
            samples.push(column_of(s.u, s.v, s.a, s.lambda, objective.column()));
            if integ.reached(t_end) {
                break;
            }
            integ.step(t_end).expect("the step succeeds");
        }
        let last = samples.len() - 1;
        for (n, &y) in samples.iter().enumerate() {
            let w = weight(objective, n, last, y);
            psi += match objective {
                Objective::Final(_) => w * y,
                Objective::Sum(_) => y,
                Objective::Fit { measured, .. } => (y - measured[n]).powi(2),
            };
            eta += w.abs() * TOL * y.abs().max(10.0);
        }
        (psi, eta)
    };
    for (k, &value) in nominal.iter().enumerate() {
        let delta = 1e-3 * value;
        let at = |s: f64| {
            let mut p = nominal.to_vec();
            p[k] += s * delta;
            psi(&p)
        };
        let ((p1, eta), (m1, _), (p2, _), (m2, _)) = (at(1.0), at(-1.0), at(2.0), at(-2.0));
        let d1 = (p1 - m1) / (2.0 * delta);
        let d2 = (p2 - m2) / (4.0 * delta);
        let richardson = (4.0 * d1 - d2) / 3.0;
        let tolerance = (d1 - d2).abs() / 3.0 + 1.5 * eta / delta;
        assert!(
            (g.values[k] - richardson).abs() <= tolerance,
            "parameter {k}: adjoint {} against extrapolated differences {richardson} \
             (tolerance {tolerance:.3e}, D1 = {d1}, D2 = {d2})",
            g.values[k]
        );
    }
}

#[test]
fn pendulum_adjoint_matches_extrapolated_differences() {
    check_against_differences(
        pendulum,
        &[1.3, 0.9],
        &Objective::Fit {
            column: Column::Position(1),
            measured: measured(61, -0.8),
        },
        (Newton::Full, Memory::Store),
    );
}

#[test]
fn slider_crank_adjoint_matches_extrapolated_differences() {
    check_against_differences(
        slider_crank,
        &[2.0, 1.5, 4.0, 30.0],
        &Objective::Final(Column::Position(6)),
        (Newton::Full, Memory::Store),
    );
}

#[test]
fn checkpointed_modified_newton_matches_extrapolated_differences() {
    check_against_differences(
        slider_crank,
        &[2.0, 1.5, 4.0, 30.0],
        &Objective::Sum(Column::Multiplier(2)),
        (
            Newton::Modified { max_rate: 0.5 },
            Memory::Checkpoints { every: 9 },
        ),
    );
}

/// With full Newton the recomputed segments repeat the forward steps
/// exactly, so the two modes see the same states and their gradients agree
/// to the order in which round-off is summed (identical here).
#[test]
fn checkpointed_and_stored_modes_agree() {
    let nominal = [2.0, 1.5, 4.0, 30.0];
    let ps = params(slider_crank, &nominal);
    let refs: Vec<&dyn Parameterized> = ps.iter().map(|p| p as &dyn Parameterized).collect();
    let model = slider_crank(&nominal);
    let config = config(Newton::Full, 0.7);
    let objective = Objective::Sum(Column::Velocity(3));
    let stored = adjoint(&model, &config, 0.5, &refs, &objective, Memory::Store)
        .expect("the gradient is computed");
    for memory in [
        Memory::Checkpoints { every: 7 },
        Memory::Checkpoints { every: 1 },
        Memory::Budget { bytes: 1000 },
    ] {
        let g = adjoint(&model, &config, 0.5, &refs, &objective, memory)
            .expect("the gradient is computed");
        assert!(g.checkpoint_every.is_some(), "{memory:?}");
        // Every segment, the last included, is recomputed once.
        assert_eq!(g.recomputed_steps, g.steps, "{memory:?}");
        assert_eq!(g.objective, stored.objective);
        let scale = stored.values.iter().fold(0.0_f64, |a, b| a.max(b.abs()));
        for (a, b) in g.values.iter().zip(&stored.values) {
            assert!(
                (a - b).abs() <= 16.0 * f64::EPSILON * scale,
                "{memory:?}: {a} vs {b}"
            );
        }
    }
    // 51 states × (4·8 + 7 + 2) numbers do not fit in 1000 bytes: ⌈√50⌉ = 8.
    let g = adjoint(
        &model,
        &config,
        0.5,
        &refs,
        &objective,
        Memory::Budget { bytes: 1000 },
    )
    .expect("the gradient is computed");
    assert_eq!(g.checkpoint_every, Some(8));
}

#[test]
fn bad_objectives_are_errors() {
    let ps = params(pendulum, &[1.0, 1.0]);
    let refs: Vec<&dyn Parameterized> = ps.iter().map(|p| p as &dyn Parameterized).collect();
    let model = pendulum(&[1.0, 1.0]);
    let config = config(Newton::Full, 0.8);
    let run = |objective: Objective, memory| match adjoint(
        &model, &config, 0.1, &refs, &objective, memory,
    ) {
        Err(IntegrationError::Config(why)) => why,
        other => panic!("{objective:?}: {other:?}"),
    };
    let why = run(Objective::Final(Column::Multiplier(2)), Memory::Store);
    assert!(why.contains("multiplier 2") && why.contains("2"), "{why}");
    let why = run(
        Objective::Fit {
            column: Column::Position(0),
            measured: vec![0.0; 3],
        },
        Memory::Store,
    );
    assert!(
        why.contains("3 given") && why.contains("11 samples"),
        "{why}"
    );
    let why = run(
        Objective::Final(Column::Position(0)),
        Memory::Checkpoints { every: 0 },
    );
    assert!(why.contains("at least 1"), "{why}");
}
