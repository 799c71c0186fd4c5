//! Line charts for the studies: one or more panels of named series, stacked
//! vertically in one PNG, with legend, axis labels and optional log axes.
//!
//! The helper knows nothing about mechanics: a study builds [`Panel`]s of
//! [`Series`] and calls [`draw`]. Data outside a panel's fixed range is clipped
//! at the plot frame (plotters itself does not clip), and on a log axis the
//! non-positive values are left out, so a curve that leaves the range or
//! crosses zero is drawn as several pieces.

use std::path::Path;
use std::sync::Once;

use anyhow::{Context as _, Result, anyhow};
use plotters::coord::Shift;
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::prelude::*;
use plotters::style::FontStyle;

pub use plotters::style::RGBColor;

/// Blue, for the integrator under study.
pub const BLUE: RGBColor = RGBColor(31, 119, 180);
/// Orange, for a second quantity of the integrator under study.
pub const ORANGE: RGBColor = RGBColor(255, 127, 14);
/// Green, for a second integrator.
pub const GREEN: RGBColor = RGBColor(44, 160, 44);
/// Red.
pub const RED: RGBColor = RGBColor(214, 39, 40);
/// Black, for references (oracles).
pub const BLACK: RGBColor = RGBColor(0, 0, 0);
/// Grey.
pub const GREY: RGBColor = RGBColor(127, 127, 127);

/// Width of the image, pixels.
pub const WIDTH: u32 = 900;
/// Height of a one-panel image, pixels.
pub const HEIGHT: u32 = 500;
/// Height of each panel when an image has several, pixels.
pub const PANEL_HEIGHT: u32 = 400;

static FONT: Once = Once::new();

/// How a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Style {
    /// Colour.
    pub color: RGBColor,
    /// Line width, pixels.
    pub width: u32,
    /// Dashed instead of solid.
    pub dashed: bool,
}

impl Style {
    /// A solid line, 2 px wide.
    #[must_use]
    pub fn solid(color: RGBColor) -> Self {
        Self {
            color,
            width: 2,
            dashed: false,
        }
    }

    /// A dashed line, 2 px wide (for references drawn over a solid curve).
    #[must_use]
    pub fn dashed(color: RGBColor) -> Self {
        Self {
            color,
            width: 2,
            dashed: true,
        }
    }

    /// The same style with another width.
    #[must_use]
    pub fn width(self, width: u32) -> Self {
        Self { width, ..self }
    }
}

/// One named curve.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// Legend text.
    pub name: String,
    /// Points `(x, y)`, in drawing order.
    pub points: Vec<(f64, f64)>,
    /// How it is drawn.
    pub style: Style,
}

impl Series {
    /// A series from its name, points and style.
    #[must_use]
    pub fn new(name: impl Into<String>, points: Vec<(f64, f64)>, style: Style) -> Self {
        Self {
            name: name.into(),
            points,
            style,
        }
    }
}

/// Where the legend goes inside the plot frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Legend {
    /// Top right (default).
    #[default]
    UpperRight,
    /// Top left.
    UpperLeft,
    /// Bottom right.
    LowerRight,
    /// Bottom left.
    #[allow(
        dead_code,
        reason = "part of the helper's interface for the other studies"
    )]
    LowerLeft,
}

/// Axis scales.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Scale {
    /// Both axes linear (default).
    #[default]
    Linear,
    /// Linear x, logarithmic y.
    LogY,
    /// Logarithmic x, linear y (a cost per body against N).
    LogX,
    /// Both axes logarithmic (convergence studies).
    #[allow(
        dead_code,
        reason = "part of the helper's interface for the convergence study"
    )]
    LogLog,
}

/// One chart: title, axis labels, series and ranges.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Panel {
    /// Title above the chart.
    pub title: String,
    /// x-axis label, with unit.
    pub x_label: String,
    /// y-axis label, with unit.
    pub y_label: String,
    /// The curves.
    pub series: Vec<Series>,
    /// Axis scales (default: linear).
    pub scale: Scale,
    /// x range; `None` fits the data.
    pub x_range: Option<(f64, f64)>,
    /// y range; `None` fits the data (within `x_range`). Data outside is clipped.
    pub y_range: Option<(f64, f64)>,
    /// Legend position (default: upper right).
    pub legend: Legend,
}

