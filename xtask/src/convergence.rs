//! `cargo xtask convergence`: observed orders of convergence in `u`, `u̇`, `ü`
//! and `λ` against the RK4 oracle.
//!
//! The pendulum (m = l = 1, g₀ = 10) from rest at θ₀ = π/2 and from the moving
//! start θ₀ = 0.5, θ̇₀ = 3 (from rest `u⃛₀ = 0` and some start effects vanish),
//! integrated to t = 1 s with h = 0.02 … 0.000625 by the paper's scheme and
//! start, trapezoidal Newmark, HHT α = −0.1 and generalized-α ρ∞ = 0.9, 0.6
//! from a consistent start, and generalized-α ρ∞ = 0.9 without the start
//! correction. Errors are max-norms over the coordinates, at t = 1 s and as
//! the maximum over (0, 1] s; the orders are least-squares slopes
//! ([`fitted_order`]).

use std::f64::consts::FRAC_PI_2;
use std::path::Path;

use anyhow::Result;
use mstar::analysis::fitted_order;
use mstar::{Config, PendulumChain, Sample};

use crate::common::{
    Case, Initial, Table, color, draw_figures, generalized_alpha, hht, paper_scheme, sci,
    trapezoidal,
};
use crate::plot::{Legend, Panel, Scale, Series, Style};

/// The study's name.
const STUDY: &str = "convergence";
/// The step sizes, s.
const HS: [f64; 6] = [0.02, 0.01, 0.005, 0.0025, 0.00125, 0.000625];
/// End time, s.
const T_END: f64 = 1.0;

/// A quantity of a sample.
type Field = fn(&Sample) -> &[f64];

/// The four compared quantities: name and accessor.
const FIELDS: [(&str, Field); 4] = [
    ("u", |s| &s.u),
    ("u̇", |s| &s.v),
    ("ü", |s| &s.a),
    ("λ", |s| &s.lambda),
];

/// The configuration of a scheme for a step size.
type ConfigFor = fn(f64) -> Config;

/// The integrators: name and configuration for a step size.
fn schemes() -> Vec<(&'static str, ConfigFor)> {
    vec![
        ("paper (trapezoidal, M* start, λ₀ = (−10, 0))", |h| {
            paper_scheme(h, vec![-10.0, 0.0])
        }),
        ("trapezoidal, consistent start", trapezoidal),
        ("HHT α = −0.1", |h| hht(h, -0.1)),
        ("gen.-α ρ∞ = 0.9", |h| generalized_alpha(h, 0.9)),
        ("gen.-α ρ∞ = 0.9, tol = 1e-12", |h| Config {
            tol: 1e-12,
            ..generalized_alpha(h, 0.9)
        }),
        ("gen.-α ρ∞ = 0.6", |h| generalized_alpha(h, 0.6)),
        ("gen.-α ρ∞ = 0.9, corrected_start: false", |h| Config {
            corrected_start: false,
            ..generalized_alpha(h, 0.9)
        }),
    ]
}

/// Errors of one scheme for every h: `[field][h]`, at t = 1 s and max over
/// (0, 1] s. A run that stops early gives NaN.
struct Errors {
    /// At t = T_END.
    at_end: Vec<Vec<f64>>,
    /// Max over (0, T_END].
    max: Vec<Vec<f64>>,
    /// Time of the largest λ error, per h.
    worst_at: Vec<f64>,
    /// Accepted steps that took no Newton iteration (the predictor was
    /// accepted as converged), per h.
    zero_iterations: Vec<usize>,
    /// Why runs stopped early.
    failures: Vec<String>,
}

