//! `cargo xtask stability`: the period-2h mode of `ü` and `λ` over 100 s.
//!
//! Integrates the paper's pendulum (m = l = 1, g₀ = 10, θ₀ = π/2, h = 0.01)
//! and a double pendulum (two links m = l = 1, g₀ = 9.81, h = 0.01) from a
//! small (θ₀ = (0.5, 0.5)) and a large (θ₀ = (π/2, π/2), chaotic) amplitude
//! with the paper's scheme and start, trapezoidal Newmark from a consistent
//! start, and generalized-α with ρ∞ = 0.9 and 0.6. Prints per run the
//! multiplier error in growing windows, the period-2h amplitude of `ü` and `λ`
//! per 1-s window, the energy error and where a run stopped; writes the
//! amplitudes as CSV and PNG. Then the start-correction table (a moving start,
//! max λ error over 0.2 s against h) and the condition number of the
//! iteration matrix with and without scaling (`docs/stability.md`).

use std::f64::consts::FRAC_PI_2;
use std::path::Path;

use anyhow::{Context as _, Result};
use mstar::analysis::{fitted_order, nyquist_amplitude};
use mstar::kkt::condition_number;
use mstar::linearize::Linearization;
use mstar::{Config, Link, PendulumChain, Sample, StateRef};

use crate::common::{
    Case, Initial, Table, color, draw_figures, generalized_alpha, paper_scheme, sci, trapezoidal,
    write_columns,
};
use crate::plot::{Legend, Panel, Scale, Series, Style};

/// The study's name (output directory and docs figure folder).
const STUDY: &str = "stability";
/// Step size, s.
const H: f64 = 0.01;
/// End time, s.
const T_END: f64 = 100.0;

/// A model and initial state to integrate.
struct Problem {
    /// Short name, used in file names.
    key: &'static str,
    /// Table and title name.
    label: &'static str,
    /// The model.
    sys: PendulumChain,
    /// The initial state.
    init: Initial,
    /// The paper start's `λ₀`.
    lambda0: Vec<f64>,
}

/// The three problems.
fn problems() -> Vec<Problem> {
    let double =
        || PendulumChain::new(vec![Link { m: 1.0, l: 1.0 }, Link { m: 1.0, l: 1.0 }], 9.81);
    let two = |a: f64| Initial {
        theta: vec![a, a],
        omega: vec![0.0, 0.0],
    };
    vec![
        Problem {
            key: "pendulum",
            label: "pendulum θ₀ = π/2",
            sys: PendulumChain::paper(1.0, 1.0, 10.0),
            init: Initial::one(FRAC_PI_2, 0.0),
            lambda0: vec![-10.0, 0.0],
        },
        Problem {
            key: "double_small",
            label: "double pendulum θ₀ = (0.5, 0.5)",
            sys: double(),
            init: two(0.5),
            lambda0: vec![0.0; 4],
        },
        Problem {
            key: "double_large",
            label: "double pendulum θ₀ = (π/2, π/2)",
            sys: double(),
            init: two(FRAC_PI_2),
            lambda0: vec![0.0; 4],
        },
    ]
}

/// The four integrators, by name.
fn configs(lambda0: &[f64]) -> Vec<(&'static str, Config)> {
    vec![
        (
            "paper (trapezoidal, M* start)",
            paper_scheme(H, lambda0.to_vec()),
        ),
        ("trapezoidal, consistent start", trapezoidal(H)),
        ("gen.-α ρ∞ = 0.9", generalized_alpha(H, 0.9)),
        ("gen.-α ρ∞ = 0.6", generalized_alpha(H, 0.6)),
    ]
}

/// How the period-2h amplitude of a window is measured.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Filter {
    /// [`nyquist_amplitude`]: `max |x_{k+1} − 2x_k + x_{k−1}| / 4`, which adds
    /// `h² |x''| / 4` of the smooth part.
    Second,
    /// [`nyquist_amplitude`] of the sequence of second differences / 4: a
    /// fourth difference / 16, which adds only `h⁴ |x''''| / 16`.
    Fourth,
}

