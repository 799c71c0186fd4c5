//! The animation as one self-contained HTML page: an inline SVG drawing of
//! the first frame (so the page shows the mechanism even without script),
//! the frames as JSON numbers in the page, and a small script with
//! play/pause, a time slider and a speed choice. Nothing is fetched: no
//! external URL, font or script; names from the model are escaped.

use std::fmt::Write as _;

use super::geometry::Shape;
use super::results::Results;
use super::scene::{INK, Item, Scene, View, body_colour};

/// The most frames a page carries (longer runs are resampled evenly).
pub const MAX_FRAMES: usize = 2000;

/// Text for HTML content and attribute values: `&`, `<`, `>`, `"`, `'`
/// escaped.
#[must_use]
pub fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// The page's legend: one item per body, its colour and its name (escaped).
pub(crate) fn legend<'a>(names: impl Iterator<Item = &'a str>) -> String {
    names
        .enumerate()
        .map(|(i, name)| {
            format!(
                "<li><span class=\"swatch\" style=\"background:{}\"></span>{}</li>",
                body_colour(i).hex(),
                escape(name)
            )
        })
        .collect()
}

/// A pixel coordinate to 0.1 px, in its shortest form.
fn coord(out: &mut String, x: f64) {
    let r = (x * 10.0).round() / 10.0;
    let _ = write!(out, "{}", if r == 0.0 { 0.0 } else { r });
}

/// The page for `frames` (already at most [`MAX_FRAMES`]) of `scene` in
/// `view`; `title` says what it shows.
#[must_use]
pub fn page(scene: &Scene, view: &View, frames: &Results, title: &str) -> String {
    let items: Vec<Vec<Item>> = frames.states.iter().map(|u| scene.items(u, view)).collect();
    let first = items.first().map(Vec::as_slice).unwrap_or_default();
    let moving: Vec<bool> = (0..first.len())
        .map(|i| items.iter().any(|f| rounded(&f[i]) != rounded(&first[i])))
        .collect();
    let mut svg = String::new();
    for (item, &dynamic) in first.iter().zip(&moving) {
        element(&mut svg, item, dynamic, scene);
    }
    let data = data(frames, &items, &moving);
    let legend = legend(scene.sketch().bodies.iter().map(|b| b.name.as_str()));
    let font = (18.0 * view.unit).max(10.0);
    fill(
        TEMPLATE,
        &[
            ("title", &escape(title)),
            ("w", &view.width.to_string()),
            ("h", &view.height.to_string()),
            ("font", &format!("{font:.1}")),
            ("tx", &format!("{:.1}", 10.0 * view.unit)),
            ("ty", &format!("{:.1}", 8.0 * view.unit + font)),
            ("ink", &INK.hex()),
            ("last", &frames.times.len().saturating_sub(1).to_string()),
            (
                "t0",
                &format!("t = {:.3} s", frames.times.first().copied().unwrap_or(0.0)),
            ),
            ("legend", &legend),
            ("svg", &svg),
            ("script", SCRIPT),
            ("data", &data),
        ],
    )
}

/// `template` with each `{key}` of `values` replaced, in one pass: text
/// that was put in is never searched again (a body may be called `{data}`).
pub(crate) fn fill(template: &str, values: &[(&str, &str)]) -> String {
    let mut out = String::with_capacity(template.len());
    let mut rest = template;
    while let Some(open) = rest.find('{') {
        out.push_str(&rest[..open]);
        let after = &rest[open + 1..];
        let hit = values
            .iter()
            .find(|(key, _)| after.starts_with(key) && after[key.len()..].starts_with('}'));
        match hit {
            Some((key, value)) => {
                out.push_str(value);
                rest = &after[key.len() + 1..];
            }
            None => {
                out.push('{');
                rest = after;
            }
        }
    }
    out.push_str(rest);
    out
}

/// An item's points to 0.1 px, for telling moving items from still ones.
fn rounded(item: &Item) -> Vec<[i64; 2]> {
    let r = |x: f64| (x * 10.0).round() as i64;
    item.shape
        .points()
        .iter()
        .map(|p| [r(p[0]), r(p[1])])
        .collect()
}

/// `{"t":[times],"n":[points per moving item],"f":[[x,y,… per frame]]}`:
/// numbers only.
fn data(frames: &Results, items: &[Vec<Item>], moving: &[bool]) -> String {
    let mut out = String::from("{\"t\":[");
    for (k, t) in frames.times.iter().enumerate() {
        let _ = write!(out, "{}{t}", if k > 0 { "," } else { "" });
    }
    out.push_str("],\"n\":[");
    let counts: Vec<String> = items
        .first()
        .map(Vec::as_slice)
        .unwrap_or_default()
        .iter()
        .zip(moving)
        .filter(|(_, m)| **m)
        .map(|(i, _)| i.shape.points().len().to_string())
        .collect();
    out.push_str(&counts.join(","));
    out.push_str("],\"f\":[");
    for (k, frame) in items.iter().enumerate() {
        out.push_str(if k > 0 { ",[" } else { "[" });
        let mut first = true;
        for (item, _) in frame.iter().zip(moving).filter(|(_, m)| **m) {
            for p in item.shape.points() {
                for &x in p {
                    if !first {
                        out.push(',');
                    }
                    first = false;
                    coord(&mut out, x);
                }
            }
        }
        out.push(']');
    }
    out.push_str("]}");
    out
}

