//! `[[sensor]]` and `[output] columns` (docs/model-format.md, "`[[sensor]]`",
//! "Choosing columns", "Binary output"): a model with a sensor of every
//! type writes exactly the chosen columns, in CSV and in `.npz`, and each
//! sensor's values agree with what the test works out from the full
//! output's coordinates, velocities and accelerations by its own formulas
//! (planar: rigid-body kinematics written out; spatial: the rotation matrix
//! of a unit quaternion in its textbook form, and central differences in
//! time for the rates). Malformed sensors and column choices are errors at
//! `FILE:LINE:COLUMN` naming the key.

mod common;

use std::collections::HashMap;
use std::path::Path;

use common::{model, mstar, scratch, text};

/// A CSV file's columns by name, and the names in order.
fn read_csv(path: &Path) -> (Vec<String>, HashMap<String, Vec<f64>>) {
    let body = std::fs::read_to_string(path).expect("the CSV file");
    let mut lines = body.lines();
    let names: Vec<String> = lines
        .next()
        .expect("a header")
        .split(',')
        .map(String::from)
        .collect();
    let mut columns: HashMap<String, Vec<f64>> = HashMap::new();
    for line in lines {
        for (name, field) in names.iter().zip(line.split(',')) {
            let x: f64 = field.parse().expect("a number");
            columns.entry(name.clone()).or_default().push(x);
        }
    }
    (names, columns)
}

/// Runs `mstar run FILE --out OUT` plus `extra`, which must succeed.
fn run(file: &Path, out: &Path, extra: &[&str]) {
    let (f, o) = (file.display().to_string(), out.display().to_string());
    let mut args = vec!["run", f.as_str(), "--out", o.as_str()];
    args.extend_from_slice(extra);
    let r = mstar(&args);
    assert!(r.status.success(), "{}", text(&r.stderr));
}

/// `|got − want| ≤ tol` at every row, NaN failing.
fn close(what: &str, got: &[f64], want: &[f64], tol: f64) {
    assert_eq!(got.len(), want.len(), "{what}: rows");
    for (k, (g, w)) in got.iter().zip(want).enumerate() {
        assert!(
            (g - w).abs() <= tol,
            "{what}, row {k}: {g} against {w} (tol {tol:e})"
        );
    }
}

const PLANAR_SENSORS: &str = r#"
[[sensor]]
name = "tip"
type = "position"
body = "coupler"
point = [0.2, 0.05]

[[sensor]]
name = "tip_v"
type = "velocity"
body = "coupler"
point = [0.2, 0.05]

[[sensor]]
name = "tip_a"
type = "acceleration"
body = "coupler"
point = [0.2, 0.05]

[[sensor]]
name = "spin"
type = "angular-velocity"
body = "rocker"

[[sensor]]
name = "angle"
type = "orientation"
body = "rocker"

[[sensor]]
name = "gap"
type = "distance"
bodies = ["ground", "coupler"]
points = [[0.6, 0.0], [0.2, 0.05]]

[[sensor]]
name = "pin"
type = "reaction"
joint = "O2"

[[sensor]]
name = "drive"
type = "effort"
driver = "motor"

[output]
columns = ["t", "sensor:*", "reaction:O2.*", "effort:*"]
"#;

