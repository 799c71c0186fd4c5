//! A spatial run as one self-contained 3-D page: a canvas that a small
//! hand-written renderer (`page3d.js`, Canvas 2-D, painter's algorithm)
//! draws each body into as a shaded box ([`Solid`]) with its axes, the joint
//! points as dots, rods and springs as lines, the ground's axes and a grid.
//! The mouse turns the view (drag), zooms (wheel) and pans (shift-drag or
//! right-drag). The frames are numbers in the page: each body's position and
//! Euler parameters. Without script the page shows the first frame as the
//! GIF draws it (inline SVG). Nothing is fetched; names are escaped.

use std::fmt::Write as _;

use mstar::model::spatial::{SpatialAttachment, SpatialSketch};

use super::html::{element, escape, fill};
use super::results::Results;
use super::scene::{INK, Scene, View, body_colour};
use super::solid::Solid;
use super::spatial::Projection;

/// The renderer, a file of its own so it reads as JavaScript.
const SCRIPT: &str = include_str!("page3d.js");

/// The element kinds that get no joint dot: loads at a body as a whole, and
/// a force's second end (a placeholder at the ground's origin).
fn dotted(kind: &str, driver: bool) -> bool {
    !driver && !matches!(kind, "torque" | "rotational spring-damper" | "force")
}

/// What the 3-D page shows besides the frames.
pub struct Model3d<'a> {
    /// The bodies and elements.
    pub sketch: &'a SpatialSketch,
    /// Each body's box.
    pub solids: &'a [Solid],
    /// The first view (`--view`).
    pub projection: Projection,
}

/// The camera's first angles, degrees: the yaw about the global z axis (0:
/// looking along +y, x to the right) and the elevation (90: from above).
#[must_use]
pub fn camera(projection: Projection) -> [f64; 2] {
    match projection {
        Projection::Oblique => [30.0, 20.0],
        Projection::Xz => [0.0, 0.0],
        Projection::Yz => [90.0, 0.0],
        Projection::Xy => [0.0, 90.0],
    }
}

/// The page for `frames` (at most [`super::html::MAX_FRAMES`]) of `model`;
/// `scene` in `view` draws the first frame for a browser without script.
#[must_use]
pub fn page(
    model: &Model3d<'_>,
    scene: &Scene,
    view: &View,
    frames: &Results,
    title: &str,
) -> String {
    let mut svg = String::new();
    if let Some(u) = frames.states.first() {
        for item in scene.items(u, view) {
            element(&mut svg, &item, false, scene);
        }
    }
    let legend = super::html::legend(model.sketch.bodies.iter().map(|b| b.name.as_str()));
    fill(
        TEMPLATE,
        &[
            ("title", &escape(title)),
            ("w", &view.width.to_string()),
            ("h", &view.height.to_string()),
            ("ink", &INK.hex()),
            ("last", &frames.times.len().saturating_sub(1).to_string()),
            (
                "t0",
                &format!("t = {:.3} s", frames.times.first().copied().unwrap_or(0.0)),
            ),
            ("legend", &legend),
            ("svg", &svg),
            ("script", SCRIPT),
            ("data", &data(model, frames)),
        ],
    )
}

/// `x` rounded to `decimals` places, without trailing zeros.
fn num(out: &mut String, x: f64, decimals: usize) {
    let text = format!("{x:.decimals$}");
    let text = if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.')
    } else {
        &text
    };
    out.push_str(if text == "-0" || text.is_empty() {
        "0"
    } else {
        text
    });
}

/// Numbers joined by commas.
fn list(out: &mut String, xs: impl IntoIterator<Item = f64>, decimals: usize) {
    for (k, x) in xs.into_iter().enumerate() {
        if k > 0 {
            out.push(',');
        }
        num(out, x, decimals);
    }
}

