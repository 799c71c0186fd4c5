//! `cargo xtask paper`: the paper's pendulum example (§3, Figs. 4-13) against
//! the RK4 oracle.
//!
//! Runs [`PendulumRun::paper`] (trapezoidal Newmark, `M*` start, λ₀ = (−10, 0)),
//! the same model with [`Config::default`] (generalized-α, consistent start)
//! and, to tell the scheme from the start, trapezoidal Newmark from a
//! consistent start. Writes to `target/studies/paper/` the CSVs `paper.csv`,
//! `rk4.csv` (the oracle at the paper run's times), `generalized_alpha.csv`,
//! `newmark_consistent.csv` and `rk4_grid.csv` (the oracle from 0 to t_end),
//! one PNG per paper figure (copied to `docs/figures/paper/`) and a multiplier
//! error plot, and prints a summary table.
//!
//! The paper preset is expected to stop early (Newton fails once the period-2h
//! oscillation in λ has grown large, `algorithm.md` §5); that is a result of
//! the study, not a failure of it.

use std::path::{Path, PathBuf};

use anyhow::{Context as _, Result};
use mstar::pendulum::PendulumRun;
use mstar::{Config, IntegrationError, RunStats, Sample, Start};

use crate::common::{sci, width};
use crate::plot::{self, Legend, Panel, Scale, Series, Style};

/// Where the figures are copied for the docs, relative to the project root.
const DOCS_FIGURES: &str = "docs/figures/paper";

/// The window of the zoomed panels, s: long enough to see the oracle, short
/// enough that the paper run's growing λ and ü stay on the same scale.
const ZOOM: f64 = 2.0;

/// One integrator run with its oracle at the same times.
struct Run {
    /// Column heading and legend name.
    name: &'static str,
    /// Accepted samples, starting with the initial state.
    samples: Vec<Sample>,
    /// The RK4 reference at the samples' times.
    oracle: Vec<Sample>,
    /// How the run ended.
    result: Result<RunStats, IntegrationError>,
}

impl Run {
    /// Integrates `preset` and evaluates the oracle at the samples' times.
    fn new(name: &'static str, preset: &PendulumRun) -> Self {
        let (samples, result) = preset.run();
        let times: Vec<f64> = samples.iter().map(|s| s.t).collect();
        let oracle = preset.reference(&times);
        Self {
            name,
            samples,
            oracle,
            result,
        }
    }

    /// Largest `|f(ours) − f(oracle)|` over the samples with `lo < t ≤ hi`
    /// (`lo = −1` includes the initial state).
    fn max_err(&self, lo: f64, hi: f64, f: impl Fn(&Sample) -> f64) -> f64 {
        self.samples
            .iter()
            .zip(&self.oracle)
            .filter(|(s, _)| s.t > lo && s.t <= hi)
            .map(|(s, r)| (f(s) - f(r)).abs())
            .fold(0.0, f64::max)
    }

    /// Largest `|λᵢ − λᵢ,ref|` over both multipliers for `0 < t ≤ hi`.
    fn lambda_err(&self, hi: f64) -> f64 {
        self.max_err(0.0, hi, |s| s.lambda[0])
            .max(self.max_err(0.0, hi, |s| s.lambda[1]))
    }

    /// Time of the last accepted sample.
    fn t_reached(&self) -> f64 {
        self.samples.last().map_or(0.0, |s| s.t)
    }

    /// `(t, f(ours))` for every sample.
    fn curve(&self, f: impl Fn(&Sample) -> f64) -> Vec<(f64, f64)> {
        self.samples.iter().map(|s| (s.t, f(s))).collect()
    }
}

/// `(t, f(s))` for every sample.
fn curve(samples: &[Sample], f: impl Fn(&Sample) -> f64) -> Vec<(f64, f64)> {
    samples.iter().map(|s| (s.t, f(s))).collect()
}