/// The planar four-bar with every sensor: the chosen columns only, and
/// values from rigid-body kinematics written out here.
#[test]
fn planar_sensors_are_the_kinematics_of_the_full_output() {
    let dir = scratch("sensors-planar");
    let base = std::fs::read_to_string(model("four-bar.toml")).expect("the model");
    let file = dir.join("four-bar-sensors.toml");
    std::fs::write(&file, format!("{base}{PLANAR_SENSORS}")).expect("written");
    let (full, chosen) = (dir.join("full.csv"), dir.join("chosen.csv"));
    run(&file, &chosen, &["--t-end", "0.2"]);
    run(&file, &full, &["--t-end", "0.2", "--columns", "*"]);
    let (names, s) = read_csv(&chosen);
    let want: Vec<&str> = vec![
        "t",
        "reaction:O2.fx",
        "reaction:O2.fy",
        "reaction:O2.tau",
        "effort:motor",
        "sensor:tip.x",
        "sensor:tip.y",
        "sensor:tip_v.x",
        "sensor:tip_v.y",
        "sensor:tip_a.x",
        "sensor:tip_a.y",
        "sensor:spin.w",
        "sensor:angle.theta",
        "sensor:gap",
        "sensor:pin.fx",
        "sensor:pin.fy",
        "sensor:pin.tau",
        "sensor:drive",
    ];
    assert_eq!(names, want);
    let (_, f) = read_csv(&full);
    let col = |name: &str| f.get(name).unwrap_or_else(|| panic!("{name}")).clone();
    let (x, y, th) = (
        col("u:coupler.x"),
        col("u:coupler.y"),
        col("u:coupler.theta"),
    );
    let (vx, vy, w) = (
        col("v:coupler.x"),
        col("v:coupler.y"),
        col("v:coupler.theta"),
    );
    let (ax, ay, dw) = (
        col("a:coupler.x"),
        col("a:coupler.y"),
        col("a:coupler.theta"),
    );
    let (px, py) = (0.2, 0.05);
    let rows = x.len();
    let mut want: HashMap<&str, Vec<f64>> = HashMap::new();
    for k in 0..rows {
        let (sin, cos) = th[k].sin_cos();
        // The point relative to the centre, in global axes, and ω × it.
        let (dx, dy) = (cos * px - sin * py, sin * px + cos * py);
        let mut push = |name, v| want.entry(name).or_default().push(v);
        push("sensor:tip.x", x[k] + dx);
        push("sensor:tip.y", y[k] + dy);
        push("sensor:tip_v.x", vx[k] - w[k] * dy);
        push("sensor:tip_v.y", vy[k] + w[k] * dx);
        push("sensor:tip_a.x", ax[k] - dw[k] * dy - w[k] * w[k] * dx);
        push("sensor:tip_a.y", ay[k] + dw[k] * dx - w[k] * w[k] * dy);
        push("sensor:gap", (x[k] + dx - 0.6).hypot(y[k] + dy));
    }
    for (name, values) in &want {
        close(name, &s[*name], values, 1e-12 * (1.0 + values[0].abs()));
    }
    close("spin", &s["sensor:spin.w"], &col("v:rocker.theta"), 0.0);
    close(
        "angle",
        &s["sensor:angle.theta"],
        &col("u:rocker.theta"),
        0.0,
    );
    for c in ["fx", "fy", "tau"] {
        close(
            c,
            &s[&format!("sensor:pin.{c}")],
            &col(&format!("reaction:O2.{c}")),
            0.0,
        );
    }
    // The effort is −λ of the driver's row.
    let minus: Vec<f64> = col("lambda:motor").iter().map(|l| -l).collect();
    close("effort", &s["sensor:drive"], &minus, 0.0);
}

const SPATIAL_SENSORS: &str = r#"
[[sensor]]
name = "end"
type = "position"
body = "lower"
point = [0.0, 0.5, 0.0]

[[sensor]]
name = "end_v"
type = "velocity"
body = "lower"
point = [0.0, 0.5, 0.0]

[[sensor]]
name = "end_a"
type = "acceleration"
body = "lower"
point = [0.0, 0.5, 0.0]

[[sensor]]
name = "omega"
type = "angular-velocity"
body = "lower"

[[sensor]]
name = "attitude"
type = "orientation"
body = "lower"

[[sensor]]
name = "reach"
type = "distance"
bodies = ["ground", "lower"]
points = [[0.0, 0.0, 0.0], [0.0, 0.5, 0.0]]

[[sensor]]
name = "elbow_load"
type = "reaction"
joint = "elbow"
"#;

/// The rotation matrix of the unit quaternion `[e0, e1, e2, e3]`
/// (Shuster, "A survey of attitude representations", 1993, eq. 161,
/// transposed to body → global).
fn quaternion_matrix(e: [f64; 4]) -> [[f64; 3]; 3] {
    let [w, x, y, z] = e;
    [
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - w * z),
            2.0 * (x * z + w * y),
        ],
        [
            2.0 * (x * y + w * z),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - w * x),
        ],
        [
            2.0 * (x * z - w * y),
            2.0 * (y * z + w * x),
            1.0 - 2.0 * (x * x + y * y),
        ],
    ]
}

