//! `cargo xtask n-four-bar-file` and `cargo xtask setup`: the IFToMM
//! N-four-bar (`models/n-four-bar.toml`) written for any N, and the time
//! from the command line to the first step of `mstar check` and `mstar run`
//! on it at 10³, 10⁴ and 10⁵ bodies (release build).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use anyhow::{Context as _, Result, bail};

use crate::common::Table;
use crate::study_dir;

/// The N-four-bar with `bars` couplers (`2 bars + 1` bodies, as
/// `models/n-four-bar.toml` for 40), released as there; with `duplicate`,
/// a second copy of the joint `B{k}-C{k+1}` (`k = bars / 2`) named
/// `B{k}-C{k+1}-again` after the others: one redundant joint.
#[must_use]
pub fn n_four_bar(bars: usize, duplicate: bool) -> String {
    let mut s = String::with_capacity(600 * (2 * bars + 1));
    s.push_str("# IFToMM benchmark A02, the N-four-bar (cargo xtask n-four-bar-file).\n");
    let _ = writeln!(s, "# N = {bars}: {} bodies.", 2 * bars + 1);
    s.push_str("format = \"mstar.planar/1\"\ngravity = [0.0, -9.81]\n\n");
    let body = |s: &mut String, name: String, pose: [f64; 3], velocity: [f64; 3]| {
        let _ = writeln!(
            s,
            "[[body]]\nname = \"{name}\"\nmass = 1.0\ninertia = 0.08333333333333333\npose = [{:?}, {:?}, {:?}]\nvelocity = [{:?}, {:?}, {:?}]\n",
            pose[0], pose[1], pose[2], velocity[0], velocity[1], velocity[2]
        );
    };
    let half_pi = std::f64::consts::FRAC_PI_2;
    for i in 0..=bars {
        body(
            &mut s,
            format!("V{i}"),
            [i as f64, 0.5, half_pi],
            [0.5, 0.0, -1.0],
        );
    }
    for i in 1..=bars {
        body(
            &mut s,
            format!("C{i}"),
            [i as f64 - 0.5, 1.0, 0.0],
            [1.0, 0.0, 0.0],
        );
    }
    let joint = |s: &mut String, name: String, a: String, b: String, points: [f64; 4]| {
        let _ = writeln!(
            s,
            "[[joint]]\nname = \"{name}\"\ntype = \"revolute\"\nbodies = [\"{a}\", \"{b}\"]\npoints = [[{:?}, {:?}], [{:?}, {:?}]]\n",
            points[0], points[1], points[2], points[3]
        );
    };
    for i in 0..=bars {
        let points = [i as f64, 0.0, -0.5, 0.0];
        joint(
            &mut s,
            format!("A{i}"),
            "ground".into(),
            format!("V{i}"),
            points,
        );
    }
    for i in 0..bars {
        let c = format!("C{}", i + 1);
        let left = [0.5, 0.0, -0.5, 0.0];
        joint(
            &mut s,
            format!("B{i}-{c}"),
            format!("V{i}"),
            c.clone(),
            left,
        );
        let right = [0.5, 0.0, 0.5, 0.0];
        joint(
            &mut s,
            format!("B{}-{c}", i + 1),
            format!("V{}", i + 1),
            c,
            right,
        );
    }
    if duplicate && bars > 0 {
        let k = bars / 2;
        let (v, c) = (format!("V{k}"), format!("C{}", k + 1));
        let name = format!("B{k}-{c}-again");
        joint(&mut s, name, v, c, [0.5, 0.0, -0.5, 0.0]);
    }
    s.push_str("[simulation]\nt_end = 1e-3\nh = 1e-3\n");
    s
}

/// Writes [`n_four_bar`] to `out`.
///
/// # Errors
/// If the file cannot be written.
pub fn write_file(bars: usize, duplicate: bool, out: &Path) -> Result<()> {
    std::fs::write(out, n_four_bar(bars, duplicate))
        .with_context(|| format!("could not write {}", out.display()))?;
    println!(
        "{}: the N-four-bar, N = {bars} ({} bodies{})",
        out.display(),
        2 * bars + 1,
        if duplicate { ", one joint twice" } else { "" }
    );
    Ok(())
}

