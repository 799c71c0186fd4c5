//! `cargo xtask validate`: every model of `models/` against its independent
//! reference at the published spans (`mstar_testkit::validation`, level `Tight`:
//! IFToMM A01's 2000 s run only here); prints the table and writes it to
//! `docs/validation.md`. Fails when a row does.

use std::path::Path;
use std::time::Instant;

use anyhow::{Result, bail};
use mstar_testkit::validation::{CASES, Level, Row, markdown};

/// Runs the validation and writes `docs/validation.md`.
pub fn run() -> Result<()> {
    let models = Path::new("models");
    let mut rows: Vec<Row> = Vec::new();
    let mut errors = Vec::new();
    for case in CASES {
        let clock = Instant::now();
        match (case.run)(models, Level::Tight) {
            Ok(r) => {
                let pass = r.iter().all(Row::pass);
                println!(
                    "{:32} {} rows, {} ({:.1} s)",
                    case.model,
                    r.len(),
                    if pass { "pass" } else { "FAIL" },
                    clock.elapsed().as_secs_f64()
                );
                rows.extend(r);
            }
            Err(e) => {
                println!("{:32} error: {e}", case.model);
                errors.push(format!("{}: {e}", case.model));
            }
        }
    }
    let table = markdown(&rows);
    println!("\n{table}");
    std::fs::write("docs/validation.md", page(&table))?;
    println!("wrote docs/validation.md");
    let failed: Vec<String> = rows
        .iter()
        .filter(|r| !r.pass())
        .map(|r| format!("{}: {}", r.model, r.quantity))
        .collect();
    if !failed.is_empty() || !errors.is_empty() {
        bail!(
            "validation failed: {}",
            [failed, errors].concat().join("; ")
        );
    }
    Ok(())
}

/// `docs/validation.md`: what each reference is, then the table with the
/// machine its CPU times were measured on.
fn page(table: &str) -> String {
    format!(
        "{}\n## The table\n\nWritten by `cargo xtask validate` on {} ({}; CPU times are the wall \
         clock of one run on one thread; about a minute in all, most of it A01).\n\n{table}",
        include_str!("validation_intro.md"),
        crate::bench::machine(),
        today(),
    )
}

/// Today's date (UTC), `YYYY-MM-DD`, from the system clock: the civil date
/// of a day count since 1970-01-01 (H. Hinnant, "chrono-compatible low-level
/// date algorithms", `civil_from_days`).
fn today() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let z = i64::try_from(secs / 86_400).unwrap_or(0) + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!("{year:04}-{month:02}-{day:02}")
}
