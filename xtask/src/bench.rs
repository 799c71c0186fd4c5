//! `cargo xtask bench`: the chain benchmark (criterion, release build) as a
//! table and a log-log plot, then the same models as files through `mstar
//! run` ([`crate::bench_files`]).
//!
//! Runs `cargo bench -p mstar-benches --bench chain`, then reads criterion's
//! median estimates (`target/criterion/chain_step/<N>/new/estimates.json`, and
//! the per-phase ones, and the spatial chain's `chain_spatial/<N>`) and the
//! counts the benchmark writes
//! (`target/studies/bench/counts.csv`).

use std::path::Path;
use std::process::Command;

use anyhow::{Context as _, Result, bail};

use crate::common::{Table, draw_figures};
use crate::plot::{Legend, Panel, Scale, Style};
use crate::study_dir;

/// Median time in µs of one criterion benchmark, if it ran.
fn median_us(id: &str) -> Option<f64> {
    let path = Path::new("target/criterion")
        .join(id)
        .join("new/estimates.json");
    let text = std::fs::read_to_string(path).ok()?;
    let after = &text[text.find("\"median\"")?..];
    let value = &after[after.find("\"point_estimate\":")? + "\"point_estimate\":".len()..];
    let end = value.find([',', '}'])?;
    value[..end].trim().parse::<f64>().ok().map(|ns| ns / 1e3)
}

/// The machine, for the record.
pub(crate) fn machine() -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into());
    let cores = std::thread::available_parallelism().map_or(0, usize::from);
    format!("{cpu}, {cores} cores")
}

/// Runs the benchmark up to `max_n` bodies (unless `report_only`) and reports
/// it.
///
/// # Errors
/// If `cargo bench` fails or produces no estimates.
pub fn run(max_n: usize, report_only: bool, files_only: bool) -> Result<()> {
    let out = study_dir("bench")?;
    if !files_only {
        if !report_only {
            run_criterion(max_n)?;
        }
        report(&out)?;
    }
    if !report_only {
        crate::bench_files::run(&out, max_n)?;
    }
    Ok(())
}

/// `cargo bench -p mstar-benches --bench chain` up to `max_n` bodies.
fn run_criterion(max_n: usize) -> Result<()> {
    println!(
        "running the chain benchmark up to N = {max_n} (release build; the first build takes a few minutes)"
    );
    let status = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
        .args(["bench", "-p", "mstar-benches", "--bench", "chain"])
        .env("MSTAR_BENCH_MAX_N", max_n.to_string())
        .status()
        .context("could not run cargo bench")?;
    if !status.success() {
        bail!("cargo bench failed ({status})");
    }
    Ok(())
}

/// Prints the tables and draws the figure from criterion's estimates and the
/// benchmark's counts.
fn report(out: &Path) -> Result<()> {
    let counts = std::fs::read_to_string(out.join("counts.csv"))
        .context("the benchmark wrote no counts.csv")?;
    let mut table = step_table();
    let mut phases = phases_table();
    let mut curves = Curves::default();
    for line in counts.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let Some(n) = f.first().and_then(|s| s.parse::<usize>().ok()) else {
            continue;
        };
        let Some(step) = median_us(&format!("chain_step/{n}")) else {
            continue;
        };
        curves.push(n, step);
        table.row(step_row(n, step, &f));
        phases.row(phases_row(n));
    }
    if curves.per_step.is_empty() {
        bail!("no criterion estimates found under target/criterion/chain_step/");
    }
    table.print();
    table.write_csv(&out.join("bench.csv"))?;
    phases.print();
    phases.write_csv(&out.join("phases.csv"))?;
    let spatial = spatial_table();
    spatial.print();
    spatial.write_csv(&out.join("spatial.csv"))?;
    draw_figures("bench", out, &[("chain.png".to_string(), curves.panels())])?;
    Ok(())
}

/// The empty per-step table, one row per N to come, titled with the machine.
fn step_table() -> Table {
    Table::new(
        format!(
            "chain of N bars, h = 1e-3, generalized-α ρ∞ = 0.8, tol 1e-8, default (modified) Newton and KKT solver (Schur), one thread — {}",
            machine()
        ),
        &[
            "N",
            "µs/step",
            "µs/body/step",
            "Newton it./step",
            "µs/Newton it.",
            "factorizations/step",
            "µs/step, full Newton",
            "µs/step, 2 threads",
            "peak MiB",
        ],
    )
}

