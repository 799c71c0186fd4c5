//! Static equilibrium: a bar on a torsional spring under gravity
//! (`models/torsion-bar.toml`) solved as `mstar equilibrium` solves it, against
//! the root of the scalar moment balance `k φ = m g (l/2) cos φ` found here
//! by safeguarded Newton (no mstar code), and the hinge's load `m g`.

use std::path::Path;

use super::{Case, Level, Row};
use mstar::equilibrium::EquilibriumOptions;
use mstar::file::{Mechanism, MechanismFile};

/// `models/torsion-bar.toml`.
pub(super) const CASE: Case = Case {
    model: "torsion-bar.toml",
    run: torsion,
};

const MODEL: &str = "torsion-bar.toml";
/// The file's data: mass (kg), length (m), g (m/s²), stiffness (N m/rad).
const M: f64 = 1.0;
const L: f64 = 1.0;
const G: f64 = 9.81;
const K: f64 = 5.0;

/// The droop `φ` below the horizontal: the root in `(0, π/2)` of
/// `f(φ) = k φ − m g (l/2) cos φ` (`f(0) < 0 < f(π/2)`, `f' > 0`), by Newton
/// steps kept inside a shrinking bracket (bisection when a step leaves it).
fn droop(k: f64, m: f64, g: f64, l: f64) -> f64 {
    let w = m * g * l / 2.0;
    let f = |phi: f64| k * phi - w * phi.cos();
    let (mut lo, mut hi) = (0.0, std::f64::consts::FRAC_PI_2);
    let mut phi = 0.5 * (lo + hi);
    for _ in 0..200 {
        let value = f(phi);
        if value < 0.0 {
            lo = phi;
        } else {
            hi = phi;
        }
        let newton = phi - value / (k + w * phi.sin());
        let next = if newton > lo && newton < hi {
            newton
        } else {
            0.5 * (lo + hi)
        };
        if (next - phi).abs() <= 2.0 * f64::EPSILON * phi || hi - lo <= 2.0 * f64::EPSILON {
            return next;
        }
        phi = next;
    }
    phi
}

/// The equilibrium of the file, as `mstar equilibrium` finds it: the file's
/// pose, `mstar::equilibrium::solve` with the default options. Returns the
/// bar's angle, `‖λ‖₂` of the hinge, and the Newton steps taken.
fn solve(models: &Path) -> Result<(f64, f64, usize), String> {
    let file = MechanismFile::load_with(&models.join(MODEL), &[]).map_err(|e| e.to_string())?;
    let Mechanism::Planar(planar) = &file.mechanism else {
        return Err(format!("{MODEL}: not a planar model"));
    };
    let bar = planar
        .body("bar")
        .ok_or(format!("{MODEL}: no body 'bar'"))?;
    let theta = bar
        .theta
        .ok_or(format!("{MODEL}: 'bar' is not a rigid body"))?;
    let sys = mstar::run::lookup(&file.mechanism);
    let eq =
        mstar::equilibrium::solve(sys, &sys.initial_position(), &EquilibriumOptions::default())
            .map_err(|e| format!("{MODEL}: {e}"))?;
    let load = eq.lambda.iter().map(|l| l * l).sum::<f64>().sqrt();
    Ok((eq.u[theta], load, eq.iterations))
}

/// The rows: the angle and the hinge's load. Tolerances from the solver's
/// convergence test `‖r‖∞ ≤ 1e-11 F` (docs/analysis.md), `F` the largest
/// force scale met, at most `m g + k π` for a bar within a half-turn: an
/// unbalanced moment `r` moves the angle by `r / k_eff`, `k_eff = k + m g
/// (l/2) sin φ` the stiffness of the potential there, and the hinge's force
/// by `r`; plus round-off.
fn torsion(models: &Path, _level: Level) -> Result<Vec<Row>, String> {
    let phi = droop(K, M, G, L);
    let (theta, load, steps) = solve(models)?;
    let force_scale = M * G + K * std::f64::consts::PI;
    let k_eff = K + M * G * L / 2.0 * phi.sin();
    let angle_tol = 1e-11 * force_scale / k_eff + 8.0 * f64::EPSILON * phi;
    let load_tol = 1e-11 * force_scale + 8.0 * f64::EPSILON * M * G;
    Ok(vec![
        Row {
            model: MODEL.to_string(),
            quantity: format!("equilibrium angle −θ (mstar equilibrium, {steps} Newton steps)"),
            reference: format!("root of k φ = m g (l/2) cos φ: {phi:.15} rad"),
            ours: format!("{:.15} rad", -theta),
            error: (-theta - phi).abs(),
            tolerance: angle_tol,
        },
        Row {
            model: MODEL.to_string(),
            quantity: "the hinge's load ‖λ‖ at the equilibrium".to_string(),
            reference: format!("m g = {:.12} N", M * G),
            ours: format!("{load:.12} N"),
            error: (load - M * G).abs(),
            tolerance: load_tol,
        },
    ])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_root_balances_the_moments() {
        for (k, expect_small) in [(5.0, false), (1e4, true)] {
            let phi = droop(k, M, G, L);
            let w = M * G * L / 2.0;
            assert!(phi > 0.0 && phi < std::f64::consts::FRAC_PI_2);
            // One rounding per term of f: |f(φ)| within a few ε of its terms.
            assert!((k * phi - w * phi.cos()).abs() <= 4.0 * f64::EPSILON * k * phi);
            // A stiff spring barely droops: φ → w / k.
            if expect_small {
                assert!((phi - w / k).abs() <= (w / k).powi(3));
            }
        }
    }

    #[test]
    fn mstar_equilibrium_finds_the_root_and_the_weight() {
        let models = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models");
        let rows = torsion(&models, Level::Quick).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(rows.len(), 2);
        assert!(rows.iter().all(Row::pass), "{rows:#?}");
    }
}
