//! `mstar animate` as a user meets it: a run drawn as a GIF (counted frame by
//! frame) and as one self-contained HTML page (nothing fetched, the model's
//! names escaped, every frame inside), a failed run's partial file, and the
//! errors with their exit codes (1: results and model do not fit, or a file
//! cannot be written; 2: the model cannot be read or the command line is
//! wrong).

mod common;

use std::path::Path;

use common::{model, mstar, scratch, text};

fn path(p: &Path) -> String {
    p.display().to_string()
}

/// Runs `model` to `t_end` into `dir/<out>`, every step written.
fn run(model: &str, t_end: &str, out: &Path) {
    let ok = mstar(&["run", model, "--t-end", t_end, "--out", &path(out)]);
    assert!(ok.status.success(), "{}", text(&ok.stderr));
}

/// The frames of a GIF file, decoded.
fn gif_frames(file: &Path) -> usize {
    let data = std::fs::File::open(file).expect("the GIF");
    let mut decoder = gif::DecodeOptions::new()
        .read_info(data)
        .expect("a GIF header");
    let mut n = 0;
    while decoder.read_next_frame().expect("a valid frame").is_some() {
        n += 1;
    }
    n
}

/// The frames of a GIF file and their total delay, 1/100 s.
fn gif_frames_and_delay(file: &Path) -> (usize, u32) {
    let data = std::fs::File::open(file).expect("the GIF");
    let mut decoder = gif::DecodeOptions::new()
        .read_info(data)
        .expect("a GIF header");
    let (mut n, mut delay) = (0, 0);
    while let Some(frame) = decoder.read_next_frame().expect("a valid frame") {
        n += 1;
        delay += u32::from(frame.delay);
    }
    (n, delay)
}

/// The number of entries of the page's time list.
fn html_frames(html: &str) -> usize {
    let times = html
        .split("\"t\":[")
        .nth(1)
        .and_then(|s| s.split(']').next())
        .expect("a time list");
    times
        .split(',')
        .filter(|s| s.parse::<f64>().is_ok())
        .count()
}

