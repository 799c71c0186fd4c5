//! Helpers shared by the stability, convergence and energy studies: running a
//! [`PendulumChain`] with the oracle alongside, error measures, tables printed
//! as Markdown and written as CSV, and copying figures to the docs.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context as _, Result};
use mstar::{
    ChainOracle, Config, IntegrationError, Integrator, PendulumChain, RunStats, Sample, SampleRef,
};

use crate::plot::{self, Panel};

/// The initial state of a chain in its link angles and rates.
#[derive(Clone, Debug, PartialEq)]
pub struct Initial {
    /// Link angles θ₀ from the downward vertical, rad.
    pub theta: Vec<f64>,
    /// Link rates θ̇₀, rad/s.
    pub omega: Vec<f64>,
}

impl Initial {
    /// One link at angle `theta` with rate `omega`.
    #[must_use]
    pub fn one(theta: f64, omega: f64) -> Self {
        Self {
            theta: vec![theta],
            omega: vec![omega],
        }
    }
}

/// One integrator run with the oracle at the kept samples' times.
pub struct Case {
    /// Legend and table name.
    pub name: String,
    /// The kept samples (the initial state first, the last accepted one last).
    pub samples: Vec<Sample>,
    /// The RK4 oracle at the same times (empty when not asked for).
    pub oracle: Vec<Sample>,
    /// How the run ended.
    pub result: Result<RunStats, IntegrationError>,
}

impl Case {
    /// Integrates `sys` from `init` to `t_end` with `config`, keeping every
    /// `keep`-th sample (and the last one), and evaluates the oracle at the kept
    /// times when `with_oracle`.
    #[must_use]
    pub fn run(
        name: impl Into<String>,
        sys: &PendulumChain,
        config: Config,
        init: &Initial,
        t_end: f64,
        keep: usize,
        with_oracle: bool,
    ) -> Self {
        let (samples, result) = integrate(sys, config, init, t_end, keep);
        let oracle = if with_oracle {
            let times: Vec<f64> = samples.iter().map(|s| s.t).collect();
            ChainOracle::new(sys).solve(&init.theta, &init.omega, &times)
        } else {
            Vec::new()
        };
        Self {
            name: name.into(),
            samples,
            oracle,
            result,
        }
    }

    /// Time of the last accepted sample.
    #[must_use]
    pub fn t_reached(&self) -> f64 {
        self.samples.last().map_or(0.0, |s| s.t)
    }

    /// `max ‖f(ours) − f(oracle)‖∞` over the samples with `lo < t ≤ hi`.
    #[must_use]
    pub fn max_err(&self, lo: f64, hi: f64, f: impl Fn(&Sample) -> &[f64]) -> f64 {
        self.samples
            .iter()
            .zip(&self.oracle)
            .filter(|(s, _)| s.t > lo && s.t <= hi + 1e-12)
            .map(|(s, r)| max_diff(f(s), f(r)))
            .fold(0.0, f64::max)
    }

    /// The error `‖f(ours) − f(oracle)‖∞` at the last sample.
    #[must_use]
    pub fn final_err(&self, f: impl Fn(&Sample) -> &[f64]) -> f64 {
        match (self.samples.last(), self.oracle.last()) {
            (Some(s), Some(r)) => max_diff(f(s), f(r)),
            _ => f64::NAN,
        }
    }

    /// `"yes"` or why the run stopped.
    #[must_use]
    pub fn outcome(&self) -> String {
        match &self.result {
            Ok(_) => "finished".to_string(),
            Err(e) => format!("stopped at t = {:.2} s: {e}", self.t_reached()),
        }
    }

    /// `(t, E − E₀)` for every kept sample.
    #[must_use]
    pub fn energy_error(&self) -> Vec<(f64, f64)> {
        let e0 = self.samples.first().map_or(0.0, Sample::energy);
        self.samples
            .iter()
            .map(|s| (s.t, s.energy() - e0))
            .collect()
    }
}

/// Integrates `sys` from `init`, keeping every `keep`-th accepted sample, the
/// initial one and the last one. On an error the samples up to it are kept.
pub fn integrate(
    sys: &PendulumChain,
    config: Config,
    init: &Initial,
    t_end: f64,
    keep: usize,
) -> (Vec<Sample>, Result<RunStats, IntegrationError>) {
    let u0 = sys.position(&init.theta);
    let v0 = sys.velocity(&init.theta, &init.omega);
    let keep = keep.max(1);
    let mut kept = Vec::new();
    let mut last: Option<Sample> = None;
    let mut count = 0_usize;
    let result = Integrator::new(sys, config, 0.0, &u0, &v0).and_then(|mut integ| {
        integ.run(t_end, &mut |s: &SampleRef<'_>| {
            if count.is_multiple_of(keep) {
                kept.push(s.to_sample());
                last = None;
            } else {
                last = Some(s.to_sample());
            }
            count += 1;
        })
    });
    kept.extend(last);
    (kept, result)
}

/// `max_i |a_i − b_i|`.
#[must_use]
pub fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// A number in scientific notation with four significant digits.
#[must_use]
pub fn sci(x: f64) -> String {
    format!("{x:.3e}")
}

/// Display width of a table cell: characters without combining marks.
#[must_use]
pub fn width(s: &str) -> usize {
    s.chars()
        .filter(|c| !('\u{300}'..='\u{36f}').contains(c))
        .count()
}

/// A table: printed as Markdown (so that the docs can quote it verbatim) and
/// written as CSV.
#[derive(Clone, Debug, Default)]
pub struct Table {
    /// Printed above the table.
    pub title: String,
    /// Column headings.
    pub header: Vec<String>,
    /// Cells, row by row.
    pub rows: Vec<Vec<String>>,
}