/// One item as an SVG element; `dynamic` ones are marked `data-d` for the
/// script, body shapes carry the body's name as a tooltip.
pub(crate) fn element(out: &mut String, item: &Item, dynamic: bool, scene: &Scene) {
    let points = |out: &mut String, p: &[[f64; 2]]| {
        for (k, q) in p.iter().enumerate() {
            if k > 0 {
                out.push(' ');
            }
            coord(out, q[0]);
            out.push(',');
            coord(out, q[1]);
        }
    };
    match &item.shape {
        Shape::Line(p) => {
            out.push_str("<polyline points=\"");
            points(out, p);
            out.push('"');
        }
        Shape::Polygon(p) => {
            out.push_str("<polygon points=\"");
            points(out, p);
            out.push('"');
        }
        Shape::Circle(c, r) => {
            let _ = write!(out, "<circle r=\"{r:.1}\" cx=\"");
            coord(out, c[0]);
            out.push_str("\" cy=\"");
            coord(out, c[1]);
            out.push('"');
        }
        Shape::Square(c, h) => {
            let _ = write!(
                out,
                "<rect width=\"{:.1}\" height=\"{:.1}\" x=\"",
                2.0 * h,
                2.0 * h
            );
            coord(out, c[0] - h);
            out.push_str("\" y=\"");
            coord(out, c[1] - h);
            out.push('"');
        }
    }
    out.push_str(&attributes(item, dynamic));
    let tag = match item.shape {
        Shape::Line(_) => "polyline",
        Shape::Polygon(_) => "polygon",
        Shape::Circle(..) => "circle",
        Shape::Square(..) => "rect",
    };
    match item.body.and_then(|b| scene.sketch().bodies.get(b)) {
        Some(body) => {
            let _ = writeln!(out, "><title>{}</title></{tag}>", escape(&body.name));
        }
        None => out.push_str("/>\n"),
    }
}

/// An item's style as SVG attributes (and `data-d` when it moves).
fn attributes(item: &Item, dynamic: bool) -> String {
    let mut style = String::new();
    match item.style.fill {
        Some((c, a)) if a < 1.0 => {
            let _ = write!(style, " fill=\"{}\" fill-opacity=\"{a}\"", c.hex());
        }
        Some((c, _)) => {
            let _ = write!(style, " fill=\"{}\"", c.hex());
        }
        None => style.push_str(" fill=\"none\""),
    }
    if let Some((c, w)) = item.style.stroke {
        let _ = write!(style, " stroke=\"{}\" stroke-width=\"", c.hex());
        coord(&mut style, w);
        style.push_str("\" stroke-linecap=\"round\" stroke-linejoin=\"round\"");
    }
    if item.style.dashed {
        style.push_str(" stroke-dasharray=\"7 5\"");
    }
    if dynamic {
        style.push_str(" data-d=\"\"");
    }
    style
}

