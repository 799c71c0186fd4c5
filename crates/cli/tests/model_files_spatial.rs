//! Spatial model files (`format = "mstar.spatial/1"`, docs/model-format.md,
//! "Spatial models"): the documented top runs through `mstar run` with the
//! documented CSV columns; every file in `models/spatial/` checks and runs
//! with its constraints held; malformed files are errors at
//! `FILE:LINE:COLUMN` naming the key; an orientation off unit norm is
//! normalized with a warning; and the reaction columns are the closed-form
//! forces of two bars — one hanging at rest from a ball joint (its weight,
//! upward), one released horizontal on a hinge (the hinge carries
//! `m g (1 − m L²/4 / (J + m L²/4))`, a quarter of the weight for a slender
//! bar). Bricard's mechanism has one degree of freedom and one redundant
//! row, and runs with minimum-norm multipliers.

use std::path::{Path, PathBuf};

mod common;

use common::{mstar, scratch};
use mstar::file::{Format, Mechanism, MechanismFile};
use mstar::{SampleRef, System};

fn models() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/spatial")
}

/// The document of the brief and of docs/model-format.md, as written.
const TOP: &str = r#"format = "mstar.spatial/1"
gravity = [0.0, 0.0, -9.81]

[[body]]
name = "top"
mass = 2.0
inertia = [0.05, 0.05, 0.08]
position = [0.0, 0.0, 0.25]
orientation = [1.0, 0.0, 0.0, 0.0]
velocity = [0.0, 0.0, 0.0]
angular_velocity = [0.0, 0.0, 30.0]

[[joint]]
name = "tip"
type = "spherical"
bodies = ["ground", "top"]
points = [[0.0, 0.0, 0.0], [0.0, 0.0, -0.25]]

[simulation]
t_end = 0.05
rotational_mass = "singular"
"#;

/// The CSV file `path`: its header and its rows.
fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).expect("the CSV file");
    let mut lines = text.lines();
    let header = lines
        .next()
        .expect("a header")
        .split(',')
        .map(String::from)
        .collect();
    let rows = lines
        .map(|l| l.split(',').map(|x| x.parse().expect("a number")).collect())
        .collect();
    (header, rows)
}

fn column(header: &[String], name: &str) -> usize {
    header
        .iter()
        .position(|h| h == name)
        .unwrap_or_else(|| panic!("no column {name} in {header:?}"))
}