impl Panel {
    /// A linear panel fitted to its data.
    #[must_use]
    pub fn new(
        title: impl Into<String>,
        x_label: impl Into<String>,
        y_label: impl Into<String>,
    ) -> Self {
        Self {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            ..Self::default()
        }
    }

    /// Adds a series.
    #[must_use]
    pub fn series(
        mut self,
        name: impl Into<String>,
        points: Vec<(f64, f64)>,
        style: Style,
    ) -> Self {
        self.series.push(Series::new(name, points, style));
        self
    }

    /// Adds a series built elsewhere.
    #[must_use]
    pub fn series_from(mut self, series: Series) -> Self {
        self.series.push(series);
        self
    }

    /// Sets the axis scales.
    #[must_use]
    pub fn scale(mut self, scale: Scale) -> Self {
        self.scale = scale;
        self
    }

    /// Fixes the x range.
    #[must_use]
    pub fn x_range(mut self, lo: f64, hi: f64) -> Self {
        self.x_range = Some((lo, hi));
        self
    }

    /// Fixes the y range (data outside is clipped).
    #[must_use]
    #[allow(
        dead_code,
        reason = "part of the helper's interface for the other studies"
    )]
    pub fn y_range(mut self, lo: f64, hi: f64) -> Self {
        self.y_range = Some((lo, hi));
        self
    }

    /// Sets the legend position.
    #[must_use]
    pub fn legend(mut self, legend: Legend) -> Self {
        self.legend = legend;
        self
    }
}

/// Registers the bundled DejaVu Sans as the "sans-serif" family; there are no
/// system fonts. Idempotent.
///
/// # Errors
/// If the bundled font cannot be parsed.
pub fn register_fonts() -> Result<()> {
    let mut result = Ok(());
    FONT.call_once(|| {
        result = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            include_bytes!("../assets/DejaVuSans.ttf"),
        )
        .map_err(|_| anyhow!("the bundled DejaVuSans.ttf is not a valid font"));
    });
    result
}

/// Draws the panels, stacked vertically, into a PNG at `path`: 900×500 for
/// one panel, 900×400 per panel for more.
///
/// # Errors
/// If there are no panels, the font cannot be registered, or drawing or
/// writing the file fails.
pub fn draw(path: &Path, panels: &[Panel]) -> Result<()> {
    register_fonts()?;
    let height = match panels.len() {
        0 => return Err(anyhow!("no panels to draw into {}", path.display())),
        1 => HEIGHT,
        n => PANEL_HEIGHT * u32::try_from(n).context("too many panels")?,
    };
    let root = BitMapBackend::new(path, (WIDTH, height)).into_drawing_area();
    root.fill(&WHITE)?;
    let areas = root.split_evenly((panels.len(), 1));
    for (area, panel) in areas.iter().zip(panels) {
        draw_panel(area, panel)
            .with_context(|| format!("drawing '{}' into {}", panel.title, path.display()))?;
    }
    root.present()
        .with_context(|| format!("could not write {}", path.display()))?;
    Ok(())
}

/// A curve as the polylines that lie inside `[x0, x1] × [y0, y1]` (and in the
/// positive half-planes of log axes).
fn pieces(
    points: &[(f64, f64)],
    (x0, x1): (f64, f64),
    (y0, y1): (f64, f64),
) -> Vec<Vec<(f64, f64)>> {
    let mut out = Vec::new();
    let mut cur: Vec<(f64, f64)> = Vec::new();
    let mut flush = |cur: &mut Vec<(f64, f64)>| {
        if !cur.is_empty() {
            out.push(std::mem::take(cur));
        }
    };
    for w in points.windows(2) {
        match clip_segment(w[0], w[1], (x0, x1), (y0, y1)) {
            Some((a, b)) => {
                if cur.last() != Some(&a) {
                    flush(&mut cur);
                    cur.push(a);
                }
                cur.push(b);
            }
            None => flush(&mut cur),
        }
    }
    if points.len() == 1 {
        let p = points[0];
        if (x0..=x1).contains(&p.0) && (y0..=y1).contains(&p.1) {
            cur.push(p);
        }
    }
    flush(&mut cur);
    out
}

