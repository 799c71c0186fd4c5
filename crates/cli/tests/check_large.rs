//! `mstar check` above the dense rank computation's size
//! (`mstar::redundant::DENSE_LIMIT`): degrees of freedom and redundant
//! joints by name from the sparse elimination, never "none" unlooked.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::Command;

/// The IFToMM N-four-bar (`models/n-four-bar.toml`) with `bars` couplers;
/// with `twice`, the joint `B{k}-C{k+1}` (`k = bars / 2`) once more.
fn n_four_bar(bars: usize, twice: bool) -> String {
    let mut s = String::from("format = \"mstar.planar/1\"\n");
    let mut body = |name: String, pose: [f64; 3]| {
        let _ = writeln!(
            s,
            "[[body]]\nname = \"{name}\"\nmass = 1.0\ninertia = 0.08333333333333333\npose = [{:?}, {:?}, {:?}]",
            pose[0], pose[1], pose[2]
        );
    };
    for i in 0..=bars {
        body(
            format!("V{i}"),
            [i as f64, 0.5, std::f64::consts::FRAC_PI_2],
        );
    }
    for i in 1..=bars {
        body(format!("C{i}"), [i as f64 - 0.5, 1.0, 0.0]);
    }
    let mut joint = |name: String, a: String, b: String, p: [f64; 4]| {
        let _ = writeln!(
            s,
            "[[joint]]\nname = \"{name}\"\ntype = \"revolute\"\nbodies = [\"{a}\", \"{b}\"]\npoints = [[{:?}, {:?}], [{:?}, {:?}]]",
            p[0], p[1], p[2], p[3]
        );
    };
    for i in 0..=bars {
        joint(
            format!("A{i}"),
            "ground".into(),
            format!("V{i}"),
            [i as f64, 0.0, -0.5, 0.0],
        );
    }
    for i in 0..bars {
        let c = format!("C{}", i + 1);
        joint(
            format!("B{i}-{c}"),
            format!("V{i}"),
            c.clone(),
            [0.5, 0.0, -0.5, 0.0],
        );
        joint(
            format!("B{}-{c}", i + 1),
            format!("V{}", i + 1),
            c,
            [0.5, 0.0, 0.5, 0.0],
        );
    }
    if twice {
        let k = bars / 2;
        let c = format!("C{}", k + 1);
        joint(
            format!("B{k}-{c}-again"),
            format!("V{k}"),
            c,
            [0.5, 0.0, -0.5, 0.0],
        );
    }
    s
}

/// `mstar check` on `text`: exit code and standard output.
fn check(text: &str, name: &str) -> (Option<i32>, String) {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("check_large");
    std::fs::create_dir_all(&dir).expect("a temporary directory");
    let path = dir.join(name);
    std::fs::write(&path, text).expect("the model file");
    let out = Command::new(env!("CARGO_BIN_EXE_mstar"))
        .arg("check")
        .arg(&path)
        .output()
        .expect("mstar runs");
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
    )
}

#[test]
fn check_finds_the_repeated_joint_of_a_2001_body_n_four_bar() {
    // 1000 couplers: n = 6003 coordinates, m = 6002 rows, n·m = 3.6e7 above
    // the dense limit (4e6).
    let (code, out) = check(&n_four_bar(1000, false), "clean.toml");
    assert!(out.contains("coordinates: 6003\n"), "{out}");
    assert!(out.contains("degrees of freedom: 1\n"), "{out}");
    assert!(out.contains("redundant constraints: none\n"), "{out}");
    assert_eq!(code, Some(0), "{out}");
    let (code, out) = check(&n_four_bar(1000, true), "twice.toml");
    assert!(out.contains("degrees of freedom: 1\n"), "{out}");
    assert!(
        out.contains("redundant constraints: B500-C501-again\n"),
        "{out}"
    );
    assert_eq!(code, Some(1), "{out}");
}

/// Above the dense limit minimum-norm multipliers are refused, so the
/// redundant-joint error of `mstar run` does not offer them: it names the
/// joint and advises removing it, which runs.
#[test]
fn a_large_model_s_redundant_joint_error_gives_advice_that_runs() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("check_large");
    std::fs::create_dir_all(&dir).expect("a temporary directory");
    let run = |text: &str, name: &str| {
        let path = dir.join(name);
        std::fs::write(&path, text).expect("the model file");
        Command::new(env!("CARGO_BIN_EXE_mstar"))
            .arg("run")
            .arg(&path)
            .args(["--t-end", "0.002"])
            .output()
            .expect("mstar runs")
    };
    let out = run(&n_four_bar(1000, true), "run-twice.toml");
    let e = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{e}");
    assert!(e.contains("B500-C501-again are redundant"), "{e}");
    assert!(e.contains("remove or loosen one"), "{e}");
    assert!(!e.contains("minimum-norm\" (on"), "{e}");
    // The advice: without the repeated joint the model runs.
    let out = run(&n_four_bar(1000, false), "run-clean.toml");
    let e = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{e}");
}