/// Runs one scheme for every h.
fn errors(sys: &PendulumChain, init: &Initial, config: ConfigFor) -> Errors {
    let mut at_end = vec![Vec::new(); FIELDS.len()];
    let mut max = vec![Vec::new(); FIELDS.len()];
    let (mut worst_at, mut zero_iterations, mut failures) = (Vec::new(), Vec::new(), Vec::new());
    for &h in &HS {
        let case = Case::run("", sys, config(h), init, T_END, 1, true);
        let ok = case.result.is_ok();
        if let Err(e) = &case.result {
            failures.push(format!(
                "h = {h}: stopped at t = {:.4} s: {e}",
                case.t_reached()
            ));
        }
        let worst = case
            .samples
            .iter()
            .zip(&case.oracle)
            .skip(1)
            .map(|(s, r)| (crate::common::max_diff(&s.lambda, &r.lambda), s.t))
            .fold((0.0, 0.0), |a, b| if b.0 > a.0 { b } else { a });
        worst_at.push(worst.1);
        zero_iterations.push(
            case.samples
                .iter()
                .skip(1)
                .filter(|s| s.iterations == 0)
                .count(),
        );
        for (k, (_, f)) in FIELDS.iter().enumerate() {
            at_end[k].push(if ok { case.final_err(f) } else { f64::NAN });
            max[k].push(if ok {
                case.max_err(0.0, T_END, f)
            } else {
                f64::NAN
            });
        }
    }
    Errors {
        at_end,
        max,
        worst_at,
        zero_iterations,
        failures,
    }
}

/// The study's entry point.
///
/// # Errors
/// I/O and drawing errors.
pub fn run() -> Result<()> {
    let out = crate::study_dir(STUDY)?;
    let sys = PendulumChain::paper(1.0, 1.0, 10.0);
    let starts = [
        ("rest", "from rest, θ₀ = π/2", Initial::one(FRAC_PI_2, 0.0)),
        (
            "moving",
            "moving start, θ₀ = 0.5, θ̇₀ = 3",
            Initial::one(0.5, 3.0),
        ),
    ];
    let mut figures = Vec::new();
    let mut tables = Tables::new();
    for (key, label, init) in &starts {
        figures.extend(start_figures(&sys, (key, label), init, &mut tables));
    }
    tables.report(&out)?;
    draw_figures(STUDY, &out, &figures)?;
    Ok(())
}

/// Runs every scheme from one start (`key` for tables and file names, `label`
/// for titles), adds their rows to `tables`, and returns the two figures:
/// errors at t = 1 s and max over (0, 1] s against h.
fn start_figures(
    sys: &PendulumChain,
    (key, label): (&str, &str),
    init: &Initial,
    tables: &mut Tables,
) -> [(String, Vec<Panel>); 2] {
    let mut panels_end: Vec<Panel> = FIELDS
        .iter()
        .map(|(n, _)| panel(label, n, "at t = 1 s"))
        .collect();
    let mut panels_max: Vec<Panel> = FIELDS
        .iter()
        .map(|(n, _)| panel(label, n, "max over (0, 1] s"))
        .collect();
    for (j, (name, config)) in schemes().into_iter().enumerate() {
        let e = errors(sys, init, config);
        tables.add(key, name, &e);
        let style = scheme_style(j);
        for (k, p) in panels_end.iter_mut().enumerate() {
            p.series
                .push(Series::new(name, points(&e.at_end[k]), style));
        }
        for (k, p) in panels_max.iter_mut().enumerate() {
            p.series.push(Series::new(name, points(&e.max[k]), style));
        }
    }
    [
        (format!("{key}_at_1s.png"), panels_end),
        (format!("{key}_max.png"), panels_max),
    ]
}

/// The style of the `j`-th scheme: past six colours, dashed, in the colour of
/// the run it varies (the uncorrected start next to gen.-α ρ∞ = 0.9).
fn scheme_style(j: usize) -> Style {
    if j < 6 {
        Style::solid(color(j))
    } else {
        Style::dashed(color(j - 3))
    }
}

/// The study's tables, filled start by start and scheme by scheme, and why
/// runs stopped early.
struct Tables {
    /// Fitted orders over all h.
    orders: Table,
    /// Fitted orders over the four smallest h.
    fine: Table,
    /// The errors for every h.
    raw: Table,
    /// `start / scheme, h = …: why`, for every run that stopped early.
    stops: Vec<String>,
}

