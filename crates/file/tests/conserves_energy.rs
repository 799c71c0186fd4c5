//! `System::conserves_energy` on the model files of `models/`, against what
//! each file holds (read by hand): gravity, joints and undamped springs
//! conserve energy; a driver (a prescribed motion does work), a damper, or a
//! torque or force without a potential do not.

use std::path::PathBuf;

use mstar_file::MechanismFile;

fn conserves(file: &str) -> bool {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../models")
        .join(file);
    let model = MechanismFile::load(&path).unwrap_or_else(|e| panic!("{file}: {e}"));
    model.mechanism.system().conserves_energy()
}

#[test]
fn gravity_joints_and_undamped_springs_conserve_energy() {
    for file in [
        "pendulum.toml",
        "double-pendulum.toml",
        "n-four-bar.toml",
        "parallelogram.toml",
        "parallelogram-third-crank.toml",
        "spatial/top.toml",
        "spatial/top-steady.toml",
        "spatial/dzhanibekov.toml",
        "spatial/double-pendulum.toml",
        "spatial/tilted-hinge.toml",
        "spatial/slider-crank.toml",
    ] {
        assert!(conserves(file), "{file}");
    }
}

#[test]
fn drivers_dampers_and_torques_do_not() {
    // four-bar, slider-crank: a driver; andrews: a motor torque;
    // crank-and-spring: a damped spring and a torque; the flyball
    // governor: two spatial spring-dampers.
    for file in [
        "four-bar.toml",
        "slider-crank.toml",
        "andrews.toml",
        "crank-and-spring.toml",
        "spatial/iftomm-a05-flyball.toml",
    ] {
        assert!(!conserves(file), "{file}");
    }
}

#[test]
fn a_spring_conserves_energy_until_it_is_damped() {
    let text = |damping: f64| {
        format!(
            "format = \"mstar.planar/1\"\ngravity = [0.0, -9.81]\n\
             [[body]]\nname = \"bob\"\nmass = 1.0\ninertia = 0.1\npose = [1.0, 0.0, 0.0]\n\
             [[force]]\nname = \"s\"\ntype = \"spring-damper\"\nbodies = [\"ground\", \"bob\"]\n\
             points = [[0.0, 0.0], [0.0, 0.0]]\nstiffness = 10.0\ndamping = {damping}\nrest_length = 0.5\n"
        )
    };
    let load = |damping| {
        MechanismFile::parse(&text(damping), "s.toml", mstar_file::Format::Toml)
            .unwrap_or_else(|e| panic!("{e}"))
    };
    assert!(load(0.0).mechanism.system().conserves_energy());
    assert!(!load(0.5).mechanism.system().conserves_energy());
}
