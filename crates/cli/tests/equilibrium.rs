//! `mstar equilibrium` against closed forms: a pendulum hangs straight down
//! with the pivot carrying its weight, a bar on a torsional spring settles
//! at the root of `k φ = m g (l/2) cos φ`, a mass on a spring stretches it by
//! `m g / k`; the errors (no equilibrium, a neutral direction, an unreadable
//! file) and the `--write-model` round trip.
//!
//! Tolerances: the solver stops at `‖r‖∞ ≤ 10⁻¹¹ F` (`F` the force scale,
//! here the weights, 10-20 N) and its last Newton step is quadratic, so a
//! coordinate is off by at most about `10⁻¹¹ F / k_min` (the smallest
//! stiffness along the mechanism's motion, ≥ 10 N/m or N m/rad in these
//! models): `10⁻¹¹`. The assertions allow `10⁻¹⁰` (`10⁻⁹` where the
//! reference is itself a bisection to `10⁻¹³`), a factor ten for the
//! round-off of lengths of order one.

mod common;

use std::collections::HashMap;
use std::path::Path;

use common::{model, mstar, scratch, text};

/// The one row of an equilibrium CSV, by column name.
fn read_row(path: &Path) -> HashMap<String, f64> {
    let csv = std::fs::read_to_string(path).expect("the CSV is written");
    let mut lines = csv.lines();
    let header = lines.next().expect("a header");
    let row = lines.next().expect("one row");
    assert!(lines.next().is_none(), "one row only:\n{csv}");
    header
        .split(',')
        .zip(row.split(','))
        .map(|(k, v)| (k.to_string(), v.parse().expect("a number")))
        .collect()
}

/// Runs `mstar equilibrium MODEL --out eq.csv` and returns the row.
fn solve(dir: &Path, model: &Path) -> HashMap<String, f64> {
    let out = dir.join("eq.csv");
    let o = mstar(&[
        "equilibrium",
        &model.display().to_string(),
        "--out",
        &out.display().to_string(),
    ]);
    assert!(o.status.success(), "{}{}", text(&o.stdout), text(&o.stderr));
    read_row(&out)
}

fn close(name: &str, got: f64, want: f64, tol: f64) {
    assert!(
        (got - want).abs() <= tol,
        "{name}: {got} (want {want} ± {tol:e})"
    );
}

