//! `mstar run --sensitivity KEY` against central differences of whole runs
//! at `p ± δ` and `p ± 2δ` (`--set KEY=p±δ`), extrapolated (Richardson):
//! `D₁ = (f(p+δ) − f(p−δ))/(2δ)` and `D₂` (with `2δ`) have errors `c δ²`
//! and `4 c δ²`, `R = (4 D₁ − D₂)/3` removes them, and `|D₁ − D₂|/3`, the
//! estimate of `D₁`'s error, bounds `R`'s (`O(δ⁴)`). The runs' own errors
//! `η` (Newton tolerance `TOL` relative to the coordinates and to the
//! forces) reach `R` as at most `(8·2η + 2η)/(12δ) = 1.5 η/δ`. The
//! sensitivities are exact derivatives of the discrete solution up to the
//! central differences of the residual in `p` (`O(1e-10)` relative), far
//! inside that. Also: the errors for keys that name no number, and the
//! options `--sensitivity` refuses.

mod common;

use std::collections::HashMap;
use std::path::Path;

use common::{model, mstar, scratch, text};

/// Newton tolerance of the runs.
const TOL: &str = "1e-12";

/// The last row of a CSV, by column name.
fn last_row(path: &Path) -> HashMap<String, f64> {
    let csv = std::fs::read_to_string(path).expect("the CSV is written");
    let mut lines = csv.lines();
    let header = lines.next().expect("a header");
    let row = lines.last().expect("rows");
    header
        .split(',')
        .zip(row.split(','))
        .map(|(k, v)| (k.to_string(), v.parse().expect("a number")))
        .collect()
}

/// Runs `mstar run MODEL --tol TOL --out OUT extra…` and returns the last row.
fn run(dir: &Path, model: &str, tag: &str, extra: &[&str]) -> HashMap<String, f64> {
    let out = dir.join(format!("{tag}.csv"));
    let out_arg = out.display().to_string();
    let mut args = vec!["run", model, "--tol", TOL, "--out", &out_arg];
    args.extend_from_slice(extra);
    let o = mstar(&args);
    assert!(o.status.success(), "{}{}", text(&o.stdout), text(&o.stderr));
    last_row(&out)
}

/// `R` and its tolerance for the column `f` of runs with `key` at
/// `p ± δ`, `p ± 2δ` (`rows[0..4]`), the runs' error `eta`.
fn extrapolated(
    rows: &[HashMap<String, f64>],
    delta: f64,
    f: &dyn Fn(&HashMap<String, f64>) -> f64,
    eta: f64,
) -> (f64, f64) {
    let d1 = (f(&rows[0]) - f(&rows[1])) / (2.0 * delta);
    let d2 = (f(&rows[2]) - f(&rows[3])) / (4.0 * delta);
    (
        (4.0 * d1 - d2) / 3.0,
        (d1 - d2).abs() / 3.0 + 1.5 * eta / delta,
    )
}

/// The runs at `p ± δ`, `p ± 2δ` of `key`.
fn perturbed(
    dir: &Path,
    model: &str,
    key: &str,
    p: f64,
    delta: f64,
    extra: &[&str],
) -> Vec<HashMap<String, f64>> {
    [1.0, -1.0, 2.0, -2.0]
        .iter()
        .enumerate()
        .map(|(i, k)| {
            let set = format!("{key}={:?}", p + k * delta);
            let mut args = extra.to_vec();
            args.extend_from_slice(&["--set", &set]);
            run(dir, model, &format!("fd{i}"), &args)
        })
        .collect()
}

/// The largest `|λ|` of a row: the force scale of the Newton tolerance.
fn force_scale(row: &HashMap<String, f64>) -> f64 {
    row.iter()
        .filter(|(k, _)| k.starts_with("lambda:"))
        .fold(1.0, |m, (_, v)| m.max(v.abs()))
}

/// The multiplier error `η_λ` of the slider-crank's runs: Newton stops at
/// `‖r‖∞` within `max(TOL F, 4 β' ε max(1, ‖u‖∞) max|B|)` (the second, the
/// floor of the paper's multiplier update, `newton.rs`, dominates here), and
/// a residual `r` moves a multiplier by at most `r` over the smallest lever
/// arm of the rows of `Bᵀ`, 0.05 m (the crank's pivot and pin).
fn slider_crank_multiplier_error(forces: f64) -> f64 {
    // Generalized-α with ρ∞ = 0.9 (the default), h = 1e-3 s.
    let (rho, h): (f64, f64) = (0.9, 1e-3);
    let (alpha_m, alpha_f) = ((2.0 * rho - 1.0) / (rho + 1.0), rho / (rho + 1.0));
    let beta = (1.0 - alpha_m + alpha_f).powi(2) / 4.0;
    let beta_p = (1.0 - alpha_m) / ((1.0 - alpha_f) * beta * h * h);
    let tol: f64 = TOL.parse().expect("a number");
    let residual = (tol * forces).max(4.0 * beta_p * f64::EPSILON);
    residual / 0.05
}

