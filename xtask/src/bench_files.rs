//! `cargo xtask bench`, the user's path: the spatial bar chain and the
//! IFToMM N-four-bar written as model files at 10³–10⁵ bodies, run by the
//! release binary as a user runs them (`mstar check FILE`, `mstar run
//! FILE`): set-up time and µs per body per step, and Exudyn on the same
//! spatial chain in the same run where a Python with `exudyn` is at hand
//! (`MSTAR_EXUDYN_PYTHON`, default `python3`).

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use anyhow::{Context as _, Result, bail};

use crate::common::Table;
use crate::setup;

/// The model sizes, in bodies.
const BODIES: [usize; 3] = [1_000, 10_000, 100_000];

/// Steps of about 2·10⁶ body-steps a run (a few seconds), at least 5.
fn steps(bodies: usize) -> usize {
    (2_000_000 / bodies).clamp(5, 1000)
}

/// One model file of the study.
struct Case {
    kind: &'static str,
    bodies: usize,
    file: PathBuf,
    /// `--set` overrides of the run (matched settings for Exudyn).
    set: Vec<&'static str>,
}

/// The spatial chain (defaults, and ρ∞ 0.8 with tol 1e-8 as Exudyn runs
/// it) and the N-four-bar (defaults) up to `max_bodies` bodies.
fn cases(dir: &Path, max_bodies: usize) -> Result<Vec<Case>> {
    let mut cases = Vec::new();
    for bodies in BODIES.into_iter().filter(|&b| b <= max_bodies) {
        let chain = dir.join(format!("spatial-chain-{bodies}.toml"));
        setup::write_spatial_chain(bodies, &chain)?;
        let bars = bodies / 2;
        let four_bar = dir.join(format!("n-four-bar-{bars}.toml"));
        setup::write_file(bars, false, &four_bar)?;
        for set in [vec![], vec!["simulation.rho=0.8", "simulation.tol=1e-8"]] {
            cases.push(Case {
                kind: "spatial chain",
                bodies,
                file: chain.clone(),
                set,
            });
        }
        cases.push(Case {
            kind: "N-four-bar",
            bodies: 2 * bars + 1,
            file: four_bar,
            set: vec![],
        });
    }
    Ok(cases)
}

/// Builds the release binary, writes the files to `dir` and prints (and
/// writes `files.csv`) the table.
///
/// # Errors
/// If the build fails, a file cannot be written or a run fails.
pub fn run(dir: &Path, max_bodies: usize) -> Result<()> {
    let exe = setup::release_binary()?;
    let mut table = Table::new(
        "Model files through `mstar run` (release build, one thread, h = 1e-3 s): set-up is the \
         whole command's wall time of `mstar check` and of `mstar run --t-end 1e-3` (read, check, \
         start, one step); the step cost is the run's own figure over the steps",
        &[
            "model",
            "bodies",
            "settings",
            "check, s",
            "run to first step, s",
            "steps",
            "µs/body/step",
            "Newton it./step",
            "Exudyn µs/body/step",
        ],
    );
    let exudyn = Exudyn::find();
    let files = dir.join("files");
    std::fs::create_dir_all(&files)
        .with_context(|| format!("could not make {}", files.display()))?;
    for case in cases(&files, max_bodies)? {
        table.row(measure(exe, &case, exudyn.as_ref())?);
    }
    table.print();
    table.write_csv(&dir.join("files.csv"))?;
    Ok(())
}

