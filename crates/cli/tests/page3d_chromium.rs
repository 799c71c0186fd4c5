//! The 3-D page of a spatial run (`mstar animate SPATIAL.toml RUN.csv
//! --html`): its text is self-contained, and in headless Chromium its
//! pixels show the top, turn with a mouse drag and change as the top spins.
//!
//! Chromium: the first of `chromium`, `chromium-browser`, `google-chrome`
//! on `PATH`. Without one the browser test prints "not run: chromium not
//! found" and passes, unless `MSTAR_REQUIRE_CHROMIUM` is set (`.ci/run` sets
//! it when it could install Chromium): then a missing browser fails it.
//! About 4 s with Chromium on 2 cores (four screenshots of about 1 s each).

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use common::{model, mstar, scratch, text};

fn path(p: &Path) -> String {
    p.display().to_string()
}

/// The top's colour on the page: the first body's, Tableau 10 blue.
const TOP: [u8; 3] = [0x1f, 0x77, 0xb4];

/// Runs the top for 0.2 s and writes its 3-D page; the page's path and text.
fn top_page(dir: &Path) -> (PathBuf, String) {
    let file = model("spatial/top.toml");
    let csv = dir.join("top.csv");
    let ran = mstar(&["run", &file, "--t-end", "0.2", "--out", &path(&csv)]);
    assert!(ran.status.success(), "{}", text(&ran.stderr));
    let html = dir.join("top.html");
    let wrote = mstar(&["animate", &file, &path(&csv), "--html", &path(&html)]);
    assert!(wrote.status.success(), "{}", text(&wrote.stderr));
    let page = std::fs::read_to_string(&html).expect("the page");
    (html, page)
}