/// The study's entry point.
///
/// # Errors
/// I/O errors and drawing errors; not the paper preset stopping early.
pub fn run() -> Result<()> {
    let out = crate::study_dir("paper")?;
    let preset = PendulumRun::paper();
    let default = PendulumRun {
        config: Config::default(),
        ..PendulumRun::paper()
    };
    let sys = preset.system();

    // Separates the scheme from the start: the paper's trapezoidal Newmark
    // from consistent ü₀, λ₀.
    let trapezoidal = PendulumRun {
        config: Config {
            start: Start::Consistent,
            ..preset.config.clone()
        },
        ..PendulumRun::paper()
    };

    let paper = Run::new("paper (Newmark, M* start)", &preset);
    let cured = Run::new("default (gen.-α ρ∞=0.9)", &default);
    let consistent = Run::new("Newmark, consistent start", &trapezoidal);
    // The oracle on the full grid, so the reference curves run to t_end even
    // where the paper run stopped.
    let full = preset.reference_on_grid();

    for (file, samples) in [
        ("paper.csv", &paper.samples),
        ("rk4.csv", &paper.oracle),
        ("generalized_alpha.csv", &cured.samples),
        ("newmark_consistent.csv", &consistent.samples),
        ("rk4_grid.csv", &full),
    ] {
        mstar::csv::write_csv(&out.join(file), &sys, samples)?;
    }

    let figures = figures(&paper, &cured, &[&consistent], &full, preset.t_end);
    let docs = PathBuf::from(DOCS_FIGURES);
    std::fs::create_dir_all(&docs)
        .with_context(|| format!("could not create {}", docs.display()))?;
    for (file, panels) in &figures {
        let path = out.join(file);
        plot::draw(&path, panels)?;
        copy(&path, &docs.join(file))?;
    }

    print_summary(&[&paper, &cured, &consistent]);
    println!();
    println!(
        "wrote paper.csv, rk4.csv (at the paper run's times), generalized_alpha.csv, newmark_consistent.csv,\nrk4_grid.csv (0 to t_end) and {} figures to {}",
        figures.len(),
        out.display()
    );
    println!("copied the figures to {}", docs.display());
    Ok(())
}

/// Copies a file, naming both paths on error.
fn copy(from: &Path, to: &Path) -> Result<()> {
    std::fs::copy(from, to)
        .with_context(|| format!("could not copy {} to {}", from.display(), to.display()))?;
    Ok(())
}

/// The time axis label.
const T: &str = "t (s)";

/// A quantity of a sample.
type Get = fn(&Sample) -> f64;

/// A quantity of the integrator under study as a solid line.
fn ours(run: &Run, what: &str, style: Style, f: impl Fn(&Sample) -> f64) -> Series {
    Series::new(format!("{what}, paper algorithm"), run.curve(f), style)
}

/// The oracle's curves of several quantities as one dashed black series (one
/// legend entry; the curves are separated by a break).
fn oracle(full: &[Sample], what: &str, fs: &[Get]) -> Series {
    let mut points = Vec::new();
    for (k, f) in fs.iter().enumerate() {
        if k > 0 {
            points.push((f64::NAN, f64::NAN));
        }
        points.extend(curve(full, f));
    }
    Series::new(format!("{what}, RK4"), points, Style::dashed(plot::BLACK))
}

/// The mean of consecutive samples, at the midpoints: removes an oscillation
/// of period 2h (the paper's "filtering", §3).
fn mean2(points: &[(f64, f64)]) -> Vec<(f64, f64)> {
    points
        .windows(2)
        .map(|w| (0.5 * (w[0].0 + w[1].0), 0.5 * (w[0].1 + w[1].1)))
        .collect()
}

/// The oracle's extent of the given quantities for `t ≤ t_max`, padded by a
/// third of its span (room for the legend): the axis of a figure the paper run leaves.
fn reference_range(full: &[Sample], t_max: f64, fs: &[Get]) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for f in fs {
        for s in full.iter().filter(|s| s.t <= t_max) {
            lo = lo.min(f(s));
            hi = hi.max(f(s));
        }
    }
    let pad = 0.35 * (hi - lo).max(1e-9);
    (lo - pad, hi + pad)
}

