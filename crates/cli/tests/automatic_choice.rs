//! The automatic KKT backend and Newton variant (docs/model-format.md,
//! `[simulation]` `kkt` and `newton`; docs/performance.md, "Backends
//! compared" and "Newton variant"), as the run's summary names them: the
//! Schur backends wherever they apply, the dense LU on a small model they
//! do not take; once per step only on a model of more than 24 unknowns
//! whose Jacobians are cheap.

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
    // Revolute, universal, prismatic and cylindrical joints: Hessians by
    // dual numbers, a fresh Jacobian a step costs twice the run.
    assert_choice(
        "spatial/slider-crank.toml",
        "KKT solver: schur-lu; Newton: modified",
    );
}
