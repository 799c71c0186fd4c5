//! The spatial bar chain's fast path (the spherical joints' kernels, the
//! Schur backend's fixed-size blocks) integrates exactly the model of the
//! generic element path, and both put the tip where Exudyn does.
//!
//! Physics: N solid cylinders (1 kg, 1 m, radius 0.02 m) on spherical joints,
//! released horizontally along +x under gravity −z. The motion stays in the
//! x-z plane; the tip falls freely at first (z = −g t²/2 while the chain is
//! still straight) and swings in as the chain bends.

use mstar::model::spatial::{RotationalMass, SpatialSystem, spatial_bar_chain};
use mstar::{Config, Integrator, Newton, SampleRef, Scheme};

/// `mstar chain --kind spatial-bars` with `--rho 0.8 --tol 1e-8`: h = 1e-3,
/// full Newton (the settings of `benches/exudyn/spatial_chain.py`).
fn config() -> Config {
    Config {
        h: 1e-3,
        tol: 1e-8,
        newton: Newton::Full,
        scheme: Scheme::GeneralizedAlpha { rho_inf: 0.8 },
        ..Config::default()
    }
}

/// `(u, v, λ)` at every step up to `t_end`.
fn trajectory(sys: &SpatialSystem, t_end: f64) -> Vec<(Vec<f64>, Vec<f64>, Vec<f64>)> {
    let (u0, v0) = (sys.initial_position(), sys.initial_velocity());
    let mut integ = Integrator::new(sys, config(), 0.0, &u0, &v0).expect("start");
    let mut out = Vec::new();
    integ
        .run(t_end, &mut |s: &SampleRef<'_>| {
            out.push((s.u.to_vec(), s.v.to_vec(), s.lambda.to_vec()));
        })
        .expect("integration");
    out
}

#[test]
fn fast_path_steps_equal_the_generic_path() {
    let fast = spatial_bar_chain(12, RotationalMass::Regularized);
    assert_eq!(fast.kernel_joints(), 12);
    let generic = fast.clone().with_generic_joints();
    let (a, b) = (trajectory(&fast, 0.05), trajectory(&generic, 0.05));
    assert_eq!(a.len(), b.len());
    assert!(a.len() > 40, "{} samples", a.len());
    for (k, (x, y)) in a.iter().zip(&b).enumerate() {
        for (p, q) in [(&x.0, &y.0), (&x.1, &y.1), (&x.2, &y.2)] {
            for (s, t) in p.iter().zip(q) {
                let close = (s - t).abs() <= 1e-12 * (1.0 + t.abs());
                assert!(close, "sample {k}: {s} vs {t}");
            }
        }
    }
}

/// Exudyn 1.13.6 (`benches/exudyn/spatial_chain.py --tip`): the centre of
/// bar 10 of the 10-bar chain at t = 1 s is at (7.027281445, 0, −4.905622897).
/// The two codes' Newton iterations stop at different points within the
/// tolerance 1e-8: they agree to 1e-7.
#[test]
fn ten_bar_tip_matches_exudyn() {
    let sys = spatial_bar_chain(10, RotationalMass::Regularized);
    let last = trajectory(&sys, 1.0).pop().expect("samples");
    let (x, _) = sys.body("bar10").expect("the tip bar");
    let tip = &last.0[x..x + 3];
    let want = [7.027_281_445, 0.0, -4.905_622_897];
    for (got, want) in tip.iter().zip(want) {
        assert!((got - want).abs() < 1e-7, "tip {tip:?}, Exudyn {want}");
    }
}
