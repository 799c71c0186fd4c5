//! The paper's pendulum (`algorithm.md` §5) integrated with the paper's scheme
//! — Newmark β = 1/4, γ = 1/2, Newton on (16)-(17) with M* — agrees with the
//! independent RK4 oracle on the minimal coordinate, θ̈ = −(g₀/l) sin θ, as a
//! second-order method must: within the global error bound of a second-order
//! method, with the trapezoidal rule's exact phase error at small amplitude, and
//! with an observed order of 2.

use mstar::analysis::{fitted_order, max_error};
use mstar::pendulum::PendulumRun;
use mstar::{Config, Sample, Start};

fn solve(run: &PendulumRun) -> (Vec<Sample>, Vec<Sample>) {
    run.run_with_reference()
        .unwrap_or_else(|e| panic!("integration failed: {e}"))
}

#[test]
fn paper_scheme_theta_within_the_second_order_global_error_bound() {
    let mut run = PendulumRun::paper();
    run.t_end = 2.0;
    let (samples, reference) = solve(&run);
    // A one-step method with local error h³/12 |y⃛| (the trapezoidal rule) on
    // y = (θ, θ̇/ω), whose right-hand side is Lipschitz with constant ω = √(g/l)
    // in that norm, has global error ≤ (h²/12) max|y⃛| (e^{ωT} − 1)/ω (Gronwall).
    // |θ⃛| = ω²|cos θ θ̇| ≤ ω² θ̇_max; |θ⁗|/ω ≤ ω(θ̇_max² + ω²); θ̇_max² = 2ω²(1 − cos θ₀).
    let (h, t) = (run.config.h, run.t_end);
    let w = (run.g0 / run.l).sqrt();
    let thdot_max = (2.0 * w * w * (1.0 - run.theta0.cos())).sqrt();
    let y3 = (w * w * thdot_max).max(w * (thdot_max * thdot_max + w * w));
    let bound = h * h / 12.0 * y3 * ((w * t).exp() - 1.0) / w;
    let theta = max_error(&samples, &reference, |s| s.u[2]);
    let omega = max_error(&samples, &reference, |s| s.v[2]) / w;
    assert!(
        theta <= bound,
        "max |θ − θ_RK4| = {theta:.3e} > {bound:.3e}"
    );
    assert!(
        omega <= bound,
        "max |θ̇ − θ̇_RK4|/ω = {omega:.3e} > {bound:.3e}"
    );
    // The position constraints tie x, y to θ: their errors are of the same size.
    let x = max_error(&samples, &reference, |s| s.u[0]);
    assert!(x <= run.l * bound, "max |x − x_RK4| = {x:.3e}");
}

#[test]
fn small_amplitude_error_is_the_trapezoidal_phase_error() {
    // For θ̈ = −ω²θ the trapezoidal rule is a rotation by 2 atan(ωh/2) per step,
    // so θ_k = θ₀ cos(ω' t_k) with ω' = (2/h) atan(ωh/2), and
    // |θ − θ_exact| ≤ θ₀ |ω − ω'| t. The nonlinearity shifts both frequencies by
    // the same relative θ₀²/16 to leading order: 1 % margin.
    let mut run = PendulumRun::paper();
    run.theta0 = 0.05;
    run.t_end = 2.0;
    run.config.start = Start::Consistent;
    let (samples, reference) = solve(&run);
    let h = run.config.h;
    let w = (run.g0 / run.l).sqrt();
    let w_num = 2.0 / h * (w * h / 2.0).atan();
    let bound = 1.01 * run.theta0 * (w - w_num) * run.t_end;
    let theta = max_error(&samples, &reference, |s| s.u[2]);
    assert!(
        theta <= bound,
        "max |θ − θ_RK4| = {theta:.3e} > {bound:.3e}"
    );
    // ... and not much below it: the error really is the phase error.
    assert!(
        theta >= 0.5 * bound,
        "max |θ − θ_RK4| = {theta:.3e} ≪ {bound:.3e}"
    );
}

#[test]
fn observed_order_in_theta_is_two() {
    let hs = [0.02, 0.01, 0.005, 0.0025];
    let errors: Vec<f64> = hs
        .iter()
        .map(|&h| {
            let mut run = PendulumRun::paper();
            run.t_end = 1.0;
            run.config = Config::paper(h, vec![-10.0, 0.0]);
            let (samples, reference) = solve(&run);
            max_error(&samples, &reference, |s| s.u[2])
        })
        .collect();
    let order = fitted_order(&hs, &errors);
    assert!(
        (order - 2.0).abs() <= 0.1,
        "order {order:.3}, errors {errors:?}"
    );
}