/// The slider-crank's motor torque (`effort:motor = −λ_motor`) and every
/// coordinate and multiplier at t = 0.2 s, with respect to the coupler's
/// mass (`body.rod.mass`, 0.8 kg). The mechanism has no degree of freedom:
/// its motion does not depend on the mass (`∂u/∂m = 0`) and its multipliers
/// are affine in it, so `δ` can be large (1e-2) against the runs' errors.
#[test]
fn slider_crank_motor_torque_with_respect_to_the_coupler_mass() {
    let dir = scratch("sens-slider");
    let m = model("slider-crank.toml");
    let (key, p, delta) = ("body.rod.mass", 0.8, 1e-2);
    let t_end = ["--t-end", "0.2"];
    let mut args = t_end.to_vec();
    args.extend_from_slice(&["--sensitivity", key]);
    let nominal = run(&dir, &m, "nominal", &args);
    let rows = perturbed(&dir, &m, key, p, delta, &t_end);
    let eta = slider_crank_multiplier_error(force_scale(&nominal));
    let torque = nominal[&format!("d(lambda:motor)/d({key})")];
    let (want, tolerance) = extrapolated(&rows, delta, &|r| -r["effort:motor"], eta);
    assert!(
        (torque - want).abs() <= tolerance,
        "−d(effort:motor)/d({key}) = {torque}, extrapolated differences {want} ± {tolerance:.2e}"
    );
    let mut checked = 0;
    for (name, &value) in &nominal {
        let Some(column) = name
            .strip_prefix("d(")
            .and_then(|n| n.strip_suffix(&format!(")/d({key})")))
        else {
            continue;
        };
        let scale = if column.starts_with("u:") {
            TOL.parse().expect("a number")
        } else if column.starts_with("lambda:") {
            eta
        } else {
            continue;
        };
        let (want, tolerance) = extrapolated(&rows, delta, &|r| r[column], scale);
        assert!(
            (value - want).abs() <= tolerance,
            "{name} = {value}, extrapolated differences {want} ± {tolerance:.2e}"
        );
        checked += 1;
    }
    assert_eq!(checked, 8 + 8, "every coordinate and multiplier");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The spinning top of `models/spatial/top.toml` with once-per-step Newton:
/// each step's first factorization takes the Jacobians that the
/// sensitivity evaluated at the previous converged state
/// (`System::jacobians_are_costly`, spatial models) over the first 16 such
/// steps, after which the run stops taking them (two iterations a step
/// from them, against one). Its coordinates against extrapolated
/// differences of runs without the sensitivity ([`top_against_differences`]).
#[test]
fn spatial_top_coordinates_with_respect_to_its_mass_from_shared_jacobians() {
    top_against_differences("sens-top", &["--set", "simulation.newton=\"per-step\""]);
}

/// The same with the automatic Newton variant: modified Newton from the
/// sensitivities' factorizations, turned into once per step after 16 steps
/// (the sensitivities refined with Newton's factorization from then on).
#[test]
fn spatial_top_coordinates_with_respect_to_its_mass_after_the_switch() {
    top_against_differences("sens-top-auto", &[]);
}

/// The top's seven coordinates at t = 0.2 s with respect to its mass
/// (gravity's torque about the tip; the inertia is given apart), run with
/// `extra`, against extrapolated differences of runs without the
/// sensitivity.
fn top_against_differences(tag: &str, extra: &[&str]) {
    let dir = scratch(tag);
    let m = model("spatial/top.toml");
    let (key, p, delta) = ("body.top.mass", 2.0, 1e-3);
    let mut common = vec!["--t-end", "0.2"];
    common.extend_from_slice(extra);
    let mut args = common.clone();
    args.extend_from_slice(&["--sensitivity", key]);
    let nominal = run(&dir, &m, "nominal", &args);
    let rows = perturbed(&dir, &m, key, p, delta, &common);
    // Positions converge to ‖Φ‖∞ ≤ TOL max(1, ‖u‖∞) = TOL.
    let eta: f64 = TOL.parse().expect("a number");
    let (mut checked, mut largest) = (0, 0.0f64);
    for c in ["x", "y", "z", "e0", "e1", "e2", "e3"] {
        let column = format!("u:top.{c}");
        let value = nominal[&format!("d({column})/d({key})")];
        let (want, tolerance) = extrapolated(&rows, delta, &|r| r[&column], eta);
        assert!(
            (value - want).abs() <= tolerance,
            "d({column})/d({key}) = {value}, extrapolated differences {want} ± {tolerance:.2e}"
        );
        largest = largest.max(want.abs() / tolerance);
        checked += 1;
    }
    assert_eq!(checked, 7);
    // The mass moves the top: the check is not of zeros.
    assert!(
        largest > 1e3,
        "largest sensitivity over its tolerance: {largest:.1e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A point mass on a massless rod (`joint.rod.length`, 1 m) released
/// horizontally: the angle θ = atan2(x, −y) at t = 0.5 s with respect to
/// the length, `∂θ/∂l = (−y ∂x/∂l + x ∂y/∂l)/(x² + y²)`.
#[test]
fn pendulum_angle_with_respect_to_its_length() {
    let dir = scratch("sens-pendulum");
    let file = dir.join("rod.toml");
    std::fs::write(
        &file,
        "format = \"mstar.planar/1\"\ngravity = [0.0, -9.81]\n\
         [[point_mass]]\nname = \"bob\"\nmass = 1.0\nposition = [1.0, 0.0]\n\
         [[joint]]\nname = \"rod\"\ntype = \"distance\"\nbodies = [\"ground\", \"bob\"]\n\
         points = [[0.0, 0.0], [0.0, 0.0]]\nlength = 1.0\n\
         [simulation]\nt_end = 0.5\nh = 1e-3\n",
    )
    .expect("the model is written");
    let m = file.display().to_string();
    let (key, p, delta) = ("joint.rod.length", 1.0, 1e-3);
    let nominal = run(&dir, &m, "nominal", &["--sensitivity", key]);
    let rows = perturbed(&dir, &m, key, p, delta, &[]);
    let angle = |r: &HashMap<String, f64>| r["u:bob.x"].atan2(-r["u:bob.y"]);
    let (x, y) = (nominal["u:bob.x"], nominal["u:bob.y"]);
    let dx = nominal[&format!("d(u:bob.x)/d({key})")];
    let dy = nominal[&format!("d(u:bob.y)/d({key})")];
    let got = (-y * dx + x * dy) / (x * x + y * y);
    // Positions converge to ‖Φ‖∞ ≤ TOL max(1, ‖u‖∞) = TOL.
    let (want, tolerance) = extrapolated(&rows, delta, &angle, TOL.parse().expect("a number"));
    assert!(
        (got - want).abs() <= tolerance,
        "∂θ/∂l = {got}, extrapolated differences {want} ± {tolerance:.2e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `--columns` globs choose among the sensitivity columns, and an `.npz`
/// output holds them too.
#[test]
fn columns_choose_sensitivities_and_npz_holds_them() {
    let dir = scratch("sens-columns");
    let m = model("slider-crank.toml");
    let out = dir.join("s.csv");
    let o = mstar(&[
        "run",
        &m,
        "--t-end",
        "0.01",
        "--sensitivity",
        "body.rod.mass",
        "--sensitivity",
        "body.crank.inertia",
        "--columns",
        "t,d(lambda:motor)/d(*)",
        "--out",
        &out.display().to_string(),
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    // Both keys belong to a body: their partials come from its small model.
    let report = text(&o.stdout);
    assert!(
        report.contains("sensitivities: 2 parameter(s), 2 with local partials;"),
        "{report}"
    );
    let csv = std::fs::read_to_string(&out).expect("the CSV is written");
    assert_eq!(
        csv.lines().next(),
        Some("t,d(lambda:motor)/d(body.rod.mass),d(lambda:motor)/d(body.crank.inertia)")
    );
    let npz = dir.join("s.npz");
    let o = mstar(&[
        "run",
        &m,
        "--t-end",
        "0.01",
        "--sensitivity",
        "body.rod.mass",
        "--out",
        &npz.display().to_string(),
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let (names, values) = mstar::npz::read(&npz).expect("the .npz is written");
    let k = names
        .iter()
        .position(|n| n == "d(lambda:motor)/d(body.rod.mass)")
        .expect("the column");
    let rows = values.len() / names.len();
    assert_eq!(rows, 11);
    let last = values[(rows - 1) * names.len() + k];
    assert!(last.is_finite() && last != 0.0, "{last}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Exit 2, naming the key and the closest numeric keys.
#[test]
fn a_key_that_names_no_number_is_refused() {
    let m = model("slider-crank.toml");
    for (key, says) in [
        (
            "body.rod.mas",
            "no numeric key 'body.rod.mas'; the closest numeric keys are: body.rod.mass,",
        ),
        (
            "joint.guide.type",
            "'joint.guide.type' is a string, not a number",
        ),
        ("body..mass", "no numeric key 'body..mass'"),
        ("simulation.h", "'simulation.h' is a setting of the run"),
    ] {
        let o = mstar(&["run", &m, "--t-end", "0.01", "--sensitivity", key]);
        let err = text(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{key}: {err}");
        assert!(
            err.contains(&format!("--sensitivity {key}")),
            "{key}: {err}"
        );
        assert!(err.contains(says), "{key}: {err}");
    }
}

/// Adaptive steps, rows at fixed times and built-in models are refused
/// with exit 2 and what to do.
#[test]
fn options_sensitivities_do_not_handle_are_refused() {
    let m = model("slider-crank.toml");
    let cases: [(&[&str], &str); 3] = [
        (&["run", &m, "--adaptive"], "drop --adaptive"),
        (&["run", &m, "--output-every", "0.1"], "drop --output-every"),
        (&["run", "--builtin", "pendulum"], "needs a model file"),
    ];
    for (args, says) in cases {
        let mut args = args.to_vec();
        args.extend_from_slice(&["--sensitivity", "body.rod.mass"]);
        let o = mstar(&args);
        let err = text(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(says), "{args:?}: {err}");
    }
}

/// The refusal of rows at fixed times advises rows every n steps: on a
/// file with `[output] every_time`, `--set output.every=1` (which replaces
/// it) runs, for `--sensitivity` and `--gradient` alike.
#[test]
fn the_every_time_refusal_advises_what_runs() {
    let dir = scratch("sens-every-time");
    let text_of = std::fs::read_to_string(model("slider-crank.toml")).expect("model");
    let path = dir.join("s.toml");
    std::fs::write(&path, format!("{text_of}\n[output]\nevery_time = 0.005\n")).expect("written");
    let m = path.display().to_string();
    let out = dir.join("s.csv").display().to_string();
    let sens = ["--sensitivity", "body.rod.mass", "--out", &out];
    let grad = [
        "--objective",
        "final:u:rod.x",
        "--gradient",
        "body.rod.mass",
    ];
    for extra in [&sens[..], &grad[..]] {
        let mut args = vec!["run", &m, "--t-end", "0.01"];
        args.extend_from_slice(extra);
        let o = mstar(&args);
        let e = text(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{e}");
        assert!(
            e.contains("--set output.every=1, which replaces every_time"),
            "{e}"
        );
        args.extend_from_slice(&["--set", "output.every=1"]);
        let o = mstar(&args);
        assert!(o.status.success(), "{args:?}: {}", text(&o.stderr));
    }
    // --output-every overrides both keys of the file too.
    let o = mstar(&[
        "run",
        &m,
        "--t-end",
        "0.01",
        "--set",
        "output.every=2",
        "--output-every",
        "0.005",
        "--out",
        &out,
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let rows = std::fs::read_to_string(&out)
        .expect("written")
        .lines()
        .count();
    assert_eq!(rows, 1 + 3, "a header and t = 0, 0.005, 0.01");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A key the file leaves to its default (a distance joint's `length`, taken
/// from the initial pose) is refused with what to write; written out (the
/// model file as shipped gives it), the same key runs.
#[test]
fn a_default_key_is_refused_with_what_to_write_and_the_advice_runs() {
    let dir = scratch("sens-default-key");
    let given = model("double-pendulum-modes.toml");
    let text_of = std::fs::read_to_string(&given).expect("the model");
    let defaulted = text_of.replace("length = 1.0\n", "");
    assert_ne!(defaulted, text_of, "the model gives its rods' lengths");
    let path = dir.join("defaulted.toml");
    std::fs::write(&path, defaulted).expect("written");
    let key = "joint.upper-rod.length";
    let o = mstar(&[
        "run",
        &path.display().to_string(),
        "--t-end",
        "0.01",
        "--sensitivity",
        key,
    ]);
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("'joint.upper-rod' does not give 'length'")
            && err.contains("write 'length = <value>' in the file"),
        "{err}"
    );
    let o = mstar(&["run", &given, "--t-end", "0.01", "--sensitivity", key]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let _ = std::fs::remove_dir_all(&dir);
}
