//! The extrapolating predictor (`Predictor::Extrapolated`, the default;
//! `integrator/history.rs`, docs/theory.md "The predictor") against linear
//! extrapolation: the converged solution does not depend on where Newton
//! starts (to the tolerance per step), and on a falling chain, whose
//! multipliers ring from step to step, the five-step rule starts closer, so
//! full Newton needs fewer iterations.

use mstar_model::{Link, PendulumChain, SampleRef};
use mstar_newmark::{Config, Integrator, Newton, Predictor, RunStats};

const LINKS: usize = 20;
const H: f64 = 5e-3;
const T_END: f64 = 0.3;
const TOL: f64 = 1e-10;

/// A chain of point masses on 1 m rods released horizontally from rest,
/// with `predictor` and full Newton (each iteration a fresh Jacobian, so the
/// count measures the predictor alone): the positions at the end and the
/// run's counts.
fn released_chain(predictor: Predictor) -> (Vec<f64>, RunStats) {
    let sys = PendulumChain::new(vec![Link { m: 1.0, l: 1.0 }; LINKS], 9.81);
    let theta = [std::f64::consts::FRAC_PI_2; LINKS];
    let (u, v) = (sys.position(&theta), sys.velocity(&theta, &[0.0; LINKS]));
    let config = Config {
        h: H,
        tol: TOL,
        newton: Newton::Full,
        predictor,
        ..Config::default()
    };
    let mut integ = Integrator::new(&sys, config, 0.0, &u, &v).expect("a consistent start");
    integ
        .run(T_END, &mut |_: &SampleRef<'_>| {})
        .expect("the chain falls");
    (integ.sample().u, integ.stats())
}

#[test]
fn the_five_step_rule_saves_iterations_and_changes_nothing_else() {
    let (u_linear, linear) = released_chain(Predictor::Linear);
    let (u_five, five) = released_chain(Predictor::Extrapolated);
    assert_eq!(five.steps, linear.steps);
    // Both converge every step to the residual tolerance; the solutions may
    // drift apart by that much per step.
    let bound = five.steps as f64 * TOL;
    for (a, b) in u_five.iter().zip(&u_linear) {
        let d = (a - b).abs();
        assert!(d <= bound, "positions differ by {d:.3e} > {bound:.1e}");
    }
    // Measured on 2026-11-28: 93 iterations in 60 steps with the linear
    // rule, 68 with the five-step rule.
    assert!(
        linear.iterations > linear.steps + linear.steps / 4,
        "the linear rule needs a second iteration on many steps: {linear:?}"
    );
    assert!(
        5 * (five.iterations - five.steps) < 2 * (linear.iterations - linear.steps),
        "second iterations: {} against {}",
        five.iterations - five.steps,
        linear.iterations - linear.steps
    );
}
