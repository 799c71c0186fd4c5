//! The scene's items drawn with plotters: one frame into any bitmap, the
//! animated GIF, and a single frame as a PNG picture.

use std::path::Path;

use anyhow::{Context as _, Result, anyhow};
use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::{FontStyle, RGBAColor};
use plotters_backend::DrawingErrorKind;

use super::geometry::Shape;
use super::scene::{Colour, INK, Item, Scene, View, body_colour};

/// DejaVu Sans, built into the program: plotters draws text only with a
/// registered font, and the program must not depend on the system's fonts
/// or on where it is run from.
const FONT: &[u8] = include_bytes!("../../../../xtask/assets/DejaVuSans.ttf");

/// Registers [`FONT`] as `sans-serif` (once).
fn register_font() -> Result<()> {
    static DONE: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    let ok = *DONE.get_or_init(|| {
        plotters::style::register_font("sans-serif", FontStyle::Normal, FONT).is_ok()
    });
    if ok {
        Ok(())
    } else {
        Err(anyhow!("the built-in font could not be loaded"))
    }
}

/// What every frame has besides the items: the view and the body names.
pub struct Canvas<'a> {
    /// The model and its run.
    pub scene: &'a Scene,
    /// The fitted view (its size is the picture's).
    pub view: View,
}

impl Canvas<'_> {
    /// Draws the state `u` at time `t` into `area` (white, then the items,
    /// the time in the top-left corner and, from 320×240 up, a legend of the
    /// bodies in the top-right one).
    ///
    /// # Errors
    /// What the backend reports.
    pub fn draw<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        t: f64,
        u: &[f64],
    ) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
        area.fill(&WHITE)?;
        for item in self.scene.items(u, &self.view) {
            draw_item(area, &item, self.view.unit)?;
        }
        let k = self.view.unit;
        let size = (18.0 * k).max(10.0);
        let font = ("sans-serif", size).into_font().color(&rgb(INK));
        let at = ((10.0 * k).round() as i32, (8.0 * k).round() as i32);
        area.draw(&Text::new(format!("t = {t:.3} s"), at, font))?;
        if k >= 0.5 {
            self.legend(area)?;
        }
        Ok(())
    }

    /// The bodies' names with their colours, right-aligned at the top.
    fn legend<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
    ) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
        let k = self.view.unit;
        let font = ("sans-serif", 14.0 * k).into_font().color(&rgb(INK));
        let right = f64::from(self.view.width) - 10.0 * k;
        for (i, body) in self.scene.sketch().bodies.iter().enumerate() {
            let (w, _) = area.estimate_text_size(&body.name, &font)?;
            let y = 10.0 * k + 20.0 * k * i as f64;
            let x = right - f64::from(w);
            area.draw(&Text::new(
                body.name.clone(),
                (x.round() as i32, y.round() as i32),
                font.clone(),
            ))?;
            let swatch = [
                px([x - 16.0 * k, y - 1.0 * k]),
                px([x - 6.0 * k, y + 9.0 * k]),
            ];
            area.draw(&Rectangle::new(swatch, rgb(body_colour(i)).filled()))?;
        }
        Ok(())
    }
}

fn rgb(c: Colour) -> RGBColor {
    RGBColor(c.0, c.1, c.2)
}

fn px(p: [f64; 2]) -> (i32, i32) {
    (p[0].round() as i32, p[1].round() as i32)
}