/// Liang-Barsky clipping of the segment `p`-`q` to the rectangle.
fn clip_segment(
    p: (f64, f64),
    q: (f64, f64),
    (x0, x1): (f64, f64),
    (y0, y1): (f64, f64),
) -> Option<((f64, f64), (f64, f64))> {
    if ![p.0, p.1, q.0, q.1].iter().all(|v| v.is_finite()) {
        return None;
    }
    let (dx, dy) = (q.0 - p.0, q.1 - p.1);
    let (mut t0, mut t1) = (0.0_f64, 1.0_f64);
    for (den, num) in [
        (-dx, p.0 - x0),
        (dx, x1 - p.0),
        (-dy, p.1 - y0),
        (dy, y1 - p.1),
    ] {
        if den == 0.0 {
            if num < 0.0 {
                return None;
            }
        } else {
            let t = num / den;
            if den < 0.0 {
                t0 = t0.max(t);
            } else {
                t1 = t1.min(t);
            }
        }
    }
    if t0 > t1 {
        return None;
    }
    let at = |t: f64| {
        if t == 0.0 {
            p
        } else if t == 1.0 {
            q
        } else {
            (p.0 + t * dx, p.1 + t * dy)
        }
    };
    Some((at(t0), at(t1)))
}

/// The data's extent along one axis, padded by 5 % (in log space on a log
/// axis); `lo < hi` always.
fn fit(values: impl Iterator<Item = f64>, log: bool) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite() && (!log || *v > 0.0)) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if lo > hi {
        return if log { (0.1, 10.0) } else { (-1.0, 1.0) };
    }
    if log {
        let (a, b) = (lo.log10(), hi.log10());
        let pad = if b > a { 0.05 * (b - a) } else { 0.5 };
        (10f64.powf(a - pad), 10f64.powf(b + pad))
    } else {
        let span = hi - lo;
        let pad = if span > 0.0 {
            0.05 * span
        } else {
            0.5 * lo.abs().max(1.0)
        };
        (lo - pad, hi + pad)
    }
}

/// A short tick label: plain for moderate magnitudes, scientific otherwise.
fn tick(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        "0".into()
    } else if !(1e-3..1e5).contains(&a) {
        let s = format!("{v:.1e}");
        s.replace(".0e", "e")
    } else {
        let s = format!("{v:.4}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        if s == "-0" { "0".into() } else { s.into() }
    }
}

fn draw_panel(area: &DrawingArea<BitMapBackend<'_>, Shift>, panel: &Panel) -> Result<()> {
    let (log_x, log_y) = match panel.scale {
        Scale::Linear => (false, false),
        Scale::LogY => (false, true),
        Scale::LogX => (true, false),
        Scale::LogLog => (true, true),
    };
    let all = || panel.series.iter().flat_map(|s| s.points.iter().copied());
    let xr = panel
        .x_range
        .unwrap_or_else(|| fit(all().map(|p| p.0), log_x));
    let yr = panel.y_range.unwrap_or_else(|| {
        fit(
            all()
                .filter(|p| p.0 >= xr.0 && p.0 <= xr.1 && (!log_x || p.0 > 0.0))
                .map(|p| p.1),
            log_y,
        )
    });
    match (log_x, log_y) {
        (false, false) => draw_in(area, panel, xr.0..xr.1, yr.0..yr.1, xr, yr),
        (false, true) => draw_in(area, panel, xr.0..xr.1, (yr.0..yr.1).log_scale(), xr, yr),
        (true, false) => draw_in(area, panel, (xr.0..xr.1).log_scale(), yr.0..yr.1, xr, yr),
        _ => draw_in(
            area,
            panel,
            (xr.0..xr.1).log_scale(),
            (yr.0..yr.1).log_scale(),
            xr,
            yr,
        ),
    }
}

