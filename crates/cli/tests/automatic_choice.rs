//! The automatic KKT backend and Newton variant (docs/model-format.md,
//! `[simulation]` `kkt` and `newton`; docs/performance.md, "Backends
//! compared" and "Newton variant"), as the run's summary names them: the
//! Schur backends wherever they apply, the dense LU on a small model they
//! do not take; once per step only on a model of more than 24 unknowns
//! whose Jacobians are cheap.

mod common;

use common::{model, mstar, text};

/// The summary's "KKT solver: …; Newton: …" line of a short run of `name`.
fn choice(name: &str) -> String {
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
    summary
        .lines()
        .find(|l| l.starts_with("KKT solver: "))
        .unwrap_or_else(|| panic!("{name}: no KKT line in {summary}"))
        .to_string()
}

#[test]
fn small_models_take_schur_with_modified_newton() {
    // 9 coordinates and 9 constraint rows; a diagonal mass block per bar.
    let four_bar = choice("four-bar.toml");
    assert!(
        four_bar.starts_with("KKT solver: schur; Newton: modified"),
        "{four_bar}"
    );
    // Spatial bodies' unsymmetric tangent: schur-lu.
    let top = choice("spatial/top.toml");
    assert!(
        top.starts_with("KKT solver: schur-lu; Newton: modified"),
        "{top}"
    );
}

#[test]
fn a_massless_coordinate_keeps_the_dense_lu() {
    // The paper's pendulum: the angle of a point mass has no inertia, which
    // the Schur backends (M without BᵀB) cannot factor.
    let pendulum = choice("pendulum.toml");
    assert!(
        pendulum.starts_with("KKT solver: dense; Newton: modified"),
        "{pendulum}"
    );
}

#[test]
fn once_per_step_on_large_models_with_cheap_jacobians_only() {
    let chain = choice("n-four-bar.toml");
    assert!(
        chain.starts_with("KKT solver: schur; Newton: once per step"),
        "{chain}"
    );
    // Revolute, universal, prismatic and cylindrical joints: Hessians by
    // dual numbers, a fresh Jacobian a step costs twice the run.
    let crank = choice("spatial/slider-crank.toml");
    assert!(
        crank.starts_with("KKT solver: schur-lu; Newton: modified"),
        "{crank}"
    );
}