#[test]
fn the_documented_top_runs_and_writes_the_documented_columns() {
    let dir = scratch("top");
    let model = dir.join("top.toml");
    std::fs::write(&model, TOP).expect("write");
    let out = dir.join("top.csv");
    let run = mstar(&[
        "run",
        model.to_str().expect("a UTF-8 path"),
        "--out",
        out.to_str().expect("a UTF-8 path"),
    ]);
    assert_eq!(
        run.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let (header, rows) = read_csv(&out);
    let mut expected = vec!["t".to_string()];
    for prefix in ["u", "v", "a"] {
        for c in ["x", "y", "z", "e0", "e1", "e2", "e3"] {
            expected.push(format!("{prefix}:top.{c}"));
        }
    }
    // The normalization row and the 3 rows of the ball joint, by name.
    expected.extend(
        [
            "lambda:top.norm",
            "lambda:tip.x",
            "lambda:tip.y",
            "lambda:tip.z",
        ]
        .map(String::from),
    );
    expected.extend(["energy", "iterations", "residual", "constraint"].map(String::from));
    for c in ["fx", "fy", "fz", "tx", "ty", "tz"] {
        expected.push(format!("reaction:tip.{c}"));
    }
    assert_eq!(header, expected);
    // The top stands upright and spins: it stays upright, e0 = cos(ωt/2).
    let last = rows.last().expect("rows");
    let t = last[0];
    assert!((t - 0.05).abs() < 1e-12);
    let e0 = last[column(&header, "u:top.e0")];
    let e3 = last[column(&header, "u:top.e3")];
    // (generalized-α's phase error at ω h = 0.03 over 50 steps: 1e-5)
    assert!((e0 - (15.0 * t).cos()).abs() < 1e-4, "{e0}");
    assert!((e3 - (15.0 * t).sin()).abs() < 1e-4, "{e3}");
    assert!(last[column(&header, "u:top.e1")].abs() < 1e-9);
    // Upright at rest on its tip: the tip carries the weight, m g upward.
    let fz = last[column(&header, "reaction:tip.fz")];
    assert!((fz - 2.0 * 9.81).abs() < 1e-6, "{fz}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn every_spatial_model_checks_and_runs_with_its_constraints_held() {
    let mut count = 0;
    for entry in std::fs::read_dir(models()).expect("models/spatial") {
        let path = entry.expect("entry").path();
        if path.extension().and_then(|e| e.to_str()) != Some("toml") {
            continue;
        }
        let check = mstar(&["check", path.to_str().expect("a UTF-8 path")]);
        assert_eq!(
            check.status.code(),
            Some(0),
            "{}: {}",
            path.display(),
            String::from_utf8_lossy(&check.stderr)
        );
        let file = MechanismFile::load_with(&path, &["simulation.t_end=0.1".to_string()])
            .unwrap_or_else(|e| panic!("{e}"));
        assert!(file.warnings.is_empty(), "{:?}", file.warnings);
        let Mechanism::Spatial(sys) = &file.mechanism else {
            panic!("{} is not spatial", path.display());
        };
        let mut phi = vec![0.0; sys.n_constraints()];
        let mut worst = 0.0f64;
        let mut last = 0.0;
        mstar::run::simulate(sys, &file.simulation, &mut |s: &SampleRef<'_>| {
            sys.phi_into(s.t, s.u, &mut phi);
            let v = mstar::kkt::max_abs(&phi);
            worst = if v.is_nan() || v > worst { v } else { worst };
            last = s.t;
        })
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert!(worst < 1e-8, "{}: ‖Φ‖∞ = {worst:e}", path.display());
        assert!((last - 0.1).abs() < 1e-12);
        count += 1;
    }
    assert_eq!(count, 8);
}

/// The error of `text` read as `m.toml`.
fn error(text: &str) -> String {
    match MechanismFile::parse(text, "m.toml", Format::Toml) {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn malformed_files_are_errors_at_the_key() {
    let e = error(&TOP.replace("inertia =", "inertai ="));
    assert_eq!(
        e,
        "m.toml:7:1: body 'top': unknown key 'inertai' (did you mean 'inertia'?)"
    );
    // A misspelt joint key: the typo named where it is written, not the
    // key it stands for reported missing at the table's header.
    let e = error(&TOP.replace("points =", "point ="));
    assert!(
        e.contains("unknown key 'point' (did you mean 'points'?)"),
        "{e}"
    );
    let e = error(&TOP.replace("[1.0, 0.0, 0.0, 0.0]", "[1.0, 0.0, 0.0]"));
    assert_eq!(
        e,
        "m.toml:9:15: body 'top': orientation: expected 4 numbers, found 3"
    );
    let e = error(&TOP.replace("\"ground\", \"top\"", "\"ground\", \"tpo\""));
    assert_eq!(
        e,
        "m.toml:16:10: joint 'tip': bodies: no body or point mass is called 'tpo' (known: ground, top)"
    );
    let e = error(&TOP.replace("\"spherical\"", "\"revolute\""));
    assert!(
        e.starts_with("m.toml:13:1: joint 'tip': the key 'axes' is missing"),
        "{e}"
    );
    let e = error(&TOP.replace(
        "type = \"spherical\"",
        "type = \"spherical\"\naxes = [[0, 0, 1], [0, 0, 1]]",
    ));
    assert!(
        e.starts_with("m.toml:16:8: joint 'tip': axes: a spherical joint has no axis"),
        "{e}"
    );
    // The global form is named as written.
    let e = error(&TOP.replace(
        "type = \"spherical\"",
        "type = \"spherical\"\naxis = [0, 0, 1]",
    ));
    assert!(
        e.starts_with(
            "m.toml:16:8: joint 'tip': axis: a spherical joint has no axis: 'axis' belongs to"
        ),
        "{e}"
    );
    let e = error(&TOP.replace("\"spherical\"", "\"ball\""));
    assert!(
        e.starts_with("m.toml:15:8: joint 'tip': type: 'ball' is not one of: spherical, revolute"),
        "{e}"
    );
    let e = error(&TOP.replace("mass = 2.0", "mass = -2.0"));
    assert_eq!(
        e,
        "m.toml:6:8: body 'top': mass: must be positive, in kg (got -2)"
    );
    // A builder error about a key, placed at the key (not at the body's
    // name): an inertia no rigid body has.
    let e = error(&TOP.replace("[0.05, 0.05, 0.08]", "[0.01, 0.01, 0.08]"));
    assert!(
        e.starts_with("m.toml:7:11: body 'top': inertia: no rigid body has this inertia"),
        "{e}"
    );
    // A planar-only file does not take the spatial setting.
    let planar = "format = \"mstar.planar/1\"\n[[point_mass]]\nname = \"p\"\nmass = 1.0\n\
                  position = [0.0, 0.0]\n[simulation]\nrotational_mass = \"singular\"\n";
    let e = error(planar);
    assert!(
        e.starts_with("m.toml:7:19: [simulation]: rotational_mass: applies to spatial models"),
        "{e}"
    );
}

#[test]
fn an_orientation_off_unit_norm_is_normalized_with_a_warning() {
    let text = TOP.replace("[1.0, 0.0, 0.0, 0.0]", "[2.0, 0.0, 0.0, 0.0]");
    let file = MechanismFile::parse(&text, "m.toml", Format::Toml).expect("valid");
    assert_eq!(file.warnings.len(), 1);
    assert!(
        file.warnings[0].starts_with("m.toml:9:15: body 'top': orientation: normalized"),
        "{:?}",
        file.warnings
    );
    let Mechanism::Spatial(sys) = &file.mechanism else {
        panic!("spatial")
    };
    assert_eq!(&sys.initial_position()[3..], &[1.0, 0.0, 0.0, 0.0]);
    // Within 1e-12 of 1: no warning.
    let close = TOP.replace("[1.0, 0.0, 0.0, 0.0]", "[1.0000000000001, 0.0, 0.0, 0.0]");
    let file = MechanismFile::parse(&close, "m.toml", Format::Toml).expect("valid");
    assert!(file.warnings.is_empty());
    // The command line prints it.
    let dir = scratch("warning");
    let model = dir.join("top.toml");
    std::fs::write(&model, &text).expect("write");
    let check = mstar(&["check", model.to_str().expect("a UTF-8 path")]);
    assert_eq!(check.status.code(), Some(0));
    let stderr = String::from_utf8_lossy(&check.stderr);
    assert!(
        stderr.contains("warning: ")
            && stderr.contains(":9:15: body 'top': orientation: normalized"),
        "{stderr}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// A bar of mass `m`, length `l` along x, attached at its end `[−l/2, 0, 0]`
/// to the ground at the origin by `joint` (extra keys in `extra`).
fn bar(joint: &str, extra: &str, centre: [f64; 3]) -> String {
    format!(
        r#"format = "mstar.spatial/1"

[[body]]
name = "bar"
mass = 2.0
inertia = [{ja}, {jt}, {jt}]
position = [{x}, {y}, {z}]
orientation = {p}

[[joint]]
name = "pin"
type = "{joint}"
bodies = ["ground", "bar"]
at = [0.0, 0.0, 0.0]
{extra}

[simulation]
t_end = 0.01
tol = 1e-12
newton = "full"
"#,
        ja = JA,
        jt = JT,
        x = centre[0],
        y = centre[1],
        z = centre[2],
        // Hanging: the bar's x axis points down (a quarter turn about y).
        p = if centre[2] < 0.0 {
            "[0.7071067811865476, 0.0, 0.7071067811865476, 0.0]"
        } else {
            "[1.0, 0.0, 0.0, 0.0]"
        },
    )
}

/// The bar's inertia about its centre: along it, and across it.
const JA: f64 = 1e-3;
const JT: f64 = 0.2;

/// Runs `text` and returns the CSV header and rows.
fn run_text(name: &str, text: &str) -> (Vec<String>, Vec<Vec<f64>>) {
    let dir = scratch(name);
    let model = dir.join("m.toml");
    std::fs::write(&model, text).expect("write");
    let out = dir.join("m.csv");
    let run = mstar(&[
        "run",
        model.to_str().expect("a UTF-8 path"),
        "--out",
        out.to_str().expect("a UTF-8 path"),
    ]);
    assert_eq!(
        run.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let csv = read_csv(&out);
    std::fs::remove_dir_all(&dir).ok();
    csv
}

#[test]
fn a_bar_hanging_at_rest_from_a_ball_joint_hangs_on_its_weight() {
    let (h, rows) = run_text("hanging", &bar("spherical", "", [0.0, 0.0, -0.5]));
    for row in &rows {
        let r = |c: &str| row[column(&h, &format!("reaction:pin.{c}"))];
        // On the bar, global axes: m g upward, through the centre of mass
        // (the joint point is straight above it): no moment.
        assert!((r("fz") - 2.0 * 9.81).abs() < 1e-7, "{}", r("fz"));
        for c in ["fx", "fy", "tx", "ty", "tz"] {
            assert!(r(c).abs() < 1e-7, "{c} = {}", r(c));
        }
    }
}

#[test]
fn a_bar_released_horizontal_on_a_hinge_loads_it_as_the_closed_form() {
    // Hinge axis y at the bar's end; released at rest, horizontal. Its
    // angular acceleration is α = m g l/2 / (J + m l²/4), its centre falls at
    // α l/2, and the hinge pushes up with F = m g − m α l/2, at the point
    // [−l/2, 0, 0] from the centre: moment (point − centre) × F = (0, F l/2, 0).
    let (m, g, l) = (2.0, 9.81, 1.0);
    let alpha = m * g * l / 2.0 / (JT + m * l * l / 4.0);
    let f = m * g - m * alpha * l / 2.0;
    let (h, rows) = run_text(
        "hinge",
        &bar("revolute", "axis = [0.0, 1.0, 0.0]", [0.5, 0.0, 0.0]),
    );
    let row = &rows[0];
    let r = |c: &str| row[column(&h, &format!("reaction:pin.{c}"))];
    assert!(
        (r("fz") - f).abs() < 1e-6 * f,
        "fz = {} against {f}",
        r("fz")
    );
    assert!((r("ty") - f * l / 2.0).abs() < 1e-6 * f, "ty = {}", r("ty"));
    for c in ["fx", "fy", "tx", "tz"] {
        assert!(r(c).abs() < 1e-6, "{c} = {}", r(c));
    }
}

#[test]
fn bricard_has_one_degree_of_freedom_and_a_redundant_row() {
    let path = models().join("bricard.toml");
    let check = mstar(&["check", path.to_str().expect("a UTF-8 path")]);
    assert_eq!(check.status.code(), Some(0));
    let stdout = String::from_utf8_lossy(&check.stdout);
    assert!(stdout.contains("coordinates: 35\n"), "{stdout}");
    assert!(stdout.contains("constraints: 35\n"), "{stdout}");
    assert!(stdout.contains("degrees of freedom: 1\n"), "{stdout}");
    assert!(
        stdout.contains(
            "redundant constraints: J5 (left out of the solve: minimum-norm multipliers)\n"
        ),
        "{stdout}"
    );
    // Without minimum-norm multipliers it is refused, by name.
    let refuse = mstar(&[
        "check",
        path.to_str().expect("a UTF-8 path"),
        "--set",
        "simulation.redundant=refuse",
    ]);
    assert_eq!(refuse.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&refuse.stdout).contains("redundant constraints: J5\n"));
}

/// The last row's coordinates `u:*` of a run of `model` with `settings`
/// (`--set` values) to t = 0.5 s; `Err(stderr)` when it does not exit 0.
fn final_coordinates(model: &Path, settings: &[&str], dir: &Path) -> Result<Vec<f64>, String> {
    let out = dir.join(format!(
        "{}.csv",
        settings.join("-").replace(['.', '='], "_")
    ));
    let mut args = vec!["run", model.to_str().expect("UTF-8"), "--t-end", "0.5"];
    args.extend(["--out", out.to_str().expect("UTF-8")]);
    for s in settings {
        args.extend(["--set", s]);
    }
    let run = mstar(&args);
    if run.status.code() != Some(0) {
        return Err(String::from_utf8_lossy(&run.stderr).to_string());
    }
    let (header, rows) = read_csv(&out);
    let last = rows.last().expect("rows");
    Ok(header
        .iter()
        .zip(last)
        .filter(|(h, _)| h.starts_with("u:"))
        .map(|(_, &x)| x)
        .collect())
}

/// Issue 20's reproduction: a spatial double pendulum whose bars start turned
/// (universal joint to the ground, revolute at the elbow) failed under the
/// defaults ("coordinate 'upper.e3' is undetermined (a redundant or
/// inconsistent constraint …)"): the automatic choice took the positive
/// diagonal of the turned bodies' rank-3 rotational blocks for a regular
/// mass. It runs under the defaults and with every backend, and all agree on
/// the final state to the Newton tolerance; so does the heavy top (spherical
/// joint, tilted) with `schur-lu`, which failed the same way.
#[test]
fn bodies_that_start_turned_run_under_the_defaults_on_every_backend() {
    let dir = scratch("turned");
    let model =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/tilted-double-pendulum.toml");
    let check = mstar(&["check", model.to_str().expect("UTF-8")]);
    let report = String::from_utf8_lossy(&check.stdout);
    assert!(report.contains("degrees of freedom: 3"), "{report}");
    let reference = final_coordinates(&model, &[], &dir).unwrap_or_else(|e| panic!("{e}"));
    // The defaults: schur-lu, with modified Newton (the automatic variant on
    // a small model, and on one with joints other than spherical ones).
    let run = mstar(&["run", model.to_str().expect("UTF-8"), "--t-end", "0.01"]);
    let summary = String::from_utf8_lossy(&run.stdout);
    assert!(
        summary.contains("KKT solver: schur-lu; Newton: modified"),
        "{summary}"
    );
    let singular = "simulation.rotational_mass=singular";
    for settings in [
        &["simulation.kkt=schur-lu"][..],
        &["simulation.kkt=lu"],
        &["simulation.kkt=dense"],
        &[singular],
        &[singular, "simulation.kkt=lu"],
    ] {
        let u = final_coordinates(&model, settings, &dir)
            .unwrap_or_else(|e| panic!("{settings:?}: {e}"));
        let worst = u
            .iter()
            .zip(&reference)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-7, "{settings:?}: {worst:e}");
    }
    // A backend that factors M block by block, chosen for a singular
    // rotational block, is refused before the start: the mass is named, not
    // the constraints, and the backends it offers ran above.
    let e = final_coordinates(&model, &[singular, "simulation.kkt=schur-lu"], &dir)
        .expect_err("schur-lu on a singular rotational mass");
    assert!(e.contains("singular at coordinate 'upper.e"), "{e}");
    assert!(e.contains("dense or lu backend"), "{e}");
    assert!(!e.contains("redundant or inconsistent constraint"), "{e}");
    let top = models().join("top.toml");
    let a = final_coordinates(&top, &["simulation.kkt=schur-lu"], &dir)
        .unwrap_or_else(|e| panic!("{e}"));
    let b = final_coordinates(&top, &["simulation.kkt=lu"], &dir).unwrap_or_else(|e| panic!("{e}"));
    let worst = a
        .iter()
        .zip(&b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    assert!(worst < 1e-7, "top: {worst:e}");
}

/// Issue 21 (12): a revolute joint whose two axes are not parallel at the
/// start was reported as redundant, and the advice (minimum-norm
/// multipliers) then failed. It is refused at the key, naming both axes in
/// global axes and the angle between them; the advice (`axis`, global) runs.
#[test]
fn revolute_axes_that_are_not_parallel_at_the_start_are_named() {
    let text = bar(
        "revolute",
        "axes = [[0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]",
        [0.5, 0.0, 0.0],
    );
    let e = error(&text);
    assert!(e.starts_with("m.toml:15:"), "{e}");
    assert!(
        e.contains("the two axes must be parallel at the initial pose"),
        "{e}"
    );
    assert!(
        e.contains(
            "[0.000000000, 1.000000000, 0.000000000] and [0.000000000, 0.000000000, 1.000000000], 1.571e0 rad apart"
        ),
        "{e}"
    );
    assert!(!e.contains("redundant"), "{e}");
    // Antiparallel axes are the same line: accepted.
    let flipped = bar(
        "revolute",
        "axes = [[0.0, 1.0, 0.0], [0.0, -1.0, 0.0]]",
        [0.5, 0.0, 0.0],
    );
    let (_, rows) = run_text("antiparallel", &flipped);
    assert!(rows.len() > 1);
    // The advice: one global axis.
    let (_, rows) = run_text(
        "global-axis",
        &bar("revolute", "axis = [0.0, 1.0, 0.0]", [0.5, 0.0, 0.0]),
    );
    assert!(rows.len() > 1);
}

/// Issue 21 (also found): a bar on a ball joint given only an angular
/// velocity had its rates shared with its centre's velocity by the start's
/// projection (ė₃ from 0.5 to 0.25), shown as a note only. `mstar run`
/// warns, naming the value and the fix; with the centre's velocity `ω × r`
/// given too (the fix), nothing is changed and nothing is said.
#[test]
fn a_start_that_changes_given_velocities_warns() {
    let text = |velocity: &str| {
        format!(
            "format = \"mstar.spatial/1\"\n[[body]]\nname = \"bar\"\nmass = 1.0\n\
             inertia = [0.001, 0.1, 0.1]\nposition = [0.5, 0.0, 0.0]\n\
             orientation = [1.0, 0.0, 0.0, 0.0]\n{velocity}angular_velocity = [0.0, 0.0, 1.0]\n\
             [[joint]]\nname = \"pin\"\ntype = \"spherical\"\nbodies = [\"ground\", \"bar\"]\n\
             points = [[0.0, 0.0, 0.0], [-0.5, 0.0, 0.0]]\n[simulation]\nt_end = 0.01\n"
        )
    };
    let dir = scratch("projection-warning");
    let model = dir.join("m.toml");
    let stderr = |velocity: &str| {
        std::fs::write(&model, text(velocity)).expect("write");
        let run = mstar(&["run", model.to_str().expect("UTF-8")]);
        assert_eq!(
            run.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
        String::from_utf8_lossy(&run.stderr).to_string()
    };
    let e = stderr("");
    assert!(
        e.contains("warning: the start changed the given velocities"),
        "{e}"
    );
    // ė₃ = ω/2 = 0.5 given, 0.25 after the projection (and ẏ = 0.25 m/s).
    assert!(e.contains("'bar.e3' from 0.5 to 0.25"), "{e}");
    // The advice names the fix, which the next run follows.
    assert!(
        e.contains("its centre's velocity ω × r is given as well"),
        "{e}"
    );
    let e = stderr("velocity = [0.0, 0.5, 0.0]\n");
    assert!(!e.contains("warning"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}
