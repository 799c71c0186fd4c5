//! Vibration modes (`mstar::modes`, what `mstar modes` computes: about the
//! static equilibrium found from the file's pose) against closed forms
//! derived by hand: a double pendulum of point masses, a fixed–fixed spring
//! chain, a damped single mode. Tolerance `10⁻⁹` relative: the equilibrium
//! is found to `10⁻¹¹` of the force scale, which moves `ω²` by about as
//! much, and the eigensolvers add round-off (`10⁻¹⁵`–`10⁻¹³`).

use std::f64::consts::{PI, TAU};
use std::path::Path;

use mstar::equilibrium::EquilibriumOptions;
use mstar::file::MechanismFile;
use mstar::modes::{Modes, ModesOptions};

use super::{Case, Level, Row};

/// `models/double-pendulum-modes.toml`.
pub(super) const DOUBLE_PENDULUM: Case = Case {
    model: "double-pendulum-modes.toml",
    run: double_pendulum,
};

/// `models/spring-chain-modes.toml`.
pub(super) const SPRING_CHAIN: Case = Case {
    model: "spring-chain-modes.toml",
    run: spring_chain,
};

/// `models/damped-mode.toml`.
pub(super) const DAMPED: Case = Case {
    model: "damped-mode.toml",
    run: damped,
};

/// Relative tolerance of a frequency, absolute of a damping ratio.
const TOL: f64 = 1e-9;

/// The lowest `count` modes of a model file about its equilibrium.
fn modes_of(models: &Path, name: &str, count: usize) -> Result<Modes, String> {
    let file = MechanismFile::load_with(&models.join(name), &[]).map_err(|e| e.to_string())?;
    let sys = mstar::run::lookup(&file.mechanism);
    let u0 = sys.initial_position();
    let eq = mstar::equilibrium::solve(sys, &u0, &EquilibriumOptions::default())
        .map_err(|e| format!("{name}: {e}"))?;
    let options = ModesOptions {
        count,
        ..ModesOptions::default()
    };
    mstar::modes::modes(sys, &eq.u, &eq.lambda, &options).map_err(|e| format!("{name}: {e}"))
}

/// The row of one frequency, Hz, relative error.
fn frequency_row(model: &str, k: usize, reference: &str, want: f64, got: f64) -> Row {
    let error = ((got - want) / want).abs();
    Row {
        model: model.to_string(),
        quantity: format!("f of mode {k} (|s|/2π), relative"),
        reference: format!("{reference} = {want:.10} Hz"),
        ours: format!("{got:.10} Hz"),
        error: if error.is_nan() { f64::NAN } else { error },
        tolerance: TOL,
    }
}

fn double_pendulum(models: &Path, _: Level) -> Result<Vec<Row>, String> {
    let name = "double-pendulum-modes.toml";
    let found = modes_of(models, name, 2)?;
    let (g, l) = (9.81_f64, 1.0_f64);
    let rows = found
        .modes
        .iter()
        .zip([("−", -1.0), ("+", 1.0)])
        .enumerate()
        .map(|(k, (mode, (sign, s)))| {
            let want = ((g / l) * (2.0 + s * 2.0_f64.sqrt())).sqrt() / TAU;
            let reference = format!("√((g/l)(2 {sign} √2))/2π");
            frequency_row(name, k + 1, &reference, want, mode.frequency_hz)
        })
        .collect();
    Ok(rows)
}

fn spring_chain(models: &Path, _: Level) -> Result<Vec<Row>, String> {
    let name = "spring-chain-modes.toml";
    let (n, k, m) = (5_usize, 100.0_f64, 1.0_f64);
    let found = modes_of(models, name, n)?;
    let rows = found
        .modes
        .iter()
        .enumerate()
        .map(|(j, mode)| {
            let arg = (j + 1) as f64 * PI / (2.0 * (n as f64 + 1.0));
            let want = 2.0 * (k / m).sqrt() * arg.sin() / TAU;
            let reference = format!("2√(k/m) sin({}π/12)/2π", j + 1);
            frequency_row(name, j + 1, &reference, want, mode.frequency_hz)
        })
        .collect();
    Ok(rows)
}

fn damped(models: &Path, _: Level) -> Result<Vec<Row>, String> {
    let name = "damped-mode.toml";
    let (m, k, c) = (2.0_f64, 50.0_f64, 3.0_f64);
    let found = modes_of(models, name, 1)?;
    let mode = found.modes.first().ok_or("no mode")?;
    let (re, im) = (-c / (2.0 * m), (k / m - (c / (2.0 * m)).powi(2)).sqrt());
    let s_error = (mode.s.0 - re).hypot(mode.s.1 - im) / re.hypot(im);
    let zeta = c / (2.0 * (k * m).sqrt());
    Ok(vec![
        Row {
            model: name.to_string(),
            quantity: "s of the mode, relative".to_string(),
            reference: format!("−c/2m + i√(k/m − (c/2m)²) = {re} + {im:.10}i 1/s"),
            ours: format!("{:.10} + {:.10}i 1/s", mode.s.0, mode.s.1),
            error: s_error,
            tolerance: TOL,
        },
        Row {
            model: name.to_string(),
            quantity: "damping ratio ζ = −Re(s)/|s|".to_string(),
            reference: format!("c/(2√(k m)) = {zeta}"),
            ours: format!("{:.10}", mode.damping_ratio),
            error: (mode.damping_ratio - zeta).abs(),
            tolerance: TOL,
        },
    ])
}
