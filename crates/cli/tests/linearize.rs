//! `mstar linearize` against closed forms and against `mstar run`: a
//! mass–spring–damper on a prismatic joint (`A`, `B`, `C`, `D` known
//! exactly), the paper's pendulum about its hanging equilibrium (`A =
//! [[0, 1], [−g/l, 0]]` in θ), a damped double pendulum's response to a
//! small torque step against the nonlinear run; and the errors.

mod common;

use std::path::Path;

use common::{model, mstar, scratch, text};

/// The JSON file a run wrote, parsed.
fn read_json(path: &Path) -> serde_json::Value {
    let s = std::fs::read_to_string(path).expect("the JSON is written");
    serde_json::from_str(&s).expect("valid JSON")
}

/// A matrix field as rows.
fn matrix(v: &serde_json::Value, key: &str) -> Vec<Vec<f64>> {
    v[key]
        .as_array()
        .unwrap_or_else(|| panic!("{key} is an array"))
        .iter()
        .map(|row| {
            row.as_array()
                .expect("a row")
                .iter()
                .map(|x| x.as_f64().expect("a number"))
                .collect()
        })
        .collect()
}

/// A list of strings.
fn names(v: &serde_json::Value, key: &str) -> Vec<String> {
    v[key]
        .as_array()
        .unwrap_or_else(|| panic!("{key} is an array"))
        .iter()
        .map(|x| x.as_str().expect("a string").to_string())
        .collect()
}

fn close(name: &str, got: f64, want: f64, tol: f64) {
    assert!(
        (got - want).abs() <= tol,
        "{name}: {got} (want {want} ± {tol:e})"
    );
}

/// Runs `mstar` with `args`, expecting success; returns standard output.
fn ok(args: &[&str]) -> String {
    let o = mstar(args);
    assert!(o.status.success(), "{}{}", text(&o.stdout), text(&o.stderr));
    text(&o.stdout)
}

/// Mass m = 2 kg on a horizontal guide, a spring-damper k = 50 N/m, c = 3
/// N s/m along the guide, a force `push` along it; gravity across the guide
/// (the guide carries it, the spring has no tension at rest: no geometric
/// stiffness).
const SLIDER: &str = r#"format = "mstar.planar/1"
gravity = [0.0, -9.81]

[[point_mass]]
name = "slider"
mass = 2.0
position = [0.0, 0.0]

[[joint]]
name = "guide"
type = "prismatic"
bodies = ["ground", "slider"]
points = [[0.0, 0.0], [0.0, 0.0]]
axis = [1.0, 0.0]

[[force]]
name = "spring"
type = "spring-damper"
bodies = ["ground", "slider"]
points = [[-1.0, 0.0], [0.0, 0.0]]
stiffness = 50.0
damping = 3.0
rest_length = 1.0

[[force]]
name = "push"
type = "force"
body = "slider"
fx = 0.0
"#;

/// [`SLIDER`] with two sensors: the distance from the spring's anchor
/// (`1 + x`) and the slider's acceleration.
fn slider_with_sensors() -> String {
    SLIDER.to_string()
        + r#"
[[sensor]]
name = "gap"
type = "distance"
bodies = ["ground", "slider"]
points = [[-1.0, 0.0], [0.0, 0.0]]

[[sensor]]
name = "acc"
type = "acceleration"
body = "slider"
"#
}

