//! `cargo xtask energy`: the energy error `E(t) − E₀` of the pendulum over
//! 1000 s.
//!
//! The paper's pendulum (m = l = 1, g₀ = 10, θ₀ = π/2, h = 0.01) integrated by
//! classic RK4 on the minimal coordinate at the same step ([`ChainOracle`] with
//! `max_step = h`), trapezoidal Newmark from a consistent start, and
//! generalized-α with ρ∞ = 0.9 and 0.6. Every tenth sample (0.1 s) is kept, so
//! memory stays bounded. Prints max |E − E₀| over [0, 10], [0, 100] and
//! [0, 1000] s, the least-squares drift rate and where a run stopped.

use std::f64::consts::FRAC_PI_2;
use std::path::Path;

use anyhow::Result;
use mstar::{ChainOracle, PendulumChain, Sample};

use crate::common::{
    Case, Initial, Table, color, draw_figures, generalized_alpha, sci, trapezoidal, write_columns,
};
use crate::plot::{Legend, Panel, Scale, Series, Style};

/// The study's name.
const STUDY: &str = "energy";
/// Step size, s.
const H: f64 = 0.01;
/// End time, s.
const T_END: f64 = 1000.0;
/// Keep every `KEEP`-th step (0.1 s).
const KEEP: usize = 10;

/// One energy history: name, `(t, E − E₀)` and how the run ended.
struct History {
    /// Legend and table name.
    name: String,
    /// `(t, E − E₀)` every 0.1 s.
    points: Vec<(f64, f64)>,
    /// `None` when the run reached [`T_END`], else why it stopped.
    stopped: Option<String>,
}

impl History {
    /// Largest `|E − E₀|` for `t ≤ hi`.
    fn max_until(&self, hi: f64) -> f64 {
        self.points
            .iter()
            .filter(|p| p.0 <= hi + 1e-9)
            .map(|p| p.1.abs())
            .fold(0.0, f64::max)
    }

    /// Least-squares slope of `E − E₀` against t, J/s.
    fn drift(&self) -> f64 {
        let n = self.points.len() as f64;
        let (mt, me) = self
            .points
            .iter()
            .fold((0.0, 0.0), |a, p| (a.0 + p.0 / n, a.1 + p.1 / n));
        let (sxy, sxx) = self.points.iter().fold((0.0, 0.0), |a, p| {
            (a.0 + (p.0 - mt) * (p.1 - me), a.1 + (p.0 - mt) * (p.0 - mt))
        });
        sxy / sxx
    }

    /// Mean of `E − E₀` over `lo < t ≤ hi` (NaN without samples there).
    fn mean(&self, lo: f64, hi: f64) -> f64 {
        let v: Vec<f64> = self
            .points
            .iter()
            .filter(|p| p.0 > lo && p.0 <= hi + 1e-9)
            .map(|p| p.1)
            .collect();
        if v.is_empty() {
            f64::NAN
        } else {
            v.iter().sum::<f64>() / v.len() as f64
        }
    }

    /// Time of the last point.
    fn t_reached(&self) -> f64 {
        self.points.last().map_or(0.0, |p| p.0)
    }
}

/// `(t, E − E₀)` of samples.
fn energy_points(samples: &[Sample]) -> Vec<(f64, f64)> {
    let e0 = samples.first().map_or(0.0, Sample::energy);
    samples.iter().map(|s| (s.t, s.energy() - e0)).collect()
}

/// The study's entry point.
///
/// # Errors
/// I/O and drawing errors.
pub fn run() -> Result<()> {
    let out = crate::study_dir(STUDY)?;
    let histories = histories();
    let table = summary_table(&histories);
    table.print();
    table.write_csv(&out.join("summary.csv"))?;
    write_histories(&out, &histories)?;
    println!();
    draw_figures(STUDY, &out, &figures(&histories))?;
    Ok(())
}

/// Integrates the pendulum with RK4 and the three Newmark-family schemes and
/// keeps their energy errors.
fn histories() -> Vec<History> {
    let sys = PendulumChain::paper(1.0, 1.0, 10.0);
    let init = Initial::one(FRAC_PI_2, 0.0);
    let mut histories = vec![rk4_history(&sys, &init)];
    for (name, config) in [
        ("trapezoidal, consistent start", trapezoidal(H)),
        ("gen.-α ρ∞ = 0.9", generalized_alpha(H, 0.9)),
        ("gen.-α ρ∞ = 0.6", generalized_alpha(H, 0.6)),
    ] {
        let case = Case::run(name, &sys, config, &init, T_END, KEEP, false);
        histories.push(History {
            name: name.to_string(),
            points: energy_points(&case.samples),
            stopped: case.result.is_err().then(|| case.outcome()),
        });
    }
    histories
}