/// A quantity that oscillates with period 2h and grows (ü, λ), in three
/// panels: the first [`ZOOM`] seconds on the oracle's scale (the oscillation
/// clipped, its two-sample mean and the oracle visible), the same window on
/// the run's scale, and the whole run.
fn oscillating(
    title: &str,
    y_label: &str,
    t_end: f64,
    stop: &str,
    range: (f64, f64),
    series: &[Series],
) -> Vec<Panel> {
    let with = |mut p: Panel| {
        p.series = series.to_vec();
        p.legend(Legend::UpperLeft)
    };
    vec![
        with(
            Panel::new(
                format!("{title}, first {ZOOM} s, axis at the RK4 range"),
                T,
                y_label,
            )
            .x_range(0.0, ZOOM)
            .y_range(range.0, range.1),
        ),
        with(Panel::new(format!("{title}, first {ZOOM} s"), T, y_label).x_range(0.0, ZOOM)),
        with(Panel::new(format!("{title}, whole run{stop}"), T, y_label).x_range(0.0, t_end)),
    ]
}

/// A figure: its file name and its panels.
type Figure = (String, Vec<Panel>);

/// The figures, paper numbering (Figs. 4-13), as `(file name, panels)`.
fn figures(paper: &Run, cured: &Run, others: &[&Run], full: &[Sample], t_end: f64) -> Vec<Figure> {
    let stop = stop_note(paper);
    let mut figs = vec![
        fig04_theta(paper, full, t_end),
        fig05_position(paper, full, t_end),
        fig06_velocity(paper, full, t_end),
        fig07_energy(paper, cured, full, t_end),
        fig08_theta_ddot_rk4(full, t_end),
    ];
    figs.extend(figs09_13_oscillating(paper, cured, full, t_end, &stop));
    figs.push(lambda_error_figure(paper, cured, others, t_end));
    figs
}

/// The title suffix saying where the paper run stopped (empty if it
/// finished), so that the whole-run panels explain their end.
fn stop_note(paper: &Run) -> String {
    match &paper.result {
        Ok(_) => String::new(),
        Err(_) => format!(" (paper run stopped at t = {:.2} s)", paper.t_reached()),
    }
}

/// A panel over the whole run on the oracle's scale of `fs`: Figs. 4-7, where
/// the diverged paper run's curves leave the frame (clipped, not rescaled).
fn clipped(full: &[Sample], t_end: f64, title: &str, y_label: &str, fs: &[Get]) -> Panel {
    let (lo, hi) = reference_range(full, t_end, fs);
    Panel::new(format!("{title}, axis at the RK4 range"), T, y_label)
        .x_range(0.0, t_end)
        .y_range(lo, hi)
}

/// A clipped panel of one or two quantities `(name, f)` of the paper run
/// (blue, then orange) and the oracle's curves of all of them as one series
/// named `oracle_name`: the pattern of Figs. 4-6.
fn against_oracle(
    paper: &Run,
    full: &[Sample],
    t_end: f64,
    (title, y_label): (&str, &str),
    quantities: &[(&str, Get)],
    oracle_name: &str,
) -> Panel {
    let fs: Vec<Get> = quantities.iter().map(|(_, f)| *f).collect();
    let styles = [Style::solid(plot::BLUE), Style::solid(plot::ORANGE)];
    let mut panel = clipped(full, t_end, title, y_label, &fs);
    for ((what, f), style) in quantities.iter().zip(styles) {
        panel = panel.series_from(ours(paper, what, style, f));
    }
    panel.series_from(oracle(full, oracle_name, &fs))
}

/// Fig. 4: the angle θ and the angular velocity dθ/dt.
fn fig04_theta(paper: &Run, full: &[Sample], t_end: f64) -> Figure {
    let th: Get = |s| s.u[2];
    let om: Get = |s| s.v[2];
    let theta = against_oracle(
        paper,
        full,
        t_end,
        ("Fig. 4a — angle θ", "θ (rad)"),
        &[("θ", th)],
        "θ",
    )
    .legend(Legend::LowerLeft);
    let omega = against_oracle(
        paper,
        full,
        t_end,
        ("Fig. 4b — angular velocity dθ/dt", "dθ/dt (rad/s)"),
        &[("dθ/dt", om)],
        "dθ/dt",
    )
    .legend(Legend::LowerRight);
    ("fig04_theta.png".to_string(), vec![theta, omega])
}