/// Sensor outputs of the mass–spring–damper: `sensor:gap = 1 + x` (`C =
/// [1, 0]`, `D = 0`), `sensor:acc.x = ẍ` (`C = [−k/m, −c/m]`, `D = 1/m`),
/// `sensor:acc.y = 0`. The distance is differenced along the state
/// (`10⁻¹⁰` of its scale, 1 m; `10⁻⁹` allowed); the acceleration is linear
/// in `ü`, so round-off of entries of order 25 (`10⁻¹²` of them).
#[test]
fn sensor_outputs_of_the_mass_spring_damper() {
    let dir = scratch("lin-sensors");
    let file = dir.join("slider.toml");
    std::fs::write(&file, slider_with_sensors()).expect("model written");
    let out = dir.join("ss.json");
    ok(&[
        "linearize",
        &file.display().to_string(),
        "--inputs",
        "force.push.fx",
        "--outputs",
        "sensor:*",
        "--out",
        &out.display().to_string(),
    ]);
    let ss = read_json(&out);
    assert_eq!(
        names(&ss, "outputs"),
        ["sensor:gap", "sensor:acc.x", "sensor:acc.y"]
    );
    let (m, k, c) = (2.0, 50.0, 3.0);
    let (cm, d) = (matrix(&ss, "C"), matrix(&ss, "D"));
    let want = [
        ([1.0, 0.0, 0.0], 1e-9),
        ([-k / m, -c / m, 1.0 / m], 25e-12),
        ([0.0, 0.0, 0.0], 25e-12),
    ];
    for (i, (row, tol)) in want.iter().enumerate() {
        close(&format!("C[{i}][0]"), cm[i][0], row[0], *tol);
        close(&format!("C[{i}][1]"), cm[i][1], row[1], *tol);
        close(&format!("D[{i}]"), d[i][0], row[2], *tol);
    }
    close(
        "y0[gap]",
        ss["y0"][0].as_f64().expect("a number"),
        1.0,
        1e-15,
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `m ẍ + c ẋ + k x = p`: `A = [[0, 1], [−k/m, −c/m]]`, `B = [0; 1/m]`;
/// the outputs `u:slider.x` (`C = [1, 0]`), `a:slider.x` (`C = [−k/m,
/// −c/m]`, `D = 1/m`) and the guide's multiplier (`λ` holds the weight:
/// no dependence on `x` or `p`). Every entry is a sum of a few products of
/// the data, and the outputs `u:`, `a:`, `lambda:` are linear in the state,
/// so the tolerance is round-off: `10⁻¹²` of entries of order 25.
#[test]
fn mass_spring_damper_is_exact() {
    let dir = scratch("lin-msd");
    let file = dir.join("slider.toml");
    std::fs::write(&file, SLIDER).expect("model written");
    let out = dir.join("ss.json");
    ok(&[
        "linearize",
        &file.display().to_string(),
        "--inputs",
        "force.push.fx",
        "--outputs",
        "u:slider.x",
        "a:slider.x",
        "lambda:*",
        "--out",
        &out.display().to_string(),
    ]);
    let ss = read_json(&out);
    assert_eq!(names(&ss, "states"), ["u:slider.x", "v:slider.x"]);
    assert_eq!(
        names(&ss, "outputs"),
        ["u:slider.x", "a:slider.x", "lambda:guide.line"]
    );
    let (m, k, c) = (2.0, 50.0, 3.0);
    let tol = 1e-12 * 25.0;
    let want_a = [[0.0, 1.0], [-k / m, -c / m]];
    let a = matrix(&ss, "A");
    for (i, row) in want_a.iter().enumerate() {
        for (j, want) in row.iter().enumerate() {
            close(&format!("A[{i}][{j}]"), a[i][j], *want, tol);
        }
    }
    let b = matrix(&ss, "B");
    close("B[0]", b[0][0], 0.0, tol);
    close("B[1]", b[1][0], 1.0 / m, tol);
    let (cm, d) = (matrix(&ss, "C"), matrix(&ss, "D"));
    let want_c = [[1.0, 0.0, 0.0], [-k / m, -c / m, 1.0 / m], [0.0, 0.0, 0.0]];
    for (i, row) in want_c.iter().enumerate() {
        close(&format!("C[{i}][0]"), cm[i][0], row[0], tol);
        close(&format!("C[{i}][1]"), cm[i][1], row[1], tol);
        close(&format!("D[{i}]"), d[i][0], row[2], tol);
    }
    // δu = N δx: x itself, y fixed by the guide.
    assert_eq!(names(&ss, "coordinates"), ["slider.x", "slider.y"]);
    let n = matrix(&ss, "N");
    close("N[x]", n[0][0], 1.0, tol);
    close("N[y]", n[1][0], 0.0, tol);
    let _ = std::fs::remove_dir_all(&dir);
}

/// The paper's pendulum (m = 1 kg, l = 1 m, g = 10) about its hanging
/// equilibrium: `θ̈ = −(g/l) θ`, so `A = [[0, 1], [−10, 0]]` in the
/// state `(θ, θ̇)`; the bob moves sideways by `l δθ` (`N`), and the hinge's
/// horizontal reaction on it is the restoring force `−m g δθ`. Tolerances:
/// the equilibrium is found to `10⁻¹¹` of the force scale (10 N), and
/// the reaction's derivative is a central difference with an error of
/// about `10⁻¹⁰` of it.
#[test]
fn pendulum_about_its_hanging_equilibrium() {
    let dir = scratch("lin-pendulum");
    let out = dir.join("ss.json");
    ok(&[
        "linearize",
        &model("pendulum.toml"),
        "--outputs",
        "u:bob.x",
        "reaction:hinge.fx",
        "--out",
        &out.display().to_string(),
    ]);
    let ss = read_json(&out);
    assert_eq!(ss["about"], "equilibrium");
    let a = matrix(&ss, "A");
    let want = [[0.0, 1.0], [-10.0, 0.0]];
    for (i, row) in want.iter().enumerate() {
        for (j, w) in row.iter().enumerate() {
            close(&format!("A[{i}][{j}]"), a[i][j], *w, 1e-9);
        }
    }
    // One independent coordinate; δx = l δθ along the swing whichever it is.
    let states = names(&ss, "states");
    let n = matrix(&ss, "N");
    let coordinates = names(&ss, "coordinates");
    let at = |name: &str| coordinates.iter().position(|c| c == name).expect(name);
    let (x, y, theta) = (at("bob.x"), at("bob.y"), at("bob.theta"));
    close("N[y]/N[θ]", n[y][0] / n[theta][0], 0.0, 1e-9);
    close("N[x]/N[θ]", n[x][0] / n[theta][0], 1.0, 1e-9);
    assert_eq!(states.len(), 2, "{states:?}");
    let c = matrix(&ss, "C");
    // Per unit of the state: C = ∂y/∂q with δθ = δq / N[θ].
    close("C[u:bob.x]", c[0][0] / n[theta][0], 1.0, 1e-9);
    close("C[reaction:hinge.fx]", c[1][0] / n[theta][0], -10.0, 1e-8);
    let _ = std::fs::remove_dir_all(&dir);
}

/// About the file's pose (`--about initial`): the paper's pendulum released
/// horizontally at rest. There `θ̈ = −(g/l) sin θ` has `∂θ̈/∂θ = −(g/l) cos θ
/// = 0` (and the rod carries no tension, `λ = 0`: no geometric stiffness),
/// so `A = [[0, 1], [0, 0]]`, and the drift is `θ̈₀ = −g/l = −10` per unit
/// of θ (`xdot0`, scaled by `N`). Tolerance: round-off of `cos(π/2)`
/// times `g/l` and of the acceleration problem's solve, `10⁻¹²`.
#[test]
fn pendulum_about_its_initial_pose() {
    let dir = scratch("lin-initial");
    let out = dir.join("ss.json");
    ok(&[
        "linearize",
        &model("pendulum.toml"),
        "--about",
        "initial",
        "--out",
        &out.display().to_string(),
    ]);
    let ss = read_json(&out);
    assert_eq!(ss["about"], "initial");
    let a = matrix(&ss, "A");
    let want = [[0.0, 1.0], [0.0, 0.0]];
    for (i, row) in want.iter().enumerate() {
        for (j, w) in row.iter().enumerate() {
            close(&format!("A[{i}][{j}]"), a[i][j], *w, 1e-12);
        }
    }
    let coordinates = names(&ss, "coordinates");
    let theta = coordinates
        .iter()
        .position(|c| c == "bob.theta")
        .expect("θ");
    let n = matrix(&ss, "N");
    let xdot0 = ss["xdot0"].as_array().expect("xdot0");
    close("xdot0[0]", xdot0[0].as_f64().expect("a number"), 0.0, 1e-12);
    let q_ddot = xdot0[1].as_f64().expect("a number");
    close("θ̈₀", q_ddot * n[theta][0], -10.0, 1e-12);
    let _ = std::fs::remove_dir_all(&dir);
}

/// `models/double-pendulum.toml` with a motor torque on the upper bar
/// (0 in the file) and a damper at the elbow.
fn damped_double_pendulum() -> String {
    let base = std::fs::read_to_string(model("double-pendulum.toml")).expect("the model");
    base + r#"
[[force]]
name = "motor"
type = "torque"
body = "upper"
function = 0.0

[[force]]
name = "elbow-damper"
type = "rotational-spring-damper"
bodies = ["upper", "lower"]
stiffness = 0.0
damping = 0.05
"#
}

/// The rows of a CSV by column name, at the times `times` (exact rows).
fn csv_at(path: &Path, columns: &[String], times: &[f64]) -> Vec<Vec<f64>> {
    let csv = std::fs::read_to_string(path).expect("the CSV");
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().expect("a header").split(',').collect();
    let index = |c: &str| header.iter().position(|h| *h == c).expect(c);
    let t = index("t");
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|x| x.parse().expect("a number")).collect())
        .collect();
    times
        .iter()
        .map(|&time| {
            let row = rows
                .iter()
                .find(|r| (r[t] - time).abs() < 1e-9)
                .expect("a row at the time");
            columns.iter().map(|c| row[index(c)]).collect()
        })
        .collect()
}

