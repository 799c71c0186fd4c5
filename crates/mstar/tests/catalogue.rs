//! Every model of the catalogue (`mstar_testkit::catalogue`) through one harness,
//! across the three schemes, every registered KKT backend and both Newton
//! variants. What an index-3 integrator owes each of them:
//!
//! - the constraints hold to the Newton tolerance after every step;
//! - the compared quantity (a tip position) agrees with the independent
//!   reference with second-order error: halving `h` divides the error by 4
//!   (the observed order within 2 ± 0.1: the step sizes are in the asymptotic
//!   range, where the next term, `O(h³)`, moves it by about `h` relative);
//! - every backend and Newton variant gives the same trajectory as the
//!   default to the Newton tolerance (they solve the same equations), or, on
//!   a model it cannot take, refuses it with an error: a backend that needs
//!   a symmetric matrix (`ldlt`, `schur`) a system whose tangent is not
//!   symmetric, and any backend but the automatic choice a singular `M` (the
//!   consistent start solves `[M Bᵀ; B 0]` without `BᵀB`, which the
//!   backends that factor without pivoting cannot). Never a different answer.

use mstar::kkt::{Backend, KktOptions, backends};
use mstar::{Config, IntegrationError, Integrator, Newton, SampleRef, Scheme, StateRef, System};
use mstar_testkit::catalogue::{Case, cases};
use mstar_testkit::testing::check_derivatives;

/// The Newton tolerance of every run (relative).
const TOL: f64 = 1e-12;

/// The schemes: generalized-α (the default), HHT-α and the paper's Newmark.
fn schemes() -> [Scheme; 3] {
    [
        Scheme::GeneralizedAlpha { rho_inf: 0.9 },
        Scheme::Hht { alpha: -0.1 },
        Scheme::Newmark {
            beta: 0.25,
            gamma: 0.5,
        },
    ]
}

/// A run's samples (`u` at every step) and its largest `‖Φ‖∞ / η`.
struct Run {
    u: Vec<Vec<f64>>,
    worst_constraint: f64,
    backend: Backend,
}

/// Integrates `case` with `config`, checking `Φ` after every step.
fn run(case: &Case, config: Config) -> Result<Run, IntegrationError> {
    let sys: &dyn System = case.system.as_ref();
    let tol = config.tol;
    let mut integ = Integrator::new(sys, config, 0.0, &case.u0, &case.v0)?;
    let backend = integ.backend();
    let mut phi = vec![0.0; sys.n_constraints()];
    let (mut u, mut worst) = (Vec::new(), 0.0f64);
    integ.run(case.t_end, &mut |s: &SampleRef<'_>| {
        sys.phi_into(s.t, s.u, &mut phi);
        let eta = tol * s.u.iter().fold(1.0f64, |m, x| m.max(x.abs()));
        let norm = mstar::kkt::max_abs(&phi);
        // NaN-aware: a NaN constraint makes `worst` NaN, which fails below.
        worst = if norm.is_nan() || norm / eta > worst {
            norm / eta
        } else {
            worst
        };
        u.push(s.u.to_vec());
    })?;
    Ok(Run {
        u,
        worst_constraint: worst,
        backend,
    })
}

fn config(scheme: Scheme, h: f64) -> Config {
    Config {
        scheme,
        h,
        // Step control off: the same steps in every run.
        h_min: Some(h),
        tol: TOL,
        ..Config::default()
    }
}

/// `‖probe(u) − expected‖∞`.
fn error(case: &Case, u: &[f64]) -> f64 {
    let got = (case.probe)(u);
    got.iter()
        .zip(&case.expected)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, |m: f64, d| if d.is_nan() { d } else { m.max(d) })
}

/// Second order against the reference: the error at `h` over the error at
/// `h/2` is 4 (order 2 ± 0.1).
fn converges_at_second_order(case: &Case, scheme: Scheme) -> Run {
    let coarse = run(case, config(scheme, case.h))
        .unwrap_or_else(|e| panic!("{} with {scheme:?} at h = {}: {e}", case.name, case.h));
    let fine = run(case, config(scheme, case.h / 2.0))
        .unwrap_or_else(|e| panic!("{} with {scheme:?} at h = {}: {e}", case.name, case.h / 2.0));
    let (last_coarse, last_fine) = (
        coarse.u.last().expect("samples"),
        fine.u.last().expect("samples"),
    );
    let (e_coarse, e_fine) = (error(case, last_coarse), error(case, last_fine));
    let order = (e_coarse / e_fine).log2();
    assert!(
        (order - 2.0).abs() <= 0.1,
        "{} with {scheme:?} against {}: error {e_coarse:.3e} at h = {}, {e_fine:.3e} at h/2 (order {order:.2})",
        case.name,
        case.reference,
        case.h
    );
    for r in [&coarse, &fine] {
        assert!(
            r.worst_constraint <= 1.0,
            "{} with {scheme:?}: ‖Φ‖∞ reached {:.3} η",
            case.name,
            r.worst_constraint
        );
    }
    coarse
}