fn draw_in<X, Y>(
    area: &DrawingArea<BitMapBackend<'_>, Shift>,
    panel: &Panel,
    x_spec: X,
    y_spec: Y,
    xr: (f64, f64),
    yr: (f64, f64),
) -> Result<()>
where
    X: AsRangedCoord<Value = f64>,
    Y: AsRangedCoord<Value = f64>,
    X::CoordDescType: ValueFormatter<f64>,
    Y::CoordDescType: ValueFormatter<f64>,
{
    let mut chart = ChartBuilder::on(area)
        .caption(&panel.title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(80)
        .build_cartesian_2d(x_spec, y_spec)?;
    chart
        .configure_mesh()
        .x_desc(panel.x_label.as_str())
        .y_desc(panel.y_label.as_str())
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(*v))
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 16))
        // No minor grid: plotters saves PNGs with fast compression, and the
        // minor grid alone triples the file size.
        .light_line_style(TRANSPARENT)
        .draw()?;
    for s in &panel.series {
        let shape = ShapeStyle::from(s.style.color).stroke_width(s.style.width);
        let mut labelled = false;
        for piece in pieces(&s.points, xr, yr) {
            let anno = if s.style.dashed {
                chart.draw_series(DashedLineSeries::new(piece, 8, 5, shape))?
            } else if s.style.width > 1 && piece.len() > 2 {
                // plotters joins thick polylines with miters, which shoot far
                // out of the frame at the sharp turns of a zig-zag (a period-2h
                // oscillation); separate segments have no joins.
                chart.draw_series(
                    piece
                        .windows(2)
                        .map(|w| PathElement::new(vec![w[0], w[1]], shape)),
                )?
            } else {
                chart.draw_series(LineSeries::new(piece, shape))?
            };
            if !labelled {
                label(anno, &s.name, shape);
                labelled = true;
            }
        }
        if !labelled {
            // Nothing in range: still name the curve in the legend.
            let anno = chart.draw_series(LineSeries::new(Vec::<(f64, f64)>::new(), shape))?;
            label(anno, &format!("{} (out of range)", s.name), shape);
        }
    }
    let position = match panel.legend {
        Legend::UpperRight => SeriesLabelPosition::UpperRight,
        Legend::UpperLeft => SeriesLabelPosition::UpperLeft,
        Legend::LowerRight => SeriesLabelPosition::LowerRight,
        Legend::LowerLeft => SeriesLabelPosition::LowerLeft,
    };
    chart
        .configure_series_labels()
        .position(position)
        .label_font(("sans-serif", 14))
        .background_style(WHITE.mix(0.85))
        .border_style(RGBColor(0, 0, 0).mix(0.4))
        .draw()?;
    Ok(())
}

fn label<DB: DrawingBackend>(
    anno: &mut plotters::chart::SeriesAnno<'_, DB>,
    name: &str,
    shape: ShapeStyle,
) {
    anno.label(name)
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], shape));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clipping_splits_a_curve_that_leaves_the_range() {
        let pts = [(0.0, 0.0), (1.0, 2.0), (2.0, 0.0), (3.0, 0.5)];
        let p = pieces(&pts, (0.0, 3.0), (-1.0, 1.0));
        assert_eq!(p.len(), 2);
        assert_eq!(p[0], vec![(0.0, 0.0), (0.5, 1.0)]);
        assert_eq!(p[1], vec![(1.5, 1.0), (2.0, 0.0), (3.0, 0.5)]);
    }

    #[test]
    fn fitted_ranges_are_never_empty() {
        assert_eq!(fit([2.0, 2.0].into_iter(), false), (1.0, 3.0));
        let (lo, hi) = fit([-1.0, 0.0].into_iter(), true);
        assert!(lo < hi);
    }

    #[test]
    fn tick_labels_are_short() {
        assert_eq!(tick(0.5), "0.5");
        assert_eq!(tick(2.0), "2");
        assert_eq!(tick(1.0e7), "1e7");
        assert_eq!(tick(-2.5e-5), "-2.5e-5");
    }
}