/// Fig. 5: the displacements x and y.
fn fig05_position(paper: &Run, full: &[Sample], t_end: f64) -> Figure {
    let (x, y): (Get, Get) = (|s| s.u[0], |s| s.u[1]);
    let pos = against_oracle(
        paper,
        full,
        t_end,
        ("Fig. 5 — displacements x, y", "x, y (m)"),
        &[("x", x), ("y", y)],
        "x and y",
    );
    ("fig05_position.png".to_string(), vec![pos])
}

/// Fig. 6: the velocities dx/dt and dy/dt.
fn fig06_velocity(paper: &Run, full: &[Sample], t_end: f64) -> Figure {
    let (vx, vy): (Get, Get) = (|s| s.v[0], |s| s.v[1]);
    let vel = against_oracle(
        paper,
        full,
        t_end,
        ("Fig. 6 — velocities dx/dt, dy/dt", "dx/dt, dy/dt (m/s)"),
        &[("dx/dt", vx), ("dy/dt", vy)],
        "dx/dt and dy/dt",
    );
    ("fig06_velocity.png".to_string(), vec![vel])
}

/// Fig. 7: kinetic, potential and total energy over the whole run, and a
/// detail of the total energy error E − E₀ of the paper and default runs.
fn fig07_energy(paper: &Run, cured: &Run, full: &[Sample], t_end: f64) -> Figure {
    let (kin, pot): (Get, Get) = (|s| s.kinetic, |s| s.potential);
    let energy = clipped(
        full,
        t_end,
        "Fig. 7 — kinetic, potential, total energy",
        "energy (J)",
        &[kin, pot],
    )
    .legend(Legend::LowerRight)
    .series(
        "kinetic K, paper algorithm",
        paper.curve(kin),
        Style::solid(plot::BLUE),
    )
    .series(
        "potential P, paper algorithm",
        paper.curve(pot),
        Style::solid(plot::ORANGE),
    )
    .series(
        "total E = K + P, paper algorithm",
        paper.curve(Sample::energy),
        Style::solid(plot::RED),
    )
    .series_from(oracle(full, "K and P", &[kin, pot]));
    let detail = Panel::new(
        format!("Fig. 7, detail — total energy error E − E₀, first {ZOOM} s"),
        T,
        "E − E₀ (J)",
    )
    .x_range(0.0, ZOOM)
    .legend(Legend::UpperLeft)
    .series(
        "paper algorithm",
        energy_drift(paper),
        Style::solid(plot::RED).width(1),
    )
    .series(cured.name, energy_drift(cured), Style::solid(plot::GREEN));
    ("fig07_energy.png".to_string(), vec![energy, detail])
}

/// `(t, E − E₀)` of a run: the energy error of Fig. 7's detail.
fn energy_drift(run: &Run) -> Vec<(f64, f64)> {
    let e0 = run.samples.first().map_or(0.0, Sample::energy);
    run.curve(|s| s.energy() - e0)
}

/// Fig. 8: the oracle's angular acceleration d²θ/dt² alone.
fn fig08_theta_ddot_rk4(full: &[Sample], t_end: f64) -> Figure {
    let tdd: Get = |s| s.a[2];
    let (lo, hi) = reference_range(full, t_end, &[tdd]);
    let rk4_acc = Panel::new(
        "Fig. 8 — angular acceleration d²θ/dt², RK4",
        T,
        "d²θ/dt² (rad/s²)",
    )
    .x_range(0.0, t_end)
    .y_range(lo, hi)
    .series("d²θ/dt², RK4", curve(full, tdd), Style::solid(plot::BLACK));
    ("fig08_theta_ddot_rk4.png".to_string(), vec![rk4_acc])
}