/// Period-2h amplitude of the error `f(ours) − f(oracle)` per 1-s window
/// `[k, k+1]`: `(k + 1, max over the components)`, for the windows with at
/// least five samples. Measured on the error rather than on `f` because
/// [`nyquist_amplitude`] of the pendulum's smooth λ alone is about 2.5e-2 N.
fn amplitude_per_second(
    case: &Case,
    filter: Filter,
    f: impl Fn(&Sample) -> &[f64],
) -> Vec<(f64, f64)> {
    let windows = case.t_reached().floor() as usize;
    let n = case.samples.first().map_or(0, |s| f(s).len());
    let pairs: Vec<(&Sample, &Sample)> = case.samples.iter().zip(&case.oracle).collect();
    (0..windows)
        .filter_map(|k| {
            let (lo, hi) = (k as f64 - 1e-9, k as f64 + 1.0 + 1e-9);
            let win: Vec<_> = pairs
                .iter()
                .filter(|(s, _)| s.t >= lo && s.t <= hi)
                .collect();
            (win.len() >= 5).then(|| {
                let amp = (0..n)
                    .map(|i| {
                        let mut e: Vec<f64> = win.iter().map(|(s, r)| f(s)[i] - f(r)[i]).collect();
                        if filter == Filter::Fourth {
                            e = e
                                .windows(3)
                                .map(|w| (w[2] - 2.0 * w[1] + w[0]) / 4.0)
                                .collect();
                        }
                        nyquist_amplitude(&e)
                    })
                    .fold(0.0, f64::max);
                (k as f64 + 1.0, amp)
            })
        })
        .collect()
}

/// First time at which a link angle is more than 0.1 rad off the oracle.
fn lost_at(case: &Case) -> String {
    let n_links = case.samples.first().map_or(0, |s| s.u.len() / 3);
    case.samples
        .iter()
        .zip(&case.oracle)
        .find(|(s, r)| (0..n_links).any(|k| (s.u[3 * k + 2] - r.u[3 * k + 2]).abs() > 0.1))
        .map_or("never".to_string(), |(s, _)| format!("{:.2}", s.t))
}

/// `(t, ‖λ − λ_ref‖∞)` for every `every`-th sample with `t > 0`.
fn lambda_error_curve(case: &Case, every: usize) -> Vec<(f64, f64)> {
    case.samples
        .iter()
        .zip(&case.oracle)
        .skip(1)
        .step_by(every)
        .map(|(s, r)| (s.t, crate::common::max_diff(&s.lambda, &r.lambda)))
        .collect()
}

/// The study's entry point.
///
/// # Errors
/// I/O and drawing errors; not a run stopping early (that is a result).
pub fn run() -> Result<()> {
    let out = crate::study_dir(STUDY)?;
    let mut figures = Vec::new();
    let mut table = summary_table();
    let mut stops = Vec::new();
    for p in problems() {
        let cases: Vec<Case> = configs(&p.lambda0)
            .into_iter()
            .map(|(name, config)| Case::run(name, &p.sys, config, &p.init, T_END, 1, true))
            .collect();
        let amps: Vec<Amplitudes> = cases.iter().map(Amplitudes::new).collect();
        for (c, a) in cases.iter().zip(&amps) {
            table.row(summary_row(&p, c, a));
            if c.result.is_err() {
                stops.push(format!("{} / {}: {}", p.label, c.name, c.outcome()));
            }
        }
        write_nyquist_csv(&out, &p, &cases, &amps)?;
        for c in &cases {
            let file = format!("{}_{}.csv", p.key, crate::common::slug(&c.name));
            mstar::csv::write_csv(&out.join(&file), &p.sys, &c.samples)
                .with_context(|| format!("could not write {file}"))?;
        }
        figures.push((
            format!("{}_nyquist.png", p.key),
            nyquist_panels(&p, &cases, &amps),
        ));
        figures.push((
            format!("{}_energy_lambda.png", p.key),
            energy_lambda_panels(&p, &cases),
        ));
    }
    table.print();
    table.write_csv(&out.join("summary.csv"))?;
    for s in &stops {
        println!("{s}");
    }
    println!();
    print_side_tables(&out)?;
    draw_figures(STUDY, &out, &figures)?;
    Ok(())
}

