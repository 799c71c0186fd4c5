//! `cargo xtask paper`: the paper's pendulum example (§3, Figs. 4-13) against
//! the RK4 oracle, with the default integrator as a second column.
//!
//! Runs [`PendulumRun::paper`] (trapezoidal Newmark, `M*` start, λ₀ = (−10, 0))
//! and the same model with [`Config::default`] (generalized-α, consistent
//! start); writes `target/studies/paper/{paper,rk4,generalized_alpha}.csv`, one
//! PNG per paper figure (copied to `docs/figures/paper/`) and prints a summary.
//! The paper preset is expected to stop early (Newton fails once the undamped
//! period-2h mode in λ has grown large, `algorithm.md` §5); that is a result of
//! the study, not a failure of it.

use std::path::{Path, PathBuf};

use anyhow::{Context as _, Result};
use mstar::pendulum::PendulumRun;
use mstar::{Config, IntegrationError, RunStats, Sample};

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

    let paper = Run::new("paper (Newmark, M* start)", &preset);
    let cured = Run::new("default (gen.-α ρ∞=0.9)", &default);
    // The oracle on the full grid, so the reference curves run to t_end even
    // where the paper run stopped.
    let full = preset.reference_on_grid();

    for (file, samples) in [
        ("paper.csv", &paper.samples),
        ("rk4.csv", &paper.oracle),
        ("generalized_alpha.csv", &cured.samples),
    ] {
        mstar::csv::write_csv(&out.join(file), &sys, samples)?;
    }

    let figures = figures(&paper, &cured, &full, preset.t_end);
    let docs = PathBuf::from(DOCS_FIGURES);
    std::fs::create_dir_all(&docs)
        .with_context(|| format!("could not create {}", docs.display()))?;
    for (file, panels) in &figures {
        let path = out.join(file);
        plot::draw(&path, panels)?;
        copy(&path, &docs.join(file))?;
    }

    print_summary(&[&paper, &cured]);
    println!();
    println!(
        "wrote paper.csv, rk4.csv, generalized_alpha.csv and {} figures to {}",
        figures.len(),
        out.display()
    );
    println!("copied the figures to {}", docs.display());
    Ok(())
}

fn copy(from: &Path, to: &Path) -> Result<()> {
    std::fs::copy(from, to)
        .with_context(|| format!("could not copy {} to {}", from.display(), to.display()))?;
    Ok(())
}

const T: &str = "t (s)";

/// Ours solid in `color`, the oracle dashed black on top.
fn versus(
    ours: &Run,
    full: &[Sample],
    what: &str,
    color: plot::RGBColor,
    f: impl Fn(&Sample) -> f64,
) -> [Series; 2] {
    [
        Series::new(
            format!("{what}, paper algorithm"),
            ours.curve(&f),
            Style::solid(color),
        ),
        Series::new(
            format!("{what}, RK4"),
            curve(full, &f),
            Style::dashed(plot::BLACK),
        ),
    ]
}

/// A quantity that grows before the paper run stops: the first [`ZOOM`]
/// seconds (where the oracle is visible), then the whole run on a scale that
/// shows the growth.
fn zoomed(title: &str, y_label: &str, t_end: f64, series: &[Series]) -> Vec<Panel> {
    let mut first = Panel::new(format!("{title}: first {ZOOM} s"), T, y_label).x_range(0.0, ZOOM);
    let mut whole = Panel::new(format!("{title}: whole run"), T, y_label)
        .x_range(0.0, t_end)
        .legend(Legend::UpperLeft);
    first.series = series.to_vec();
    whole.series = series.to_vec();
    vec![first, whole]
}