/// One item: outlines `width` px wide, fills with their opacity; open marks
/// as a filled disc (or square) of the outline colour with the fill inside.
fn draw_item<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    item: &Item,
    unit: f64,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let stroke = item.style.stroke.map(|(c, w)| ShapeStyle {
        color: rgb(c).to_rgba(),
        filled: false,
        stroke_width: w.round().max(1.0) as u32,
    });
    let fill = item
        .style
        .fill
        .map(|(c, a)| RGBAColor(c.0, c.1, c.2, a).filled());
    let half = item.style.stroke.map_or(0.0, |(_, w)| 0.5 * w);
    match &item.shape {
        Shape::Line(points) => {
            let points: Vec<(i32, i32)> = points.iter().map(|&p| px(p)).collect();
            match stroke {
                Some(s) if item.style.dashed => {
                    let (dash, gap) = ((7.0 * unit).max(2.0) as u32, (5.0 * unit).max(2.0) as u32);
                    area.draw(&DashedPathElement::new(points, dash, gap, s))?;
                }
                Some(s) => area.draw(&PathElement::new(points, s))?,
                None => {}
            }
        }
        Shape::Polygon(points) => {
            let mut points: Vec<(i32, i32)> = points.iter().map(|&p| px(p)).collect();
            if let Some(f) = fill {
                area.draw(&Polygon::new(points.clone(), f))?;
            }
            if let (Some(s), Some(&first)) = (stroke, points.first()) {
                points.push(first);
                area.draw(&PathElement::new(points, s))?;
            }
        }
        Shape::Circle(c, r) => {
            let disc =
                |r: f64, style: ShapeStyle| Circle::new(px(*c), r.round().max(1.0) as u32, style);
            if let Some(s) = stroke {
                area.draw(&disc(r + half, s.color.filled()))?;
            }
            if let Some(f) = fill {
                area.draw(&disc(r - half, f))?;
            }
        }
        Shape::Square(c, h) => {
            let square = |h: f64, style: ShapeStyle| {
                Rectangle::new([px([c[0] - h, c[1] - h]), px([c[0] + h, c[1] + h])], style)
            };
            if let Some(s) = stroke {
                area.draw(&square(h + half, s.color.filled()))?;
            }
            if let Some(f) = fill {
                area.draw(&square(h - half, f))?;
            }
        }
    }
    Ok(())
}

/// Runs `write` on a temporary path beside `path` (with the same extension,
/// which the image encoder goes by) and renames it into place: `path` is
/// written completely or not at all.
/// A device or a FIFO is written directly, never replaced; a directory is an
/// error (see [`mstar::csv::target`]). A stop signal removes the temporary
/// file: one that comes while `write` draws is `write`'s to answer, one
/// after it stops before the rename (at `t_last`, the time of the last
/// frame), and a second one ends the program at once, after removing it
/// ([`crate::signals::removed_if_killed`]).
fn via_temporary(path: &Path, t_last: f64, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    let path = &match mstar::csv::target(path)? {
        mstar::csv::Target::Replace(target) => target,
        mstar::csv::Target::Stdout => return write(Path::new("/dev/stdout")),
        mstar::csv::Target::Direct => {
            return write(path).with_context(|| format!("could not write {}", path.display()));
        }
    };
    let name = path
        .file_name()
        .with_context(|| format!("{} is not a file name", path.display()))?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let tmp = dir.join(format!(
        ".{}.tmp.{}",
        std::process::id(),
        name.to_string_lossy()
    ));
    // Created here first: an I/O error then reads as one (plotters' own
    // errors print their internals).
    // Everything up to the rename (or the removal) under the guard: a
    // second signal at any point removes the temporary file.
    let result = crate::signals::removed_if_killed(&tmp, || {
        let result = std::fs::File::create(&tmp)
            .map_err(anyhow::Error::from)
            .and_then(|_| write(&tmp))
            .and_then(|()| {
                std::fs::File::open(&tmp)
                    .and_then(|f| f.sync_all())
                    .map_err(anyhow::Error::from)?;
                // A signal after the last frame: no file, as before it.
                if let Some(signal) = crate::signals::received() {
                    return Err(crate::signals::Interrupted { signal, t: t_last }.into());
                }
                std::fs::rename(&tmp, path).map_err(anyhow::Error::from)
            });
        if result.is_err() {
            let _ = std::fs::remove_file(&tmp);
        }
        result
    });
    result.with_context(|| format!("could not write {}", path.display()))
}

/// The picture formats `--png` writes, by extension (the encoder goes by it).
const PICTURE_EXTENSIONS: [&str; 4] = ["png", "jpg", "jpeg", "bmp"];

/// Refuses a `--png` path whose extension names no picture format.
///
/// # Errors
/// With the extensions that work.
pub fn check_picture_name(path: &Path) -> Result<()> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_lowercase())
        .unwrap_or_default();
    // (A device or standard output is written as the encoder can.)
    let direct = matches!(
        mstar::csv::target(path),
        Ok(mstar::csv::Target::Direct | mstar::csv::Target::Stdout)
    );
    if direct || PICTURE_EXTENSIONS.contains(&ext.as_str()) {
        return Ok(());
    }
    Err(anyhow!(
        "--png {}: the picture format follows the extension; name a file ending in .png (or .jpg, .bmp)",
        path.display()
    ))
}