/// The period-2h amplitudes of one run's errors per 1-s window
/// ([`amplitude_per_second`]): `(end of window, amplitude)`.
struct Amplitudes {
    /// A₂ of `λ − λ_ref`.
    lambda2: Vec<(f64, f64)>,
    /// A₄ of `λ − λ_ref`.
    lambda4: Vec<(f64, f64)>,
    /// A₂ of `ü − ü_ref`.
    a2: Vec<(f64, f64)>,
    /// A₄ of `ü − ü_ref`.
    a4: Vec<(f64, f64)>,
}

impl Amplitudes {
    /// Measures the four amplitudes of `case` (once: the table, the CSV and
    /// the figures share them).
    fn new(case: &Case) -> Self {
        Self {
            lambda2: amplitude_per_second(case, Filter::Second, |s| &s.lambda),
            lambda4: amplitude_per_second(case, Filter::Fourth, |s| &s.lambda),
            a2: amplitude_per_second(case, Filter::Second, |s| &s.a),
            a4: amplitude_per_second(case, Filter::Fourth, |s| &s.a),
        }
    }
}

/// The empty summary table, one row per problem and run to come.
fn summary_table() -> Table {
    Table::new(
        format!("Stability over {T_END} s, h = {H} (cargo xtask stability)"),
        &[
            "problem",
            "run",
            "max|Δλ| (0,1] s",
            "(0,10] s",
            "(0,100] s",
            "A₂(Δλ) 1st s",
            "A₂(Δλ) last s",
            "A₄(Δλ) 1st s",
            "A₄(Δλ) last s",
            "A₄(Δü) 1st s",
            "A₄(Δü) last s",
            "max|E−E₀|",
            "θ off by 0.1 at t",
            "t reached",
        ],
    )
}

/// One run's summary row: λ errors in growing windows, the amplitudes in the
/// first and last window, the energy error and where the run got to.
fn summary_row(p: &Problem, c: &Case, amps: &Amplitudes) -> Vec<String> {
    let first = |v: &[(f64, f64)]| v.first().map_or(f64::NAN, |p| p.1);
    let last = |v: &[(f64, f64)]| v.last().map_or(f64::NAN, |p| p.1);
    let max_de = c
        .energy_error()
        .iter()
        .map(|p| p.1.abs())
        .fold(0.0, f64::max);
    vec![
        p.label.to_string(),
        c.name.clone(),
        sci(c.max_err(0.0, 1.0, |s| &s.lambda)),
        sci(c.max_err(0.0, 10.0, |s| &s.lambda)),
        sci(c.max_err(0.0, 100.0, |s| &s.lambda)),
        sci(first(&amps.lambda2)),
        sci(last(&amps.lambda2)),
        sci(first(&amps.lambda4)),
        sci(last(&amps.lambda4)),
        sci(first(&amps.a4)),
        sci(last(&amps.a4)),
        sci(max_de),
        lost_at(c),
        format!("{:.2}", c.t_reached()),
    ]
}

/// Writes `<problem>_nyquist.csv`: per 1-s window, the four amplitudes of
/// every run (NaN after a run stopped).
fn write_nyquist_csv(out: &Path, p: &Problem, cases: &[Case], amps: &[Amplitudes]) -> Result<()> {
    let mut columns: Vec<Vec<f64>> = (1..=T_END as usize).map(|k| vec![k as f64]).collect();
    let mut header = vec!["t_end_of_window".to_string()];
    for (c, a) in cases.iter().zip(amps) {
        for (curve, what) in [
            (&a.lambda2, "A2_lambda"),
            (&a.lambda4, "A4_lambda"),
            (&a.a2, "A2_a"),
            (&a.a4, "A4_a"),
        ] {
            header.push(format!("{}:{what}", crate::common::slug(&c.name)));
            for (j, row) in columns.iter_mut().enumerate() {
                row.push(curve.get(j).map_or(f64::NAN, |p| p.1));
            }
        }
    }
    let header: Vec<&str> = header.iter().map(String::as_str).collect();
    write_columns(
        &out.join(format!("{}_nyquist.csv", p.key)),
        &header,
        &columns,
    )
}

