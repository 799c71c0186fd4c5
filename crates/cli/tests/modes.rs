//! `mstar modes` against closed forms: the double pendulum of point masses
//! (`ω² = (g/l)(2 ∓ √2)`), the fixed–fixed spring chain (`ω_j = 2 √(k/m)
//! sin(jπ/(2(n+1)))`), a damped single mode (`s = −c/2m ± i √(k/m −
//! (c/2m)²)`); the sparse eigensolver against the dense one on a hanging
//! chain; a rigid mode; the errors and exit codes; `mstar animate --mode`.
//!
//! Tolerances: the equilibrium is found to `‖r‖∞ ≤ 10⁻¹¹ F`, which moves
//! the stiffness (and `ω²`) by about `10⁻¹¹` relative; the eigensolvers add
//! round-off of `10⁻¹⁵`–`10⁻¹³` relative (the condition of `ω²` for
//! symmetric problems is one). The frequencies are checked to `10⁻⁹`
//! relative, shapes (of condition `‖K‖/gap`, at most about 10 here) to
//! `10⁻⁸`.

mod common;

use std::path::Path;

use common::{model, mstar, scratch, text};

/// The rows of a modes CSV: the header and each row's numbers.
fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let csv = std::fs::read_to_string(path).expect("the CSV is written");
    let mut lines = csv.lines();
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

/// Runs `mstar modes MODEL ARGS… --out modes.csv`, checks exit 0, returns
/// the CSV and the printed report.
fn modes(dir: &Path, model: &str, args: &[&str]) -> ((Vec<String>, Vec<Vec<f64>>), String) {
    let out = dir.join("modes.csv");
    let out_arg = out.display().to_string();
    let mut all = vec!["modes", model, "--out", &out_arg];
    all.extend_from_slice(args);
    let o = mstar(&all);
    assert!(o.status.success(), "{}{}", text(&o.stdout), text(&o.stderr));
    (read_csv(&out), text(&o.stdout))
}

fn close(what: &str, got: f64, want: f64, tol: f64) {
    assert!(
        (got - want).abs() <= tol,
        "{what}: {got} (want {want} ± {tol:e})"
    );
}

const TAU: f64 = std::f64::consts::TAU;