/// `Rz(yaw) Ry(pitch) Rx(roll)`, each elementary rotation written out.
fn cardan_matrix(roll: f64, pitch: f64, yaw: f64) -> [[f64; 3]; 3] {
    let mul = |a: [[f64; 3]; 3], b: [[f64; 3]; 3]| {
        let mut c = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                c[i][j] = (0..3).map(|k| a[i][k] * b[k][j]).sum();
            }
        }
        c
    };
    let (sr, cr, sp, cp, sy, cy) = (
        roll.sin(),
        roll.cos(),
        pitch.sin(),
        pitch.cos(),
        yaw.sin(),
        yaw.cos(),
    );
    let rx = [[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]];
    let ry = [[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]];
    let rz = [[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]];
    mul(rz, mul(ry, rx))
}

/// The central difference of `x` (rows `h` apart) at the inner rows.
fn central(x: &[f64], h: f64) -> Vec<f64> {
    (1..x.len() - 1)
        .map(|k| (x[k + 1] - x[k - 1]) / (2.0 * h))
        .collect()
}

/// The spatial double pendulum with every point and body sensor: positions
/// and angles from the test's own rotation matrices, rates from central
/// differences of them. A central difference of a second-order solution
/// differs from its rate by `O(h²)`: at most `h² max|x⁽³⁾|` with the
/// third derivative bounded from the data (differences of the sensor's own
/// next rate, times a safety factor of 2).
#[test]
fn spatial_sensors_agree_with_rotation_matrices_and_differences() {
    let dir = scratch("sensors-spatial");
    let base = std::fs::read_to_string(model("spatial/double-pendulum.toml")).expect("model");
    let file = dir.join("double-pendulum-sensors.toml");
    std::fs::write(&file, format!("{base}{SPATIAL_SENSORS}")).expect("written");
    let out = dir.join("all.csv");
    let h = 1e-3;
    run(&file, &out, &["--t-end", "0.3", "--h", "1e-3"]);
    let (_, f) = read_csv(&out);
    let col = |name: &str| f.get(name).unwrap_or_else(|| panic!("{name}")).clone();
    let rows = col("t").len();
    let e: Vec<[f64; 4]> = (0..rows)
        .map(|k| ["e0", "e1", "e2", "e3"].map(|c| col(&format!("u:lower.{c}"))[k]))
        .collect();
    let a: Vec<[[f64; 3]; 3]> = e.iter().map(|&q| quaternion_matrix(q)).collect();
    let c: Vec<[f64; 3]> = (0..rows)
        .map(|k| ["x", "y", "z"].map(|c| col(&format!("u:lower.{c}"))[k]))
        .collect();
    // Positions: r + A s, s = (0, 0.5, 0).
    for (i, axis) in ["x", "y", "z"].iter().enumerate() {
        let want: Vec<f64> = (0..rows).map(|k| c[k][i] + 0.5 * a[k][i][1]).collect();
        close(
            &format!("end.{axis}"),
            &col(&format!("sensor:end.{axis}")),
            &want,
            1e-9,
        );
    }
    let reach: Vec<f64> = (0..rows)
        .map(|k| {
            ["x", "y", "z"]
                .iter()
                .map(|ax| col(&format!("sensor:end.{ax}"))[k].powi(2))
                .sum::<f64>()
                .sqrt()
        })
        .collect();
    close("reach", &col("sensor:reach"), &reach, 1e-12);
    // Orientation: the Cardan angles give back the quaternion's matrix.
    for k in 0..rows {
        let [r, p, y] = ["roll", "pitch", "yaw"].map(|n| col(&format!("sensor:attitude.{n}"))[k]);
        let m = cardan_matrix(r, p, y);
        for i in 0..3 {
            for j in 0..3 {
                assert!(
                    (m[i][j] - a[k][i][j]).abs() < 1e-9,
                    "row {k}: {m:?} against {:?}",
                    a[k]
                );
            }
        }
    }
    // Rates: velocity and acceleration of the end, and ω, against central
    // differences of position, velocity and A (ω̃ = Ȧ Aᵀ).
    for axis in ["x", "y", "z"] {
        let (p, v, acc) = (
            col(&format!("sensor:end.{axis}")),
            col(&format!("sensor:end_v.{axis}")),
            col(&format!("sensor:end_a.{axis}")),
        );
        let jerk = central(&acc, h).iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        let tol = 2.0 * h * h * jerk.max(1.0);
        close(
            &format!("end_v.{axis}"),
            &central(&p, h),
            &v[1..rows - 1],
            tol,
        );
        let snap = central(&central(&acc, h), h)
            .iter()
            .fold(0.0_f64, |m, x| m.max(x.abs()));
        let tol = 2.0 * h * h * snap.max(1.0);
        close(
            &format!("end_a.{axis}"),
            &central(&v, h),
            &acc[1..rows - 1],
            tol,
        );
    }
    let omega: Vec<[f64; 3]> = (0..rows)
        .map(|k| ["wx", "wy", "wz"].map(|n| col(&format!("sensor:omega.{n}"))[k]))
        .collect();
    let alpha_max = (1..rows - 1)
        .flat_map(|k| (0..3).map(move |i| (k, i)))
        .map(|(k, i)| ((omega[k + 1][i] - omega[k - 1][i]) / (2.0 * h)).abs())
        .fold(0.0_f64, f64::max);
    let w_max = omega.iter().flatten().fold(0.0_f64, |m, x| m.max(x.abs()));
    // (Ȧ's difference errs by h² |A⁽³⁾| ≤ h² (|ω|³ + 3|ω||α| + |α̇|).)
    let tol = 2.0 * h * h * (w_max.powi(3) + 3.0 * w_max * alpha_max + 10.0 * alpha_max + 1.0);
    for k in 1..rows - 1 {
        let mut w_tilde = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                w_tilde[i][j] = (0..3)
                    .map(|m| (a[k + 1][i][m] - a[k - 1][i][m]) / (2.0 * h) * a[k][j][m])
                    .sum();
            }
        }
        let from_a = [w_tilde[2][1], w_tilde[0][2], w_tilde[1][0]];
        for i in 0..3 {
            assert!(
                (from_a[i] - omega[k][i]).abs() <= tol,
                "row {k}: ω {:?} against {from_a:?} (tol {tol:e})",
                omega[k]
            );
        }
    }
    for comp in ["fx", "fy", "fz", "tx", "ty", "tz"] {
        close(
            comp,
            &col(&format!("sensor:elbow_load.{comp}")),
            &col(&format!("reaction:elbow.{comp}")),
            0.0,
        );
    }
}

