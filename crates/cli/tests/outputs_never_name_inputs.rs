//! Outputs never destroy inputs: `mstar equilibrium` refuses an `--out` or
//! `--write-model` that names its model file (or each other), and
//! `mstar convert` an `--out` that names its URDF, through relative paths
//! too; the input is left as it was (exit 2, as every usage error). Every
//! command's outputs also stay off the URDF a spatial model file reads, a
//! `fit:` objective's CSV and each other, and refuse a read-only file.

mod common;

use common::{model, mstar, scratch, text};

#[test]
fn equilibrium_and_convert_refuse_outputs_that_name_their_inputs() {
    let dir = scratch("outputs-inputs");
    let toml = dir.join("pendulum.toml");
    std::fs::copy(model("pendulum.toml"), &toml).expect("copied");
    let urdf = dir.join("arm.urdf");
    std::fs::copy(model("urdf/two-link-arm.urdf"), &urdf).expect("copied");
    let before = (
        std::fs::read(&toml).expect("toml"),
        std::fs::read(&urdf).expect("urdf"),
    );
    let t = toml.display().to_string();
    let same = dir.join(".").join("pendulum.toml").display().to_string();
    let other = dir.join("eq.csv").display().to_string();
    let u = urdf.display().to_string();
    let cases: [(Vec<&str>, &str); 4] = [
        (vec!["equilibrium", &t, "--out", &same], "--out"),
        (
            vec!["equilibrium", &t, "--write-model", &t],
            "--write-model",
        ),
        (
            vec!["equilibrium", &t, "--out", &other, "--write-model", &other],
            "names the same file as --out",
        ),
        (vec!["convert", &u, "--out", &u], "names the URDF file"),
    ];
    for (args, want) in &cases {
        let r = mstar(args);
        let err = text(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.contains(want) && err.contains("name another file"),
            "{args:?}: {err}"
        );
    }
    assert_eq!(std::fs::read(&toml).expect("toml"), before.0);
    assert_eq!(std::fs::read(&urdf).expect("urdf"), before.1);
    assert!(!dir.join("eq.csv").exists());
}

/// A scratch copy of `models/urdf/two-link-arm-start.toml` and the URDF it
/// reads (`urdf = "two-link-arm.urdf"`), with a short results CSV.
fn arm_with_urdf(tag: &str) -> common::Scratch {
    let dir = scratch(tag);
    for name in ["two-link-arm-start.toml", "two-link-arm.urdf"] {
        std::fs::copy(model(&format!("urdf/{name}")), dir.join(name)).expect("copied");
    }
    std::fs::copy(model("double-pendulum.toml"), dir.join("dp.toml")).expect("copied");
    std::fs::write(dir.join("fit.csv"), "t,x\n0,0\n").expect("written");
    let r = common::sh(
        "$M run two-link-arm-start.toml --t-end 0.01 --out a.csv",
        &dir,
    );
    assert!(r.status.success(), "{}", text(&r.stderr));
    dir
}

