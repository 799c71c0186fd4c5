//! Every spatial element's derivatives (`B`, `K_T` with the constraint
//! Hessian, the quadratic-velocity forces and `∂(M ü)/∂u`, `C_T`, `Φ_t`, the
//! acceleration right-hand side) against central finite differences at
//! random states, with the singular and the regularized rotational mass.

use mstar_linearize::check_derivatives;
use mstar_model::StateRef;
use mstar_model::System;
use proptest::prelude::*;
use proptest::test_runner::FileFailurePersistence;

/// As in `derivatives_match_finite_differences.rs`: central differences are
/// good to about 1e-10 relative; a wrong term is an error of order 1.
const FD_TOL: f64 = 1e-6;

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 16,
        failure_persistence: Some(Box::new(FileFailurePersistence::WithSource("regressions"))),
        ..ProptestConfig::default()
    })]
    #[test]
    fn every_spatial_element_derivatives(
        params in prop::collection::vec(-1.0f64..1.0, 24),
        state in prop::collection::vec(-1.0f64..1.0, 60),
        t in 0.0f64..2.0,
    ) {
        let examples = mstar_model::spatial::element_examples(&params);
        prop_assert!(examples.len() >= 80, "{} examples", examples.len());
        for (what, sys) in examples {
            let (n, m) = (sys.n_coords(), sys.n_constraints());
            // Near the initial state (Euler parameters near unit length).
            let u0 = sys.initial_position();
            let u: Vec<f64> = u0.iter().zip(&state).map(|(x, d)| x + 0.1 * d).collect();
            let (v, a) = (&state[14..14 + n], &state[28..28 + n]);
            let lambda = &state[42..42 + m];
            let e = check_derivatives(&sys, &StateRef { t, u: &u, v, a, lambda });
            prop_assert!(e.max() < FD_TOL, "{what}: {e:?}");
        }
    }
}
