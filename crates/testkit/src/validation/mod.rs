//! The classic mechanisms of `models/` against independent references — the
//! table of `cargo xtask validate` and `docs/validation.md`, and the tests of
//! `crates/mstar/tests/validation.rs`.
//!
//! Each case loads its model file, runs it through [`mstar::run::simulate`]
//! (what `mstar run` does; the vibration modes through [`mstar::modes`], what
//! `mstar modes` does) and compares with a reference that shares no code
//! with the integration path: a closed form, a loop-closure solve, the RK4
//! oracle on minimal coordinates (`mstar-rk4`), published values, a closed
//! form in elliptic functions; the static equilibrium of `torsion-bar.toml`
//! is found by `mstar::equilibrium::solve` (what `mstar equilibrium` runs)
//! and compared with a scalar root. Tolerances come from the method (second
//! order: errors fall by 4 when `h` halves) or from the source (the test
//! set's digits, the benchmark's threshold).

pub mod andrews;
mod crank_and_spring;
mod elliptic;
mod iftomm_a01;
mod iftomm_a05;
mod kinematics;
mod modes;
mod n_four_bar;
mod order;
mod parallelogram;
mod pendulums;
mod sensitivity;
mod slider_crank;
mod spatial;
mod top;
mod torsion_bar;

use std::path::Path;

use mstar::file::{Mechanism, MechanismFile, ModelFile};
use mstar::model::SampleRef;
use mstar::model::spatial::SpatialSystem;

/// One line of the validation table.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// The model file, e.g. `andrews.toml`.
    pub model: String,
    /// What is compared.
    pub quantity: String,
    /// The reference and where it comes from.
    pub reference: String,
    /// Our value, as shown.
    pub ours: String,
    /// The error measured.
    pub error: f64,
    /// The largest error allowed.
    pub tolerance: f64,
}

impl Row {
    /// Whether the error is within the tolerance (a NaN error fails).
    #[must_use]
    pub fn pass(&self) -> bool {
        self.error <= self.tolerance
    }
}

/// How hard a case works: `Quick` for `cargo test` (short spans, few step
/// sizes), `Tight` for `cargo xtask validate` (the full spans of the
/// references).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Level {
    /// Seconds in all, for the test suite.
    Quick,
    /// The published spans and step sizes.
    Tight,
}

/// A validation case: a name and its rows.
pub struct Case {
    /// The model file it validates, in `models/`.
    pub model: &'static str,
    /// Runs it with the model files of `models`.
    pub run: fn(&Path, Level) -> Result<Vec<Row>, String>,
}

/// Every case, in the order of the table.
pub const CASES: &[Case] = &[
    pendulums::PENDULUM,
    pendulums::DOUBLE_PENDULUM,
    pendulums::DOUBLE_PENDULUM_JSON,
    slider_crank::CASE,
    slider_crank::FOUR_BAR,
    crank_and_spring::CASE,
    andrews::CASE,
    n_four_bar::CASE,
    parallelogram::CASE,
    top::TOP,
    top::TOP_STEADY,
    spatial::DZHANIBEKOV,
    spatial::TILTED_HINGE,
    spatial::DOUBLE_PENDULUM,
    spatial::BRICARD,
    spatial::SLIDER_CRANK,
    modes::DOUBLE_PENDULUM,
    modes::SPRING_CHAIN,
    modes::DAMPED,
    iftomm_a01::CASE,
    iftomm_a05::CASE,
    torsion_bar::CASE,
    sensitivity::PENDULUM,
    sensitivity::SLIDER_CRANK,
];

/// A model file of `models`, with overrides (`simulation.h=…`).
fn load(models: &Path, name: &str, set: &[String]) -> Result<ModelFile, String> {
    ModelFile::load_with(&models.join(name), set).map_err(|e| e.to_string())
}

/// A spatial model file of `models`, with overrides.
fn load_spatial(models: &Path, name: &str, set: &[String]) -> Result<SpatialSystem, String> {
    match MechanismFile::load_with(&models.join(name), set)
        .map_err(|e| e.to_string())?
        .mechanism
    {
        Mechanism::Spatial(sys) => Ok(sys),
        Mechanism::Planar(_) => Err(format!("{name}: not a spatial model")),
    }
}

/// Every sample's `(t, u, u̇, λ)` of a model file's run, planar or spatial
/// (its settings, with overrides), as `mstar run` would compute them.
fn samples(models: &Path, name: &str, set: &[String]) -> Result<Vec<Sample>, String> {
    let model = MechanismFile::load_with(&models.join(name), set).map_err(|e| e.to_string())?;
    let mut out = Vec::new();
    let sys = mstar::run::lookup(&model.mechanism);
    mstar::run::simulate(sys, &model.simulation, &mut |s: &SampleRef<'_>| {
        out.push(Sample {
            t: s.t,
            u: s.u.to_vec(),
            v: s.v.to_vec(),
            lambda: s.lambda.to_vec(),
            energy: s.energy(),
            kinetic: s.kinetic,
        });
    })
    .map_err(|e| format!("{name}: {e}"))?;
    Ok(out)
}

/// What the cases keep of a sample.
#[derive(Clone, Debug)]
struct Sample {
    t: f64,
    u: Vec<f64>,
    v: Vec<f64>,
    lambda: Vec<f64>,
    energy: f64,
    kinetic: f64,
}

/// The larger of two errors, NaN winning.
fn worse(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::NAN
    } else {
        a.max(b)
    }
}

/// The table as Markdown: model, quantity, reference, ours, error,
/// tolerance, pass.
#[must_use]
pub fn markdown(rows: &[Row]) -> String {
    let mut out = String::from(
        "| model | quantity | reference | ours | error | tolerance | pass |\n|---|---|---|---|---|---|---|\n",
    );
    // A `|` in a cell (|Δx|) would end it.
    let cell = |s: &str| s.replace('|', "\\|");
    for r in rows {
        out.push_str(&format!(
            "| {} | {} | {} | {} | {:.2e} | {:.1e} | {} |\n",
            cell(&r.model),
            cell(&r.quantity),
            cell(&r.reference),
            cell(&r.ours),
            r.error,
            r.tolerance,
            if r.pass() { "yes" } else { "**no**" }
        ));
    }
    out
}