impl Tables {
    /// The empty tables.
    fn new() -> Self {
        let names: Vec<String> = FIELDS
            .iter()
            .map(|(n, _)| format!("{n} at 1 s"))
            .chain(FIELDS.iter().map(|(n, _)| format!("{n} max (0,1]")))
            .collect();
        let mut header = vec!["start", "scheme"];
        header.extend(names.iter().map(String::as_str));
        let orders = Table::new(
            format!(
                "Fitted orders, pendulum g₀ = 10, h = {} … {} (cargo xtask convergence)",
                HS[0],
                HS[HS.len() - 1]
            ),
            &header,
        );
        let fine = Table::new(
            "Fitted orders over the four smallest h only (cargo xtask convergence)",
            &header,
        );
        let mut raw_header = vec!["start", "scheme", "h"];
        raw_header.extend(names.iter().map(String::as_str));
        raw_header.extend(["t of max λ err", "0-iteration steps"]);
        let raw = Table::new(
            "Errors (max-norm over coordinates) against RK4 (cargo xtask convergence)",
            &raw_header,
        );
        Self {
            orders,
            fine,
            raw,
            stops: Vec::new(),
        }
    }

    /// Adds one scheme's errors from the start `key`: its fitted orders, its
    /// errors per h and why its runs stopped.
    fn add(&mut self, key: &str, name: &str, e: &Errors) {
        self.stops
            .extend(e.failures.iter().map(|f| format!("{key} / {name}, {f}")));
        let order_all = |v: &[f64]| order(&HS, v);
        let order_fine = |v: &[f64]| order(&HS[2..], &v[2..]);
        let mut row = vec![key.to_string(), name.to_string()];
        let mut row_fine = row.clone();
        for v in e.at_end.iter().chain(&e.max) {
            row.push(order_all(v));
            row_fine.push(order_fine(v));
        }
        self.orders.row(row);
        self.fine.row(row_fine);
        for (i, h) in HS.iter().enumerate() {
            let mut r = vec![key.to_string(), name.to_string(), format!("{h}")];
            r.extend(e.at_end.iter().chain(&e.max).map(|v| sci(v[i])));
            r.push(format!("{:.4}", e.worst_at[i]));
            r.push(e.zero_iterations[i].to_string());
            self.raw.row(r);
        }
    }

    /// Prints the errors, why runs stopped and the order tables, and writes
    /// them as `errors.csv`, `orders.csv` and `orders_fine.csv`.
    fn report(&self, out: &Path) -> Result<()> {
        self.raw.print();
        self.raw.write_csv(&out.join("errors.csv"))?;
        for s in &self.stops {
            println!("{s}");
        }
        println!("(* in the order tables: fitted without the runs that stopped early)");
        println!();
        self.orders.print();
        self.orders.write_csv(&out.join("orders.csv"))?;
        self.fine.print();
        self.fine.write_csv(&out.join("orders_fine.csv"))?;
        Ok(())
    }
}

/// The fitted order over the finite errors, marked `*` when runs that stopped
/// early were left out; `—` with fewer than three points.
fn order(hs: &[f64], errors: &[f64]) -> String {
    let (h, e): (Vec<f64>, Vec<f64>) = hs
        .iter()
        .zip(errors)
        .filter(|(_, e)| e.is_finite() && **e > 0.0)
        .map(|(h, e)| (*h, *e))
        .unzip();
    if h.len() < 3 {
        return "—".to_string();
    }
    let mark = if h.len() < hs.len() { "*" } else { "" };
    format!("{:.2}{mark}", fitted_order(&h, &e))
}

/// `(h, error)` for the finite errors.
fn points(errors: &[f64]) -> Vec<(f64, f64)> {
    HS.iter()
        .copied()
        .zip(errors.iter().copied())
        .filter(|(_, e)| e.is_finite() && *e > 0.0)
        .collect()
}

/// A log-log panel of the error in `what` against h.
fn panel(start: &str, what: &str, measure: &str) -> Panel {
    Panel::new(
        format!("error in {what}, {measure}, {start}"),
        "h (s)",
        format!("‖{what} − {what}_RK4‖∞"),
    )
    .scale(Scale::LogLog)
    .legend(Legend::LowerRight)
}