/// Malformed sensors and column choices: `mstar check` and `mstar run`
/// name the file, line, column and key, and say what is known (exit 2).
#[test]
fn malformed_sensors_and_columns_are_placed_errors() {
    let dir = scratch("sensors-errors");
    let base = std::fs::read_to_string(model("four-bar.toml")).expect("the model");
    let cases: [(&str, &str); 7] = [
        (
            "[[sensor]]\nname = \"s\"\ntype = \"position\"\nbody = \"coupla\"\n",
            ":62:8: sensor 's': body: no body or point mass is called 'coupla' (known: ground, coupler, crank, rocker)",
        ),
        (
            "[[sensor]]\nname = \"s\"\ntype = \"speed\"\nbody = \"coupler\"\n",
            ":61:8: sensor 's': type:",
        ),
        (
            "[[sensor]]\nname = \"s\"\ntype = \"effort\"\ndriver = \"O2\"\n",
            ":62:10: sensor 's': driver: no driver is called 'O2' ('O2' is a joint) (known: motor)",
        ),
        (
            "[[sensor]]\nname = \"s\"\ntype = \"reaction\"\njoint = \"crank\"\n",
            ":62:9: sensor 's': joint: no joint or driver is called 'crank' ('crank' is a body)",
        ),
        (
            "[[sensor]]\nname = \"s\"\ntype = \"position\"\nbody = \"coupler\"\npoint = [1.0]\n",
            ":63:9: sensor 's': point: expected 2 numbers, found 1",
        ),
        (
            "[[sensor]]\nname = \"O2\"\ntype = \"position\"\nbody = \"coupler\"\n",
            "the name 'O2' is used twice",
        ),
        (
            "[output]\ncolumns = []\n",
            ":60:11: [output]: columns: an empty list selects no column",
        ),
    ];
    for (k, (extra, want)) in cases.iter().enumerate() {
        let file = dir.join(format!("bad{k}.toml"));
        std::fs::write(&file, format!("{base}\n{extra}")).expect("written");
        let f = file.display().to_string();
        for command in ["check", "run"] {
            let r =
                mstar(&[command, &f, "--t-end", "0.01"][..if command == "check" { 2 } else { 4 }]);
            let err = text(&r.stderr);
            assert_eq!(r.status.code(), Some(2), "{command} case {k}: {err}");
            assert!(
                err.contains(&format!("{f}{want}"))
                    || (!want.starts_with(':') && err.contains(want)),
                "{command} case {k}: {err}"
            );
        }
    }
    // A pattern that names no column: the closest names (exit 2).
    let r = mstar(&[
        "run",
        &model("four-bar.toml"),
        "--t-end",
        "0.01",
        "--out",
        &dir.join("o.csv").display().to_string(),
        "--columns",
        "t,reaction:O3.*",
    ]);
    let err = text(&r.stderr);
    assert_eq!(r.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--columns: 'reaction:O3.*' names no column (did you mean reaction:O2.fx"),
        "{err}"
    );
    // The same in the file's `[output] columns`: placed at the key.
    let file = dir.join("bad-columns.toml");
    std::fs::write(
        &file,
        format!("{base}\n[output]\ncolumns = [\"t\", \"reaction:O3.*\"]\n"),
    )
    .expect("written");
    let f = file.display().to_string();
    let out = dir.join("o.csv").display().to_string();
    let r = mstar(&["run", &f, "--t-end", "0.01", "--out", &out]);
    let err = text(&r.stderr);
    assert_eq!(r.status.code(), Some(2), "{err}");
    assert!(
        err.contains(&format!(
            "{f}:60:11: [output]: columns: 'reaction:O3.*' names no column (did you mean reaction:O2.fx"
        )),
        "{err}"
    );
}

/// A sweep's runs write the chosen columns, and its summary has each
/// sensor's value at the last state under the CSV's name: the last row of
/// the run's own file.
#[test]
fn a_sweep_summary_has_the_sensors_last_values() {
    let dir = scratch("sensors-sweep");
    let base = std::fs::read_to_string(model("four-bar.toml")).expect("the model");
    let file = dir.join("four-bar-sensors.toml");
    std::fs::write(&file, format!("{base}{PLANAR_SENSORS}")).expect("written");
    let out = dir.join("sweep");
    let r = mstar(&[
        "sweep",
        &file.display().to_string(),
        "--set",
        "body.coupler.mass=1.0,1.5",
        "--set",
        "simulation.t_end=0.05",
        "--out",
        &out.display().to_string(),
    ]);
    assert!(r.status.success(), "{}", text(&r.stderr));
    let body = std::fs::read_to_string(out.join("summary.csv")).expect("the summary");
    let mut lines = body.lines();
    let names: Vec<String> = lines
        .next()
        .expect("a header")
        .split(',')
        .map(String::from)
        .collect();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    let summary = |name: &str, run: usize| -> f64 {
        let k = names.iter().position(|n| n == name).expect("a column");
        rows[run][k].parse().expect("a number")
    };
    for run in 0..2 {
        let (run_names, rows) = read_csv(&out.join(format!("runs/{run}.csv")));
        assert_eq!(run_names[0], "t");
        assert!(
            run_names.iter().all(|n| n == "t"
                || n.starts_with("sensor:")
                || n.starts_with("reaction:O2.")
                || n.starts_with("effort:")),
            "{run_names:?}"
        );
        for name in run_names.iter().filter(|n| n.starts_with("sensor:")) {
            assert!(names.contains(name), "{name} not in {names:?}");
            let last = *rows[name].last().expect("rows");
            assert_eq!(
                summary(name, run).to_bits(),
                last.to_bits(),
                "{name}, run {run}"
            );
        }
    }
}
