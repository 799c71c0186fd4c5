//! `cargo xtask validate`: every model of `models/` against its independent
//! reference at the published spans (`mstar_testkit::validation`, level `Tight`);
//! prints the table and writes it to `docs/validation.md`. Fails when a row
//! does.

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

/// `docs/validation.md`: what each reference is, then the table.
fn page(table: &str) -> String {
    format!(
        "{}\n## The table\n\nWritten by `cargo xtask validate` (release build; a few seconds).\n\n{table}",
        include_str!("validation_intro.md")
    )
}
