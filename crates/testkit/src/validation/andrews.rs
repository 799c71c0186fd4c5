//! Andrews' squeezing mechanism against the IVP test set (Mazzia et al.,
//! problem "andrews"; Hairer & Wanner II §VII.7): the seven angles at
//! t = 0.03 s, published to 16 digits (PSIDE at rtol = atol = 1e-14).

use std::path::Path;

use super::{Case, Level, Row, samples};

/// `models/andrews.toml`.
pub(super) const CASE: Case = Case {
    model: "andrews.toml",
    run: andrews,
};

/// The test set's `β, Θ, γ, Φ, δ, Ω, ε` at t = 0.03 s.
pub const REFERENCE: [(&str, f64); 7] = [
    ("β", 0.158_107_711_962_990_4e2),
    ("Θ", -0.157_563_710_598_429_8e2),
    ("γ", 0.408_222_401_307_310_1e-1),
    ("Φ", -0.534_730_116_322_694_8),
    ("δ", 0.524_409_965_880_530_4),
    ("Ω", 0.534_730_116_322_694_8),
    ("ε", 0.104_808_074_104_226_3e1),
];

/// The test set's angles `β, Θ, γ, Φ, δ, Ω, ε` from the bodies' absolute
/// angles K1 … K7 of `models/andrews.toml`: K1 β, K2 β + Θ, K3 γ, K4 Φ + δ,
/// K5 δ, K6 Ω + ε, K7 ε (the model file's header).
#[must_use]
pub fn angles(a: [f64; 7]) -> [f64; 7] {
    [
        a[0],
        a[1] - a[0],
        a[2],
        a[3] - a[4],
        a[4],
        a[5] - a[6],
        a[6],
    ]
}

fn andrews(models: &Path, _: Level) -> Result<Vec<Row>, String> {
    // One level: the file's h = 1e-6 s runs in under a second.
    let model = super::load(models, "andrews.toml", &[])?;
    let mut theta = [0usize; 7];
    for (k, slot) in theta.iter_mut().enumerate() {
        let name = format!("K{}", k + 1);
        *slot = model
            .system
            .body(&name)
            .and_then(|b| b.theta)
            .ok_or(format!("andrews.toml: no rigid body '{name}'"))?;
    }
    let run = samples(models, "andrews.toml", &[])?;
    let last = run.last().ok_or("andrews.toml: no samples")?;
    if (last.t - 0.03).abs() > 1e-12 {
        return Err(format!("andrews.toml ends at t = {}, not 0.03", last.t));
    }
    let ours = angles(theta.map(|i| last.u[i]));
    Ok(REFERENCE
        .iter()
        .zip(ours)
        .map(|(&(name, want), got)| Row {
            model: "andrews.toml".to_string(),
            quantity: format!("{name} at t = 0.03 s, relative"),
            reference: format!("{want:.16} (test set)"),
            ours: format!("{got:.16}"),
            error: ((got - want) / want).abs(),
            tolerance: 1e-6,
        })
        .collect())
}
