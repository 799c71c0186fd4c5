//! `cargo xtask work-precision`: error against CPU time, fixed steps against
//! error-controlled ones, on three problems with independent references:
//!
//! - the pendulum (m = l = 1, g₀ = 9.81) released from 2 rad, 5 s: the angle
//!   against RK4 (`ChainOracle`, 1e-4 s);
//! - a chain of 10 point masses on 0.1 m rods released horizontally, 1 s
//!   (it whips at the end): the largest angle error against RK4 in the
//!   joint angles;
//! - Andrews' squeezing mechanism (`models/andrews.toml`), 0.03 s: the
//!   largest relative error of the seven angles against the IVP test set.
//!
//! Each run's CPU time is the fastest of several repetitions (start-up
//! included), one thread. Writes `docs/work-precision.md` with the tables and
//! `docs/figures/work-precision.png`.

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use anyhow::{Context as _, Result};
use mstar::file::ModelFile;
use mstar::{
    ChainOracle, Config, ErrorControl, Integrator, Link, PendulumChain, SampleRef, Scheme,
    StepMode, System,
};

use crate::common::{Table, color, sci};
use crate::plot::{self, Legend, Panel, Scale, Style};

/// One way to choose the step sizes.
#[derive(Clone, Copy, Debug)]
struct Method {
    name: &'static str,
    mode: StepMode,
    rho: f64,
}

const METHODS: [Method; 4] = [
    Method {
        name: "fixed h, ρ∞ = 0.9 (default)",
        mode: StepMode::Monitor,
        rho: 0.9,
    },
    Method {
        name: "fixed h, ρ∞ = 0.5",
        mode: StepMode::Monitor,
        rho: 0.5,
    },
    Method {
        name: "adaptive, ρ∞ = 0.5 (--adaptive)",
        mode: StepMode::Adaptive,
        rho: 0.5,
    },
    Method {
        name: "adaptive, ρ∞ = 0.9",
        mode: StepMode::Adaptive,
        rho: 0.9,
    },
];

/// The tolerances of the adaptive runs (`rtol = atol`).
const TOLS: [f64; 6] = [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8];

/// One problem: its system, start, span, step sizes and error measure.
struct Problem<'a> {
    name: &'static str,
    sys: &'a dyn System,
    u0: Vec<f64>,
    v0: Vec<f64>,
    t_end: f64,
    /// Fixed step sizes; the first one starts the adaptive runs too.
    hs: Vec<f64>,
    h_adaptive: f64,
    /// The error of the final coordinates.
    error: ErrorOf<'a>,
}

/// The error of a run from its final coordinates.
type ErrorOf<'a> = Box<dyn Fn(&[f64]) -> f64 + 'a>;

/// One run: error, CPU time (s), accepted and rejected steps.
#[derive(Clone, Copy, Debug)]
struct Point {
    knob: f64,
    error: f64,
    cpu: f64,
    steps: usize,
    rejected: usize,
}

/// Runs the study.
pub fn run() -> Result<()> {
    let pendulum = PendulumChain::paper(1.0, 1.0, 9.81);
    let links = vec![Link { m: 1.0, l: 0.1 }; 10];
    let chain = PendulumChain::new(links, 9.81);
    let andrews = ModelFile::load_with(Path::new("models/andrews.toml"), &[])
        .context("models/andrews.toml")?;
    let problems = [
        pendulum_problem(&pendulum),
        chain_problem(&chain),
        andrews_problem(&andrews)?,
    ];
    let mut page = String::from(include_str!("work_precision_intro.md"));
    let mut panels = Vec::new();
    for p in &problems {
        let results: Vec<Vec<Point>> = METHODS.iter().map(|m| sweep(p, m)).collect();
        let table = table(p, &results);
        table.print();
        let _ = write!(page, "\n{}\n", table.markdown());
        panels.push(panel(p, &results));
    }
    let figure = Path::new("docs/figures/work-precision.png");
    plot::draw(figure, &panels)?;
    std::fs::write("docs/work-precision.md", page)?;
    println!("wrote docs/work-precision.md and {}", figure.display());
    Ok(())
}

fn pendulum_problem(sys: &PendulumChain) -> Problem<'_> {
    let (theta0, t_end) = (2.0, 5.0);
    let mut oracle = ChainOracle::new(sys);
    oracle.max_step = 1e-4;
    let exact = oracle.solve(&[theta0], &[0.0], &[t_end]);
    let theta_end = exact.last().map_or(f64::NAN, |s| s.u[2]);
    Problem {
        name: "pendulum from 2 rad, 5 s",
        sys,
        u0: sys.position(&[theta0]),
        v0: sys.velocity(&[theta0], &[0.0]),
        t_end,
        hs: vec![0.02, 0.01, 0.005, 0.0025, 0.00125, 0.000625],
        h_adaptive: 1e-3,
        error: Box::new(move |u| (u[2] - theta_end).abs()),
    }
}