/// The spatial bar chain of `mstar chain --kind spatial-bars`
/// (`mstar::model::spatial::spatial_bar_chain`) as a model file: `links`
/// solid cylinders (1 kg, 1 m, radius 0.02 m) on spherical joints, along +x
/// at rest, gravity −z, h = 1e-3 s; every other setting at its default.
#[must_use]
pub fn spatial_chain(links: usize) -> String {
    let (axial, transverse) = (0.5 * 0.02 * 0.02, (3.0 * 0.02 * 0.02 + 1.0) / 12.0);
    let mut s = String::with_capacity(300 * links + 200);
    s.push_str(
        "# The spatial bar chain (cargo xtask spatial-chain-file).
",
    );
    s.push_str("format = \"mstar.spatial/1\"\ngravity = [0.0, 0.0, -9.81]\n\n");
    for k in 0..links {
        let _ = writeln!(
            s,
            "[[body]]\nname = \"bar{}\"\nmass = 1.0\ninertia = [{axial:?}, {transverse:?}, {transverse:?}]\n\
             position = [{:?}, 0.0, 0.0]\norientation = [1.0, 0.0, 0.0, 0.0]\n",
            k + 1,
            k as f64 + 0.5
        );
    }
    for k in 0..links {
        let (a, at) = if k == 0 {
            ("ground".to_string(), "[0.0, 0.0, 0.0]")
        } else {
            (format!("bar{k}"), "[0.5, 0.0, 0.0]")
        };
        let _ = writeln!(
            s,
            "[[joint]]\nname = \"joint{}\"\ntype = \"spherical\"\nbodies = [\"{a}\", \"bar{}\"]\n\
             points = [{at}, [-0.5, 0.0, 0.0]]\n",
            k + 1,
            k + 1
        );
    }
    s.push_str("[simulation]\nh = 1e-3\n");
    s
}

/// A planar chain of `links` uniform bars (1 kg, 1 m, `J = m l²/12`, as
/// `mstar chain`) on revolute joints, hanging straight down from the origin
/// at rest: its static equilibrium, for `mstar modes` (docs/performance.md,
/// "Vibration modes").
#[must_use]
pub fn hanging_chain(links: usize) -> String {
    let mut s = String::with_capacity(250 * links + 200);
    s.push_str(
        "# A hanging bar chain (cargo xtask hanging-chain-file).
",
    );
    s.push_str("format = \"mstar.planar/1\"\ngravity = [0.0, -9.81]\n\n");
    for k in 0..links {
        let _ = writeln!(
            s,
            "[[body]]\nname = \"bar{}\"\nmass = 1.0\ninertia = {:?}\npose = [0.0, {:?}, {:?}]\n",
            k + 1,
            1.0 / 12.0,
            -(k as f64 + 0.5),
            -std::f64::consts::FRAC_PI_2
        );
    }
    for k in 0..links {
        let (a, at) = if k == 0 {
            ("ground".to_string(), "[0.0, 0.0]")
        } else {
            (format!("bar{k}"), "[0.5, 0.0]")
        };
        let _ = writeln!(
            s,
            "[[joint]]\nname = \"joint{}\"\ntype = \"revolute\"\nbodies = [\"{a}\", \"bar{}\"]\n\
             points = [{at}, [-0.5, 0.0]]\n",
            k + 1,
            k + 1
        );
    }
    s.push_str("[simulation]\nh = 1e-3\n");
    s
}

/// Writes [`hanging_chain`] to `out`.
///
/// # Errors
/// If the file cannot be written.
pub fn write_hanging_chain(links: usize, out: &Path) -> Result<()> {
    std::fs::write(out, hanging_chain(links))
        .with_context(|| format!("could not write {}", out.display()))?;
    println!("{}: a hanging bar chain, {links} bars", out.display());
    Ok(())
}

/// Writes [`spatial_chain`] to `out`.
///
/// # Errors
/// If the file cannot be written.
pub fn write_spatial_chain(links: usize, out: &Path) -> Result<()> {
    std::fs::write(out, spatial_chain(links))
        .with_context(|| format!("could not write {}", out.display()))?;
    println!("{}: the spatial bar chain, {links} bars", out.display());
    Ok(())
}

/// The couplers of the studied sizes: about 10³, 10⁴, 10⁵ bodies.
const SIZES: [usize; 3] = [500, 5_000, 50_000];

/// Builds the release binary of `mstar` and returns its path.
///
/// # Errors
/// If the build fails.
pub fn release_binary() -> Result<&'static Path> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let status = Command::new(cargo)
        .args(["build", "--release", "-p", "mstar-cli", "--bin", "mstar"])
        .status()
        .context("could not run cargo build")?;
    if !status.success() {
        bail!("cargo build --release failed ({status})");
    }
    Ok(Path::new("target/release/mstar"))
}