/// The page around the drawing. Placeholders in braces are filled by
/// [`page`]; the data and script come last so no user text follows them.
const TEMPLATE: &str = r##"<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>{title}</title>
<style>
body { font-family: sans-serif; margin: 1em; color: {ink}; }
svg { width: 100%; max-width: {w}px; height: auto; border: 1px solid #ccc; display: block; }
.controls { display: flex; gap: 0.6em; align-items: center; max-width: {w}px; margin-top: 0.4em; }
.controls input[type=range] { flex: 1; }
ul.legend { list-style: none; padding: 0; display: flex; flex-wrap: wrap; gap: 1em; }
.swatch { display: inline-block; width: 0.9em; height: 0.9em; margin-right: 0.3em; vertical-align: -0.1em; }
p.caption { margin: 0 0 0.4em 0; }
</style>
</head>
<body>
<p class="caption">{title}</p>
<svg id="view" viewBox="0 0 {w} {h}" width="{w}" height="{h}" role="img" aria-label="the mechanism moving">
<rect x="0" y="0" width="{w}" height="{h}" fill="#fff"/>
{svg}<text id="time" x="{tx}" y="{ty}" font-size="{font}" fill="{ink}">{t0}</text>
</svg>
<div class="controls">
<button id="play" type="button">Pause</button>
<input id="slider" type="range" min="0" max="{last}" value="0" step="1" aria-label="time">
<label>speed <select id="speed">
<option value="0.1">0.1×</option><option value="0.25">0.25×</option><option value="0.5">0.5×</option>
<option value="1" selected>1×</option><option value="2">2×</option><option value="5">5×</option>
</select></label>
</div>
<ul class="legend">{legend}</ul>
<script type="application/json" id="frames">{data}</script>
<script>{script}</script>
</body>
</html>
"##;

/// Plays the frames by simulated time (at the chosen speed, looping), or
/// shows the frame the slider picks.
const SCRIPT: &str = r#"
(function () {
  'use strict';
  const D = JSON.parse(document.getElementById('frames').textContent);
  const T = D.t, N = T.length, span = T[N - 1] - T[0];
  const els = document.querySelectorAll('#view [data-d]');
  const label = document.getElementById('time');
  const slider = document.getElementById('slider');
  const button = document.getElementById('play');
  const speed = document.getElementById('speed');
  let k = 0, simT = T[0], last = null, playing = N > 1 && span > 0;
  function show(i) {
    k = i;
    const f = D.f[i];
    let j = 0;
    els.forEach(function (el, m) {
      const n = D.n[m];
      if (el.tagName === 'circle') {
        el.setAttribute('cx', f[j]);
        el.setAttribute('cy', f[j + 1]);
      } else if (el.tagName === 'rect') {
        const h = Number(el.getAttribute('width')) / 2;
        el.setAttribute('x', (f[j] - h).toFixed(1));
        el.setAttribute('y', (f[j + 1] - h).toFixed(1));
      } else {
        const p = [];
        for (let q = 0; q < n; q++) p.push(f[j + 2 * q] + ',' + f[j + 2 * q + 1]);
        el.setAttribute('points', p.join(' '));
      }
      j += 2 * n;
    });
    label.textContent = 't = ' + T[i].toFixed(3) + ' s';
    slider.value = String(i);
  }
  function frameAt(t) {
    let lo = 0, hi = N - 1;
    while (lo < hi) {
      const mid = (lo + hi + 1) >> 1;
      if (T[mid] <= t) lo = mid; else hi = mid - 1;
    }
    return lo;
  }
  function setPlaying(on) {
    playing = on && N > 1 && span > 0;
    last = null;
    button.textContent = playing ? 'Pause' : 'Play';
  }
  function tick(now) {
    if (playing) {
      if (last !== null) {
        simT += (now - last) / 1000 * Number(speed.value);
        if (simT > T[N - 1]) simT = T[0] + (simT - T[0]) % span;
        const i = frameAt(simT);
        if (i !== k) show(i);
      }
      last = now;
    }
    requestAnimationFrame(tick);
  }
  button.addEventListener('click', function () { setPlaying(!playing); });
  slider.addEventListener('input', function () {
    const i = Number(slider.value);
    simT = T[i];
    show(i);
  });
  setPlaying(playing);
  requestAnimationFrame(tick);
})();
"#;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn placeholders_are_filled_once() {
        let filled = fill("a {x} {y} {z}", &[("x", "{y}"), ("y", "2")]);
        assert_eq!(filled, "a {y} 2 {z}");
    }

    #[test]
    fn escapes_markup() {
        assert_eq!(
            escape("</script><b>\"x\" & 'y'"),
            "&lt;/script&gt;&lt;b&gt;&quot;x&quot; &amp; &#39;y&#39;"
        );
    }

    #[test]
    fn the_page_carries_every_frame_and_only_moving_items_in_them() {
        let sys = crate::animate::hinged_bar("<bar>");
        let u0 = sys.initial_position();
        // The bar swung down by a quarter turn about the hinge.
        let u1 = vec![0.0, -0.5, -std::f64::consts::FRAC_PI_2];
        let frames = Results {
            times: vec![0.0, 0.5, 1.0],
            states: vec![u0.clone(), u1.clone(), u1],
        };
        let scene = Scene::new(
            Box::new(crate::animate::figure::PlanarFigure::new(sys.sketch())),
            &frames.states,
        );
        let view = View::fit(scene.bounds(&frames.states), 400, 300);
        let html = page(&scene, &view, &frames, "a & b");
        assert!(html.contains("<title>a &amp; b</title>"));
        assert!(html.contains("&lt;bar&gt;") && !html.contains("<bar>"));
        assert!(html.contains("\"t\":[0,0.5,1]"), "{html}");
        // Moving: the bar, its centre, the hinge's ring (its body point, which
        // stays put up to round-off, is drawn where the joint is); still:
        // the ground symbol.
        let moving = html.matches("data-d=\"\"").count();
        assert_eq!(moving, 2, "{html}");
        let frames_json = html
            .split("\"f\":[")
            .nth(1)
            .and_then(|s| s.split("]}").next())
            .expect("frames");
        assert_eq!(frames_json.matches('[').count(), 3, "{frames_json}");
        // Bar (2 points) and centre (1): six numbers a frame.
        assert_eq!(
            frames_json
                .split("],[")
                .next()
                .map(|f| f.split(',').count()),
            Some(6)
        );
    }
}