fn chain_problem(sys: &PendulumChain) -> Problem<'_> {
    let n = sys.links.len();
    let theta0 = vec![std::f64::consts::FRAC_PI_2; n];
    let t_end = 1.0;
    let mut oracle = ChainOracle::new(sys);
    oracle.max_step = 1e-5;
    let exact = oracle.solve(&theta0, &vec![0.0; n], &[t_end]);
    let angles: Vec<f64> = exact
        .last()
        .map(|s| (0..n).map(|k| s.u[3 * k + 2]).collect())
        .unwrap_or_default();
    Problem {
        name: "10-link chain (point masses) released horizontally, 1 s",
        sys,
        u0: sys.position(&theta0),
        v0: vec![0.0; 3 * n],
        t_end,
        hs: vec![2e-3, 1e-3, 5e-4, 2.5e-4, 1.25e-4, 6.25e-5],
        h_adaptive: 1e-4,
        error: Box::new(move |u| {
            (0..n)
                .map(|k| (u[3 * k + 2] - angles[k]).abs())
                .fold(0.0, f64::max)
        }),
    }
}

fn andrews_problem(file: &ModelFile) -> Result<Problem<'_>> {
    let sys = &file.system;
    let mut theta = [0usize; 7];
    for (k, slot) in theta.iter_mut().enumerate() {
        *slot = sys
            .body(&format!("K{}", k + 1))
            .and_then(|b| b.theta)
            .context("andrews.toml: a body K1 … K7")?;
    }
    Ok(Problem {
        name: "Andrews' squeezing mechanism, 0.03 s",
        sys,
        u0: sys.initial_position(),
        v0: sys.initial_velocity(),
        t_end: 0.03,
        hs: vec![4e-5, 2e-5, 1e-5, 5e-6, 2.5e-6, 1.25e-6],
        h_adaptive: 1e-6,
        error: Box::new(move |u| {
            let ours = mstar_testkit::validation::andrews::angles(theta.map(|i| u[i]));
            mstar_testkit::validation::andrews::REFERENCE
                .iter()
                .zip(ours)
                .map(|(&(_, want), got)| ((got - want) / want).abs())
                .fold(0.0, f64::max)
        }),
    })
}

/// Every step size (fixed) or tolerance (adaptive) of `method` on `p`.
fn sweep(p: &Problem<'_>, method: &Method) -> Vec<Point> {
    let knobs: Vec<f64> = match method.mode {
        StepMode::Adaptive => TOLS.to_vec(),
        StepMode::Monitor | StepMode::Strict => p.hs.clone(),
    };
    knobs
        .iter()
        .filter_map(|&knob| {
            let config = Config {
                h: if method.mode == StepMode::Adaptive {
                    p.h_adaptive
                } else {
                    knob
                },
                scheme: Scheme::GeneralizedAlpha {
                    rho_inf: method.rho,
                },
                error: ErrorControl {
                    rtol: knob,
                    atol: knob,
                    mode: method.mode,
                    h_max: None,
                },
                ..Config::default()
            };
            measure(p, &config).map(|(error, cpu, steps, rejected)| Point {
                knob,
                error,
                cpu,
                steps,
                rejected,
            })
        })
        .collect()
}

/// One configuration: (error, fastest CPU time of up to 10 repetitions or
/// 0.3 s, accepted and rejected steps); `None` when the run fails.
fn measure(p: &Problem<'_>, config: &Config) -> Option<(f64, f64, usize, usize)> {
    let mut best = f64::INFINITY;
    let mut spent = 0.0;
    let mut result = None;
    for _ in 0..10 {
        let clock = Instant::now();
        let mut integ = Integrator::new(p.sys, config.clone(), 0.0, &p.u0, &p.v0).ok()?;
        integ.run(p.t_end, &mut |_: &SampleRef<'_>| {}).ok()?;
        let cpu = clock.elapsed().as_secs_f64();
        best = best.min(cpu);
        spent += cpu;
        let st = integ.stats();
        result = Some(((p.error)(integ.view().u), st.steps, st.rejected));
        if spent > 0.3 {
            break;
        }
    }
    result.map(|(e, steps, rejected)| (e, best, steps, rejected))
}

fn table(p: &Problem<'_>, results: &[Vec<Point>]) -> Table {
    let mut t = Table::new(
        format!("### {}", p.name),
        &[
            "method",
            "h or tol",
            "error",
            "CPU time, s",
            "steps",
            "rejected",
        ],
    );
    for (m, points) in METHODS.iter().zip(results) {
        for q in points {
            t.row(vec![
                m.name.to_string(),
                format!("{:e}", q.knob),
                sci(q.error),
                sci(q.cpu),
                q.steps.to_string(),
                q.rejected.to_string(),
            ]);
        }
    }
    t
}

fn panel(p: &Problem<'_>, results: &[Vec<Point>]) -> Panel {
    let mut panel = Panel::new(p.name, "CPU time, s", "error")
        .scale(Scale::LogLog)
        .legend(Legend::UpperRight);
    for (k, (m, points)) in METHODS.iter().zip(results).enumerate() {
        let xy: Vec<(f64, f64)> = points
            .iter()
            .filter(|q| q.error > 0.0 && q.error.is_finite())
            .map(|q| (q.cpu, q.error))
            .collect();
        let style = if m.mode == StepMode::Adaptive {
            Style::solid(color(k))
        } else {
            Style::dashed(color(k))
        };
        panel = panel.series(m.name, xy, style.width(2));
    }
    panel
}
