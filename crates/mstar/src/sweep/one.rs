//! One run of a sweep: the model with the run's overrides, integrated as
//! `mstar run` integrates it ([`crate::run::simulate`]), its CSV file written
//! by [`crate::record::Recorder`], and its summary row.

use std::time::Instant;

use mstar_file::MechanismFile;

use super::files::{Dir, Row};
use super::{Plan, SweepError};
use crate::columns::Columns;
use crate::columns::{OutputColumns, Selection};
use crate::csv::{CsvStream, format_number};
use crate::record::{Grid, Recorder, Rows};

/// The figures of a run for its summary row.
struct Figures {
    /// `None` when it reached its end, else why not.
    error: Option<String>,
    /// The accuracy warning of a run that reached its end with steps beyond
    /// the error tolerance (`mstar run`'s exit 3: [`crate::accuracy`]).
    beyond: Option<String>,
    /// The time reached and the last coordinates (none before the start).
    last: Option<(f64, Vec<f64>)>,
    /// The sensors' values at the last state (none before the start).
    sensors: Option<Vec<f64>>,
    max_constraint: Option<f64>,
    drift: Option<f64>,
    steps: Option<usize>,
}

impl Figures {
    fn failed(why: impl ToString) -> Self {
        Self {
            error: Some(why.to_string()),
            beyond: None,
            last: None,
            sensors: None,
            max_constraint: None,
            drift: None,
            steps: None,
        }
    }
}

/// Runs run `index` of `plan` into `dir` and saves its row: a failed run is
/// a row too (a panic of the run included). `None` when `stop` said so
/// before a step: the run has no row (a rerun runs it again) and keeps its
/// samples so far in `<index>.partial.csv`.
///
/// # Errors
/// Only when the row file cannot be written.
pub(super) fn run(
    plan: &Plan,
    dir: &Dir,
    index: usize,
    stop: &dyn Fn() -> bool,
) -> Result<Option<Row>, SweepError> {
    let clock = Instant::now();
    let figures = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        integrate(plan, dir, index, stop)
    }))
    .unwrap_or_else(|panic| {
        let why = panic
            .downcast_ref::<&str>()
            .map(|s| (*s).to_string())
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .unwrap_or_default();
        Some(Figures::failed(format!("the run panicked: {why}")))
    });
    let Some(figures) = figures else {
        return Ok(None);
    };
    let mut row = row(plan, index, &figures, clock.elapsed().as_secs_f64());
    if row.error().is_none() {
        // What a rerun and a merge check the CSV file against.
        row.csv_bytes = std::fs::metadata(dir.csv(index)).ok().map(|m| m.len());
    }
    dir.save(&row)?;
    Ok(Some(row))
}

/// Integrates run `index`, writing its CSV file (or, when it fails, the
/// samples so far as `<index>.partial.csv`); `None` when `stop` stopped it.
fn integrate(plan: &Plan, dir: &Dir, index: usize, stop: &dyn Fn() -> bool) -> Option<Figures> {
    let origin = plan.model().display().to_string();
    let overrides = plan.overrides(index);
    let file = match MechanismFile::parse_with(&plan.text, &origin, plan.format, &overrides) {
        Ok(file) => file,
        Err(e) => return Some(Figures::failed(e)),
    };
    let sys = crate::run::lookup(&file.mechanism);
    let (config, t_end) = match crate::run::config(&file.simulation) {
        Ok(c) => c,
        Err(e) => return Some(Figures::failed(e)),
    };
    let columns = match OutputColumns::new(sys, &file.output.sensors) {
        Ok(columns) => columns,
        Err(e) => return Some(Figures::failed(e)),
    };
    let extra = columns.names();
    let selection = match &file.output.columns {
        Some(patterns) => {
            let mut names = crate::csv::header(sys);
            names.extend_from_slice(&extra);
            match Selection::new(&names, patterns) {
                Ok(s) => Some(s),
                Err(e) => {
                    let why = file
                        .output
                        .columns_error(&e)
                        .map_or_else(|| format!("[output] columns: {e}"), |at| at.to_string());
                    return Some(Figures::failed(why));
                }
            }
        }
        None => None,
    };
    let stream = match CsvStream::create_selected(&dir.csv(index), sys, &extra, selection.as_ref())
    {
        Ok(stream) => stream,
        Err(e) => return Some(Figures::failed(e)),
    };
    let grid = match Grid::new(file.output.every_time) {
        Ok(grid) => grid,
        Err(e) => return Some(Figures::failed(e)),
    };
    let rows = Rows {
        every: file.output.every,
        grid,
    };
    let mut recorder =
        Recorder::new(Some(stream), Some(&columns), rows, t_end).keeping_last_state();
    let result = crate::run::simulate_until(sys, &file.simulation, &mut recorder, &mut || stop());
    recorder.finish_rows();
    let mut figures = Figures {
        error: None,
        beyond: None,
        last: recorder.last().map(|(t, u)| (t, u.to_vec())),
        sensors: recorder.last_state().map(|s| {
            let mut values = Vec::new();
            columns.sensors().values(&s, &mut values);
            values
        }),
        max_constraint: Some(recorder.max_constraint()),
        drift: Some(recorder.energy_drift()),
        steps: None,
    };
    let Some(stream) = recorder.into_stream() else {
        return Some(Figures::failed("no CSV stream"));
    };
    match result {
        Ok(stats) => match stream.finish() {
            Ok(_) => {
                figures.steps = Some(stats.steps);
                // The verdict of `mstar run` (its exit 3), from the same
                // statistics and configuration.
                figures.beyond =
                    crate::accuracy::warning(&stats, &config, &|i| sys.coord_name(i), true)
                        .map(|w| as_sweep_options(&w));
                // A run resumed after an interrupt: its complete file
                // replaces the samples the interrupt kept.
                let _ = std::fs::remove_file(dir.partial(index));
            }
            Err(e) => figures.error = Some(e.to_string()),
        },
        Err(e) => {
            let _ = stream.keep_partial(&dir.partial(index));
            if matches!(e, crate::run::RunError::Stopped { .. }) {
                return None;
            }
            figures.error = Some(e.to_string());
        }
    }
    Some(figures)
}