/// A log-y panel titled after the problem.
fn log_panel(p: &Problem, title: &str, x: &str, y: &str, legend: Legend) -> Panel {
    Panel::new(format!("{}: {title}", p.label), x, y)
        .scale(Scale::LogY)
        .legend(legend)
}

/// The amplitude figure's panels: A₄ of Δλ, A₄ of Δü and A₂ of Δλ per 1-s
/// window, one series per run.
fn nyquist_panels(p: &Problem, cases: &[Case], amps: &[Amplitudes]) -> Vec<Panel> {
    let window = "end of window t (s)";
    let upper = Legend::UpperRight;
    let mut amp_l2 = log_panel(
        p,
        "A₂ = nyquist_amplitude(λ − λ_RK4) per 1-s window",
        window,
        "amplitude (N)",
        upper,
    );
    let mut amp_l = log_panel(
        p,
        "period-2h amplitude A₄ of λ − λ_RK4 per 1-s window",
        window,
        "amplitude (N)",
        upper,
    );
    let mut amp_a = log_panel(
        p,
        "period-2h amplitude A₄ of ü − ü_RK4 per 1-s window",
        window,
        "amplitude (m/s², rad/s²)",
        upper,
    );
    for (k, (c, a)) in cases.iter().zip(amps).enumerate() {
        let style = Style::solid(color(k));
        let series = |points: &Vec<(f64, f64)>| Series::new(c.name.clone(), points.clone(), style);
        amp_l.series.push(series(&a.lambda4));
        amp_l2.series.push(series(&a.lambda2));
        amp_a.series.push(series(&a.a4));
    }
    vec![amp_l, amp_a, amp_l2]
}

/// The error figure's panels: ‖λ − λ_ref‖∞ and |E − E₀| against t, every
/// tenth sample, one series per run.
fn energy_lambda_panels(p: &Problem, cases: &[Case]) -> Vec<Panel> {
    let mut energy = log_panel(
        p,
        "energy error |E − E₀|",
        "t (s)",
        "|E − E₀| (J)",
        Legend::LowerRight,
    );
    let mut lam = log_panel(
        p,
        "multiplier error ‖λ − λ_RK4‖∞",
        "t (s)",
        "error (N)",
        Legend::LowerRight,
    );
    for (k, c) in cases.iter().enumerate() {
        let style = Style::solid(color(k)).width(1);
        let de: Vec<(f64, f64)> = c
            .energy_error()
            .into_iter()
            .step_by(10)
            .map(|(t, e)| (t, e.abs()))
            .collect();
        energy.series.push(Series::new(c.name.clone(), de, style));
        lam.series.push(Series::new(
            c.name.clone(),
            lambda_error_curve(c, 10),
            style,
        ));
    }
    vec![lam, energy]
}

/// Prints and writes the three tables beside the runs: the trapezoidal
/// growth, the start correction and the conditioning.
fn print_side_tables(out: &Path) -> Result<()> {
    let growth = growth_table();
    growth.print();
    growth.write_csv(&out.join("trapezoidal_growth.csv"))?;
    let start = start_table();
    start.print();
    start.write_csv(&out.join("start_correction.csv"))?;
    let cond = condition_table()?;
    cond.print();
    cond.write_csv(&out.join("condition.csv"))?;
    Ok(())
}

