//! `mstar run MODEL --objective SPEC --gradient KEY…`: the gradient of a
//! scalar objective over the run by the discrete adjoint
//! (`mstar_newmark::Integrator::gradient`; `docs/analysis.md`, "Adjoint
//! gradients"). The parameters are model-file keys, as for
//! `--sensitivity` ([`FileParameter`]).

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use mstar::newmark::{Column, Memory, Objective, Parameterized, Short};
use mstar::sensitivity::{FileParameter, FileParameters};
use mstar::{Integrator, System, csv};

use crate::output::usage;

/// The memory the stored states may take before the backward pass
/// recomputes segments from checkpoints instead.
pub const MEMORY_BUDGET: usize = 1 << 30;

/// What `--objective`, `--gradient` and `--gradient-out` ask for.
pub struct Request<'a> {
    /// The model file.
    pub model: Option<&'a Path>,
    /// The run's `--set` overrides (and `--h`, `--t-end`, …).
    pub set: &'a [String],
    /// `final:COLUMN`, `sum:COLUMN` or `fit:COLUMN=FILE.csv`.
    pub spec: &'a str,
    /// The parameters' keys.
    pub keys: &'a [String],
    /// Where to write the gradient as JSON.
    pub out: Option<&'a Path>,
    /// Whether the run's rows go to `--out` (refused: the gradient is
    /// printed instead).
    pub rows_out: bool,
    /// Whether redundant constraints are solved on a subset of rows.
    pub redundant: bool,
    /// `--output-every` or `[output] every_time`.
    pub every_time: Option<f64>,
}

/// An objective as parsed: its kind, column and (for a fit) file.
enum Spec {
    Final(String),
    Sum(String),
    Fit(String, PathBuf),
}

/// Parses `final:COLUMN`, `sum:COLUMN`, `fit:COLUMN=FILE.csv`.
fn parse_spec(spec: &str) -> Result<Spec> {
    let bad = || {
        usage(format!(
            "--objective {spec}: give final:COLUMN, sum:COLUMN or fit:COLUMN=FILE.csv, COLUMN \
             a u:, v:, a: or lambda: column of the run's CSV (e.g. final:u:rod.x)"
        ))
    };
    let (kind, rest) = spec.split_once(':').ok_or_else(bad)?;
    match kind.trim() {
        "final" => Ok(Spec::Final(rest.trim().to_string())),
        "sum" => Ok(Spec::Sum(rest.trim().to_string())),
        "fit" => {
            let (column, file) = rest.rsplit_once('=').ok_or_else(bad)?;
            Ok(Spec::Fit(
                column.trim().to_string(),
                PathBuf::from(file.trim()),
            ))
        }
        _ => Err(bad()),
    }
}

/// The CSV a `fit:COLUMN=FILE.csv` objective reads (an input no output
/// may name); `None` for any other objective or a malformed one.
pub fn fit_file(spec: &str) -> Option<PathBuf> {
    match parse_spec(spec) {
        Ok(Spec::Fit(_, file)) => Some(file),
        _ => None,
    }
}

/// The state column `name` (`u:…`, `v:…`, `a:…`, `lambda:…`) of `sys`.
fn column<S: System + ?Sized>(sys: &S, name: &str) -> Result<Column> {
    if let Some(c) = mstar::sensitivity::state_column(sys, name) {
        return Ok(c);
    }
    let n = sys.n_coords();
    let header = csv::header(sys);
    let state = &header[1..1 + 3 * n + sys.n_constraints()];
    let prefix = name.split(':').next().unwrap_or_default();
    let like: Vec<&str> = state
        .iter()
        .filter(|c| c.starts_with(&format!("{prefix}:")))
        .take(6)
        .map(String::as_str)
        .collect();
    Err(usage(format!(
        "--objective: '{name}' is not a state column of this model; the objective reads \
         u:, v:, a: or lambda: columns of the run's CSV header{}",
        if like.is_empty() {
            String::new()
        } else {
            format!(" (e.g. {})", like.join(", "))
        }
    )))
}

/// The times and the values of column `name` in the CSV file `path` (a
/// header row naming `t` and `name`, as `mstar run --out` writes).
fn measured(path: &Path, name: &str) -> Result<(Vec<f64>, Vec<f64>)> {
    let shown = path.display();
    let mut reader = ::csv::ReaderBuilder::new()
        .has_headers(true)
        .trim(::csv::Trim::All)
        .from_path(path)
        .with_context(|| format!("{shown}: cannot read the measured values"))?;
    let header = reader
        .headers()
        .with_context(|| format!("{shown}:1: cannot read the header row"))?
        .clone();
    let find = |want: &str| {
        header.iter().position(|h| h == want).ok_or_else(|| {
            usage(format!(
                "{shown}:1: no column '{want}' in the header; the file needs the columns 't' \
                 and '{name}' (as mstar run --out writes them)"
            ))
        })
    };
    let (it, iy) = (find("t")?, find(name)?);
    let (mut times, mut values) = (Vec::new(), Vec::new());
    for record in reader.records() {
        let record = record.with_context(|| format!("{shown}: cannot read a row"))?;
        let line = record.position().map_or(0, ::csv::Position::line);
        let number = |i: usize, what: &str| -> Result<f64> {
            let text = record.get(i).unwrap_or_default();
            text.parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| {
                    usage(format!(
                        "{shown}:{line}:{}: '{text}' in column '{what}' is not a finite number",
                        i + 1
                    ))
                })
        };
        times.push(number(it, "t")?);
        values.push(number(iy, name)?);
    }
    Ok((times, values))
}