#[test]
fn a_run_becomes_a_gif_and_a_page() {
    let dir = scratch("animate-both");
    let csv = dir.join("four-bar.csv");
    run(&model("four-bar.toml"), "0.2", &csv);
    let (gif, html) = (dir.join("four-bar.gif"), dir.join("four-bar.html"));
    let ok = mstar(&[
        "animate",
        &model("four-bar.toml"),
        &path(&csv),
        "--gif",
        &path(&gif),
        "--html",
        &path(&html),
        "--fps",
        "10",
        "--speed",
        "1",
        "--size",
        "160x120",
    ]);
    assert!(ok.status.success(), "{}", text(&ok.stderr));
    let out = text(&ok.stdout);
    assert!(out.contains("(3 frames, 160×120)"), "{out}");
    assert!(out.contains("(201 frames,"), "{out}");
    let bytes = std::fs::read(&gif).expect("the GIF");
    assert!(bytes.starts_with(b"GIF89a"));
    // 10 fps in real time over 0.2 s: t = 0, 0.1, 0.2.
    assert_eq!(gif_frames(&gif), 3);
    let page = std::fs::read_to_string(&html).expect("the page");
    for external in ["http://", "https://", "src=", "href=", "@import", "url("] {
        assert!(!page.contains(external), "{external} in the page");
    }
    assert!(page.contains("<button id=\"play\""), "a play button");
    assert!(page.contains("type=\"range\""), "a slider");
    assert!(page.contains("max=\"200\""), "the slider spans the frames");
    assert_eq!(page.matches("<svg").count(), 1);
    assert_eq!(html_frames(&page), 201);
    // Every body's name, in the legend and as a tooltip.
    for body in ["crank", "coupler", "rocker"] {
        assert!(page.contains(&format!("<title>{body}</title>")), "{body}");
    }
    // Nothing left beside the outputs.
    let left: Vec<String> = std::fs::read_dir(&dir)
        .expect("dir")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains("tmp"))
        .collect();
    assert!(left.is_empty(), "{left:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn names_from_the_model_cannot_break_the_page() {
    let dir = scratch("animate-names");
    let name = r#"</script><b>"x",y"#;
    let toml = format!(
        "format = \"mstar.planar/1\"\n\
         [[body]]\nname = '{name}'\nmass = 1.0\ninertia = 0.1\npose = [0.5, 0.0, 0.0]\n\
         [[joint]]\nname = '<i>hinge</i>'\ntype = \"revolute\"\nbodies = [\"ground\", '{name}']\nat = [0.0, 0.0]\n"
    );
    let file = dir.join("odd.toml");
    std::fs::write(&file, toml).expect("write");
    let csv = dir.join("odd.csv");
    run(&path(&file), "0.1", &csv);
    let html = dir.join("odd.html");
    let ok = mstar(&["animate", &path(&file), &path(&csv), "--html", &path(&html)]);
    assert!(ok.status.success(), "{}", text(&ok.stderr));
    let page = std::fs::read_to_string(&html).expect("the page");
    assert!(
        !page.contains("<b>") && !page.contains("<i>"),
        "markup injected"
    );
    assert!(
        page.contains("&lt;/script&gt;&lt;b&gt;&quot;x&quot;,y"),
        "the name, escaped"
    );
    // Only the page's own two scripts (the data and the player) open and close.
    assert_eq!(page.matches("<script").count(), 2);
    assert_eq!(page.matches("</script>").count(), 2);
    assert_eq!(html_frames(&page), 101);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_failed_run_s_partial_file_animates() {
    let dir = scratch("animate-partial");
    let out = dir.join("fast.csv");
    let failed = mstar(&[
        "run",
        &model("slider-crank.toml"),
        "--h",
        "0.05",
        "--set",
        "simulation.h_min=0.05",
        "--set",
        "simulation.max_iterations=2",
        "--out",
        &path(&out),
    ]);
    assert_eq!(failed.status.code(), Some(1));
    let partial = dir.join("fast.partial.csv");
    assert!(partial.exists());
    let png = dir.join("frame.png");
    let ok = mstar(&[
        "animate",
        &model("slider-crank.toml"),
        &path(&partial),
        "--png",
        &path(&png),
        "--size",
        "160x120",
    ]);
    assert!(ok.status.success(), "{}", text(&ok.stderr));
    let bytes = std::fs::read(&png).expect("the picture");
    assert!(bytes.starts_with(b"\x89PNG\r\n\x1a\n"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn errors_say_what_and_where() {
    let dir = scratch("animate-errors");
    let csv = dir.join("four-bar.csv");
    run(&model("four-bar.toml"), "0.05", &csv);
    let html = dir.join("out.html");
    // Results of another model: the slider-crank's rod has no columns here.
    let other = mstar(&[
        "animate",
        &model("slider-crank.toml"),
        &path(&csv),
        "--html",
        &path(&html),
    ]);
    assert_eq!(other.status.code(), Some(1));
    let e = text(&other.stderr);
    assert!(
        e.contains(
            "four-bar.csv: no column 'u:rod.x' — was it written by 'mstar run' for this model?"
        ),
        "{e}"
    );
    assert!(!html.exists());
    // A field that is not a number: its line and column.
    let text_csv = std::fs::read_to_string(&csv).expect("the CSV");
    let mut lines: Vec<String> = text_csv.lines().map(String::from).collect();
    let mut fields: Vec<&str> = lines[3].split(',').collect();
    fields[1] = "oops";
    lines[3] = fields.join(",");
    let broken = dir.join("broken.csv");
    std::fs::write(&broken, lines.join("\n")).expect("write");
    let bad = mstar(&[
        "animate",
        &model("four-bar.toml"),
        &path(&broken),
        "--html",
        &path(&html),
    ]);
    assert_eq!(bad.status.code(), Some(1));
    let e = text(&bad.stderr);
    assert!(
        e.contains("broken.csv:4:2: column 'u:crank.x': 'oops' is not a finite number"),
        "{e}"
    );
    // A model file with an error: exit 2, FILE:LINE:COLUMN.
    let model_file = dir.join("bad.toml");
    std::fs::write(&model_file, "format = \"mstar.planar/1\"\n\n[[body]]\nname = \"b\"\nmass = 1.0\ninertia = -1.0\npose = [0.0, 0.0, 0.0]\n").expect("write");
    let unreadable = mstar(&[
        "animate",
        &path(&model_file),
        &path(&csv),
        "--html",
        &path(&html),
    ]);
    assert_eq!(unreadable.status.code(), Some(2));
    let e = text(&unreadable.stderr);
    assert!(
        e.contains("bad.toml:6:11: body 'b': inertia: must be positive"),
        "{e}"
    );
    // No output asked for: a usage error naming the options.
    let nothing = mstar(&["animate", &model("four-bar.toml"), &path(&csv)]);
    assert_eq!(nothing.status.code(), Some(2));
    let e = text(&nothing.stderr);
    assert!(
        e.contains("required") && e.contains("--gif") && e.contains("--html"),
        "{e}"
    );
    // An output that cannot be written (a directory is in the way): exit 1,
    // and no temporary file left beside it.
    let in_the_way = dir.join("taken.gif");
    std::fs::create_dir_all(&in_the_way).expect("a directory");
    let blocked = mstar(&[
        "animate",
        &model("four-bar.toml"),
        &path(&csv),
        "--gif",
        &path(&in_the_way),
        "--size",
        "32x32",
    ]);
    assert_eq!(blocked.status.code(), Some(1));
    assert!(
        text(&blocked.stderr).contains("could not write"),
        "{}",
        text(&blocked.stderr)
    );
    let left = std::fs::read_dir(&dir)
        .expect("dir")
        .filter(|e| {
            e.as_ref()
                .is_ok_and(|e| e.file_name().to_string_lossy().contains("tmp"))
        })
        .count();
    assert_eq!(left, 0);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Two equal point masses (1 kg) on two 1 m distance joints, hanging:
/// the modes' angular frequencies are `ω² = (g/l)(2 ∓ √2)`, the roots of
/// `det(K − ω² M) = 0` for the small angles `(θ₁, θ₂)` with `M = m l² [[2,
/// 1], [1, 1]]` and `K = m g l [[2, 0], [0, 1]]`.
const DOUBLE_PENDULUM: &str = r#"format = "mstar.planar/1"
gravity = [0.0, -9.81]

[[point_mass]]
name = "p1"
mass = 1.0
position = [0.0, -1.0]

[[point_mass]]
name = "p2"
mass = 1.0
position = [0.0, -2.0]

[[joint]]
name = "rod1"
type = "distance"
bodies = ["ground", "p1"]
points = [[0.0, 0.0], [0.0, 0.0]]
length = 1.0

[[joint]]
name = "rod2"
type = "distance"
bodies = ["p1", "p2"]
points = [[0.0, 0.0], [0.0, 0.0]]
length = 1.0
"#;

/// `--mode K` draws two periods of mode K: the page's last time is
/// `2 · 2π/ω_K` (ω_K from the closed form, to the eigensolver's round-off),
/// the GIF has a frame per 1/30 s of the (slowed, ≥ 1 s) motion; a mode
/// past the degrees of freedom is exit 1 naming them; a results file and
/// `--mode` together are exit 2.
#[test]
fn a_vibration_mode_is_drawn_moving() {
    let dir = scratch("animate-mode");
    let file = dir.join("double.toml");
    std::fs::write(&file, DOUBLE_PENDULUM).expect("written");
    for (k, sign) in [(1, -1.0), (2, 1.0)] {
        let page = dir.join(format!("mode{k}.html"));
        let gif = dir.join(format!("mode{k}.gif"));
        let o = mstar(&[
            "animate",
            &path(&file),
            "--mode",
            &k.to_string(),
            "--html",
            &path(&page),
            "--gif",
            &path(&gif),
        ]);
        assert!(o.status.success(), "{}", text(&o.stderr));
        let html = std::fs::read_to_string(&page).expect("the page");
        let times: Vec<f64> = html
            .split("\"t\":[")
            .nth(1)
            .and_then(|s| s.split(']').next())
            .expect("a time list")
            .split(',')
            .map(|s| s.parse().expect("a time"))
            .collect();
        let omega = (9.81_f64 * (2.0 + sign * 2.0_f64.sqrt())).sqrt();
        let want = 2.0 * std::f64::consts::TAU / omega;
        let last = times.last().copied().unwrap_or(f64::NAN);
        assert!(
            (last - want).abs() <= 1e-9 * want,
            "mode {k}: {last} vs {want}"
        );
        assert_eq!(times.len(), 97, "48 frames a period and the last");
        assert!(gif_frames(&gif) > 1);
    }
    let o = mstar(&[
        "animate",
        &path(&file),
        "--mode",
        "3",
        "--gif",
        &path(&dir.join("m3.gif")),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        text(&o.stderr).contains("give --mode 1 to 2"),
        "{}",
        text(&o.stderr)
    );
    assert!(!dir.join("m3.gif").exists());
    let o = mstar(&[
        "animate",
        &path(&file),
        "r.csv",
        "--mode",
        "1",
        "--gif",
        "x.gif",
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o.stderr));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A mode's GIF shows its two periods once per loop, as docs/model-format.md
/// says: at `--fps 10 --duration 3` 30 frames of 1/10 s (3 s, the first
/// state not repeated at the end); by default in real time, round(2T /
/// 0.03 s) frames of 3/100 s. A `--mode` that is not a mode number (0, -1,
/// 2.5, a word) says which numbers are (exit 2); one past the degrees of
/// freedom names them (exit 1); a model without degrees of freedom says so,
/// and its advice, a run drawn instead, works.
#[test]
fn a_mode_gif_loops_over_two_periods_and_bad_modes_say_what_is_valid() {
    let dir = scratch("animate-mode-gif");
    let file = dir.join("double.toml");
    std::fs::write(&file, DOUBLE_PENDULUM).expect("written");
    let gif = dir.join("mode1.gif");
    let model_file = path(&file);
    let draw = |extra: &[&str]| {
        let mut args = vec!["animate", model_file.as_str(), "--mode", "1"];
        args.extend_from_slice(extra);
        mstar(&args)
    };
    let o = draw(&["--gif", &path(&gif), "--fps", "10", "--duration", "3"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert_eq!(gif_frames_and_delay(&gif), (30, 300));
    let o = draw(&["--gif", &path(&gif)]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let omega = (9.81_f64 * (2.0 - 2.0_f64.sqrt())).sqrt();
    let two_periods = 2.0 * std::f64::consts::TAU / omega;
    let count = (two_periods / 0.03).round() as usize;
    assert_eq!(gif_frames_and_delay(&gif), (count, 3 * count as u32));
    for bad in ["0", "-1", "2.5", "first"] {
        let o = mstar(&["animate", &path(&file), "--mode", bad, "--gif", &path(&gif)]);
        let e = text(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{bad}: {e}");
        assert!(
            e.contains(&format!(
                "'{bad}' is not a mode number: give a whole number from 1"
            )),
            "{bad}: {e}"
        );
    }
    let four_bar = model("four-bar.toml");
    let o = mstar(&["animate", &four_bar, "--mode", "1", "--gif", &path(&gif)]);
    let e = text(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(e.contains("the model has no degrees of freedom"), "{e}");
    assert!(e.contains("draw a run instead"), "{e}");
    let csv = dir.join("four-bar.csv");
    run(&four_bar, "0.1", &csv);
    let o = mstar(&["animate", &four_bar, &path(&csv), "--gif", &path(&gif)]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A results file saved with `\r\n` line ends animates, and an error in it
/// is reported at the line an editor shows, as for the same file with `\n`
/// (a blank line counted too).
#[test]
fn errors_in_a_crlf_results_file_name_the_right_line() {
    let dir = scratch("animate-crlf");
    let double = model("double-pendulum.toml");
    let csv = dir.join("run.csv");
    run(&double, "0.01", &csv);
    let lf = std::fs::read_to_string(&csv).expect("the CSV");
    let mut lines: Vec<String> = lf.lines().map(String::from).collect();
    let crlf = dir.join("crlf.csv");
    std::fs::write(&crlf, lines.join("\r\n") + "\r\n").expect("written");
    let png = dir.join("frame.png");
    let o = mstar(&["animate", &double, &path(&crlf), "--png", &path(&png)]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    // Line 7 holds a word where u:upper.x (the second column) was, after a
    // blank line 4.
    let fields: Vec<&str> = lines[5].splitn(3, ',').collect();
    lines[5] = format!("{},abc,{}", fields[0], fields[2]);
    lines.insert(3, String::new());
    for (name, ending) in [("lf.csv", "\n"), ("crlf.csv", "\r\n")] {
        let file = dir.join(name);
        std::fs::write(&file, lines.join(ending) + ending).expect("written");
        let o = mstar(&["animate", &double, &path(&file), "--png", &path(&png)]);
        let e = text(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{name}: {e}");
        assert!(
            e.contains(&format!(
                "{name}:7:2: column 'u:upper.x': 'abc' is not a finite number"
            )),
            "{name}: {e}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