/// `x(t)` of `ẋ = A x + B p`, `x(0) = 0`, at `times`, by RK4 with 10⁴
/// steps a second: its error, `O((ω h)⁴)` with `ω h ≤ 10⁻³`, is far below
/// the tolerance.
fn step_response(a: &[Vec<f64>], b: &[Vec<f64>], p: f64, times: &[f64]) -> Vec<Vec<f64>> {
    let n = a.len();
    let f = |x: &[f64]| -> Vec<f64> {
        (0..n)
            .map(|i| (0..n).map(|j| a[i][j] * x[j]).sum::<f64>() + b[i][0] * p)
            .collect()
    };
    let h = 1e-4;
    let mut x = vec![0.0; n];
    let mut t = 0.0;
    let mut out = Vec::new();
    for &end in times {
        while t < end - 1e-12 {
            let k1 = f(&x);
            let x2: Vec<f64> = (0..n).map(|i| x[i] + 0.5 * h * k1[i]).collect();
            let k2 = f(&x2);
            let x3: Vec<f64> = (0..n).map(|i| x[i] + 0.5 * h * k2[i]).collect();
            let k3 = f(&x3);
            let x4: Vec<f64> = (0..n).map(|i| x[i] + h * k3[i]).collect();
            let k4 = f(&x4);
            for i in 0..n {
                x[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
            }
            t += h;
        }
        out.push(x.clone());
    }
    out
}

/// The Done-when check: from the equilibrium written by `mstar equilibrium
/// --write-model`, `mstar run` with the motor's torque stepped to `δ =
/// 10⁻³ N m` against the linear model's step response `y0 + C x(t) + D δ`.
///
/// Tolerance, per output, relative to its largest deviation `Y` over the
/// run: the linearization error is `O(θ²)` relative, `θ ≤ δ / (m g l) ≈
/// 2·10⁻⁴` rad here, so below `10⁻⁷`; the run's step `h = 10⁻³` s with a
/// second-order scheme errs by `O(ω t (ω h)²)` after `t`, its phase error
/// `ω t (ω h)² / 12` (that of the trapezoidal rule, which generalized-α
/// with `ρ∞ = 0.9` is close to) being the leading part, with `ω² ≤
/// ‖M_r⁻¹ K_r‖∞` (any induced norm bounds the spectral radius), read from
/// `A`. Twice the sum is allowed (the errors measured are a twentieth to
/// a third of it, the largest for the reaction at `t = 0.25` s).
#[test]
fn step_response_matches_the_run() {
    let dir = scratch("lin-step");
    let file = dir.join("double.toml");
    std::fs::write(&file, damped_double_pendulum()).expect("model written");
    let eq = dir.join("eq.toml");
    let (file_s, eq_s) = (file.display().to_string(), eq.display().to_string());
    ok(&["equilibrium", &file_s, "--write-model", &eq_s]);
    let ss_path = dir.join("ss.json");
    ok(&[
        "linearize",
        &eq_s,
        "--inputs",
        "force.motor.function",
        "--outputs",
        "u:lower.theta",
        "u:upper.x",
        "reaction:shoulder.fx",
        "--out",
        &ss_path.display().to_string(),
    ]);
    let ss = read_json(&ss_path);
    let (a, b, c, d) = (
        matrix(&ss, "A"),
        matrix(&ss, "B"),
        matrix(&ss, "C"),
        matrix(&ss, "D"),
    );
    let y0: Vec<f64> = ss["y0"]
        .as_array()
        .expect("y0")
        .iter()
        .map(|x| x.as_f64().expect("a number"))
        .collect();
    let delta = 1e-3;
    let (h, t_end) = (1e-3, 1.0);
    let run = dir.join("run.csv");
    ok(&[
        "run",
        &eq_s,
        "--set",
        &format!("force.motor.function={delta}"),
        "--set",
        &format!("simulation.t_end={t_end}"),
        "--set",
        &format!("simulation.h={h}"),
        "--out",
        &run.display().to_string(),
    ]);
    let times = [0.25, 0.5, 0.75, 1.0];
    let outputs = names(&ss, "outputs");
    let got = csv_at(&run, &outputs, &times);
    let x = step_response(&a, &b, delta, &times);
    let r = a.len() / 2;
    let omega2 = (r..2 * r)
        .map(|i| (0..r).map(|j| a[i][j].abs()).sum::<f64>())
        .fold(0.0_f64, f64::max);
    let omega = omega2.sqrt();
    let linear: Vec<Vec<f64>> = x
        .iter()
        .map(|x| {
            (0..outputs.len())
                .map(|k| y0[k] + (0..2 * r).map(|j| c[k][j] * x[j]).sum::<f64>() + d[k][0] * delta)
                .collect()
        })
        .collect();
    for k in 0..outputs.len() {
        let scale = linear
            .iter()
            .map(|y| (y[k] - y0[k]).abs())
            .fold(0.0_f64, f64::max);
        assert!(scale > 0.0, "{} does not respond", outputs[k]);
        for (i, &t) in times.iter().enumerate() {
            let phase = omega * t * (omega * h).powi(2) / 12.0;
            let tol = 2.0 * (1e-7 + phase) * scale;
            close(
                &format!("{} at t = {t}", outputs[k]),
                got[i][k],
                linear[i][k],
                tol,
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The errors: a driver key as an input (exit 2, why and what instead), a
/// mass as an input (not a load), an output that names no column (the
/// close ones), `--out` naming the model file, a key that is not a number.
#[test]
fn errors_say_what_to_do() {
    let dir = scratch("lin-errors");
    let file = dir.join("slider.toml");
    std::fs::write(&file, SLIDER).expect("model written");
    let f = file.display().to_string();
    let out = dir.join("ss.json").display().to_string();
    let cases: [(&[&str], &str); 5] = [
        (
            &["--inputs", "driver.motor.function", "--out", &out],
            "impulse",
        ),
        (
            &["--inputs", "point_mass.slider.mass", "--out", &out],
            "the mass matrix",
        ),
        (
            &["--outputs", "u:slider.z", "--out", &out],
            "did you mean u:slider.x",
        ),
        (&["--out", &f], "names the model file"),
        (&["--inputs", "force.push", "--out", &out], "not a number"),
    ];
    for (args, want) in cases {
        let mut all = vec!["linearize", f.as_str()];
        all.extend_from_slice(args);
        let o = mstar(&all);
        let err = text(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(want), "{args:?}: {err}");
    }
    assert!(!Path::new(&out).exists(), "nothing written");
    let _ = std::fs::remove_dir_all(&dir);
}