/// Figs. 9-13: the accelerations ü and the multipliers λ, which oscillate
/// with period 2h in the paper run, as [`oscillating`] panels.
fn figs09_13_oscillating(
    paper: &Run,
    cured: &Run,
    full: &[Sample],
    t_end: f64,
    stop: &str,
) -> Vec<Figure> {
    let (tdd, xdd, ydd): (Get, Get, Get) = (|s| s.a[2], |s| s.a[0], |s| s.a[1]);
    let (l1, l2): (Get, Get) = (|s| s.lambda[0], |s| s.lambda[1]);
    let accelerations: [(&str, &str, &str, &str, Get); 5] = [
        ("fig09_theta_ddot.png", "Fig. 9", "d²θ/dt²", "rad/s²", tdd),
        ("fig10_x_ddot.png", "Fig. 10", "d²x/dt²", "m/s²", xdd),
        ("fig11_y_ddot.png", "Fig. 11", "d²y/dt²", "m/s²", ydd),
        ("fig12_lambda1.png", "Fig. 12", "λ₁", "N", l1),
        ("fig13_lambda2.png", "Fig. 13", "λ₂", "N", l2),
    ];
    accelerations
        .into_iter()
        .map(|(file, fig, what, unit, f)| {
            let series = oscillating_series(paper, cured, full, what, f);
            let range = reference_range(full, ZOOM, &[f]);
            let panels = oscillating(
                &format!("{fig} — {what}"),
                &format!("{what} ({unit})"),
                t_end,
                stop,
                range,
                &series,
            );
            (file.to_string(), panels)
        })
        .collect()
}

/// The series of one of Figs. 9-13: the raw curve thin, its two-sample mean,
/// (for λ) the default integrator, and the oracle.
fn oscillating_series(
    paper: &Run,
    cured: &Run,
    full: &[Sample],
    what: &str,
    f: Get,
) -> Vec<Series> {
    let raw = paper.curve(f);
    let mut series = vec![
        Series::new(
            format!("{what}, paper algorithm"),
            raw.clone(),
            Style::solid(plot::BLUE).width(1),
        ),
        Series::new(
            format!("{what}, paper algorithm, 2-sample mean"),
            mean2(&raw),
            Style::solid(plot::ORANGE),
        ),
    ];
    if what.starts_with('λ') {
        series.push(Series::new(
            format!("{what}, {}", cured.name),
            cured.curve(f),
            Style::solid(plot::GREEN),
        ));
    }
    series.push(oracle(full, what, &[f]));
    series
}

/// Beyond the paper: how fast the multiplier error grows, on a log scale, for
/// every run.
fn lambda_error_figure(paper: &Run, cured: &Run, others: &[&Run], t_end: f64) -> Figure {
    let mut growth = Panel::new(
        "Multiplier error max(|λ₁ − λ₁,RK4|, |λ₂ − λ₂,RK4|), t > 0",
        T,
        "error (N)",
    )
    .x_range(0.0, t_end)
    .scale(Scale::LogY)
    .legend(Legend::LowerRight);
    for (run, color) in [(paper, plot::BLUE), (cured, plot::GREEN)]
        .into_iter()
        .chain(
            others
                .iter()
                .copied()
                .zip([plot::ORANGE, plot::RED, plot::GREY]),
        )
    {
        growth.series.push(Series::new(
            run.name,
            lambda_error(run),
            Style::solid(color).width(1),
        ));
    }
    ("lambda_error.png".to_string(), vec![growth])
}

/// `(t, max(|λ₁ − λ₁,ref|, |λ₂ − λ₂,ref|))` for every sample with `t > 0`.
fn lambda_error(run: &Run) -> Vec<(f64, f64)> {
    run.samples
        .iter()
        .zip(&run.oracle)
        .skip(1)
        .map(|(s, r)| {
            let e = (s.lambda[0] - r.lambda[0])
                .abs()
                .max((s.lambda[1] - r.lambda[1]).abs());
            (s.t, e)
        })
        .collect()
}