/// A drawing error in words: the I/O or encoder error behind plotters'
/// wrappers, whose own messages print Rust's debug form.
fn in_words(
    e: DrawingAreaErrorKind<<BitMapBackend<'static> as DrawingBackend>::ErrorType>,
) -> anyhow::Error {
    type Bitmap = <BitMapBackend<'static> as DrawingBackend>::ErrorType;
    match e {
        DrawingAreaErrorKind::BackendError(DrawingErrorKind::DrawingError(b)) => match b {
            Bitmap::IOError(io) => io.into(),
            Bitmap::GifEncodingError(g) => anyhow!("{g}"),
            Bitmap::ImageError(i) => anyhow!("{i}"),
            Bitmap::InvalidBuffer => anyhow!("the picture buffer has the wrong size"),
        },
        DrawingAreaErrorKind::BackendError(DrawingErrorKind::FontError(f)) => {
            anyhow!("the font: {f}")
        }
        other => anyhow!("{other}"),
    }
}

/// Writes the frames `(t, u)` as a looping GIF, each shown `delay_cs`
/// hundredths of a second (the GIF's unit of time), counting them on
/// `progress`.
///
/// # Errors
/// If the font cannot be loaded, or drawing or writing fails; `path` is then
/// untouched.
pub fn write_gif(
    path: &Path,
    canvas: &Canvas<'_>,
    frames: &[(f64, Vec<f64>)],
    delay_cs: u32,
    progress: &indicatif::ProgressBar,
) -> Result<()> {
    register_font()?;
    let size = (canvas.view.width, canvas.view.height);
    let t_last = frames.last().map_or(0.0, |(t, _)| *t);
    via_temporary(path, t_last, |tmp| {
        let root = BitMapBackend::gif(tmp, size, 10 * delay_cs)
            .map_err(|e| {
                in_words(DrawingAreaErrorKind::BackendError(
                    DrawingErrorKind::DrawingError(e),
                ))
            })?
            .into_drawing_area();
        for (t, u) in frames {
            // Ctrl-C, SIGTERM, SIGHUP: stop, and the temporary file goes.
            if let Some(signal) = crate::signals::received() {
                return Err(crate::signals::Interrupted { signal, t: *t }.into());
            }
            canvas.draw(&root, *t, u).map_err(in_words)?;
            root.present().map_err(in_words)?;
            progress.inc(1);
        }
        Ok(())
    })
}

/// Writes the state `u` at time `t` as a PNG picture (the format follows the
/// extension: PNG, or JPEG and BMP).
///
/// # Errors
/// As [`write_gif`].
pub fn write_png(path: &Path, canvas: &Canvas<'_>, t: f64, u: &[f64]) -> Result<()> {
    register_font()?;
    let size = (canvas.view.width, canvas.view.height);
    via_temporary(path, t, |tmp| {
        let root = BitMapBackend::new(tmp, size).into_drawing_area();
        canvas.draw(&root, t, u).map_err(in_words)?;
        root.present().map_err(in_words)?;
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::animate::scene::Bounds;

    #[test]
    fn a_frame_shows_the_body_in_its_colour() {
        let sys = crate::animate::hinged_bar("bar");
        let u = sys.initial_position();
        let scene = Scene::new(
            Box::new(crate::animate::figure::PlanarFigure::new(sys.sketch())),
            std::slice::from_ref(&u),
        );
        let view = View::fit(
            Bounds {
                min: [-0.1, -0.5],
                max: [1.1, 0.5],
            },
            200,
            100,
        );
        let canvas = Canvas {
            scene: &scene,
            view,
        };
        let mut buffer = vec![0u8; 200 * 100 * 3];
        {
            let root = BitMapBackend::with_buffer(&mut buffer, (200, 100)).into_drawing_area();
            register_font().expect("the font");
            canvas.draw(&root, 0.0, &u).expect("drawn");
            root.present().expect("presented");
        }
        let pixel = |p: [f64; 2]| {
            let (x, y) = px(view.px(p));
            let i = 3 * (y as usize * 200 + x as usize);
            (buffer[i], buffer[i + 1], buffer[i + 2])
        };
        let c = body_colour(0);
        // A bar with one joint point is drawn from it to the centre of mass:
        // halfway there, its colour; above it and beyond the centre, white.
        assert_eq!(pixel([0.25, 0.0]), (c.0, c.1, c.2));
        assert_eq!(pixel([0.25, 0.4]), (255, 255, 255));
        assert_eq!(pixel([0.9, 0.0]), (255, 255, 255));
    }
}
