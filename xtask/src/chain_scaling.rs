//! `cargo xtask chain-scaling`: the per-body cost of `mstar chain` at 10⁵
//! bodies against 10⁴, the command as a user runs it (its defaults, rayon's
//! pool as the environment sets it), in interleaved cycles of three runs at
//! 10⁴ and one at 10⁵ (docs/performance.md, "The chain command at 10⁵ bodies
//! against 10⁴"). A run at 10⁵ lasts ten times longer and averages over more
//! of a shared machine's swings; a cycle's ratio is its 10⁵ run over the
//! median of its three 10⁴ runs, so that a slow or fast stretch of the
//! machine meets both sizes.

use std::path::Path;
use std::process::Command;

use anyhow::{Context as _, Result, bail};

use crate::common::Table;
use crate::setup;

/// The two sizes compared, and the runs of each a cycle.
const SMALL: usize = 10_000;
const LARGE: usize = 100_000;
const SMALL_RUNS: usize = 3;

/// What one run of `mstar chain` printed.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Run {
    /// µs per body per step.
    per_body: f64,
    /// Newton iterations per step.
    iterations: f64,
}

/// The options of the study: the chain's kind (`None`: the command's
/// default, the planar chain) and end time (`None`: the command's default).
pub struct Options {
    pub cycles: usize,
    pub kind: Option<String>,
    pub t_end: Option<f64>,
}

/// Builds the release binary, runs the cycles, prints the table and writes
/// `target/studies/chain-scaling/cycles.csv`.
///
/// # Errors
/// If the build or a run fails, or a run's report lacks its figures.
pub fn run(options: &Options) -> Result<()> {
    if options.cycles == 0 {
        bail!("--cycles must be at least 1");
    }
    let exe = setup::release_binary()?;
    let mut table = Table::new(
        format!(
            "`mstar chain --links N{}{}` (release build), µs per body per step: {} runs at N = \
             {SMALL} and one at {LARGE} a cycle",
            options
                .kind
                .as_ref()
                .map_or(String::new(), |k| format!(" --kind {k}")),
            options
                .t_end
                .map_or(String::new(), |t| format!(" --t-end {t}")),
            SMALL_RUNS
        ),
        &[
            "cycle",
            "10⁴ runs",
            "10⁴ median",
            "10⁵",
            "ratio",
            "Newton it./step 10⁴, 10⁵",
        ],
    );
    let mut ratios = Vec::new();
    let (mut small_all, mut large_all) = (Vec::new(), Vec::new());
    for cycle in 1..=options.cycles {
        let small: Vec<Run> = (0..SMALL_RUNS)
            .map(|_| chain(exe, SMALL, options))
            .collect::<Result<_>>()?;
        let large = chain(exe, LARGE, options)?;
        let per_body: Vec<f64> = small.iter().map(|r| r.per_body).collect();
        let small_median = median(&per_body);
        let ratio = large.per_body / small_median;
        table.row(vec![
            cycle.to_string(),
            per_body
                .iter()
                .map(|x| format!("{x:.3}"))
                .collect::<Vec<_>>()
                .join(", "),
            format!("{small_median:.3}"),
            format!("{:.3}", large.per_body),
            format!("{ratio:.2}"),
            format!("{:.2}, {:.2}", small[0].iterations, large.iterations),
        ]);
        eprintln!(
            "cycle {cycle} of {}: 10⁴ {per_body:.3?} µs, 10⁵ {:.3} µs, ratio {ratio:.2}",
            options.cycles, large.per_body
        );
        ratios.push(ratio);
        small_all.extend(per_body);
        large_all.push(large.per_body);
    }
    table.print();
    let within = ratios.iter().filter(|&&r| r <= 1.3).count();
    println!(
        "median of the cycles' ratios: {:.2} ({:.2}–{:.2}; {within} of {} within 1.3); medians of \
         all runs: {:.3} µs at 10⁴ ({} runs), {:.3} at 10⁵ ({})",
        median(&ratios),
        ratios.iter().copied().fold(f64::INFINITY, f64::min),
        ratios.iter().copied().fold(0.0, f64::max),
        ratios.len(),
        median(&small_all),
        small_all.len(),
        median(&large_all),
        large_all.len(),
    );
    let dir = Path::new("target/studies/chain-scaling");
    std::fs::create_dir_all(dir).with_context(|| format!("could not make {}", dir.display()))?;
    table.write_csv(&dir.join("cycles.csv"))
}