/// The spatial bar chain (`chain/spatial`, `mstar chain --kind spatial-bars`
/// at the command's defaults), one row per N that ran.
fn spatial_table() -> Table {
    let mut table = Table::new(
        "spatial chain of N solid cylinders on spherical joints (Euler parameters), h = 1e-3, generalized-α ρ∞ = 0.9, tol 1e-10, full Newton, Schur, one thread",
        &["N", "µs/step", "µs/body/step"],
    );
    for n in [10, 100, 1_000, 10_000, 100_000] {
        if let Some(step) = median_us(&format!("chain_spatial/{n}")) {
            table.row(vec![
                n.to_string(),
                format!("{step:.1}"),
                format!("{:.3}", step / n as f64),
            ]);
        }
    }
    table
}

/// The empty phase table, one row per N to come.
fn phases_table() -> Table {
    Table::new(
        "phases of one Newton iteration (µs; Schur on the matrix without BᵀB, LDLᵀ and LU on the one with M*)",
        &[
            "N",
            "residual",
            "residual, 2 thr.",
            "Jacobians+assembly",
            "Jac.+asm., 2 thr.",
            "factor Schur",
            "solve Schur",
            "factor LDLᵀ",
            "solve LDLᵀ",
            "factor LU",
            "solve LU",
        ],
    )
}

/// A median in µs with one decimal, `-` if that benchmark did not run.
fn median_cell(id: &str) -> String {
    median_us(id).map_or("-".into(), |v| format!("{v:.1}"))
}

/// The per-step row of a chain of `n` bodies taking `step` µs per step; `f`
/// is its line of `counts.csv` (N, …, Newton iterations, factorizations, peak
/// MiB).
fn step_row(n: usize, step: f64, f: &[&str]) -> Vec<String> {
    let iterations = f.get(2).and_then(|s| s.parse::<f64>().ok());
    vec![
        n.to_string(),
        format!("{step:.1}"),
        format!("{:.3}", step / n as f64),
        f.get(2).copied().unwrap_or("-").to_string(),
        iterations.map_or("-".into(), |k| format!("{:.1}", step / k.max(1.0))),
        f.get(3).copied().unwrap_or("-").to_string(),
        median_cell(&format!("chain_step/full-newton/{n}")),
        median_cell(&format!("chain_step/2-threads/{n}")),
        f.get(4).copied().unwrap_or("-").to_string(),
    ]
}

/// The phase times of one Newton iteration for a chain of `n` bodies.
fn phases_row(n: usize) -> Vec<String> {
    let mut row = vec![n.to_string()];
    row.extend(
        [
            "residual",
            "residual-2-threads",
            "jacobians+assembly",
            "jacobians+assembly-2-threads",
            "factor-schur",
            "solve-schur",
            "factor-ldlt",
            "solve-ldlt",
            "factor-lu",
            "solve-lu",
        ]
        .map(|name| median_cell(&format!("chain_phase/{name}/{n}"))),
    );
    row
}

/// The figure's curves, `(N, µs)`: per step and per body per step, for
/// modified Newton (the default) and full Newton (where it ran).
#[derive(Default)]
struct Curves {
    /// Modified Newton, µs per step.
    per_step: Vec<(f64, f64)>,
    /// Modified Newton, µs per body per step.
    per_body: Vec<(f64, f64)>,
    /// Full Newton, µs per step.
    full_step: Vec<(f64, f64)>,
    /// Full Newton, µs per body per step.
    full_body: Vec<(f64, f64)>,
}

impl Curves {
    /// Adds the chain of `n` bodies taking `step` µs per step, and its full
    /// Newton time if that benchmark ran.
    fn push(&mut self, n: usize, step: f64) {
        self.per_step.push((n as f64, step));
        self.per_body.push((n as f64, step / n as f64));
        if let Some(full) = median_us(&format!("chain_step/full-newton/{n}")) {
            self.full_step.push((n as f64, full));
            self.full_body.push((n as f64, full / n as f64));
        }
    }

    /// The two panels, time per step (log-log) and per body per step (log-x),
    /// one curve per Newton variant in each.
    fn panels(self) -> Vec<Panel> {
        vec![
            variants(
                Panel::new("time per step", "N (bodies)", "µs per step").scale(Scale::LogLog),
                self.per_step,
                self.full_step,
            ),
            variants(
                Panel::new(
                    "time per body per step",
                    "N (bodies)",
                    "µs per body per step",
                )
                .scale(Scale::LogX)
                .y_range(0.0, 0.5),
                self.per_body,
                self.full_body,
            ),
        ]
    }
}

/// `panel` with one curve per Newton variant: modified (the default) and full.
fn variants(panel: Panel, modified: Vec<(f64, f64)>, full: Vec<(f64, f64)>) -> Panel {
    panel
        .series(
            "modified Newton (default)",
            modified,
            Style::solid(crate::common::color(0)),
        )
        .series("full Newton", full, Style::solid(crate::common::color(2)))
        .legend(Legend::UpperLeft)
}