/// The paper's pendulum (1 kg, 1 m, g = 10) released horizontally hangs
/// straight down: bob at (0, −1), θ = 0 (mod 2π), the hinge carrying m g
/// upward and nothing sideways; velocities, accelerations are zero.
#[test]
fn pendulum_hangs_straight_down() {
    let dir = scratch("eq-pendulum");
    let row = solve(&dir, Path::new(&model("pendulum.toml")));
    close("u:bob.x", row["u:bob.x"], 0.0, 1e-10);
    close("u:bob.y", row["u:bob.y"], -1.0, 1e-10);
    let theta = row["u:bob.theta"].rem_euclid(std::f64::consts::TAU);
    let theta = theta.min(std::f64::consts::TAU - theta);
    close("u:bob.theta (mod 2π)", theta, 0.0, 1e-10);
    close("reaction:hinge.fx", row["reaction:hinge.fx"], 0.0, 1e-9);
    close("reaction:hinge.fy", row["reaction:hinge.fy"], 10.0, 1e-9);
    // (About the bob's centre, through which the rod's force passes.)
    close("reaction:hinge.tau", row["reaction:hinge.tau"], 0.0, 1e-9);
    for k in ["v:bob.x", "v:bob.y", "a:bob.theta"] {
        assert_eq!(row[k], 0.0, "{k}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A bar (m = 2 kg, l = 1 m) hinged at one end to the ground, with a
/// torsional spring k = 20 N m/rad relaxed with the bar horizontal: it
/// settles at φ below the horizontal with `k φ = m g (l/2) cos φ`.
#[test]
fn bar_on_torsional_spring() {
    let (m, l, k, g) = (2.0, 1.0, 20.0, 9.81);
    let dir = scratch("eq-spring-bar");
    let file = dir.join("bar.toml");
    let toml = format!(
        r#"format = "mstar.planar/1"
gravity = [0.0, -{g}]

[[body]]
name = "bar"
mass = {m}
inertia = {j}
pose = [{half}, 0.0, 0.0]

[[joint]]
name = "hinge"
type = "revolute"
bodies = ["ground", "bar"]
points = [[0.0, 0.0], [-{half}, 0.0]]

[[force]]
name = "spring"
type = "rotational-spring-damper"
bodies = ["ground", "bar"]
stiffness = {k}
"#,
        j = m * l * l / 12.0,
        half = l / 2.0
    );
    std::fs::write(&file, toml).expect("written");
    // The reference: f(φ) = k φ − m g (l/2) cos φ rises from −m g l/2 at 0
    // to k π/2 at π/2; bisection to 10⁻¹³.
    let f = |phi: f64| k * phi - m * g * (l / 2.0) * phi.cos();
    let (mut lo, mut hi) = (0.0_f64, std::f64::consts::FRAC_PI_2);
    while hi - lo > 1e-13 {
        let mid = 0.5 * (lo + hi);
        if f(mid) > 0.0 { hi = mid } else { lo = mid }
    }
    let phi = 0.5 * (lo + hi);
    let row = solve(&dir, &file);
    close("u:bar.theta", row["u:bar.theta"], -phi, 1e-9);
    close("u:bar.x", row["u:bar.x"], (l / 2.0) * phi.cos(), 1e-9);
    close("u:bar.y", row["u:bar.y"], -(l / 2.0) * phi.sin(), 1e-9);
    // The spring's rest angle is the file's initial pose, so the model
    // cannot start at the equilibrium as written: refused, no file left.
    let eq = dir.join("eq.toml");
    let o = mstar(&[
        "equilibrium",
        &file.display().to_string(),
        "--write-model",
        &eq.display().to_string(),
    ]);
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("bar.theta") && err.contains("initial pose") && err.contains("rest_angle"),
        "{err}"
    );
    assert!(!eq.exists());
    // The advice: the rest angle written out (0, the file's initial
    // angle). The written model starts at the equilibrium: solved again, it
    // takes no Newton step, and the spring is the same (the same angle).
    let given = dir.join("bar-rest.toml");
    let text_of = std::fs::read_to_string(&file).expect("written");
    std::fs::write(&given, format!("{text_of}rest_angle = 0.0\n")).expect("written");
    let o = mstar(&[
        "equilibrium",
        &given.display().to_string(),
        "--write-model",
        &eq.display().to_string(),
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let again = solve(&dir, &eq);
    close("u:bar.theta (again)", again["u:bar.theta"], -phi, 1e-9);
    assert_eq!(again["iterations"], 0.0, "{again:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A 2 kg point mass on a spring (k = 100 N/m, rest length 1 m) from a
/// ground point, free in the plane: it hangs below the point, the spring
/// stretched by m g / k.
#[test]
fn mass_on_a_spring_stretches_it_by_weight_over_stiffness() {
    let (m, k, l0, g) = (2.0, 100.0, 1.0, 9.81);
    let dir = scratch("eq-spring-mass");
    let file = dir.join("spring.toml");
    let toml = format!(
        r#"format = "mstar.planar/1"
gravity = [0.0, -{g}]

[[point_mass]]
name = "p"
mass = {m}
position = [0.0, -{l0}]

[[force]]
name = "spring"
type = "spring-damper"
bodies = ["ground", "p"]
points = [[0.0, 0.0], [0.0, 0.0]]
stiffness = {k}
rest_length = {l0}
"#
    );
    std::fs::write(&file, toml).expect("written");
    let row = solve(&dir, &file);
    close("u:p.x", row["u:p.x"], 0.0, 1e-10);
    close("u:p.y", row["u:p.y"], -(l0 + m * g / k), 1e-10);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A model of one point mass with gravity (and what else `extra` adds).
fn point_mass(extra: &str) -> String {
    format!(
        "format = \"mstar.planar/1\"\ngravity = [0.0, -9.81]\n\n[[point_mass]]\nname = \"slider\"\nmass = 1.0\nposition = [0.0, 0.0]\n{extra}"
    )
}

/// A free point mass under gravity: no equilibrium, its y coordinate named.
/// On a horizontal guide: balanced, but neutral along x.
#[test]
fn no_equilibrium_and_neutral_directions_are_named() {
    let dir = scratch("eq-errors");
    let free = dir.join("free.toml");
    std::fs::write(&free, point_mass("")).expect("written");
    let o = mstar(&["equilibrium", &free.display().to_string()]);
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("no equilibrium found") && err.contains("slider.y"),
        "{err}"
    );
    assert!(!err.contains("slider.x"), "x is balanced: {err}");

    let guided = dir.join("guided.toml");
    let guide = "\n[[joint]]\nname = \"guide\"\ntype = \"prismatic\"\nbodies = [\"ground\", \"slider\"]\npoints = [[0.0, 0.0], [0.0, 0.0]]\naxis = [1.0, 0.0]\n";
    std::fs::write(&guided, point_mass(guide)).expect("written");
    let o = mstar(&["equilibrium", &guided.display().to_string()]);
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("neutral") && err.contains("slider.x"), "{err}");
    assert!(!err.contains("slider.y"), "y is held by the guide: {err}");

    let o = mstar(&[
        "equilibrium",
        &dir.join("missing.toml").display().to_string(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o.stderr));
    let _ = std::fs::remove_dir_all(&dir);
}

/// `--write-model`: the pendulum's file with the hanging pose, its comments
/// kept; `mstar check` finds it on its constraints, and the equilibrium
/// solved again from it takes at most one Newton step.
#[test]
fn written_model_starts_at_the_equilibrium() {
    let dir = scratch("eq-write-model");
    let eq = dir.join("eq.toml");
    let o = mstar(&[
        "equilibrium",
        &model("pendulum.toml"),
        "--write-model",
        &eq.display().to_string(),
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let written = std::fs::read_to_string(&eq).expect("written");
    assert!(written.contains("# The paper's pendulum"), "{written}");
    assert!(!written.contains("1.5707963267948966"), "{written}");
    let o = mstar(&["check", &eq.display().to_string()]);
    let out = text(&o.stdout);
    assert!(o.status.success(), "{out}{}", text(&o.stderr));
    let violation = out
        .lines()
        .find_map(|l| l.strip_prefix("initial position violation: "))
        .expect("the violation line");
    let size: f64 = violation
        .split_whitespace()
        .next()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0.0);
    // 1 m lengths: a few ulps.
    assert!(violation == "none" || size <= 1e-14, "{out}");
    let o = mstar(&["equilibrium", &eq.display().to_string()]);
    let out = text(&o.stdout);
    assert!(o.status.success(), "{out}{}", text(&o.stderr));
    assert!(
        out.starts_with("equilibrium found: 0 Newton steps")
            || out.starts_with("equilibrium found: 1 Newton steps"),
        "{out}"
    );
    // A JSON model is not rewritten: said so, nothing written.
    let json = dir.join("eq-from-json.toml");
    let o = mstar(&[
        "equilibrium",
        &model("double-pendulum.json"),
        "--write-model",
        &json.display().to_string(),
    ]);
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("TOML model files only"), "{err}");
    assert!(!json.exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// A spatial bar (`models/spatial/tilted-hinge.toml`: 1 m, on a hinge at
/// its end whose axis `a = (cos 30°, 0, sin 30°)` is tilted 30° from the
/// horizontal) under gravity along −z: its centre, 0.5 m from the axis on
/// the circle in the plane normal to `a`, comes to rest at the circle's
/// lowest point, `0.5 d / |d|` with `d = −ẑ + (ẑ·a) a` (−ẑ without its part
/// along the axis) = (0.25, 0, −0.25 √3).
#[test]
fn spatial_bar_on_tilted_hinge_hangs_at_its_lowest_point() {
    let dir = scratch("eq-spatial");
    let file = dir.join("hinge.toml");
    let original = std::fs::read_to_string(model("spatial/tilted-hinge.toml")).expect("read");
    let with_gravity = original.replacen(
        "format = \"mstar.spatial/1\"",
        "format = \"mstar.spatial/1\"\ngravity = [0.0, 0.0, -9.81]",
        1,
    );
    std::fs::write(&file, with_gravity).expect("written");
    let row = solve(&dir, &file);
    let (s, c) = (0.5_f64, 3.0_f64.sqrt() / 2.0); // sin 30°, cos 30°
    let a = [c, 0.0, s];
    let d = [s * a[0], 0.0, -1.0 + s * a[2]];
    let norm = (d[0] * d[0] + d[2] * d[2]).sqrt();
    close("u:bar.x", row["u:bar.x"], 0.5 * d[0] / norm, 1e-10);
    close("u:bar.y", row["u:bar.y"], 0.0, 1e-10);
    close("u:bar.z", row["u:bar.z"], 0.5 * d[2] / norm, 1e-10);
    close("hand check x", 0.5 * d[0] / norm, 0.25, 1e-15);
    // The hinge carries the weight, m g = 9.81 N upward; its moment is
    // reported about the bar's centre of mass (docs/model-format.md), where
    // the weight acts: at rest the moments on the bar sum to zero, so it
    // is zero.
    close("reaction:hinge.fz", row["reaction:hinge.fz"], 9.81, 1e-9);
    for k in ["fx", "fy", "tx", "ty", "tz"] {
        close(k, row[&format!("reaction:hinge.{k}")], 0.0, 1e-9);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The paper's pendulum with its hinge given twice: the two hinges' rows
/// depend on each other. The equilibrium is solved without the dependent
/// rows: the bob hangs straight down, and the minimum-norm multipliers
/// split the weight m g = 10 N equally between the two hinges; a note
/// names the rows left out. `mstar modes` about it and about the initial
/// pose run too: the hanging point pendulum's frequency is `√(g/l) / 2π`.
#[test]
fn a_duplicated_hinge_shares_the_weight() {
    let dir = scratch("eq-redundant");
    let text_of = std::fs::read_to_string(model("pendulum.toml")).expect("the model");
    let twice = dir.join("twice.toml");
    let second = "\n[[joint]]\nname = \"hinge2\"\ntype = \"revolute\"\nbodies = [\"ground\", \"bob\"]\npoints = [[0.0, 0.0], [0.0, 1.0]]\n";
    std::fs::write(&twice, format!("{text_of}{second}")).expect("written");
    let out = dir.join("eq.csv");
    let o = mstar(&[
        "equilibrium",
        &twice.display().to_string(),
        "--out",
        &out.display().to_string(),
    ]);
    let err = text(&o.stderr);
    assert!(o.status.success(), "{}{err}", text(&o.stdout));
    assert!(
        err.contains("hinge2.x") && err.contains("hinge2.y"),
        "{err}"
    );
    let row = read_row(&out);
    close("u:bob.x", row["u:bob.x"], 0.0, 1e-10);
    close("u:bob.y", row["u:bob.y"], -1.0, 1e-10);
    for hinge in ["hinge", "hinge2"] {
        let fy = row[&format!("reaction:{hinge}.fy")];
        close(&format!("reaction:{hinge}.fy"), fy, 5.0, 1e-9);
        let fx = row[&format!("reaction:{hinge}.fx")];
        close(&format!("reaction:{hinge}.fx"), fx, 0.0, 1e-9);
    }
    let want = (10.0_f64).sqrt() / std::f64::consts::TAU;
    for about in ["equilibrium", "initial"] {
        let o = mstar(&["modes", &twice.display().to_string(), "--about", about]);
        let said = text(&o.stdout);
        assert!(o.status.success(), "{said}{}", text(&o.stderr));
        if about == "equilibrium" {
            assert!(
                said.contains(&format!("f = {want:.9e}")),
                "want {want}: {said}"
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A distance rod from (2, 0) to the bob of the paper's pendulum (at (1, 0),
/// the rod of length 1) touches the pendulum's circle there: at the initial
/// pose its row depends on the hinge's, but it allows no other pose. The
/// equilibrium solved without it would hang below the hinge, where the rod
/// cannot reach: the error says the redundant row does not hold there.
#[test]
fn a_redundant_row_that_does_not_hold_at_the_equilibrium_is_named() {
    let dir = scratch("eq-contradicting");
    let text_of = std::fs::read_to_string(model("pendulum.toml")).expect("the model");
    let file = dir.join("touching.toml");
    let rod = "\n[[joint]]\nname = \"rod\"\ntype = \"distance\"\nbodies = [\"ground\", \"bob\"]\npoints = [[2.0, 0.0], [0.0, 0.0]]\n";
    std::fs::write(&file, format!("{text_of}{rod}")).expect("written");
    let o = mstar(&["equilibrium", &file.display().to_string()]);
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{}{err}", text(&o.stdout));
    assert!(
        err.contains("redundant at the initial pose") && err.contains("rod"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A bar (2 kg, 1 m) hinged at one end, started 0.5 rad from upright:
/// Newton's steps lead to the upright equilibrium, which is unstable; the
/// search goes on from beside it to the stable one, the bar hanging below
/// its pivot (centre of mass at (0, −0.5), θ = −π/2), without a warning.
#[test]
fn a_bar_started_near_upright_hangs() {
    let dir = scratch("eq-inverted");
    let file = dir.join("inverted.toml");
    let (s, c) = (0.5_f64.sin(), 0.5_f64.cos());
    let model = format!(
        "format = \"mstar.planar/1\"\n\n[[body]]\nname = \"bar\"\nmass = 2.0\ninertia = 0.16666666666666666\npose = [{}, {}, {}]\n\n[[joint]]\nname = \"hinge\"\ntype = \"revolute\"\nbodies = [\"ground\", \"bar\"]\npoints = [[0.0, 0.0], [-0.5, 0.0]]\n",
        0.5 * s,
        0.5 * c,
        std::f64::consts::FRAC_PI_2 - 0.5
    );
    std::fs::write(&file, model).expect("written");
    let out = dir.join("eq.csv");
    let o = mstar(&[
        "equilibrium",
        &file.display().to_string(),
        "--out",
        &out.display().to_string(),
    ]);
    let err = text(&o.stderr);
    assert!(o.status.success(), "{}{err}", text(&o.stdout));
    assert!(!err.contains("unstable"), "{err}");
    let row = read_row(&out);
    close("u:bar.x", row["u:bar.x"], 0.0, 1e-10);
    close("u:bar.y", row["u:bar.y"], -0.5, 1e-10);
    let theta =
        (row["u:bar.theta"] + std::f64::consts::FRAC_PI_2).rem_euclid(std::f64::consts::TAU);
    close(
        "u:bar.theta + π/2 (mod 2π)",
        theta.min(std::f64::consts::TAU - theta),
        0.0,
        1e-10,
    );
    let _ = std::fs::remove_dir_all(&dir);
}