/// The centre and radius of a ball around every body's box and every
/// joint point over the frames, m.
fn extent(model: &Model3d<'_>, frames: &Results) -> ([f64; 3], f64) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    let mut reach = 0.0f64;
    let mut grow = |p: [f64; 3]| {
        if p.iter().all(|x| x.is_finite()) {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
    };
    for u in &frames.states {
        for body in &model.sketch.bodies {
            grow([u[body.x], u[body.x + 1], u[body.x + 2]]);
        }
        for e in &model.sketch.elements {
            for end in &e.ends {
                grow(model.sketch.position(end, u));
            }
        }
    }
    for s in model.solids {
        let h = s.half_sides();
        reach = reach.max((h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).sqrt());
    }
    if !lo[0].is_finite() {
        return ([0.0; 3], 1.0);
    }
    let centre: [f64; 3] = std::array::from_fn(|k| 0.5 * (lo[k] + hi[k]));
    let half = (0..3)
        .map(|k| (hi[k] - centre[k]).powi(2))
        .sum::<f64>()
        .sqrt();
    let r = half + reach;
    (centre, if r > 1e-9 { r } else { 1.0 })
}

/// The decimals that keep a length to about 10⁻⁴ of `r`.
fn decimals(r: f64) -> usize {
    (4.0 - r.log10().floor()).clamp(0.0, 12.0) as usize
}

/// The frames and the model as JSON numbers: `t` times; `b` per body
/// `[rigid, colour, 9 half-axis numbers]`; `m` joint dots
/// `[body (−1: ground), x, y, z]`; `e` lines `[dot, dot, 0 rod | 1 spring]`;
/// `f` per frame each body's `x, y, z` (and `e0 … e3` if rigid); `c`, `r`
/// the centre and radius of the run; `v` the first camera angles.
fn data(model: &Model3d<'_>, frames: &Results) -> String {
    let (centre, r) = extent(model, frames);
    let d = decimals(r);
    let mut out = String::from("{\"t\":[");
    list(&mut out, frames.times.iter().copied(), 6);
    out.push_str("],\"b\":[");
    for (i, (body, solid)) in model.sketch.bodies.iter().zip(model.solids).enumerate() {
        let _ = write!(
            out,
            "{}[{},\"{}\",",
            if i > 0 { "," } else { "" },
            u8::from(body.rigid),
            body_colour(i).hex()
        );
        list(&mut out, solid.half_axes.iter().flatten().copied(), d);
        out.push(']');
    }
    out.push_str("],\"m\":[");
    let (dots, lines) = dots_and_lines(model.sketch);
    for (k, (body, p)) in dots.iter().enumerate() {
        let _ = write!(out, "{}[{body},", if k > 0 { "," } else { "" });
        list(&mut out, p.iter().copied(), d);
        out.push(']');
    }
    out.push_str("],\"e\":[");
    for (k, l) in lines.iter().enumerate() {
        let _ = write!(
            out,
            "{}[{},{},{}]",
            if k > 0 { "," } else { "" },
            l[0],
            l[1],
            l[2]
        );
    }
    out.push_str("],\"f\":[");
    for (k, u) in frames.states.iter().enumerate() {
        out.push_str(if k > 0 { ",[" } else { "[" });
        for (i, body) in model.sketch.bodies.iter().enumerate() {
            if i > 0 {
                out.push(',');
            }
            list(&mut out, u[body.x..body.x + 3].iter().copied(), d);
            if body.rigid {
                out.push(',');
                list(&mut out, u[body.x + 3..body.x + 7].iter().copied(), 4);
            }
        }
        out.push(']');
    }
    out.push_str("],\"c\":[");
    list(&mut out, centre, d);
    out.push_str("],\"r\":");
    num(&mut out, r, d + 1);
    out.push_str(",\"v\":[");
    list(&mut out, camera(model.projection), 1);
    out.push_str("]}");
    out
}

/// A joint point: its body (−1: the ground) and where it is in the body's
/// axes (the ground's: global), m.
type Dot = (i64, [f64; 3]);

/// The distinct joint points and the lines of rods (0) and springs (1)
/// between two of them, `[dot, dot, kind]`.
fn dots_and_lines(sketch: &SpatialSketch) -> (Vec<Dot>, Vec<[usize; 3]>) {
    let mut dots: Vec<Dot> = Vec::new();
    let mut lines = Vec::new();
    for e in sketch.elements.iter().filter(|e| dotted(e.kind, e.driver)) {
        let ends = e.ends.map(|end| {
            let dot = match end {
                SpatialAttachment::Ground(p) => (-1, p),
                SpatialAttachment::Body { body, local } => (body as i64, local),
            };
            dots.iter().position(|d| *d == dot).unwrap_or_else(|| {
                dots.push(dot);
                dots.len() - 1
            })
        });
        match e.kind {
            "distance" => lines.push([ends[0], ends[1], 0]),
            "spring-damper" => lines.push([ends[0], ends[1], 1]),
            _ => {}
        }
    }
    (dots, lines)
}

/// The page around the canvas. Placeholders in braces are filled by
/// [`page`]; the data and script come last so no user text follows them.
const TEMPLATE: &str = r##"<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>{title}</title>
<style>
body { font-family: sans-serif; margin: 1em; color: {ink}; }
canvas, svg { width: 100%; max-width: {w}px; height: auto; border: 1px solid #ccc; display: block; touch-action: none; }
canvas { cursor: grab; }
.controls { display: flex; gap: 0.6em; align-items: center; max-width: {w}px; margin-top: 0.4em; }
.controls input[type=range] { flex: 1; }
ul.legend { list-style: none; padding: 0; display: flex; flex-wrap: wrap; gap: 1em; }
.swatch { display: inline-block; width: 0.9em; height: 0.9em; margin-right: 0.3em; vertical-align: -0.1em; }
p.caption, p.help { margin: 0 0 0.4em 0; }
p.help { font-size: 85%; color: #666; }
</style>
</head>
<body>
<p class="caption">{title}</p>
<canvas id="view" width="{w}" height="{h}" role="img" aria-label="the mechanism moving, in 3-D"></canvas>
<noscript><svg viewBox="0 0 {w} {h}" width="{w}" height="{h}" role="img" aria-label="the first frame">
<rect x="0" y="0" width="{w}" height="{h}" fill="#fff"/>
{svg}</svg></noscript>
<div class="controls">
<button id="play" type="button">Pause</button>
<input id="slider" type="range" min="0" max="{last}" value="0" step="1" aria-label="time">
<span id="time">{t0}</span>
<label>speed <select id="speed">
<option value="0.1">0.1×</option><option value="0.25">0.25×</option><option value="0.5">0.5×</option>
<option value="1" selected>1×</option><option value="2">2×</option><option value="5">5×</option>
</select></label>
<button id="reset" type="button">Reset view</button>
</div>
<p class="help">Drag to turn, wheel to zoom, shift-drag or right-drag to pan. Body axes: x red, y green, z blue.</p>
<ul class="legend">{legend}</ul>
<script type="application/json" id="frames">{data}</script>
<script>{script}</script>
</body>
</html>
"##;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_short() {
        let mut s = String::new();
        list(&mut s, [1.5, -0.00001, 2.0, 0.123_456_7], 4);
        assert_eq!(s, "1.5,0,2,0.1235");
        assert_eq!(decimals(0.5), 5);
        assert_eq!(decimals(20.0), 3);
    }
}
