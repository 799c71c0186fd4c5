//! The classic mechanisms of `models/` against their independent references
//! (`mstar_testkit::validation`, docs/validation.md), on the short spans of
//! `Level::Quick`; `cargo xtask validate` runs the full ones.

use std::path::{Path, PathBuf};

use mstar_testkit::validation::{CASES, Level, Row};

fn models() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models")
}

/// Every case of `model` (its references, and for some the sensitivities
/// of `mstar_testkit::validation::sensitivity`).
fn check(model: &str) {
    let cases: Vec<_> = CASES.iter().filter(|c| c.model == model).collect();
    assert!(!cases.is_empty(), "no validation case for {model}");
    for case in cases {
        let rows = (case.run)(&models(), Level::Quick).unwrap_or_else(|e| panic!("{e}"));
        assert!(!rows.is_empty(), "{model}: no rows");
        let failed: Vec<&Row> = rows.iter().filter(|r| !r.pass()).collect();
        assert!(failed.is_empty(), "{failed:#?}");
    }
}

#[test]
fn the_paper_s_pendulum_converges_to_rk4_at_second_order() {
    check("pendulum.toml");
}

#[test]
fn the_double_pendulum_converges_to_rk4_at_second_order() {
    check("double-pendulum.toml");
}

#[test]
fn the_slider_crank_follows_its_closed_form_and_inverse_dynamics() {
    check("slider-crank.toml");
}

#[test]
fn the_four_bar_follows_its_loop_closure() {
    check("four-bar.toml");
}

#[test]
fn the_json_double_pendulum_converges_to_rk4_at_second_order() {
    check("double-pendulum.json");
}

#[test]
fn the_example_s_slider_and_motor_follow_their_equations() {
    check("crank-and-spring.toml");
}

#[test]
fn andrews_squeezing_mechanism_matches_the_test_set() {
    check("andrews.toml");
}

#[test]
fn the_n_four_bar_passes_its_singular_positions_as_its_minimal_form() {
    check("n-four-bar.toml");
}

#[test]
fn the_third_crank_leaves_the_parallelogram_s_motion_as_it_was() {
    check("parallelogram-third-crank.toml");
}

#[test]
fn the_heavy_top_keeps_its_invariants_and_converges_to_the_index1_reference() {
    check("spatial/top.toml");
}

#[test]
fn the_heavy_top_precesses_and_nutates_at_the_closed_form_rates() {
    check("spatial/top-steady.toml");
}

#[test]
fn the_free_body_flips_at_the_closed_form_period() {
    check("spatial/dzhanibekov.toml");
}

#[test]
fn the_tilted_hinge_swings_as_a_one_angle_pendulum() {
    check("spatial/tilted-hinge.toml");
}

#[test]
fn the_spatial_double_pendulum_converges_to_the_index1_reference_at_second_order() {
    check("spatial/double-pendulum.toml");
}

#[test]
fn bricard_s_mechanism_conserves_energy_with_minimum_norm_multipliers() {
    check("spatial/bricard.toml");
}

#[test]
fn the_spatial_slider_crank_converges_to_the_index1_reference_at_second_order() {
    check("spatial/slider-crank.toml");
}

#[test]
fn every_model_with_a_reference_is_validated() {
    // A model file in models/ is a reference case, or the reference of one
    // (parallelogram.toml), or an example (crank-and-spring, the sensors of
    // the four-bar, the JSON copy).
    let examples = [
        "crank-and-spring.toml",
        "four-bar-sensors.toml",
        "double-pendulum.json",
        "parallelogram.toml",
    ];
    for dir in ["", "spatial/"] {
        for entry in std::fs::read_dir(models().join(dir)).expect("models/") {
            let entry = entry.expect("entry");
            if entry.path().is_dir() {
                continue;
            }
            let name = format!("{dir}{}", entry.file_name().to_string_lossy());
            if examples.contains(&name.as_str()) {
                continue;
            }
            assert!(
                CASES.iter().any(|c| c.model == name),
                "{name} has no validation case"
            );
        }
    }
}

#[test]
fn a_row_fails_on_nan() {
    let row = Row {
        model: "m".to_string(),
        quantity: "q".to_string(),
        reference: "r".to_string(),
        ours: "o".to_string(),
        error: f64::NAN,
        tolerance: 1.0,
    };
    assert!(!row.pass());
}
