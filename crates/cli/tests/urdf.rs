//! URDF robots through the program: `mstar run`, `check`, `convert` and
//! `animate` on a `.urdf`, a `mstar.spatial/1` file that starts from one
//! (`urdf = …`), against Pinocchio's articulated-body algorithm on the same
//! URDF (benches/pinocchio/urdf_two_link.py), and the errors.

mod common;

use std::path::Path;

use common::{model, mstar, scratch, text};

/// The columns of a CSV file by name.
fn columns(path: &Path) -> std::collections::HashMap<String, Vec<f64>> {
    let body = std::fs::read_to_string(path).expect("the CSV");
    let mut lines = body.lines();
    let header: Vec<String> = lines
        .next()
        .expect("a header")
        .split(',')
        .map(str::to_string)
        .collect();
    let mut cols: Vec<Vec<f64>> = vec![Vec::new(); header.len()];
    for line in lines {
        for (k, x) in line.split(',').enumerate() {
            cols[k].push(x.parse().expect("a number"));
        }
    }
    header.into_iter().zip(cols).collect()
}

/// The reference's data file.
fn data(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

/// The largest distance over the reference's rows (every 0.01 s) between
/// mstar's centres of mass, run at step `h`, and Pinocchio's.
fn error_against_pinocchio(model_file: &str, reference: &str, h: f64, dir: &Path) -> f64 {
    let out = dir.join(format!("run-{h}.csv"));
    let o = mstar(&[
        "run",
        model_file,
        "--t-end",
        "1",
        "--h",
        &h.to_string(),
        "--out",
        out.to_str().expect("utf-8"),
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let run = columns(&out);
    let pin = columns(&data(reference));
    let every = (0.01 / h).round() as usize;
    let mut worst = 0.0_f64;
    for body in ["upper_arm", "forearm"] {
        for axis in ["x", "y", "z"] {
            let ours = &run[&format!("u:{body}.{axis}")];
            let theirs = &pin[&format!("{body}.{axis}")];
            assert_eq!(theirs.len(), 101);
            assert!(
                (ours[0] - theirs[0]).abs() < 1e-14,
                "{body}.{axis} at t = 0"
            );
            for (k, x) in theirs.iter().enumerate() {
                worst = worst.max((ours[k * every] - x).abs());
            }
        }
    }
    worst
}

/// The arm (the URDF as it is: released at rest; and started at non-zero
/// joint angles and rates by a TOML file with `urdf =` and `[[initial]]`)
/// follows Pinocchio's solution with an error that falls as h², as
/// generalized-α's second order says: halving h divides it by 4. Orders 1
/// and 3 would give 2 and 8, and an error in the model (an inertia, an
/// axis, an initial velocity converted wrongly) one that does not fall
/// (ratio → 1): the ratio must be nearer 4 than either neighbour on a log
/// scale, within [2√2, 4√2]. The reference's own error (RK4 at 1e-5 s) is
/// below 1e-15 m. Absolute: the error at h = 2.5e-3 s over 1 s must be
/// within 1e-4 m, 1e-4 of the arm's 0.9 m reach (it is 7e-5 m; the h²
/// coefficient measured from the two runs, 12 m/s², gives the same).
#[test]
fn two_link_arm_matches_pinocchio_at_second_order() {
    let dir = scratch("urdf-pinocchio");
    for (file, reference) in [
        ("urdf/two-link-arm.urdf", "urdf-two-link-rest.csv"),
        ("urdf/two-link-arm-start.toml", "urdf-two-link-start.csv"),
    ] {
        let e1 = error_against_pinocchio(&model(file), reference, 5e-3, &dir);
        let e2 = error_against_pinocchio(&model(file), reference, 2.5e-3, &dir);
        let ratio = e1 / e2;
        let sqrt2 = std::f64::consts::SQRT_2;
        assert!(
            (2.0 * sqrt2..4.0 * sqrt2).contains(&ratio),
            "{file}: errors {e1:e} at h = 5e-3, {e2:e} at 2.5e-3: ratio {ratio}"
        );
        assert!(e2 < 1e-4, "{file}: error {e2:e} m at h = 2.5e-3");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `mstar convert` writes the model `mstar run` reads from the URDF: the
/// two runs' CSV files are the same, byte for byte. And the notes about
/// ignored elements come once each.
#[test]
fn converted_file_runs_as_the_urdf_byte_for_byte() {
    let dir = scratch("urdf-convert");
    let toml = dir.join("arm.toml");
    let o = mstar(&[
        "convert",
        &model("urdf/two-link-arm.urdf"),
        "--out",
        toml.to_str().expect("utf-8"),
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let notes = text(&o.stderr);
    for tag in ["<visual>", "<limit>", "<dynamics>"] {
        assert_eq!(notes.matches(tag).count(), 1, "{notes}");
    }
    let mut csv = Vec::new();
    for (k, input) in [model("urdf/two-link-arm.urdf"), toml.display().to_string()]
        .iter()
        .enumerate()
    {
        let out = dir.join(format!("{k}.csv"));
        let o = mstar(&[
            "run",
            input,
            "--t-end",
            "0.2",
            "--set",
            "simulation.h=2e-3",
            "--out",
            out.to_str().expect("utf-8"),
        ]);
        assert!(o.status.success(), "{}", text(&o.stderr));
        csv.push(std::fs::read(&out).expect("the CSV"));
    }
    assert!(csv[0].len() > 1000);
    assert!(csv[0] == csv[1], "the two runs differ");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The four-bar as a URDF chain (crank, coupler, rocker) closed by one
/// revolute joint D in TOML. Degrees of freedom by hand: 3 rigid bodies, 21
/// coordinates; rows 3 (norms) + 4 revolute joints × 5 = 23. The loop is
/// planar (all axes along y), so it moves as a planar four-bar: Grübler's
/// 3 (4 − 1) − 2 · 4 = 1 degree of freedom, rank 21 − 1 = 20, and D's rows
/// repeat 3 of the chain's (the out-of-plane ones): D is redundant. The run
/// (minimum-norm multipliers) holds the loop to round-off: the constraint
/// column (‖Φ‖∞ after each step's Newton iteration, whose tolerance is on
/// the residual) stays at 1e-12, as the repository's other loops.
#[test]
fn four_bar_closed_in_toml_has_one_degree_of_freedom_and_holds() {
    let o = mstar(&["check", &model("urdf/four-bar.toml")]);
    let out = text(&o.stdout);
    assert!(o.status.success(), "{out}{}", text(&o.stderr));
    assert!(out.contains("coordinates: 21\n"), "{out}");
    assert!(out.contains("constraints: 23\n"), "{out}");
    assert!(out.contains("degrees of freedom: 1\n"), "{out}");
    assert!(out.contains("redundant constraints: D "), "{out}");
    let dir = scratch("urdf-four-bar");
    let csv = dir.join("four-bar.csv");
    let o = mstar(&[
        "run",
        &model("urdf/four-bar.toml"),
        "--t-end",
        "1",
        "--out",
        csv.to_str().expect("utf-8"),
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let cols = columns(&csv);
    let worst = cols["constraint"]
        .iter()
        .fold(0.0_f64, |m, x| m.max(x.abs()));
    assert!(worst <= 1e-12, "constraint {worst:e}");
    // It moves: the crank turns (e2 = sin(θ/2) of its turn about y).
    let turned = cols["u:crank.e2"]
        .iter()
        .fold(0.0_f64, |m, x| m.max(x.abs()));
    assert!(turned > 0.05, "{turned}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `mstar animate` reads a URDF as `run` does.
#[test]
fn animate_draws_a_urdf_run() {
    let dir = scratch("urdf-animate");
    let csv = dir.join("arm.csv");
    let png = dir.join("arm.png");
    let urdf = model("urdf/two-link-arm.urdf");
    let o = mstar(&[
        "run",
        &urdf,
        "--t-end",
        "0.1",
        "--out",
        csv.to_str().expect("utf-8"),
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let o = mstar(&[
        "animate",
        &urdf,
        csv.to_str().expect("utf-8"),
        "--png",
        png.to_str().expect("utf-8"),
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(std::fs::metadata(&png).expect("the picture").len() > 0);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Errors: `FILE:LINE:COLUMN: what`, exit 2, for `check`, `run` and
/// `convert` alike.
#[test]
fn malformed_urdfs_are_errors_with_a_place() {
    let dir = scratch("urdf-errors");
    let arm = std::fs::read_to_string(model("urdf/two-link-arm.urdf")).expect("the URDF");
    let cases = [
        // The close tag of the elbow joint dropped: <robot> closes it (line 57).
        (
            arm.replacen(
                "  </joint>\n\n  <joint name=\"tool_mount\"",
                "\n  <joint name=\"tool_mount\"",
                1,
            ),
            "XML syntax",
        ),
        (
            arm.replace("type=\"continuous\"", "type=\"floating\""),
            "joint 'elbow': type: 'floating' is not supported",
        ),
        (
            arm.replace(
                "<parent link=\"upper_arm\"/>",
                "<parent link=\"upperarm\"/>",
            ),
            "joint 'elbow': parent: no link is called 'upperarm'",
        ),
    ];
    for (k, (body, says)) in cases.iter().enumerate() {
        let path = dir.join(format!("bad-{k}.urdf"));
        std::fs::write(&path, body).expect("written");
        let p = path.to_str().expect("utf-8");
        for args in [vec!["check", p], vec!["run", p], vec!["convert", p]] {
            let o = mstar(&args);
            let err = text(&o.stderr);
            assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
            let place = format!("error: {p}:");
            let rest = err
                .split(&place)
                .nth(1)
                .unwrap_or_else(|| panic!("{args:?}: {err}"));
            // LINE:COLUMN: then the message.
            let mut parts = rest.splitn(3, ':');
            for _ in 0..2 {
                let n = parts.next().unwrap_or("");
                assert!(n.parse::<usize>().is_ok(), "{args:?}: {err}");
            }
            assert!(err.contains(says), "{args:?}: {err}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `--set` reaches the URDF's bodies, in a `.urdf` and in a file that
/// starts from one; a value out of range is the model's error, named by
/// its body and the override that gave it (and not placed in the URDF,
/// which does not hold it).
#[test]
fn overrides_reach_the_urdf_bodies() {
    for file in ["urdf/two-link-arm.urdf", "urdf/two-link-arm-start.toml"] {
        let o = mstar(&["check", &model(file), "--set", "body.forearm.mass=1.5"]);
        assert!(o.status.success(), "{file}: {}", text(&o.stderr));
        let o = mstar(&["check", &model(file), "--set", "body.forearm.mass=-1"]);
        let err = text(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{file}: {err}");
        assert!(
            err.contains(&format!(
                "{}: --set body.forearm.mass=-1: body 'forearm': mass: must be positive",
                model(file)
            )),
            "{file}: {err}"
        );
    }
}
