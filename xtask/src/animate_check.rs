//! `cargo xtask animate-check`: `mstar animate`'s HTML page in a real
//! browser. Runs the four-bar for 1 s, writes the page and a GIF, opens the
//! page in headless Chromium (Debian's `chromium`) for a screenshot and for
//! the DOM after the script has played a little, and checks that the script
//! ran: the time label and the moving shapes changed. Also draws one frame
//! of the slider-crank as a PNG for the README. Writes to
//! target/studies/animate/ and docs/figures/.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use anyhow::{Context as _, Result, bail};

/// The browser's window, px.
const WINDOW: &str = "800,600";
/// Virtual time the page may run before the screenshot or the DOM dump, ms.
const BUDGET_MS: &str = "1500";

/// Runs the check.
///
/// # Errors
/// If the program cannot be built or run, Chromium is missing or fails, or
/// the page's script did not run.
pub fn run() -> Result<()> {
    let dir = crate::study_dir("animate")?;
    let mstar = build_mstar()?;
    let csv = dir.join("four-bar.csv");
    let (html, gif) = (dir.join("four-bar.html"), dir.join("four-bar.gif"));
    let model = "models/four-bar.toml";
    program(
        &mstar,
        &["run", model, "--t-end", "1", "--out", &show(&csv)],
    )?;
    let wrote = program(
        &mstar,
        &[
            "animate",
            model,
            &show(&csv),
            "--html",
            &show(&html),
            "--gif",
            &show(&gif),
        ],
    )?;
    print!("{}", String::from_utf8_lossy(&wrote.stdout));
    let url = format!(
        "file://{}",
        std::fs::canonicalize(&html)
            .with_context(|| format!("could not find {}", html.display()))?
            .display()
    );
    let screenshot = dir.join("four-bar.png");
    chromium(&[
        &format!("--screenshot={}", show(&screenshot)),
        &format!("--window-size={WINDOW}"),
        &format!("--virtual-time-budget={BUDGET_MS}"),
        &url,
    ])?;
    let figures = Path::new("docs").join("figures");
    std::fs::create_dir_all(&figures)
        .with_context(|| format!("could not create {}", figures.display()))?;
    copy(&screenshot, &figures.join("animate-four-bar.png"))?;
    let dom = chromium(&[
        &format!("--virtual-time-budget={BUDGET_MS}"),
        "--dump-dom",
        &url,
    ])?;
    let dom = String::from_utf8_lossy(&dom.stdout).into_owned();
    std::fs::write(dir.join("four-bar.dom.html"), &dom).context("could not save the DOM")?;
    let page = std::fs::read_to_string(&html).context("could not read the page")?;
    check_played(&page, &dom)?;
    slider_crank_frame(&mstar, &dir, &figures)?;
    for f in [&html, &gif] {
        let bytes = std::fs::metadata(f).map(|m| m.len()).unwrap_or(0);
        println!("{}: {:.0} kB", f.display(), bytes as f64 / 1000.0);
    }
    println!(
        "screenshot: {} (and docs/figures/animate-four-bar.png)",
        screenshot.display()
    );
    Ok(())
}

/// The page's script ran: the time label left its first value and the first
/// moving shape moved.
fn check_played(page: &str, dom: &str) -> Result<()> {
    let before = time_label(page).context("the page has no time label")?;
    let after = time_label(dom).context("the browser's DOM has no time label")?;
    println!("time label: '{before}' in the file, '{after}' after the script ran");
    if before == after {
        bail!("the time label stayed at '{before}': the page's script did not play");
    }
    let (moved_from, moved_to) = (first_moving(page), first_moving(dom));
    if moved_from.is_none() || moved_from == moved_to {
        bail!("the first moving shape did not move: {moved_from:?}");
    }
    Ok(())
}

/// The text of `<text id="time" …>…</text>`.
fn time_label(html: &str) -> Option<&str> {
    let start = html.find("id=\"time\"")?;
    let text = &html[start..];
    let open = text.find('>')? + 1;
    let close = text[open..].find('<')?;
    Some(&text[open..open + close])
}

/// The start tag of the first element the script moves (`data-d`).
fn first_moving(html: &str) -> Option<&str> {
    let mark = html.find("data-d")?;
    let open = html[..mark].rfind('<')?;
    let close = mark + html[mark..].find('>')?;
    Some(&html[open..=close])
}

/// One frame of the slider-crank (t = 0.1 s) as docs/figures/animate-slider-crank.png.
fn slider_crank_frame(mstar: &Path, dir: &Path, figures: &Path) -> Result<()> {
    let csv = dir.join("slider-crank.csv");
    let model = "models/slider-crank.toml";
    program(mstar, &["run", model, "--out", &show(&csv)])?;
    let png = figures.join("animate-slider-crank.png");
    program(
        mstar,
        &[
            "animate",
            model,
            &show(&csv),
            "--png",
            &show(&png),
            "--at",
            "0.1",
        ],
    )?;
    println!("frame: {}", png.display());
    Ok(())
}

fn show(p: &Path) -> String {
    p.display().to_string()
}

fn copy(from: &Path, to: &Path) -> Result<()> {
    std::fs::copy(from, to)
        .with_context(|| format!("could not copy {} to {}", from.display(), to.display()))?;
    Ok(())
}

/// Builds the `mstar` program (the dev profile, as `cargo xtask` itself)
/// and returns its path.
fn build_mstar() -> Result<PathBuf> {
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let status = Command::new(cargo)
        .args(["build", "--quiet", "-p", "mstar-cli", "--bin", "mstar"])
        .status()
        .context("could not run cargo")?;
    if !status.success() {
        bail!("cargo build -p mstar-cli failed");
    }
    let target =
        std::env::var_os("CARGO_TARGET_DIR").map_or_else(|| PathBuf::from("target"), PathBuf::from);
    Ok(target
        .join("debug")
        .join(format!("mstar{}", std::env::consts::EXE_SUFFIX)))
}

/// Runs `mstar` with `args`; its output on success, its error output in the
/// error otherwise.
fn program(mstar: &Path, args: &[&str]) -> Result<Output> {
    let out = Command::new(mstar)
        .args(args)
        .output()
        .with_context(|| format!("could not run {}", mstar.display()))?;
    if !out.status.success() {
        bail!(
            "mstar {} failed:\n{}",
            args.join(" "),
            String::from_utf8_lossy(&out.stderr)
        );
    }
    Ok(out)
}

/// Runs headless Chromium with `args`.
fn chromium(args: &[&str]) -> Result<Output> {
    let out = Command::new("chromium")
        .args([
            "--headless",
            "--disable-gpu",
            "--no-sandbox",
            "--hide-scrollbars",
        ])
        .args(args)
        .output();
    let out = match out {
        Ok(out) => out,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => bail!(
            "chromium is not installed: install Debian's package with `apt-get install -y chromium`"
        ),
        Err(e) => return Err(e).context("could not run chromium"),
    };
    if !out.status.success() {
        bail!(
            "chromium {} failed:\n{}",
            args.join(" "),
            String::from_utf8_lossy(&out.stderr)
        );
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_the_label_and_the_moving_shape() {
        let html = "<svg><polyline points=\"1,2\" data-d=\"\"/><text id=\"time\" x=\"1\">t = 0.000 s</text>";
        assert_eq!(time_label(html), Some("t = 0.000 s"));
        assert_eq!(
            first_moving(html),
            Some("<polyline points=\"1,2\" data-d=\"\"/>")
        );
        let played = html.replace("1,2", "3,4").replace("0.000", "0.500");
        assert!(check_played(html, &played).is_ok());
        assert!(check_played(html, html).is_err());
    }
}