/// Two equal point masses (1 kg) on two 1 m rods hanging from the origin,
/// g = 9.81: `ω² = (g/l)(2 ∓ √2)`; in the lower mode the masses swing
/// together, `x_lower / x_upper = 1 + √2` (the angles' ratio `θ₂/θ₁ = √2`),
/// in the upper mode against each other, `1 − √2`; unit modal mass
/// `m (x₁² + x₂²) = 1` (the vertical components vanish at the hanging pose).
#[test]
fn double_pendulum_of_point_masses() {
    let dir = scratch("modes-double");
    let ((header, rows), report) = modes(&dir, &model("double-pendulum-modes.toml"), &[]);
    assert_eq!(
        header,
        [
            "mode",
            "frequency_hz",
            "damping_ratio",
            "u:upper.x",
            "u:upper.y",
            "u:lower.x",
            "u:lower.y"
        ]
    );
    assert_eq!(rows.len(), 2, "two degrees of freedom: {report}");
    let (g, l) = (9.81_f64, 1.0_f64);
    let r2 = 2.0_f64.sqrt();
    for (row, (sign, ratio)) in rows.iter().zip([(-1.0, 1.0 + r2), (1.0, 1.0 - r2)]) {
        let f = ((g / l) * (2.0 + sign * r2)).sqrt() / TAU;
        close("frequency", row[1], f, 1e-9 * f);
        assert_eq!(row[2], 0.0, "undamped");
        close("x_lower / x_upper", row[5] / row[3], ratio, 1e-8);
        close("y_upper", row[4], 0.0, 1e-8);
        close("y_lower", row[6], 0.0, 1e-8);
        close("modal mass", row[3] * row[3] + row[5] * row[5], 1.0, 1e-8);
    }
    assert!(report.contains("mode 1: f = 3.81526133"), "{report}");
    assert!(report.contains("mode 2: f = 9.21085566"), "{report}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Five 1 kg masses on a guide between two walls, six 100 N/m springs:
/// `ω_j = 2 √(k/m) sin(jπ/12)`, shapes `x_i ∝ sin(i j π/6)` with unit
/// modal mass `Σ m x_i² = 1`, i.e. `x_i = sin(i j π/6) / √3`.
#[test]
fn fixed_fixed_spring_chain() {
    let dir = scratch("modes-chain");
    let ((header, rows), _) = modes(&dir, &model("spring-chain-modes.toml"), &[]);
    assert_eq!(
        rows.len(),
        5,
        "five degrees of freedom (the default count, 10, is capped)"
    );
    let (k, m, n) = (100.0_f64, 1.0_f64, 5);
    for (j, row) in rows.iter().enumerate() {
        let j1 = (j + 1) as f64;
        let f = 2.0 * (k / m).sqrt() * (j1 * std::f64::consts::PI / 12.0).sin() / TAU;
        close("frequency", row[1], f, 1e-9 * f);
        let sign = row[3].signum();
        for i in 0..n {
            let x = header
                .iter()
                .position(|h| *h == format!("u:m{}.x", i + 1))
                .expect("column");
            let want = ((i + 1) as f64 * j1 * std::f64::consts::PI / 6.0).sin() / 3.0_f64.sqrt();
            close("shape", sign * row[x], want, 1e-8);
            close("y", row[x + 1], 0.0, 1e-12);
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// m = 2 kg, k = 50 N/m, c = 3 N s/m: `|s| = √(k/m) = 5`, `ζ = c / (2
/// √(k m)) = 0.15`, the damped frequency `√(k/m − (c/2m)²) / 2π`; the
/// shape `1/√m` along the guide.
#[test]
fn damped_single_mode() {
    let dir = scratch("modes-damped");
    let ((_, rows), report) = modes(&dir, &model("damped-mode.toml"), &[]);
    let (m, k, c) = (2.0_f64, 50.0_f64, 3.0_f64);
    close("frequency", rows[0][1], (k / m).sqrt() / TAU, 1e-9);
    close(
        "damping ratio",
        rows[0][2],
        c / (2.0 * (k * m).sqrt()),
        1e-9,
    );
    close("shape", rows[0][3], m.sqrt().recip(), 1e-12);
    let damped = (k / m - (c / (2.0 * m)).powi(2)).sqrt() / TAU;
    assert!(
        report.contains(&format!("Im(s)/2π = {damped:.6e} Hz")),
        "{report}\n{damped:.6e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A hanging chain of `links` uniform bars (1 kg, 1 m) on revolute joints,
/// straight down (its equilibrium).
fn hanging_chain(links: usize) -> String {
    let mut s = String::from("format = \"mstar.planar/1\"\n");
    for k in 0..links {
        s.push_str(&format!(
            "[[body]]\nname = \"bar{}\"\nmass = 1.0\ninertia = 0.08333333333333333\npose = [0.0, {:?}, -1.5707963267948966]\n",
            k + 1,
            -(k as f64 + 0.5)
        ));
    }
    for k in 0..links {
        let (a, p) = if k == 0 {
            ("ground".to_string(), "[0.0, 0.0]")
        } else {
            (format!("bar{k}"), "[0.5, 0.0]")
        };
        s.push_str(&format!(
            "[[joint]]\nname = \"j{}\"\ntype = \"revolute\"\nbodies = [\"{a}\", \"bar{}\"]\npoints = [{p}, [-0.5, 0.0]]\n",
            k + 1,
            k + 1
        ));
    }
    s
}

/// Shift-invert Lanczos on the sparse KKT matrix and the dense null-space
/// method agree on the six lowest modes of a 40-bar hanging chain:
/// frequencies to `10⁻⁹` relative, shapes (up to sign) to `10⁻⁷`.
#[test]
fn sparse_and_dense_agree_on_a_hanging_chain() {
    let dir = scratch("modes-sparse");
    let file = dir.join("chain.toml");
    std::fs::write(&file, hanging_chain(40)).expect("written");
    let f = file.display().to_string();
    let ((_, dense), _) = modes(&dir, &f, &["--count", "6", "--method", "dense"]);
    let ((_, sparse), report) = modes(&dir, &f, &["--count", "6", "--method", "sparse"]);
    assert!(report.contains("shift-invert Lanczos"), "{report}");
    for (d, s) in dense.iter().zip(&sparse) {
        close("frequency", s[1], d[1], 1e-9 * d[1]);
        let sign = (d[3] * s[3]).signum();
        for (a, b) in d[3..].iter().zip(&s[3..]) {
            close("shape", sign * b, *a, 1e-7);
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A mass on a horizontal guide without a spring: the equilibrium is
/// neutral, and its one mode is rigid (f = 0).
#[test]
fn a_free_slider_is_a_rigid_mode() {
    let dir = scratch("modes-rigid");
    let file = dir.join("free.toml");
    let text_model = std::fs::read_to_string(model("damped-mode.toml"))
        .expect("read")
        .replace("stiffness = 50.0", "stiffness = 0.0")
        .replace("damping = 3.0", "damping = 0.0");
    std::fs::write(&file, text_model).expect("written");
    let o = mstar(&["modes", &file.display().to_string()]);
    let (out, err) = (text(&o.stdout), text(&o.stderr));
    assert!(o.status.success(), "{out}{err}");
    assert!(err.contains("neutral"), "{err}");
    assert!(
        out.contains("mode 1: f = 0.000000000e0 Hz, ζ = 0 (rigid"),
        "{out}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Errors: too many modes (exit 1, with the degrees of freedom), no
/// equilibrium (exit 1, suggesting `--about initial`), an unreadable file
/// (exit 2), an `--out` naming the model (exit 2, the model untouched).
#[test]
fn errors_say_what_to_try() {
    let dir = scratch("modes-errors");
    let pendulum = model("pendulum.toml");
    let o = mstar(&["modes", &pendulum, "--count", "3"]);
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("1 degree of freedom") && err.contains("--count 1 or fewer"),
        "{err}"
    );

    // A point mass on a vertical guide falls for ever.
    let falling = dir.join("falling.toml");
    let text_model = std::fs::read_to_string(model("damped-mode.toml"))
        .expect("read")
        .replace("axis = [1.0, 0.0]", "axis = [0.0, 1.0]")
        .replace("stiffness = 50.0", "stiffness = 0.0");
    std::fs::write(&falling, text_model).expect("written");
    let o = mstar(&["modes", &falling.display().to_string()]);
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("no equilibrium") && err.contains("--about initial"),
        "{err}"
    );
    // About the initial pose it has one rigid mode (gravity has no stiffness).
    let o = mstar(&[
        "modes",
        &falling.display().to_string(),
        "--about",
        "initial",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(text(&o.stdout).contains("(rigid"), "{}", text(&o.stdout));

    let o = mstar(&["modes", &dir.join("missing.toml").display().to_string()]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o.stderr));

    let copy = dir.join("pendulum.toml");
    std::fs::copy(&pendulum, &copy).expect("copied");
    let before = std::fs::read(&copy).expect("read");
    let c = copy.display().to_string();
    let o = mstar(&["modes", &c, "--out", &c]);
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("names the model file"), "{err}");
    assert_eq!(std::fs::read(&copy).expect("read"), before);
    let _ = std::fs::remove_dir_all(&dir);
}