/// The summary's `status` of a run: `ok`, `beyond tolerance: <warning>`
/// (two warnings set apart by ` | `) or why it did not reach its end, on
/// one line whatever the message.
fn status(error: Option<&str>, beyond: Option<&str>) -> String {
    let one_line = |why: &str| why.split_whitespace().collect::<Vec<_>>().join(" ");
    match (error, beyond) {
        (Some(why), _) => one_line(why),
        (None, Some(warning)) => {
            // Each warning (the local error's, the energy's) on its own.
            let each: Vec<String> = warning
                .lines()
                .map(|w| one_line(w.strip_prefix("warning: ").unwrap_or(w)))
                .collect();
            format!("{}{}", super::files::BEYOND, each.join(" | "))
        }
        (None, None) => super::files::OK.to_string(),
    }
}

/// The summary row (see [`super::summary_header`]).
fn row(plan: &Plan, index: usize, f: &Figures, wall: f64) -> Row {
    let mut fields = vec![index.to_string()];
    fields.extend(plan.values(index).into_iter().map(str::to_string));
    let status = status(f.error.as_deref(), f.beyond.as_deref());
    fields.push(status);
    let number = |x: Option<f64>| x.map(format_number).unwrap_or_default();
    fields.push(number(f.last.as_ref().map(|l| l.0)));
    match &f.last {
        Some((_, u)) => fields.extend(u.iter().map(|&x| format_number(x))),
        None => fields.extend(plan.coords.iter().map(|_| String::new())),
    }
    match &f.sensors {
        Some(values) => fields.extend(values.iter().map(|&x| format_number(x))),
        None => fields.extend(plan.sensors.iter().map(|_| String::new())),
    }
    fields.push(number(f.max_constraint));
    fields.push(number(f.drift));
    fields.push(f.steps.map(|s| s.to_string()).unwrap_or_default());
    fields.push(format!("{wall:.6}"));
    Row::new(index, plan.params().len() + 1, fields)
}

#[cfg(test)]
mod tests {
    use super::status;

    #[test]
    fn a_status_is_one_line_and_sets_two_warnings_apart() {
        assert_eq!(status(None, None), "ok");
        assert_eq!(status(Some("a\n  b"), Some("warning: c")), "a b");
        let two = "warning: the local   error\nwarning: the energy";
        assert_eq!(
            status(None, Some(two)),
            "beyond tolerance: the local error | the energy"
        );
    }
}

/// `mstar run`'s advice in the options of a sweep: `--h X`, `--tol X`,
/// `--rtol X`, `--atol X`, `--h-max X` as `--set simulation.<key>=X`,
/// `--adaptive` and `--strict` as `--set simulation.error_control=…`.
fn as_sweep_options(advice: &str) -> String {
    const VALUED: [(&str, &str); 5] = [
        ("--h-max", "h_max"),
        ("--h", "h"),
        ("--tol", "tol"),
        ("--rtol", "rtol"),
        ("--atol", "atol"),
    ];
    let words: Vec<&str> = advice.split(' ').collect();
    let mut out: Vec<String> = Vec::with_capacity(words.len());
    let mut k = 0;
    while k < words.len() {
        let word = words[k];
        let valued = VALUED.iter().find(|(option, _)| *option == word);
        match (valued, words.get(k + 1)) {
            (Some((_, key)), Some(value)) => {
                // (A trailing `)` or `,` stays after the value.)
                let cut = value.find([')', ',', ';']).unwrap_or(value.len());
                out.push(format!(
                    "--set simulation.{key}={}{}",
                    &value[..cut],
                    &value[cut..]
                ));
                k += 2;
                continue;
            }
            _ => out.push(match word {
                "--adaptive" => "--set simulation.error_control=adaptive".to_string(),
                "(--strict" => "(--set simulation.error_control=strict".to_string(),
                "--strict" => "--set simulation.error_control=strict".to_string(),
                w => w.to_string(),
            }),
        }
        k += 1;
    }
    out.join(" ")
}

#[cfg(test)]
mod sweep_options_tests {
    use super::as_sweep_options;

    #[test]
    fn run_options_become_the_sweep_s_settings() {
        assert_eq!(
            as_sweep_options(
                "the results are not accurate; rerun with --h 0.0079 (estimated to bring every step within it) or with --adaptive (--strict stops at the first such step)"
            ),
            "the results are not accurate; rerun with --set simulation.h=0.0079 (estimated to bring every step within it) or with --set simulation.error_control=adaptive (--set simulation.error_control=strict stops at the first such step)"
        );
        assert_eq!(
            as_sweep_options("rerun with --tol 1e-12, then"),
            "rerun with --set simulation.tol=1e-12, then"
        );
    }
}