/// Mean and largest Newton iterations per accepted step.
fn iterations(samples: &[Sample]) -> (f64, usize) {
    let steps = samples.iter().skip(1);
    let n = steps.len().max(1);
    let total: usize = steps.clone().map(|s| s.iterations).sum();
    let max = steps.map(|s| s.iterations).max().unwrap_or(0);
    (total as f64 / n as f64, max)
}

/// A row of the summary table: label and one cell per run.
type Row = (String, Vec<String>);

/// A row with the cell `f(run)` for each run.
fn row(runs: &[&Run], label: &str, f: impl Fn(&Run) -> String) -> Row {
    (label.to_string(), runs.iter().map(|r| f(r)).collect())
}

/// Prints the comparison table, one column per run, and why a run stopped.
fn print_summary(runs: &[&Run]) {
    let mut rows = error_rows(runs);
    rows.extend(mean_lambda_rows(runs));
    rows.extend(state_rows(runs));
    rows.extend(run_rows(runs));
    print_table(runs, &rows);
    print_stops(runs);
}

/// The largest errors against the oracle in θ, θ̇, (x, y), (ẋ, ẏ), (ẍ, ÿ) and
/// λ, over the whole run and over the first [`ZOOM`] seconds.
fn error_rows(runs: &[&Run]) -> Vec<Row> {
    let all = f64::INFINITY;
    vec![
        row(runs, "max |θ − θ_RK4| (rad)", |r| {
            sci(r.max_err(-1.0, all, |s| s.u[2]))
        }),
        row(runs, "max |θ − θ_RK4|, t ≤ 2 s (rad)", |r| {
            sci(r.max_err(-1.0, ZOOM, |s| s.u[2]))
        }),
        row(runs, "max |θ̇ − θ̇_RK4| (rad/s)", |r| {
            sci(r.max_err(-1.0, all, |s| s.v[2]))
        }),
        row(runs, "max |θ̇ − θ̇_RK4|, t ≤ 2 s (rad/s)", |r| {
            sci(r.max_err(-1.0, ZOOM, |s| s.v[2]))
        }),
        row(runs, "max |(x,y) − RK4| (m)", |r| {
            sci(r
                .max_err(-1.0, all, |s| s.u[0])
                .max(r.max_err(-1.0, all, |s| s.u[1])))
        }),
        row(runs, "max |(ẋ,ẏ) − RK4| (m/s)", |r| {
            sci(r
                .max_err(-1.0, all, |s| s.v[0])
                .max(r.max_err(-1.0, all, |s| s.v[1])))
        }),
        row(runs, "max |ẍ,ÿ − RK4|, 0 < t ≤ 2 s (m/s²)", |r| {
            sci(r
                .max_err(0.0, ZOOM, |s| s.a[0])
                .max(r.max_err(0.0, ZOOM, |s| s.a[1])))
        }),
        row(runs, "max |λ − λ_RK4|, t > 0 (N)", |r| {
            sci(r.lambda_err(all))
        }),
        row(runs, "max |λ − λ_RK4|, 0 < t ≤ 2 s (N)", |r| {
            sci(r.lambda_err(ZOOM))
        }),
    ]
}

/// The error of the two-sample mean of λ (the paper's filtering) against the
/// oracle's, up to 1 s and up to [`ZOOM`] s.
fn mean_lambda_rows(runs: &[&Run]) -> Vec<Row> {
    [1.0, ZOOM]
        .into_iter()
        .map(|hi| {
            row(
                runs,
                &format!("max |2-sample mean of λ − RK4 mean|, t ≤ {hi} s (N)"),
                |r| sci(mean_lambda_err(r, hi)),
            )
        })
        .collect()
}

/// Largest `|mean2(λᵢ) − mean2(λᵢ,ref)|` over both multipliers at the
/// midpoints `t ≤ hi`.
fn mean_lambda_err(r: &Run, hi: f64) -> f64 {
    let m = |v: &[Sample], i: usize| mean2(&curve(v, |s| s.lambda[i]));
    let mut err = 0.0_f64;
    for i in 0..2 {
        // Skip the first mean: it contains the given λ₀.
        for (a, b) in m(&r.samples, i).iter().zip(&m(&r.oracle, i)).skip(1) {
            if a.0 <= hi {
                err = err.max((a.1 - b.1).abs());
            }
        }
    }
    err
}