/// The row of one case.
fn measure(exe: &Path, case: &Case, exudyn: Option<&Exudyn>) -> Result<Vec<String>> {
    let file = case.file.display().to_string();
    let sets: Vec<String> = case
        .set
        .iter()
        .flat_map(|s| ["--set".to_string(), (*s).to_string()])
        .collect();
    let (check, _) = timed(exe, &["check", &file])?;
    let mut first = vec![
        "run".to_string(),
        file.clone(),
        "--t-end".into(),
        "1e-3".into(),
    ];
    first.extend(sets.iter().cloned());
    let (start, _) = timed(exe, &first)?;
    let n = steps(case.bodies);
    let mut long = vec![
        "run".to_string(),
        file,
        "--t-end".into(),
        format!("{:e}", n as f64 * 1e-3),
    ];
    long.extend(sets);
    let (_, report) = timed(exe, &long)?;
    let us_step = figure(&report, "wall time:", "(", " µs per step")?;
    let newton = figure(&report, "steps:", "(", " per accepted step")?;
    let matched = case.set.contains(&"simulation.tol=1e-8");
    let exudyn = match exudyn {
        Some(e) if matched && case.bodies <= 10_000 => e.us_per_body_step(case.bodies)?,
        _ => "—".to_string(),
    };
    Ok(vec![
        case.kind.to_string(),
        case.bodies.to_string(),
        if case.set.is_empty() {
            "defaults".into()
        } else {
            case.set.join(", ")
        },
        format!("{check:.2}"),
        format!("{start:.2}"),
        n.to_string(),
        format!("{:.2}", us_step / case.bodies as f64),
        format!("{newton:.2}"),
        exudyn,
    ])
}

/// Runs `exe args` on one thread: its wall time and standard output.
fn timed(exe: &Path, args: &[impl AsRef<std::ffi::OsStr>]) -> Result<(f64, String)> {
    let clock = Instant::now();
    let out = Command::new(exe)
        .args(args)
        .env("RAYON_NUM_THREADS", "1")
        .output()
        .with_context(|| format!("could not run {}", exe.display()))?;
    let wall = clock.elapsed().as_secs_f64();
    if !out.status.success() {
        bail!(
            "{} failed ({}): {}",
            exe.display(),
            out.status,
            String::from_utf8_lossy(&out.stderr)
        );
    }
    Ok((wall, String::from_utf8_lossy(&out.stdout).into_owned()))
}

/// The number between `after` and `before` on the line of `report` that
/// starts with `line`.
fn figure(report: &str, line: &str, after: &str, before: &str) -> Result<f64> {
    report
        .lines()
        .find(|l| l.starts_with(line))
        .and_then(|l| {
            let tail = &l[l.rfind(after)? + after.len()..];
            tail[..tail.find(before)?].trim().parse().ok()
        })
        .with_context(|| format!("no '{line} … {before}' in:\n{report}"))
}

/// A Python that imports `exudyn`, and `benches/exudyn/spatial_chain.py`.
struct Exudyn {
    python: String,
}

impl Exudyn {
    /// `MSTAR_EXUDYN_PYTHON` (default `python3`) if it imports exudyn.
    fn find() -> Option<Self> {
        let python = std::env::var("MSTAR_EXUDYN_PYTHON").unwrap_or_else(|_| "python3".into());
        let ok = Command::new(&python)
            .args(["-c", "import exudyn"])
            .output()
            .is_ok_and(|o| o.status.success());
        if !ok {
            println!(
                "Exudyn: not found ({python} -c 'import exudyn' fails; set MSTAR_EXUDYN_PYTHON)"
            );
        }
        ok.then_some(Self { python })
    }

    /// Exudyn's µs per body per step on the spatial chain of `bodies`
    /// bars (ρ∞ 0.8, tol 1e-8, h = 1e-3, one thread).
    fn us_per_body_step(&self, bodies: usize) -> Result<String> {
        let out = Command::new(&self.python)
            .args([
                "benches/exudyn/spatial_chain.py",
                "--json",
                "--repeats",
                "1",
            ])
            .args(["--max-wait", "120", "--sizes"])
            .arg(bodies.to_string())
            .env("OMP_NUM_THREADS", "1")
            .output()
            .context("could not run benches/exudyn/spatial_chain.py")?;
        let stdout = String::from_utf8_lossy(&out.stdout);
        let line = stdout
            .lines()
            .find(|l| l.contains(&format!("\"n\": {bodies},")))
            .with_context(|| format!("Exudyn gave no result for N = {bodies}: {stdout}"))?;
        let value = figure(line, "{", "\"us_per_body_step\": ", ",")?;
        Ok(format!("{value:.2}"))
    }
}