/// The figures, paper numbering (Figs. 4-13), as `(file name, panels)`.
fn figures(paper: &Run, cured: &Run, full: &[Sample], t_end: f64) -> Vec<(String, Vec<Panel>)> {
    let stop = match &paper.result {
        Ok(_) => String::new(),
        Err(_) => format!(" (run stopped at t = {:.2} s)", paper.t_reached()),
    };
    let panel =
        |title: &str, y: &str| Panel::new(format!("{title}{stop}"), T, y).x_range(0.0, t_end);
    let mut figs = Vec::new();

    let mut theta = panel("Fig. 4a — angle θ", "θ (rad)");
    theta
        .series
        .extend(versus(paper, full, "θ", plot::BLUE, |s| s.u[2]));
    let mut omega = panel("Fig. 4b — angular velocity dθ/dt", "dθ/dt (rad/s)");
    omega
        .series
        .extend(versus(paper, full, "dθ/dt", plot::BLUE, |s| s.v[2]));
    figs.push(("fig04_theta.png".to_string(), vec![theta, omega]));

    let mut pos = panel("Fig. 5 — displacements x, y", "x, y (m)").legend(Legend::LowerRight);
    pos.series
        .extend(versus(paper, full, "x", plot::BLUE, |s| s.u[0]));
    pos.series
        .extend(versus(paper, full, "y", plot::ORANGE, |s| s.u[1]));
    figs.push(("fig05_position.png".to_string(), vec![pos]));

    let mut vel =
        panel("Fig. 6 — velocities dx/dt, dy/dt", "dx/dt, dy/dt (m/s)").legend(Legend::LowerRight);
    vel.series
        .extend(versus(paper, full, "dx/dt", plot::BLUE, |s| s.v[0]));
    vel.series
        .extend(versus(paper, full, "dy/dt", plot::ORANGE, |s| s.v[1]));
    figs.push(("fig06_velocity.png".to_string(), vec![vel]));

    let e0 = paper.samples.first().map_or(0.0, Sample::energy);
    let mut energy = panel("Fig. 7 — kinetic, potential and total energy", "energy (J)")
        .legend(Legend::LowerRight);
    energy.series.extend([
        Series::new(
            "kinetic K",
            paper.curve(|s| s.kinetic),
            Style::solid(plot::BLUE),
        ),
        Series::new(
            "potential P",
            paper.curve(|s| s.potential),
            Style::solid(plot::ORANGE),
        ),
        Series::new(
            "total E = K + P",
            paper.curve(Sample::energy),
            Style::solid(plot::RED),
        ),
        Series::new(
            "K, RK4",
            curve(full, |s| s.kinetic),
            Style::dashed(plot::BLACK),
        ),
        Series::new(
            "P, RK4",
            curve(full, |s| s.potential),
            Style::dashed(plot::GREY),
        ),
    ]);
    let drift = panel("Fig. 7 (detail) — total energy error E − E₀", "E − E₀ (J)")
        .legend(Legend::UpperLeft)
        .series(
            "paper algorithm",
            paper.curve(|s| s.energy() - e0),
            Style::solid(plot::RED).width(1),
        );
    figs.push(("fig07_energy.png".to_string(), vec![energy, drift]));

    let rk4_acc = Panel::new(
        "Fig. 8 — angular acceleration d²θ/dt², RK4",
        T,
        "d²θ/dt² (rad/s²)",
    )
    .x_range(0.0, t_end)
    .series(
        "d²θ/dt², RK4",
        curve(full, |s| s.a[2]),
        Style::solid(plot::BLACK),
    );
    figs.push(("fig08_theta_ddot_rk4.png".to_string(), vec![rk4_acc]));

    let acc = |fig: &str, what: &str, unit: &str, k: usize| {
        let title = format!("{fig} — {what}, paper algorithm{stop}");
        zoomed(
            &title,
            &format!("{what} ({unit})"),
            t_end,
            &versus(paper, full, what, plot::BLUE, |s| s.a[k]),
        )
    };
    figs.push((
        "fig09_theta_ddot.png".to_string(),
        acc("Fig. 9", "d²θ/dt²", "rad/s²", 2),
    ));
    figs.push((
        "fig10_x_ddot.png".to_string(),
        acc("Fig. 10", "d²x/dt²", "m/s²", 0),
    ));
    figs.push((
        "fig11_y_ddot.png".to_string(),
        acc("Fig. 11", "d²y/dt²", "m/s²", 1),
    ));

    for (fig, file, i) in [
        ("Fig. 12", "fig12_lambda1.png", 0),
        ("Fig. 13", "fig13_lambda2.png", 1),
    ] {
        let what = if i == 0 { "λ₁" } else { "λ₂" };
        let mut series = versus(paper, full, what, plot::BLUE, |s| s.lambda[i]).to_vec();
        series.insert(
            1,
            Series::new(
                format!("{what}, {}", cured.name),
                cured.curve(|s| s.lambda[i]),
                Style::solid(plot::GREEN),
            ),
        );
        let title = format!("{fig} — multiplier {what}{stop}");
        figs.push((
            file.to_string(),
            zoomed(&title, &format!("{what} (N)"), t_end, &series),
        ));
    }

    // Beyond the paper: how fast the multiplier error grows, on a log scale.
    let lam_err = |run: &Run| -> Vec<(f64, f64)> {
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
    };
    let growth = Panel::new("Multiplier error max|λᵢ − λᵢ,RK4| (t > 0)", T, "error (N)")
        .x_range(0.0, t_end)
        .scale(Scale::LogY)
        .legend(Legend::LowerRight)
        .series(
            paper.name,
            lam_err(paper),
            Style::solid(plot::BLUE).width(1),
        )
        .series(
            cured.name,
            lam_err(cured),
            Style::solid(plot::GREEN).width(1),
        );
    figs.push(("lambda_error.png".to_string(), vec![growth]));
    figs
}

