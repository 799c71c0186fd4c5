//! [`Newton::PerStep`]: a fresh Jacobian at each step's first iteration,
//! reused by the step's later iterations (`algorithm.md` §4; the Newton
//! iteration converges to the same tolerance whatever Jacobian it uses, so
//! the three variants agree to the tolerance per step).

use mstar_model::{Link, PendulumChain};
use mstar_newmark::{Config, Integrator, Newton, RunStats};

/// A three-link pendulum released from a bent pose: a motion fast enough
/// that many steps need a second Newton iteration at the default
/// tolerance.
fn three_links() -> PendulumChain {
    PendulumChain::new(
        vec![
            Link { m: 1.0, l: 1.0 },
            Link { m: 2.0, l: 0.5 },
            Link { m: 0.5, l: 0.8 },
        ],
        9.81,
    )
}

const T_END: f64 = 1.0;
const H: f64 = 5e-3;
const TOL: f64 = 1e-10;

/// The positions at `T_END` and the run's counts.
fn run(newton: Newton) -> (Vec<f64>, RunStats) {
    let sys = three_links();
    let theta = [0.9, -0.7, 1.2];
    let (u, v) = (sys.position(&theta), sys.velocity(&theta, &[0.0; 3]));
    let config = Config {
        h: H,
        tol: TOL,
        newton,
        ..Config::default()
    };
    let mut integ = Integrator::new(&sys, config, 0.0, &u, &v).expect("a consistent start");
    while integ.time() < T_END - 1e-12 {
        integ.step(T_END).expect("the pendulum steps");
    }
    (integ.sample().u, integ.stats())
}

#[test]
fn one_factorization_a_step_and_the_full_newton_solution() {
    let (u_full, full) = run(Newton::Full);
    let (u_step, per_step) = run(Newton::PER_STEP);
    assert_eq!(per_step.steps, full.steps, "the same steps");
    assert_eq!(per_step.rejected, 0);
    // Full Newton factors at every iteration, and this motion takes more
    // than one iteration on some steps: otherwise the test could not tell
    // the variants apart.
    assert_eq!(full.factorizations, full.iterations);
    assert!(full.iterations > full.steps, "{full:?}");
    // Once per step: the later iterations reuse the step's factorization
    // (each contracts well on this smooth motion).
    assert_eq!(per_step.factorizations, per_step.steps, "{per_step:?}");
    assert!(per_step.iterations >= full.iterations, "{per_step:?}");
    // Both converge every step to the residual tolerance, relative to the
    // forces; the solutions may drift apart by that much per step (and the
    // positions by h² times it, bounded here by the tolerance per step).
    let bound = per_step.steps as f64 * TOL;
    for (a, b) in u_step.iter().zip(&u_full) {
        let d = (a - b).abs();
        assert!(d <= bound, "positions differ by {d:.3e} > {bound:.1e}");
    }
}

#[test]
fn modified_newton_factors_less_than_once_a_step() {
    // The variant this one sits between: modified Newton keeps the
    // factorization across steps, so it factors fewer times than there are
    // steps (the check that `PER_STEP` is not `MODIFIED` under another name).
    let (_, modified) = run(Newton::MODIFIED);
    assert!(modified.factorizations < modified.steps, "{modified:?}");
}