/// Two different times as messages print numbers (6 significant digits,
/// [`Short`]), or in full when those would read the same.
fn distinct(a: f64, b: f64) -> (String, String) {
    let (short_a, short_b) = (Short(a).to_string(), Short(b).to_string());
    if short_a == short_b {
        (a.to_string(), b.to_string())
    } else {
        (short_a, short_b)
    }
}

/// Refuses measured times that are not the run's sample times (within
/// `1e-9` of the step).
fn check_times(path: &Path, given: &[f64], run: &[f64], h: f64) -> Result<()> {
    for (k, (g, r)) in given.iter().zip(run).enumerate() {
        if (g - r).abs() > 1e-9 * h.max(r.abs()) {
            let (g, r) = distinct(*g, *r);
            return Err(usage(format!(
                "{}:{}: t = {g} where the run has a sample at t = {r}; give the measured values \
                 at the run's own sample times (the start and every step)",
                path.display(),
                k + 2
            )));
        }
    }
    Ok(())
}

/// Refuses what the adjoint does not handle (usage errors), as
/// `--sensitivity` does.
fn refuse(request: &Request<'_>, config: &mstar::Config) -> Result<()> {
    let why = if config.error.mode == mstar::StepMode::Adaptive {
        "needs fixed steps: with adaptive steps the step sizes depend on the parameters; drop \
         --adaptive (or error_control = \"adaptive\") and choose h"
    } else if request.every_time.is_some() {
        "sums over the steps' own samples: drop --output-every, and in place of [output] \
         every_time write rows every n steps ([output] every; on the command line \
         --set output.every=1, which replaces every_time)"
    } else if request.redundant {
        "does not handle redundant constraints solved on a subset of rows yet; remove the \
         redundant joints"
    } else if request.rows_out {
        "prints the gradient instead of writing rows: drop --out (write the gradient with \
         --gradient-out G.json), or run once more without --objective for the rows"
    } else {
        return Ok(());
    };
    Err(usage(format!("--objective {why}")))
}

/// Runs `sys` from `(u0, v0)` to `t_end` and prints `dΨ/d<key>` for every
/// key (and writes them with `--gradient-out`).
///
/// # Errors
/// Usage errors for a bad objective, column or measured file; the file's
/// error for a key that names no number; the run's errors.
pub fn run<S: System + ?Sized>(
    request: &Request<'_>,
    sys: &S,
    (config, u0, v0, t_end): (mstar::Config, &[f64], &[f64], f64),
) -> Result<()> {
    let Some(path) = request.model else {
        return Err(usage(
            "--objective needs a model file (its keys are the parameters), not --builtin".into(),
        ));
    };
    if request.keys.is_empty() {
        return Err(usage(
            "--objective needs at least one --gradient KEY".into(),
        ));
    }
    refuse(request, &config)?;
    let spec = parse_spec(request.spec)?;
    let mut fit_file = None;
    let objective = match &spec {
        Spec::Final(c) => Objective::Final(column(sys, c)?),
        Spec::Sum(c) => Objective::Sum(column(sys, c)?),
        Spec::Fit(c, file) => {
            let column = column(sys, c)?;
            let (times, values) = measured(file, c)?;
            fit_file = Some((file, times));
            Objective::Fit {
                column,
                measured: values,
            }
        }
    };
    let mut params = Vec::with_capacity(request.keys.len());
    let mut file = FileParameters::new(path, request.set);
    for key in request.keys {
        let p = file
            .parameter(key)
            .with_context(|| format!("--gradient {key}"))?;
        if params.iter().any(|q: &FileParameter| q.name() == p.name()) {
            return Err(usage(format!("--gradient {key}: the key is given twice")));
        }
        params.push(p);
    }
    let refs: Vec<&dyn Parameterized> = params.iter().map(|p| p as &dyn Parameterized).collect();
    let h = config.h;
    let mut integ = Integrator::new(sys, config, 0.0, u0, v0)?;
    let memory = Memory::Budget {
        bytes: MEMORY_BUDGET,
    };
    let gradient = integ
        .gradient(t_end, &refs, &objective, memory)
        .with_context(|| format!("--objective {}", request.spec))?;
    if let Some((file, times)) = fit_file {
        check_times(file, &times, &gradient.times, h)?;
    }
    println!("Ψ = {:e} ({})", gradient.objective, request.spec);
    for (name, value) in gradient.names.iter().zip(&gradient.values) {
        println!("dΨ/d{name} = {value:e}");
    }
    if let Some(out) = request.out {
        write_json(out, request.spec, &gradient)?;
    }
    Ok(())
}

/// `{"objective": SPEC, "value": Ψ, "steps": N, "gradient": {KEY: dΨ/dKEY, …}}`.
fn write_json(out: &Path, spec: &str, g: &mstar::newmark::Gradient) -> Result<()> {
    let gradient: serde_json::Map<String, serde_json::Value> = g
        .names
        .iter()
        .zip(&g.values)
        .map(|(k, v)| (k.clone(), serde_json::Value::from(*v)))
        .collect();
    let json = serde_json::json!({
        "objective": spec,
        "value": g.objective,
        "steps": g.steps,
        "gradient": gradient,
    });
    let text = serde_json::to_string_pretty(&json).context("formatting the gradient as JSON")?;
    // (Replaced whole, and never a read-only file: as every output.)
    mstar::csv::write_atomically(out, (text + "\n").as_bytes())
        .with_context(|| format!("{}: cannot write the gradient", out.display()))
}