/// When the solution is lost, the energy drift, and the start's ü₀ and λ₀.
fn state_rows(runs: &[&Run]) -> Vec<Row> {
    vec![
        row(
            runs,
            "solution lost (|θ − θ_RK4| > 0.1 rad) at t (s)",
            |r| {
                r.samples
                    .iter()
                    .zip(&r.oracle)
                    .find(|(s, o)| (s.u[2] - o.u[2]).abs() > 0.1)
                    .map_or("never".to_string(), |(s, _)| format!("{:.2}", s.t))
            },
        ),
        row(runs, "energy drift max |E − E₀| (J)", |r| {
            let e0 = r.samples.first().map_or(0.0, Sample::energy);
            sci(r
                .samples
                .iter()
                .map(|s| (s.energy() - e0).abs())
                .fold(0.0, f64::max))
        }),
        row(runs, "initial ü₀ = (ẍ, ÿ, θ̈)", |r| {
            r.samples.first().map_or(String::new(), |s| {
                format!("({:.3}, {:.3}, {:.3})", s.a[0], s.a[1], s.a[2])
            })
        }),
        row(runs, "initial λ₀ (N)", |r| {
            r.samples.first().map_or(String::new(), |s| {
                format!("({:.3}, {:.3})", s.lambda[0], s.lambda[1])
            })
        }),
    ]
}

/// The Newton iterations, the accepted steps, how far each run got and
/// whether it finished.
fn run_rows(runs: &[&Run]) -> Vec<Row> {
    vec![
        row(runs, "Newton iterations/step, mean", |r| {
            format!("{:.2}", iterations(&r.samples).0)
        }),
        row(runs, "Newton iterations/step, max", |r| {
            iterations(&r.samples).1.to_string()
        }),
        row(runs, "accepted steps", |r| {
            (r.samples.len().saturating_sub(1)).to_string()
        }),
        row(runs, "t reached (s)", |r| format!("{:.2}", r.t_reached())),
        row(runs, "finished", |r| {
            if r.result.is_ok() {
                "yes"
            } else {
                "no, stopped early"
            }
            .to_string()
        }),
    ]
}

/// Prints the title and the rows as a plain-text table, one padded column per
/// run headed by its name.
fn print_table(runs: &[&Run], rows: &[Row]) {
    let w0 = rows.iter().map(|(l, _)| width(l)).max().unwrap_or(0);
    let widths: Vec<usize> = (0..runs.len())
        .map(|j| {
            rows.iter()
                .map(|(_, c)| width(&c[j]))
                .chain(std::iter::once(width(runs[j].name)))
                .max()
                .unwrap_or(0)
        })
        .collect();
    let pad = |s: &str, w: usize| format!("{s}{}", " ".repeat(w.saturating_sub(width(s))));
    let mut line = pad("", w0);
    for (r, w) in runs.iter().zip(&widths) {
        line.push_str(" | ");
        line.push_str(&pad(r.name, *w));
    }
    println!("Pendulum, paper preset (m = 1, l = 1, g₀ = 10, h = 0.01, θ₀ = π/2), against RK4");
    println!();
    println!("{}", line.trim_end());
    println!("{}", "-".repeat(width(&line)));
    for (label, cells) in rows {
        let mut line = pad(label, w0);
        for (c, w) in cells.iter().zip(&widths) {
            line.push_str(" | ");
            line.push_str(&pad(c, *w));
        }
        println!("{}", line.trim_end());
    }
}

/// Prints why each run that stopped early stopped (a result, not a failure).
fn print_stops(runs: &[&Run]) {
    for r in runs {
        if let Err(err) = &r.result {
            println!();
            println!(
                "{} stopped early at t = {:.2} s (last accepted sample): {err}",
                r.name,
                r.t_reached()
            );
        }
    }
}