impl Table {
    /// An empty table with a title and headings.
    #[must_use]
    pub fn new(title: impl Into<String>, header: &[&str]) -> Self {
        Self {
            title: title.into(),
            header: header.iter().map(|h| (*h).to_string()).collect(),
            rows: Vec::new(),
        }
    }

    /// Appends a row.
    pub fn row(&mut self, cells: Vec<String>) {
        self.rows.push(cells);
    }

    /// The table as Markdown, columns padded to equal width.
    #[must_use]
    pub fn markdown(&self) -> String {
        let cols = self.header.len();
        let widths: Vec<usize> = (0..cols)
            .map(|j| {
                std::iter::once(&self.header)
                    .chain(&self.rows)
                    .filter_map(|r| r.get(j))
                    .map(|c| width(c))
                    .max()
                    .unwrap_or(0)
                    .max(3)
            })
            .collect();
        let line = |cells: &[String]| {
            let mut s = String::from("|");
            for (j, w) in widths.iter().enumerate() {
                let c = cells.get(j).map_or("", String::as_str);
                let _ = write!(s, " {c}{} |", " ".repeat(w.saturating_sub(width(c))));
            }
            s
        };
        let mut out = format!("{}\n\n{}\n|", self.title, line(&self.header));
        for w in &widths {
            out.push_str(&"-".repeat(w + 2));
            out.push('|');
        }
        out.push('\n');
        for r in &self.rows {
            out.push_str(&line(r));
            out.push('\n');
        }
        out
    }

    /// Prints the Markdown form and a blank line.
    pub fn print(&self) {
        println!("{}", self.markdown());
    }

    /// Writes the table as CSV (cells containing commas are quoted).
    ///
    /// # Errors
    /// If the file cannot be written.
    pub fn write_csv(&self, path: &Path) -> Result<()> {
        let quote = |c: &String| {
            if c.contains(',') || c.contains('"') {
                format!("\"{}\"", c.replace('"', "\"\""))
            } else {
                c.clone()
            }
        };
        let mut out = String::new();
        for r in std::iter::once(&self.header).chain(&self.rows) {
            out.push_str(&r.iter().map(quote).collect::<Vec<_>>().join(","));
            out.push('\n');
        }
        std::fs::write(path, out).with_context(|| format!("could not write {}", path.display()))
    }
}

/// Writes `(x, y…)` columns as CSV.
///
/// # Errors
/// If the file cannot be written.
pub fn write_columns(path: &Path, header: &[&str], rows: &[Vec<f64>]) -> Result<()> {
    let mut out = header.join(",");
    out.push('\n');
    for r in rows {
        let cells: Vec<String> = r.iter().map(|x| format!("{x:e}")).collect();
        out.push_str(&cells.join(","));
        out.push('\n');
    }
    std::fs::write(path, out).with_context(|| format!("could not write {}", path.display()))
}

/// Draws each figure into `out` and copies it to `docs/figures/<study>/`.
///
/// # Errors
/// Drawing, directory or copy errors.
pub fn draw_figures(study: &str, out: &Path, figures: &[(String, Vec<Panel>)]) -> Result<()> {
    let docs = PathBuf::from("docs").join("figures").join(study);
    std::fs::create_dir_all(&docs)
        .with_context(|| format!("could not create {}", docs.display()))?;
    for (file, panels) in figures {
        let path = out.join(file);
        plot::draw(&path, panels)?;
        let to = docs.join(file);
        std::fs::copy(&path, &to)
            .with_context(|| format!("could not copy {} to {}", path.display(), to.display()))?;
    }
    println!(
        "wrote {} figures to {} and copied them to {}",
        figures.len(),
        out.display(),
        docs.display()
    );
    Ok(())
}

/// A colour per series index, cycling.
#[must_use]
pub fn color(k: usize) -> plot::RGBColor {
    const COLORS: [plot::RGBColor; 6] = [
        plot::BLUE,
        plot::ORANGE,
        plot::GREEN,
        plot::RED,
        plot::GREY,
        plot::BLACK,
    ];
    COLORS[k % COLORS.len()]
}

/// The paper's algorithm (`Config::paper`): trapezoidal Newmark, `M*` start
/// with the given `λ₀`, full Newton, no scaling, no step control.
#[must_use]
pub fn paper_scheme(h: f64, lambda0: Vec<f64>) -> Config {
    Config::paper(h, lambda0)
}

/// The paper's trapezoidal Newmark from a consistent (and corrected) start.
#[must_use]
pub fn trapezoidal(h: f64) -> Config {
    Config {
        start: mstar::Start::Consistent,
        corrected_start: true,
        ..Config::paper(h, Vec::new())
    }
}

/// Generalized-α with spectral radius `rho_inf`, otherwise [`Config::default`].
#[must_use]
pub fn generalized_alpha(h: f64, rho_inf: f64) -> Config {
    Config {
        scheme: mstar::Scheme::GeneralizedAlpha { rho_inf },
        h,
        ..Config::default()
    }
}

/// HHT-α, otherwise [`Config::default`].
#[must_use]
pub fn hht(h: f64, alpha: f64) -> Config {
    Config {
        scheme: mstar::Scheme::Hht { alpha },
        h,
        ..Config::default()
    }
}

/// A file-name fragment from a run name.
#[must_use]
pub fn slug(name: &str) -> String {
    let mut s = String::new();
    for c in name.chars() {
        if c.is_ascii_alphanumeric() {
            s.push(c.to_ascii_lowercase());
        } else if c == '.' {
            s.push('p');
        } else if !s.ends_with('_') {
            s.push('_');
        }
    }
    s.trim_matches('_').to_string()
}
