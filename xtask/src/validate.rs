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

/// Today's date (UTC), `YYYY-MM-DD`, from the system clock.
fn today() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let (year, month, day) = civil_date(i64::try_from(secs / 86_400).unwrap_or(0));
    format!("{year:04}-{month:02}-{day:02}")
}

/// The (year, month, day) of the Gregorian calendar `days` after
/// 1970-01-01: H. Hinnant's `civil_from_days` ("chrono-compatible low-level
/// date algorithms"), counting from 0000-03-01 in 400-year eras.
fn civil_date(days: i64) -> (i64, i64, i64) {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    (yoe + era * 400 + i64::from(month <= 2), month, day)
}

#[cfg(test)]
mod tests {
    use super::civil_date;

    #[test]
    fn civil_dates_of_day_counts() {
        // Counted by hand: 30 years of 365 days and 7 leap days to 2000,
        // then January and 28 days of February; 54 years and 13 leap days
        // to 2024.
        assert_eq!(civil_date(0), (1970, 1, 1));
        assert_eq!(civil_date(10_957 + 31 + 28), (2000, 2, 29));
        assert_eq!(civil_date(10_957 + 31 + 29), (2000, 3, 1));
        assert_eq!(civil_date(19_723), (2024, 1, 1));
        assert_eq!(civil_date(-1), (1969, 12, 31));
    }
}
