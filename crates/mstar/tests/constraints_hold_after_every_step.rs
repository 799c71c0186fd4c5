//! Index-3 integration enforces the position constraints Φ(u) = 0 themselves,
//! not their derivatives: after every accepted step ‖Φ‖∞ must be within the
//! Newton tolerance η = tol · max(1, ‖u‖∞), whatever the initial angle and step
//! size. Φ is recomputed here from the returned coordinates, independently of
//! the integrator's own report.

use mstar::pendulum::PendulumRun;
use mstar::{Config, System};
use proptest::prelude::*;
use proptest::test_runner::FileFailurePersistence;

/// Just inside π: θ₀ ∈ (−π, π).
const OPEN_PI: f64 = std::f64::consts::PI * (1.0 - 1e-12);

fn check(run: &PendulumRun) -> Result<(), TestCaseError> {
    let (samples, result) = run.run();
    prop_assert!(result.is_ok(), "{:?}", result.err().map(|e| e.to_string()));
    let last = samples.last().map_or(f64::NAN, |s| s.t);
    prop_assert!((last - run.t_end).abs() <= 1e-12, "ended at t = {}", last);
    let sys = run.system();
    let mut phi = vec![0.0; sys.n_constraints()];
    for s in &samples {
        sys.phi_into(s.t, &s.u, &mut phi);
        let eta = run.config.tol * s.u.iter().fold(1.0f64, |m, x| m.max(x.abs()));
        let norm = phi.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        prop_assert!(
            norm <= eta,
            "‖Φ‖∞ = {:.3e} > η = {:.3e} at t = {}",
            norm,
            eta,
            s.t
        );
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 128,
        failure_persistence: Some(Box::new(FileFailurePersistence::WithSource("regressions"))),
        ..ProptestConfig::default()
    })]

    #[test]
    fn paper_scheme(theta0 in -OPEN_PI..OPEN_PI, h in 0.001f64..0.02) {
        let mut run = PendulumRun::paper();
        run.theta0 = theta0;
        run.t_end = 1.0;
        run.config = Config::paper(h, vec![-10.0, 0.0]);
        check(&run)?;
    }

    #[test]
    fn default_scheme(theta0 in -OPEN_PI..OPEN_PI, h in 0.001f64..0.02) {
        let mut run = PendulumRun::standard();
        run.theta0 = theta0;
        run.t_end = 1.0;
        run.config.h = h;
        check(&run)?;
    }
}