/// One run of the chain command with `links` links.
fn chain(exe: &Path, links: usize, options: &Options) -> Result<Run> {
    let mut cmd = Command::new(exe);
    cmd.args(["chain", "--links", &links.to_string()]);
    if let Some(kind) = &options.kind {
        cmd.args(["--kind", kind]);
    }
    if let Some(t_end) = options.t_end {
        cmd.args(["--t-end", &t_end.to_string()]);
    }
    let out = cmd
        .output()
        .with_context(|| format!("could not run {}", exe.display()))?;
    let report = String::from_utf8_lossy(&out.stdout);
    if !out.status.success() {
        bail!(
            "mstar chain --links {links} failed ({}): {}",
            out.status,
            String::from_utf8_lossy(&out.stderr)
        );
    }
    parse(&report).with_context(|| format!("no per-body time or Newton count in:\n{report}"))
}

/// The per-body time and Newton iterations per step of a chain report
/// ("… per body per step: 0.257 µs", "Newton iterations: 1006 (1.01 per
/// step, …").
fn parse(report: &str) -> Option<Run> {
    let line = |start: &str| report.lines().find(|l| l.contains(start));
    let timing = line("per body per step:")?;
    let tail = &timing[timing.find("per body per step:")? + "per body per step:".len()..];
    let per_body: f64 = tail[..tail.find("µs")?].trim().parse().ok()?;
    let newton = line("Newton iterations:")?;
    let tail = &newton[newton.find('(')? + 1..];
    let iterations: f64 = tail[..tail.find(" per step")?].trim().parse().ok()?;
    (per_body.is_finite() && iterations.is_finite()).then_some(Run {
        per_body,
        iterations,
    })
}

/// The median of `x` (the mean of the middle two for an even count).
fn median(x: &[f64]) -> f64 {
    let mut v = x.to_vec();
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        f64::NAN
    } else if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_chain_report_gives_its_per_body_time_and_iterations() {
        let report = "10000-link chain of bars on revolute joints\n\
            wall time: 2.571 s (+ 0.115 s setup); steps: 1000 accepted, 0 rejected\n\
            Newton iterations: 1006 (1.01 per step, 2 max); factorizations: 1000 (1.000 per step)\n\
            time per step: 2571.44 µs; per body per step: 0.257 µs\n";
        assert_eq!(
            parse(report),
            Some(Run {
                per_body: 0.257,
                iterations: 1.01
            })
        );
        assert_eq!(parse("wall time: 1 s\n"), None);
        // A NaN figure is not a measurement.
        let nan = report.replace("0.257 µs", "NaN µs");
        assert_eq!(parse(&nan), None);
    }

    #[test]
    fn no_cycles_is_refused_before_anything_is_built_or_run() {
        let options = Options {
            cycles: 0,
            kind: None,
            t_end: None,
        };
        let err = run(&options).expect_err("zero cycles measure nothing");
        assert!(
            err.to_string().contains("--cycles must be at least 1"),
            "{err}"
        );
    }

    #[test]
    fn medians_of_odd_and_even_counts() {
        assert_eq!(median(&[0.3, 0.1, 0.2]), 0.2);
        assert_eq!(median(&[0.4, 0.1, 0.2, 0.3]), 0.25);
        assert!(median(&[]).is_nan());
    }
}