/// The energy history of classic RK4 on the minimal coordinate at the same
/// step h, sampled every 0.1 s: the reference the others are judged by.
fn rk4_history(sys: &PendulumChain, init: &Initial) -> History {
    // RK4 at h exactly: a hair above h so that 0.1 s is always 10 steps.
    let mut oracle = ChainOracle::new(sys);
    oracle.max_step = H * (1.0 + 1e-9);
    let times: Vec<f64> = (0..=(T_END / (KEEP as f64 * H)).round() as usize)
        .map(|k| k as f64 * KEEP as f64 * H)
        .collect();
    let rk4 = oracle.solve(&init.theta, &init.omega, &times);
    History {
        name: "RK4 (minimal coordinate), h = 0.01".to_string(),
        points: energy_points(&rk4),
        stopped: None,
    }
}

/// The summary table: max and mean energy error over windows, the drift rate
/// and where each run got to.
fn summary_table(histories: &[History]) -> Table {
    let mut table = Table::new(
        "Pendulum energy error, g₀ = 10, θ₀ = π/2, h = 0.01, E₀ = 0 J (cargo xtask energy)",
        &[
            "integrator",
            "max|ΔE| [0,10] s",
            "[0,100] s",
            "[0,1000] s",
            "mean ΔE (0,10] s",
            "mean ΔE (990,1000] s",
            "LSQ drift (J/s)",
            "t reached",
        ],
    );
    for hst in histories {
        table.row(vec![
            hst.name.clone(),
            sci(hst.max_until(10.0)),
            sci(hst.max_until(100.0)),
            sci(hst.max_until(T_END)),
            sci(hst.mean(0.0, 10.0)),
            sci(hst.mean(T_END - 10.0, T_END)),
            sci(hst.drift()),
            format!("{:.2}", hst.t_reached()),
        ]);
    }
    table
}

/// Prints why a run stopped and writes each history as `<name>.csv`.
fn write_histories(out: &Path, histories: &[History]) -> Result<()> {
    for hst in histories {
        if let Some(why) = &hst.stopped {
            println!("{}: {why}", hst.name);
        }
        let file = out.join(format!("{}.csv", crate::common::slug(&hst.name)));
        let rows: Vec<Vec<f64>> = hst.points.iter().map(|p| vec![p.0, p.1]).collect();
        write_columns(&file, &["t", "E_minus_E0"], &rows)?;
    }
    Ok(())
}

/// The figures: |E − E₀| on a log scale, and E − E₀ linear over the whole
/// run and over the first 10 s.
fn figures(histories: &[History]) -> Vec<(String, Vec<Panel>)> {
    let mut log = Panel::new(
        "Pendulum: energy error |E − E₀|, h = 0.01 (every 0.1 s)",
        "t (s)",
        "|E − E₀| (J)",
    )
    .scale(Scale::LogY)
    .x_range(0.0, T_END)
    .legend(Legend::UpperRight);
    let (mut lin, mut zoom) = linear_panels(histories);
    for (k, hst) in histories.iter().enumerate() {
        let style = Style::solid(color(k)).width(1);
        let abs: Vec<(f64, f64)> = hst.points.iter().map(|p| (p.0, p.1.abs())).collect();
        log.series.push(Series::new(hst.name.clone(), abs, style));
        lin.series
            .push(Series::new(hst.name.clone(), hst.points.clone(), style));
        zoom.series
            .push(Series::new(hst.name.clone(), hst.points.clone(), style));
    }
    vec![
        ("energy_log.png".to_string(), vec![log]),
        ("energy_linear.png".to_string(), vec![lin, zoom]),
    ]
}

/// The empty linear panels: the whole run, on the range of the runs that
/// finish (a blow-up would flatten the others), and the first 10 s.
fn linear_panels(histories: &[History]) -> (Panel, Panel) {
    let bound = histories
        .iter()
        .filter(|h| h.stopped.is_none())
        .map(|h| h.max_until(T_END))
        .fold(0.0, f64::max)
        * 1.3;
    let lin = Panel::new(
        "Pendulum: energy error E − E₀ (runs that stop early are clipped)",
        "t (s)",
        "E − E₀ (J)",
    )
    .x_range(0.0, T_END)
    .y_range(-bound, 0.4 * bound)
    .legend(Legend::LowerLeft);
    let zoom = Panel::new(
        "Pendulum: energy error E − E₀, first 10 s",
        "t (s)",
        "E − E₀ (J)",
    )
    .x_range(0.0, 10.0)
    .y_range(-0.05, 0.05)
    .legend(Legend::LowerLeft);
    (lin, zoom)
}
