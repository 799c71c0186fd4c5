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

/// `(Newton iterations, steps, backend)` of the chain of `n` bars to `t_end`
/// at the defaults of `mstar chain` (h = 1e-3, tol 1e-10, full Newton).
fn iterations(sys: &SpatialSystem, t_end: f64) -> (usize, usize, mstar::kkt::Backend) {
    let (u0, v0) = (sys.initial_position(), sys.initial_velocity());
    let config = Config {
        h: 1e-3,
        newton: Newton::Full,
        ..Config::default()
    };
    let mut integ = Integrator::new(sys, config, 0.0, &u0, &v0).expect("start");
    integ
        .run(t_end, &mut |_: &SampleRef<'_>| {})
        .expect("integration");
    let stats = integ.stats();
    (stats.iterations, stats.steps, integ.backend())
}

/// With the exact (unsymmetric) iteration matrix the chain takes the
/// `schur-lu` backend and Newton converges in one iteration a step at the
/// default tolerance; the symmetrized matrix takes two at most steps.
#[test]
fn exact_tangent_takes_one_newton_iteration_a_step() {
    let exact = spatial_bar_chain(50, RotationalMass::Regularized);
    let (it, steps, backend) = iterations(&exact, 0.3);
    assert_eq!(backend, mstar::kkt::Backend::SCHUR_LU);
    assert_eq!((it, steps), (300, 300), "exact tangent");
    let symmetric = exact.with_symmetric_tangent();
    let (it, steps, backend) = iterations(&symmetric, 0.3);
    assert_eq!(backend, mstar::kkt::Backend::SCHUR);
    assert!(
        it * 10 >= 18 * steps,
        "symmetrized: {it} iterations, {steps} steps"
    );
}

/// The physics is unchanged by the exact tangent: at N = 1000, t = 0.1 s the
/// tip is where Exudyn 1.13.6 puts it (x = 999.499125074 m, z =
/// −0.049050000 m), at the defaults of `mstar chain`.
#[test]
fn thousand_bar_tip_matches_exudyn_with_the_exact_tangent() {
    let sys = spatial_bar_chain(1000, RotationalMass::Regularized);
    let (u0, v0) = (sys.initial_position(), sys.initial_velocity());
    let config = Config {
        h: 1e-3,
        newton: Newton::Full,
        ..Config::default()
    };
    let mut integ = Integrator::new(&sys, config, 0.0, &u0, &v0).expect("start");
    let mut last = Vec::new();
    integ
        .run(0.1, &mut |s: &SampleRef<'_>| last = s.u.to_vec())
        .expect("integration");
    let (x, _) = sys.body("bar1000").expect("the tip bar");
    let (tip_x, tip_z) = (last[x], last[x + 2]);
    assert!((tip_x - 999.499_125_074).abs() < 1e-8, "tip x {tip_x}");
    assert!((tip_z + 0.049_050_000).abs() < 1e-8, "tip z {tip_z}");
}

/// `mstar chain --kind spatial-bars` with `--kkt schur` or `ldlt`
/// runs on the symmetrized tangent (the symmetric backends refuse the exact
/// one) and ends at the same tip as the automatic choice.
#[test]
fn the_chain_command_symmetrizes_for_a_symmetric_backend() {
    let run = |kkt: &str| {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_mstar"))
            .args([
                "chain",
                "--kind",
                "spatial-bars",
                "--links",
                "5",
                "--t-end",
                "0.05",
            ])
            .args(["--kkt", kkt])
            .output()
            .expect("mstar runs");
        let text = String::from_utf8_lossy(&out.stdout).into_owned();
        assert!(
            out.status.success(),
            "--kkt {kkt}: {text}{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let solver = format!("KKT solver: {kkt}");
        assert!(kkt == "auto" || text.contains(&solver), "{text}");
        // The position part of the tip line (the ‖Φ‖ after it is round-off).
        let tip = text
            .lines()
            .find(|l| l.starts_with("tip "))
            .expect("a tip line");
        tip.split(';').next().unwrap_or_default().to_string()
    };
    let auto = run("auto");
    // The tip is printed to 9 digits: the Newton tolerance (1e-10) is far below.
    assert_eq!(run("schur"), auto);
    assert_eq!(run("ldlt"), auto);
}