/// Builds the release binary, writes the files and times `mstar check` on
/// the clean and the duplicated model and `mstar run` to its first step
/// (`t_end = h`) on the clean one, up to `max_bodies` bodies.
///
/// # Errors
/// If the build fails, a file cannot be written or a command cannot start.
pub fn run(max_bodies: usize) -> Result<()> {
    let exe = release_binary()?;
    let dir = study_dir("setup")?;
    let mut table = Table::new(
        "Set-up of the N-four-bar (release build; wall time of the whole command)",
        &["bodies", "command", "wall time, s", "exit", "result"],
    );
    for bars in SIZES.into_iter().filter(|&b| 2 * b < max_bodies) {
        let clean = dir.join(format!("n-four-bar-{bars}.toml"));
        let twice = dir.join(format!("n-four-bar-{bars}-twice.toml"));
        write_file(bars, false, &clean)?;
        write_file(bars, true, &twice)?;
        for (args, grep) in [
            (vec!["check".into(), clean.clone()], "degrees of freedom"),
            (vec!["check".into(), twice.clone()], "redundant constraints"),
            (vec!["run".into(), clean.clone()], "steps:"),
        ] {
            table.row(timed(exe, &args, grep, 2 * bars + 1)?);
        }
    }
    table.print();
    table.write_csv(&dir.join("setup.csv"))?;
    Ok(())
}

/// Runs `exe args`, its wall time, exit code and the line of its standard
/// output that starts with `grep`.
fn timed(exe: &Path, args: &[PathBuf], grep: &str, bodies: usize) -> Result<Vec<String>> {
    let clock = Instant::now();
    let out = Command::new(exe)
        .args(args)
        .output()
        .with_context(|| format!("could not run {}", exe.display()))?;
    let wall = clock.elapsed().as_secs_f64();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let line = stdout
        .lines()
        .find(|l| l.starts_with(grep))
        .unwrap_or("(no such line)");
    let command = std::iter::once(exe.display().to_string())
        .chain(args.iter().map(|a| a.display().to_string()))
        .collect::<Vec<_>>()
        .join(" ");
    Ok(vec![
        bodies.to_string(),
        command,
        format!("{wall:.2}"),
        out.status.code().map_or("signal".into(), |c| c.to_string()),
        line.chars().take(90).collect(),
    ])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_spatial_chain_file_is_the_chain_command_s_model() {
        use mstar::System as _;
        use mstar::file::{Format, Mechanism, MechanismFile};
        use mstar::model::spatial::{RotationalMass, spatial_bar_chain};
        let file = MechanismFile::parse(&spatial_chain(3), "c.toml", Format::Toml)
            .unwrap_or_else(|e| panic!("{e}"));
        let Mechanism::Spatial(sys) = &file.mechanism else {
            panic!("not spatial");
        };
        let chain = spatial_bar_chain(3, RotationalMass::Regularized);
        assert_eq!(
            (sys.n_coords(), sys.n_constraints()),
            (chain.n_coords(), chain.n_constraints())
        );
        let (u, v) = (chain.initial_position(), chain.initial_velocity());
        assert_eq!(
            (sys.initial_position(), sys.initial_velocity()),
            (u.clone(), v.clone())
        );
        let (mut a, mut b) = (vec![0.0; 21], vec![0.0; 21]);
        sys.forces_into(0.0, &u, &v, &mut a);
        chain.forces_into(0.0, &u, &v, &mut b);
        assert_eq!(a, b);
        let n = sys.mass_pattern().len();
        let (mut ma, mut mb) = (vec![0.0; n], vec![0.0; n]);
        sys.mass_into(0.0, &u, &mut ma);
        chain.mass_into(0.0, &u, &mut mb);
        assert_eq!(ma, mb);
    }

    #[test]
    fn forty_bars_are_the_model_file() {
        // models/n-four-bar.toml without its comments and settings.
        let strip = |s: &str| -> String {
            s.lines()
                .filter(|l| !l.starts_with('#'))
                .take_while(|l| !l.starts_with("[simulation]"))
                .collect::<Vec<_>>()
                .join("\n")
        };
        let file = std::fs::read_to_string(
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../models/n-four-bar.toml"),
        )
        .expect("models/n-four-bar.toml");
        assert_eq!(strip(&n_four_bar(40, false)), strip(&file));
    }
}
