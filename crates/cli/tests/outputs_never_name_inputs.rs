//! Outputs never destroy inputs: `mstar equilibrium` refuses an `--out` or
//! `--write-model` that names its model file (or each other), and
//! `mstar convert` an `--out` that names its URDF, through relative paths
//! too; the input is left as it was (exit 2, as every usage error).

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