/// Max λ error over (0, 0.2] s from the moving start θ₀ = 0.5, θ̇₀ = 3 (g₀ = 10)
/// with and without the corrected start, for h = 0.02 … 0.0025, and the fitted
/// orders.
fn start_table() -> Table {
    let hs = [0.02, 0.01, 0.005, 0.0025];
    let sys = PendulumChain::paper(1.0, 1.0, 10.0);
    let init = Initial::one(0.5, 3.0);
    let mut table = Table::new(
        "Start correction: max |λ − λ_ref| over (0, 0.2] s, θ₀ = 0.5, θ̇₀ = 3, g₀ = 10 (cargo xtask stability)",
        &[
            "h",
            "gen.-α 0.9, corrected_start: false",
            "gen.-α 0.9, corrected (default)",
            "gen.-α 0.6, false",
            "gen.-α 0.6, corrected",
        ],
    );
    let mut cols: Vec<Vec<f64>> = Vec::new();
    for rho in [0.9, 0.6] {
        for corrected in [false, true] {
            cols.push(
                hs.iter()
                    .map(|&h| {
                        let config = Config {
                            corrected_start: corrected,
                            ..generalized_alpha(h, rho)
                        };
                        Case::run("", &sys, config, &init, 0.2, 1, true)
                            .max_err(0.0, 0.2, |s| &s.lambda)
                    })
                    .collect(),
            );
        }
    }
    for (i, h) in hs.iter().enumerate() {
        let mut row = vec![format!("{h}")];
        row.extend(cols.iter().map(|c| sci(c[i])));
        table.row(row);
    }
    let mut row = vec!["fitted order".to_string()];
    row.extend(cols.iter().map(|c| format!("{:.2}", fitted_order(&hs, c))));
    table.row(row);
    table
}

/// Condition number of the pendulum's iteration matrix at a moving state
/// (θ = 0.7, θ̇ = 2, g₀ = 9.81), generalized-α ρ∞ = 0.9 coefficients, for
/// h = 1e-2 … 1e-6, without and with scaling.
fn condition_table() -> Result<Table> {
    let sys = PendulumChain::paper(1.0, 1.0, 9.81);
    let u = sys.position(&[0.7]);
    let v = sys.velocity(&[0.7], &[2.0]);
    let (a, lambda) = ([-3.0, 2.0, -6.0], [4.0, -9.0]);
    let mut lin = Linearization::new(&sys).context("linearizing the pendulum")?;
    let x = StateRef {
        t: 0.0,
        u: &u,
        v: &v,
        a: &a,
        lambda: &lambda,
    };
    lin.eval_residual(&sys, &x);
    lin.eval_jacobians(&sys, &x);
    let params = generalized_alpha(0.01, 0.9)
        .scheme
        .params()
        .context("generalized-α parameters")?;
    let mut table = Table::new(
        "Condition number of the KKT iteration matrix, pendulum, gen.-α ρ∞ = 0.9 (cargo xtask stability)",
        &["h", "unscaled", "scaled"],
    );
    for h in [1e-2, 1e-3, 1e-4, 1e-5, 1e-6] {
        let mut cond = |scaling| {
            lin.assemble(&params.coefficients(h, scaling));
            condition_number(lin.kkt())
        };
        let (plain, scaled) = (cond(false), cond(true));
        table.row(vec![format!("{h:e}"), sci(plain), sci(scaled)]);
    }
    Ok(table)
}

/// How the trapezoidal rule's period-2h mode grows with h: pendulum θ₀ = π/2,
/// g₀ = 10, consistent start, A₄(Δλ) at the end of the first five 1-s windows
/// and the mean growth factor per second over windows 1 → 4.
fn growth_table() -> Table {
    let sys = PendulumChain::paper(1.0, 1.0, 10.0);
    let init = Initial::one(FRAC_PI_2, 0.0);
    let mut table = Table::new(
        "Trapezoidal rule, consistent start, pendulum θ₀ = π/2: period-2h amplitude A₄(λ − λ_ref) per 1-s window (cargo xtask stability)",
        &[
            "h",
            "[0,1] s",
            "[1,2] s",
            "[2,3] s",
            "[3,4] s",
            "[4,5] s",
            "growth per s, windows 1→4",
            "growth per step",
            "t reached",
        ],
    );
    for h in [0.02, 0.01, 0.005] {
        let case = Case::run("", &sys, trapezoidal(h), &init, 20.0, 1, true);
        let amp = amplitude_per_second(&case, Filter::Fourth, |s| &s.lambda);
        let at = |k: usize| amp.get(k).map_or(f64::NAN, |p| p.1);
        let per_second = (at(3) / at(0)).powf(1.0 / 3.0);
        let mut row = vec![format!("{h}")];
        row.extend((0..5).map(|k| sci(at(k))));
        row.push(format!("{per_second:.2}"));
        row.push(format!("{:.4}", per_second.powf(h)));
        row.push(format!("{:.2}", case.t_reached()));
        table.row(row);
    }
    table
}
