//! The automatic KKT backend and Newton variant (docs/model-format.md,
//! `[simulation]` `kkt` and `newton`; docs/performance.md, "Backends
//! compared" and "Newton variant"), as the run's summary names them: the
//! Schur backends wherever they apply, the dense LU on a small model they
//! do not take; once per step only on a model of more than 24 unknowns
//! whose Jacobians are cheap, or when a run's sensitivities find modified
//! Newton slow from their factorizations.

mod common;

use common::{model, mstar, text};

/// Asserts that a short run of `name` names `expected` ("KKT solver: …;
/// Newton: …") in its summary.
fn assert_choice(name: &str, expected: &str) {
    let run = mstar(&[
        "run",
        &model(name),
        "--t-end",
        "0.002",
        "--out",
        "/dev/null",
    ]);
    assert!(run.status.success(), "{name}: {}", text(&run.stderr));
    let summary = text(&run.stdout);
    let line = summary
        .lines()
        .find(|l| l.starts_with("KKT solver: "))
        .unwrap_or_else(|| panic!("{name}: no KKT line in {summary}"));
    assert!(line.starts_with(expected), "{name}: {line}");
}

#[test]
fn small_models_take_schur_with_modified_newton() {
    // 9 coordinates and 9 constraint rows; a diagonal mass block per bar.
    assert_choice("four-bar.toml", "KKT solver: schur; Newton: modified");
    // Spatial bodies' unsymmetric tangent: schur-lu.
    assert_choice("spatial/top.toml", "KKT solver: schur-lu; Newton: modified");
}

#[test]
fn a_massless_coordinate_keeps_the_dense_lu() {
    // The paper's pendulum: the angle of a point mass has no inertia, which
    // the Schur backends (M without BᵀB) cannot factor.
    assert_choice("pendulum.toml", "KKT solver: dense; Newton: modified");
}

#[test]
fn once_per_step_on_large_models_with_cheap_jacobians_only() {
    assert_choice(
        "n-four-bar.toml",
        "KKT solver: schur; Newton: once per step",
    );
    // Revolute, universal, prismatic and cylindrical joints: a fresh
    // factorization a step (blocks with the ground joints' rows) costs more
    // than modified Newton's extra iterations.
    assert_choice(
        "spatial/slider-crank.toml",
        "KKT solver: schur-lu; Newton: modified",
    );
}

/// The summary of a short run of `name` with `--sensitivity key`.
fn summary_with_sensitivity(name: &str, key: &str, t_end: &str) -> String {
    let run = mstar(&[
        "run",
        &model(name),
        "--t-end",
        t_end,
        "--out",
        "/dev/null",
        "--sensitivity",
        key,
    ]);
    assert!(run.status.success(), "{name}: {}", text(&run.stderr));
    text(&run.stdout)
}

/// With sensitivities, modified Newton (the automatic choice) starts each
/// step from their factorization at the converged state. On the spinning
/// top that takes about four iterations a step (the Jacobian one step old,
/// the top turning 0.03 rad a step), so the run turns to once per step after
/// its first 16 such steps and says so, with their mean (at least 1.5); the four-bar converges in one and
/// keeps modified Newton.
#[test]
fn sensitivities_turn_modified_newton_into_once_per_step_where_it_is_slow() {
    let top = summary_with_sensitivity("spatial/top.toml", "body.top.mass", "0.05");
    let line = top
        .lines()
        .find(|l| l.starts_with("Newton: once per step from t = "))
        .unwrap_or_else(|| panic!("no switch in {top}"));
    let mean: f64 = line
        .split("(modified Newton took ")
        .nth(1)
        .and_then(|rest| rest.split(' ').next())
        .and_then(|x| x.parse().ok())
        .unwrap_or_else(|| panic!("no mean in {line}"));
    assert!(mean >= 1.5, "{line}");
    let four_bar = summary_with_sensitivity("four-bar.toml", "body.coupler.mass", "0.05");
    assert!(
        four_bar.contains("KKT solver: schur; Newton: modified"),
        "{four_bar}"
    );
    assert!(!four_bar.contains("once per step"), "{four_bar}");
}