/// Every output of every command that reads a model is refused (exit 2,
/// nothing written) when it names the URDF the model reads, the model, the
/// CSV a `fit:` objective reads or the command's other output; the inputs
/// are left byte for byte.
#[test]
fn outputs_naming_an_included_urdf_or_another_input_are_refused() {
    let dir = arm_with_urdf("outputs-urdf");
    let urdf = "two-link-arm.urdf";
    let m = "two-link-arm-start.toml";
    let grad = "--t-end 0.01 --objective final:u:lower.x --gradient body.lower.mass";
    let cases = [
        (format!("run {m} --t-end 0.01 --out {urdf}"), "--out"),
        (format!("animate {m} a.csv --html {urdf}"), "--html"),
        (format!("animate {m} a.csv --gif {urdf}"), "--gif"),
        (format!("animate {m} a.csv --png {urdf}"), "--png"),
        (format!("equilibrium {m} --out {urdf}"), "--out"),
        (
            format!("equilibrium {m} --write-model {urdf}"),
            "--write-model",
        ),
        (format!("modes {m} --out {urdf}"), "--out"),
        (format!("linearize {m} --out {urdf}"), "--out"),
    ];
    for (args, option) in &cases {
        let want = format!("{option} {urdf} names the URDF file ");
        refused(&dir, args, &want);
    }
    let others = [
        (format!("run dp.toml {grad} --gradient-out dp.toml"), "--gradient-out dp.toml names the model file dp.toml"),
        (format!("run dp.toml {grad} --gradient-out g.json --out g.json"), "--gradient-out g.json names the same file as --out g.json"),
        (
            "run dp.toml --t-end 0.01 --objective fit:u:lower.x=fit.csv --gradient body.lower.mass --gradient-out fit.csv".to_string(),
            "--gradient-out fit.csv names the fit file fit.csv",
        ),
    ];
    for (args, want) in &others {
        refused(&dir, args, want);
    }
    let copy = |name: &str, from: &str| {
        assert_eq!(
            std::fs::read(dir.join(name)).expect("kept"),
            std::fs::read(model(from)).expect("the original"),
            "{name}"
        );
    };
    copy(urdf, "urdf/two-link-arm.urdf");
    copy(m, "urdf/two-link-arm-start.toml");
    copy("dp.toml", "double-pendulum.toml");
    assert_eq!(
        std::fs::read_to_string(dir.join("fit.csv")).expect("kept"),
        "t,x\n0,0\n"
    );
    assert!(!dir.join("g.json").exists());
}

/// Runs `args` in `dir` and asserts exit 2 with `want` and the advice.
fn refused(dir: &std::path::Path, args: &str, want: &str) {
    let r = common::sh(&format!("$M {args}"), dir);
    let err = text(&r.stderr);
    assert_eq!(r.status.code(), Some(2), "{args}: {err}");
    assert!(
        err.contains(want) && err.contains(": name another file"),
        "{args}: {err}"
    );
}

/// Outputs written otherwise than as a CSV stream (`animate --png`/`--gif`,
/// `equilibrium --write-model`, `run --gradient-out`) refuse a read-only
/// file as `--out` does, even for root: exit 1, the message with its
/// advice, the file untouched; after the advice they are written.
#[test]
fn read_only_pictures_models_and_gradients_are_refused() {
    use std::os::unix::fs::PermissionsExt as _;
    let dir = arm_with_urdf("outputs-readonly");
    let m = "two-link-arm-start.toml";
    let cases = [
        ("ro.png", format!("animate {m} a.csv --png ro.png")),
        ("ro.gif", format!("animate {m} a.csv --gif ro.gif")),
        ("RO.toml", "equilibrium dp.toml --write-model RO.toml".to_string()),
        (
            "RO.json",
            "run dp.toml --t-end 0.01 --objective final:u:lower.x --gradient body.lower.mass --gradient-out RO.json"
                .to_string(),
        ),
    ];
    for (file, args) in &cases {
        let ro = dir.join(file);
        std::fs::write(&ro, "kept\n").expect("written");
        std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o444)).expect("chmod");
        let r = common::sh(&format!("$M {args}"), &dir);
        let err = text(&r.stderr);
        assert_eq!(r.status.code(), Some(1), "{args}: {err}");
        let want = format!(
            "could not write {file}: it is read-only (mode 444); make it writable (chmod u+w {file}) or name another file"
        );
        assert!(err.contains(&want), "{args}: {err}");
        assert_eq!(std::fs::read_to_string(&ro).expect("kept"), "kept\n");
        // The advice works.
        let r = common::sh(&format!("chmod u+w {file} && $M {args}"), &dir);
        assert!(r.status.success(), "{args}: {}", text(&r.stderr));
        assert_ne!(std::fs::read(&ro).expect("written"), b"kept\n");
    }
}