/// Mean and largest Newton iterations per accepted step.
fn iterations(samples: &[Sample]) -> (f64, usize) {
    let steps = samples.iter().skip(1);
    let n = steps.len().max(1);
    let total: usize = steps.clone().map(|s| s.iterations).sum();
    let max = steps.map(|s| s.iterations).max().unwrap_or(0);
    (total as f64 / n as f64, max)
}

fn print_summary(runs: &[&Run]) {
    let mut rows: Vec<(String, Vec<String>)> = Vec::new();
    let mut row = |label: &str, f: &dyn Fn(&Run) -> String| {
        rows.push((label.to_string(), runs.iter().map(|r| f(r)).collect()));
    };
    let e = |x: f64| format!("{x:.3e}");
    let all = f64::INFINITY;
    row("max |θ − θ_RK4| (rad)", &|r| {
        e(r.max_err(-1.0, all, |s| s.u[2]))
    });
    row("max |θ − θ_RK4|, t ≤ 2 s (rad)", &|r| {
        e(r.max_err(-1.0, ZOOM, |s| s.u[2]))
    });
    row("max |θ̇ − θ̇_RK4| (rad/s)", &|r| {
        e(r.max_err(-1.0, all, |s| s.v[2]))
    });
    row("max |θ̇ − θ̇_RK4|, t ≤ 2 s (rad/s)", &|r| {
        e(r.max_err(-1.0, ZOOM, |s| s.v[2]))
    });
    row("max |(x,y) − RK4| (m)", &|r| {
        e(r.max_err(-1.0, all, |s| s.u[0])
            .max(r.max_err(-1.0, all, |s| s.u[1])))
    });
    row("max |(ẋ,ẏ) − RK4| (m/s)", &|r| {
        e(r.max_err(-1.0, all, |s| s.v[0])
            .max(r.max_err(-1.0, all, |s| s.v[1])))
    });
    row("max |ẍ,ÿ − RK4|, 0 < t ≤ 2 s (m/s²)", &|r| {
        e(r.max_err(0.0, ZOOM, |s| s.a[0])
            .max(r.max_err(0.0, ZOOM, |s| s.a[1])))
    });
    row("max |λ − λ_RK4|, t > 0 (N)", &|r| e(r.lambda_err(all)));
    row("max |λ − λ_RK4|, 0 < t ≤ 2 s (N)", &|r| {
        e(r.lambda_err(ZOOM))
    });
    row("energy drift max |E − E₀| (J)", &|r| {
        let e0 = r.samples.first().map_or(0.0, Sample::energy);
        e(r.samples
            .iter()
            .map(|s| (s.energy() - e0).abs())
            .fold(0.0, f64::max))
    });
    row("initial ü₀ = (ẍ, ÿ, θ̈)", &|r| {
        r.samples.first().map_or(String::new(), |s| {
            format!("({:.3}, {:.3}, {:.3})", s.a[0], s.a[1], s.a[2])
        })
    });
    row("initial λ₀ (N)", &|r| {
        r.samples.first().map_or(String::new(), |s| {
            format!("({:.3}, {:.3})", s.lambda[0], s.lambda[1])
        })
    });
    row("Newton iterations/step, mean", &|r| {
        format!("{:.2}", iterations(&r.samples).0)
    });
    row("Newton iterations/step, max", &|r| {
        iterations(&r.samples).1.to_string()
    });
    row("accepted steps", &|r| {
        (r.samples.len().saturating_sub(1)).to_string()
    });
    row("t reached (s)", &|r| format!("{:.2}", r.t_reached()));
    row("finished", &|r| {
        if r.result.is_ok() {
            "yes"
        } else {
            "no, stopped early"
        }
        .to_string()
    });

    let w0 = rows
        .iter()
        .map(|(l, _)| l.chars().count())
        .max()
        .unwrap_or(0);
    let widths: Vec<usize> = (0..runs.len())
        .map(|j| {
            rows.iter()
                .map(|(_, c)| c[j].chars().count())
                .chain(std::iter::once(runs[j].name.chars().count()))
                .max()
                .unwrap_or(0)
        })
        .collect();
    let pad = |s: &str, w: usize| format!("{s}{}", " ".repeat(w.saturating_sub(s.chars().count())));
    let mut line = pad("", w0);
    for (r, w) in runs.iter().zip(&widths) {
        line.push_str(" | ");
        line.push_str(&pad(r.name, *w));
    }
    println!("Pendulum, paper preset (m = 1, l = 1, g₀ = 10, h = 0.01, θ₀ = π/2), against RK4");
    println!();
    println!("{}", line.trim_end());
    println!("{}", "-".repeat(line.chars().count()));
    for (label, cells) in &rows {
        let mut line = pad(label, w0);
        for (c, w) in cells.iter().zip(&widths) {
            line.push_str(" | ");
            line.push_str(&pad(c, *w));
        }
        println!("{}", line.trim_end());
    }
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