/// The page needs nothing from elsewhere, carries no model text unescaped,
/// and draws on a canvas with its script inline.
#[test]
fn the_3d_page_is_self_contained_and_escapes_names() {
    let dir = scratch("page3d-text");
    let (_, page) = top_page(&dir);
    for outside in ["http://", "https://", "src=", "href=", "@import", "url("] {
        assert!(!page.contains(outside), "the page refers to {outside}");
    }
    assert!(page.contains("<canvas id=\"view\""), "no canvas");
    assert!(
        page.contains("function rotation(q)"),
        "the renderer is not inline"
    );
    assert!(page.contains("\"v\":[30,20]"), "the oblique view's camera");
    // A body named like markup: escaped in the legend and the fallback
    // drawing, absent from the frames' JSON.
    let model_text = std::fs::read_to_string(model("spatial/top.toml"))
        .expect("top.toml")
        .replace("\"top\"", r#""</script><b>&'\"""#);
    let odd = dir.join("odd.toml");
    std::fs::write(&odd, model_text).expect("write");
    let csv = dir.join("odd.csv");
    let ran = mstar(&["run", &path(&odd), "--t-end", "0.01", "--out", &path(&csv)]);
    assert!(ran.status.success(), "{}", text(&ran.stderr));
    let html = dir.join("odd.html");
    let ok = mstar(&["animate", &path(&odd), &path(&csv), "--html", &path(&html)]);
    assert!(ok.status.success(), "{}", text(&ok.stderr));
    let page = std::fs::read_to_string(&html).expect("the page");
    assert!(!page.contains("</script><b>"), "an unescaped name");
    assert!(
        page.contains("&lt;/script&gt;&lt;b&gt;&amp;&#39;&quot;"),
        "the escaped name"
    );
    assert_eq!(
        page.matches("</script>").count(),
        2,
        "one data block, one script"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// The first Chromium on `PATH`.
fn chromium() -> Option<PathBuf> {
    let dirs = std::env::var_os("PATH")?;
    ["chromium", "chromium-browser", "google-chrome"]
        .iter()
        .flat_map(|name| std::env::split_paths(&dirs).map(move |d| d.join(name)))
        .find(|p| p.is_file())
}

/// An RGB picture.
struct Picture {
    width: usize,
    rgb: Vec<[u8; 3]>,
}

fn decode(file: &Path) -> Picture {
    let bytes = std::fs::read(file).expect("the screenshot");
    let mut decoder = png::Decoder::new(bytes.as_slice());
    decoder.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
    let mut reader = decoder.read_info().expect("a PNG");
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).expect("a frame");
    let channels = info.color_type.samples();
    assert!(channels >= 3, "a colour picture: {:?}", info.color_type);
    let rgb = buf[..info.buffer_size()]
        .chunks_exact(channels)
        .map(|c| [c[0], c[1], c[2]])
        .collect();
    Picture {
        width: info.width as usize,
        rgb,
    }
}

/// Whether `c` is the top's colour shaded by some brightness in [0.3, 1]
/// (the page's Lambert range), to the rounding of 8-bit channels and the
/// anti-aliasing of a channel's last bit or two.
fn is_top(c: [u8; 3]) -> bool {
    let f = f64::from(c[2]) / f64::from(TOP[2]);
    (0.28..=1.02).contains(&f)
        && (0..2).all(|k| (f64::from(c[k]) - f * f64::from(TOP[k])).abs() <= 3.0)
}

/// Pixels that show the top in either picture and differ between them.
fn top_changes(a: &Picture, b: &Picture) -> usize {
    a.rgb
        .iter()
        .zip(&b.rgb)
        .filter(|(p, q)| p != q && (is_top(**p) || is_top(**q)))
        .count()
}

/// Screenshot of `page` with `hash` (`t=…`, `drag=dx,dy`) in an 800×600
/// window, at most 60 s.
fn shot(browser: &Path, page: &Path, hash: &str, out: &Path, profile: &Path) -> Picture {
    let url = format!(
        "file://{}#{hash}",
        std::fs::canonicalize(page).expect("the page").display()
    );
    let mut child = Command::new(browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--hide-scrollbars",
            "--window-size=800,600",
            "--virtual-time-budget=1000",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .arg(format!("--screenshot={}", out.display()))
        .arg(&url)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("chromium starts");
    let start = Instant::now();
    loop {
        if let Some(status) = child.try_wait().expect("chromium runs") {
            assert!(status.success(), "chromium failed on {url}: {status}");
            break;
        }
        if start.elapsed() > Duration::from_secs(60) {
            let _ = child.kill();
            panic!("chromium took more than 60 s on {url}");
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    decode(out)
}

/// The top's page in Chromium: the box is drawn in the top's colour over at
/// least half the area its smallest face could cover; the same view twice
/// is the same picture (the control: the renderer is deterministic, so any
/// difference below comes from the view or the time); a drag turns it; a
/// later time turns the top.
#[test]
fn the_top_page_shows_turns_with_a_drag_and_spins_in_chromium() {
    let Some(browser) = chromium() else {
        assert!(
            std::env::var_os("MSTAR_REQUIRE_CHROMIUM").is_none(),
            "MSTAR_REQUIRE_CHROMIUM is set and no chromium, chromium-browser or google-chrome is on PATH"
        );
        eprintln!(
            "\n*** not run: chromium not found (page3d_chromium.rs; set MSTAR_REQUIRE_CHROMIUM=1 to fail instead) ***\n"
        );
        return;
    };
    let dir = scratch("page3d-chromium");
    let (html, page) = top_page(&dir);
    let profile = dir.join("profile");
    let take = |hash: &str, name: &str| shot(&browser, &html, hash, &dir.join(name), &profile);
    let first = take("t=0.1", "first.png");
    let again = take("t=0.1", "again.png");
    let turned = take("t=0.1&drag=150,60", "turned.png");
    let later = take("t=0.13", "later.png");
    assert_eq!(first.width, 800);
    // The top's box (top.toml: 2 kg, inertia 0.05, 0.05, 0.08 kg m²):
    // a² = 6 (I₂ + I₃ − I₁)/m = 0.24 m², c² = 6 (2 I₁ − I₃)/m = 0.06 m²;
    // sides 0.49, 0.49, 0.245 m. A box seen from any direction covers at
    // least its smallest face's area, 0.12 m², at the page's scale
    // (0.42 min(640, 480)/r px per m at the centre, times 4r/(4r + r) at
    // the far side of the ball of radius r around the run).
    let r: f64 = page
        .split("\"r\":")
        .nth(1)
        .and_then(|s| s.split(',').next())
        .and_then(|s| s.parse().ok())
        .expect("the page's radius");
    let k = 0.42 * 480.0 / r * 0.8;
    let least = 0.49 * 0.245 * k * k;
    let body = first.rgb.iter().filter(|c| is_top(**c)).count();
    assert!(
        body as f64 >= 0.5 * least,
        "{body} pixels in the top's colour, fewer than half of {least:.0}"
    );
    assert_eq!(
        top_changes(&first, &again),
        0,
        "the same view twice differs"
    );
    // A quarter turn of a square face about its centre leaves outside the
    // other at least (1 − 0.83) of it at 45° (the overlap is a regular
    // octagon, 2(√2 − 1) = 0.83 of the square); at 0.9 rad of spin (30 rad/s
    // over 0.03 s) the side faces also turn to the light: at least a tenth
    // of the top's pixels change. A drag of 150 px turns the view by 1.5 rad.
    for (what, picture) in [("a drag", &turned), ("0.03 s of spin", &later)] {
        let changed = top_changes(&first, picture);
        eprintln!("{what}: {changed} of the top's {body} pixels changed (bound {least:.0} px)");
        assert!(
            changed * 10 >= body,
            "{what} changed {changed} of the top's {body} pixels"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