/// The largest difference of two trajectories, relative to `max(1, |u|)`.
fn difference(a: &Run, b: &Run) -> f64 {
    assert_eq!(a.u.len(), b.u.len(), "the same steps");
    let mut worst = 0.0f64;
    for (x, y) in a.u.iter().zip(&b.u) {
        for (p, q) in x.iter().zip(y) {
            let d = (p - q).abs() / p.abs().max(1.0);
            worst = if d.is_nan() || d > worst { d } else { worst };
        }
    }
    worst
}

/// Every backend and Newton variant against the default run.
fn every_backend_agrees(case: &Case, scheme: Scheme, default: &Run) {
    for registration in backends() {
        for newton in [Newton::Full, Newton::MODIFIED, Newton::PER_STEP] {
            let mut c = config(scheme, case.h);
            c.newton = newton;
            c.kkt = KktOptions {
                backend: registration.backend,
                ..KktOptions::default()
            };
            let label = format!(
                "{} with {scheme:?}, {} backend, {newton:?}",
                case.name, registration.backend
            );
            match run(case, c) {
                Ok(r) => {
                    let d = difference(&r, default);
                    // Each step converges to the Newton tolerance (relative);
                    // the runs may drift apart by that much per step.
                    let bound = r.u.len() as f64 * TOL;
                    assert!(
                        d <= bound,
                        "{label}: differs from {} by {d:.3e} > {bound:.1e}",
                        default.backend
                    );
                    assert!(
                        r.worst_constraint <= 1.0,
                        "{label}: ‖Φ‖∞ {:.3} η",
                        r.worst_constraint
                    );
                }
                Err(e) => {
                    let unsymmetric = registration.symmetric && !case.system.tangent_is_symmetric();
                    assert!(
                        case.singular_mass || unsymmetric,
                        "{label} refused a case it must solve: {e}"
                    );
                }
            }
        }
    }
}

#[test]
fn every_case_converges_and_every_backend_agrees() {
    for case in cases() {
        for scheme in schemes() {
            let default = converges_at_second_order(&case, scheme);
            every_backend_agrees(&case, scheme, &default);
        }
    }
}

/// Every analytic derivative of every case (and every finite-difference
/// default) against central differences of the residual and `Φ`, at the
/// start with arbitrary `ü` and `λ`.
#[test]
fn every_case_has_consistent_derivatives() {
    for case in cases() {
        let sys = case.system.as_ref();
        let (n, m) = (sys.n_coords(), sys.n_constraints());
        let a: Vec<f64> = (0..n).map(|i| (0.7 * i as f64).sin()).collect();
        let lambda: Vec<f64> = (0..m).map(|i| 2.0 + (1.3 * i as f64).cos()).collect();
        let v: Vec<f64> = case
            .v0
            .iter()
            .enumerate()
            .map(|(i, x)| x + 0.3 * (i as f64).cos())
            .collect();
        for t in [0.0, 0.37] {
            let e = check_derivatives(
                sys,
                &StateRef {
                    t,
                    u: &case.u0,
                    v: &v,
                    a: &a,
                    lambda: &lambda,
                },
            );
            assert!(e.max() < 1e-6, "{} at t = {t}: {e:?}", case.name);
        }
    }
}

#[test]
fn the_catalogue_covers_what_it_promises() {
    let all = cases();
    let names: Vec<_> = all.iter().map(|c| c.name).collect();
    for want in [
        "pendulum",
        "double-pendulum",
        "bar-chain",
        "point-mass-chain",
        "random-bars",
        "joint-frame-bars",
        "rotating-wire",
    ] {
        assert!(names.contains(&want), "{want} is missing");
    }
    // A configuration-dependent, non-diagonal mass matrix.
    let joint_frame = &all[names
        .iter()
        .position(|&n| n == "joint-frame-bars")
        .expect("case")];
    let sys = joint_frame.system.as_ref();
    assert!(!sys.mass_is_constant());
    assert!(sys.mass_pattern().entries.iter().any(|&(i, j)| i != j));
    assert!(!sys.mass_du_pattern().is_empty());
    // A rheonomic constraint.
    let wire = &all[names
        .iter()
        .position(|&n| n == "rotating-wire")
        .expect("case")];
    let mut phi_t = [0.0];
    wire.system.phi_t_into(0.0, &wire.u0, &mut phi_t);
    assert!(phi_t[0].abs() > 0.1, "Φ_t = {}", phi_t[0]);
}
