//! `mstar animate`: the command, its options and its output files; the
//! drawing is [`crate::animate`]'s.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Result, bail};
use mstar::file::{Mechanism, MechanismFile};
use mstar::newmark::Short;

use crate::animate::figure::{Figure, PlanarFigure};
use crate::animate::html;
use crate::animate::mode_shape;
use crate::animate::page3d::{self, Model3d};
use crate::animate::picture::{self, Canvas};
use crate::animate::results::{self, Results};
use crate::animate::scene::{Scene, View};
use crate::animate::solid::{self, Solid};
use crate::animate::spatial::{self, Projection};

/// Arguments of `mstar animate`.
#[derive(clap::Args, Debug)]
#[command(group(
    clap::ArgGroup::new("output")
        .args(["gif", "html", "png"])
        .required(true)
        .multiple(true)
))]
pub struct AnimateArgs {
    /// The model file the results were computed with.
    model: PathBuf,
    /// The CSV file of `mstar run MODEL --out FILE` (or the
    /// `<name>.partial.csv` of a run that failed); not with --mode.
    #[arg(required_unless_present = "mode")]
    results: Option<PathBuf>,
    /// Draw vibration mode K (1 = the lowest, as `mstar modes` numbers
    /// them) moving about the state it was found at, instead of a run.
    #[arg(long, value_name = "K", conflicts_with = "results",
          value_parser = mode_number, allow_hyphen_values = true)]
    mode: Option<u32>,
    /// The state of --mode: `equilibrium` (found from the file's pose, as
    /// `mstar equilibrium`) or `initial` (the file's pose, held by the
    /// constraint forces of that instant).
    #[arg(long, value_enum, default_value_t = super::modes::About::Equilibrium, requires = "mode")]
    about: super::modes::About,
    /// Write an animated GIF (looping) to this file.
    #[arg(long, value_name = "OUT.gif")]
    gif: Option<PathBuf>,
    /// Write one self-contained HTML page (play/pause, time slider, speed;
    /// a spatial model in 3-D: drag to turn, wheel to zoom, shift-drag to
    /// pan) to this file.
    #[arg(long, value_name = "OUT.html")]
    html: Option<PathBuf>,
    /// Write one frame (the one at --at) as a PNG picture to this file.
    #[arg(long, value_name = "OUT.png")]
    png: Option<PathBuf>,
    /// The time of the --png frame, s [default: the first row's].
    #[arg(long, value_name = "T", requires = "png", allow_hyphen_values = true)]
    at: Option<f64>,
    /// GIF frames per second, 1 to 50 (a GIF keeps delays in 1/100 s: 30 fps
    /// plays at 33.3, and the frames are taken at that rate).
    #[arg(
        long,
        default_value_t = 30,
        value_parser = clap::value_parser!(u32).range(1..=50),
        allow_negative_numbers = true
    )]
    fps: u32,
    /// Simulated seconds per second of GIF [default: 1, real time; a run
    /// shorter than 1 s is slowed down to last 1 s].
    #[arg(long, value_parser = positive, conflicts_with = "duration", allow_negative_numbers = true)]
    speed: Option<f64>,
    /// The GIF's length, s: the whole run in that time (instead of --speed).
    #[arg(long, value_parser = positive, allow_negative_numbers = true)]
    duration: Option<f64>,
    /// The most GIF frames: a longer GIF is played faster to fit (with a note).
    #[arg(
        long,
        default_value_t = 600,
        value_parser = clap::value_parser!(u32).range(1..),
        allow_negative_numbers = true
    )]
    max_frames: u32,
    /// Picture size in pixels, WIDTHxHEIGHT (GIF and PNG; the HTML page's
    /// drawing, which scales with the window).
    #[arg(long, default_value = "640x480", value_parser = size)]
    size: Size,
    /// How a spatial model is projected onto the picture: `oblique` (x right,
    /// z up, y receding up and to the right at 30° and half length), `xz`
    /// (front: x right, z up), `yz` (side: y right, z up) or `xy` (top: x
    /// right, y up) [default: oblique]. Planar models are drawn in their own
    /// plane and do not take it.
    #[arg(long, value_enum)]
    view: Option<Projection>,
    /// Override a key of the model file (as for `mstar run`).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
}

/// A picture size, px.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Size {
    width: u32,
    height: u32,
}

/// `WIDTHxHEIGHT`, each from 16 to 4096.
fn size(text: &str) -> Result<Size, String> {
    let (w, h) = text
        .split_once(['x', 'X', '×'])
        .ok_or_else(|| format!("'{text}' is not WIDTHxHEIGHT, e.g. 640x480"))?;
    let side = |s: &str| match s.trim().parse::<u32>() {
        Ok(n) if (16..=4096).contains(&n) => Ok(n),
        _ => Err(format!(
            "'{s}' in '{text}' is not a whole number of pixels from 16 to 4096"
        )),
    };
    Ok(Size {
        width: side(w)?,
        height: side(h)?,
    })
}

/// A mode number: a whole number from 1 (the model's degrees of freedom
/// bound it above once the model is read: `mode_frames`).
fn mode_number(text: &str) -> Result<u32, String> {
    match text.trim().parse::<u32>() {
        Ok(k) if k >= 1 => Ok(k),
        _ => Err(format!(
            "'{text}' is not a mode number: give a whole number from 1 (the lowest mode) to the \
             model's degrees of freedom (mstar modes MODEL lists the modes)"
        )),
    }
}

/// A positive, finite number.
fn positive(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(x) if x > 0.0 && x.is_finite() => Ok(x),
        _ => Err(format!("'{text}' is not a positive number")),
    }
}

/// `mstar animate`: exit 0 when every output is written, 1 when the results
/// do not fit the model or an output cannot be written, 2 when the model
/// file cannot be read (as `mstar check`).
pub fn animate(args: &AnimateArgs) -> ExitCode {
    if let Err(e) = check_outputs(args) {
        note!("error: {e}");
        return ExitCode::from(2);
    }
    // A read-only output is a failure to write (exit 1), found before the
    // drawing rather than after it.
    if let Err(e) = crate::output::refuse_read_only(&outputs(args)) {
        note!("error: {e}");
        return ExitCode::from(1);
    }
    let file = match MechanismFile::load_with(&args.model, &args.set) {
        Ok(file) => file,
        Err(e) => {
            note!("error: {e}");
            return ExitCode::from(2);
        }
    };
    let drawing = match figure(args, &file.mechanism) {
        Ok(drawing) => drawing,
        Err(e) => {
            note!("error: {e}");
            return ExitCode::from(2);
        }
    };
    let run = match results_to_draw(args, &file.mechanism, &drawing.0.columns()) {
        Ok(run) => run,
        Err(e) => {
            note!("error: {e:#}");
            return ExitCode::from(1);
        }
    };
    match render(args, drawing, &run) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if e.downcast_ref::<crate::signals::Interrupted>().is_some() => {
            ExitCode::from(crate::output::exit_code(Err(e), false, 1))
        }
        Err(e) => {
            note!("error: {e:#}");
            ExitCode::from(1)
        }
    }
}

/// The outputs asked for, each with its option.
fn outputs(args: &AnimateArgs) -> Vec<(&'static str, &Path)> {
    [
        ("--gif", &args.gif),
        ("--html", &args.html),
        ("--png", &args.png),
    ]
    .into_iter()
    .filter_map(|(option, path)| path.as_deref().map(|p| (option, p)))
    .collect()
}

/// Refuses an output that names the model, the URDF it reads, the results
/// or another output ([`crate::output::refuse_overwriting_model`]), a
/// `--png` whose extension is no picture format, and a non-finite `--at`.
fn check_outputs(args: &AnimateArgs) -> Result<()> {
    let results: Vec<(&str, &Path)> = args
        .results
        .iter()
        .map(|r| ("the results file", r.as_path()))
        .collect();
    crate::output::refuse_overwriting_model(&args.model, &results, &outputs(args))?;
    if let Some(png) = &args.png {
        picture::check_picture_name(png)?;
    }
    if let Some(t) = args.at
        && !t.is_finite()
    {
        bail!("--at must be a finite time in seconds (got {})", Short(t));
    }
    Ok(())
}

/// A spatial model for the 3-D page: its sketch, each body's solid and the
/// first view.
struct Spatial3d {
    sketch: mstar::model::spatial::SpatialSketch,
    solids: Vec<Solid>,
    projection: Projection,
}

/// The mechanism as drawn: a planar one in its plane (which takes no
/// `--view`), a spatial one through `--view`, its bodies as solids (and in
/// 3-D on the page).
fn figure(
    args: &AnimateArgs,
    mechanism: &Mechanism,
) -> Result<(Box<dyn Figure>, Option<Spatial3d>)> {
    match (mechanism, args.view) {
        (Mechanism::Planar(sys), None) => Ok((Box::new(PlanarFigure::new(sys.sketch())), None)),
        (Mechanism::Planar(_), Some(_)) => bail!(
            "--view is for spatial models: {} is planar and is drawn in its own plane (x right, y up)",
            args.model.display()
        ),
        (Mechanism::Spatial(sys), view) => {
            let sketch = sys.sketch();
            let u0 = sys.initial_position();
            let fallback = 0.05 * solid::spread(&sketch, &u0);
            let solids = solid::solids(sys, &sketch, &u0, fallback);
            let projection = view.unwrap_or_default();
            let figure =
                spatial::SpatialFigure::new(sketch.clone(), projection).with_solids(solids.clone());
            let model = Spatial3d {
                sketch,
                solids,
                projection,
            };
            Ok((Box::new(figure), Some(model)))
        }
    }
}

/// The frames to draw: the results file's rows, or two periods of
/// `--mode K` ([`mode_shape`]).
fn results_to_draw(
    args: &AnimateArgs,
    mechanism: &Mechanism,
    columns: &[(String, usize)],
) -> Result<Results> {
    let sys = mstar::run::lookup(mechanism);
    match (&args.results, args.mode) {
        (Some(path), _) => results::read(path, columns, sys.n_coords()),
        (None, Some(k)) => mode_frames(args, sys, k as usize),
        (None, None) => bail!("give a results file or --mode K"),
    }
}

/// Mode `k` (1-based) about the state `--about` names, as frames.
fn mode_frames(args: &AnimateArgs, sys: &dyn mstar::run::ModelLookup, k: usize) -> Result<Results> {
    let (u, lambda) = super::modes::state(args.about, sys)
        .map_err(|e| anyhow::anyhow!("{}: {e:#}", args.model.display()))?;
    let options = mstar::modes::ModesOptions {
        count: k,
        ..mstar::modes::ModesOptions::default()
    };
    let found = match mstar::modes::modes(sys, &u, &lambda, &options) {
        Ok(found) => found,
        Err(mstar::modes::ModesError::TooMany { dof: 0, .. }) => bail!(
            "{}: --mode {k}: the model has no degrees of freedom (its joints and drivers fix every \
             coordinate), so no vibration modes to draw; draw a run instead (mstar run {0} --out \
             RESULTS.csv, then mstar animate {0} RESULTS.csv)",
            args.model.display()
        ),
        Err(mstar::modes::ModesError::TooMany { dof, .. }) => bail!(
            "{}: --mode {k}: the model has {dof} degree(s) of freedom; give --mode 1 to {dof}",
            args.model.display()
        ),
        Err(e) => bail!("{}: --mode {k}: {e}", args.model.display()),
    };
    let Some(mode) = found.modes.get(k - 1) else {
        bail!(
            "{}: --mode {k}: the model has {} modes",
            args.model.display(),
            found.modes.len()
        );
    };
    let names = mstar::model::coord_names(sys);
    say!(
        "mode {k}: f = {} Hz, ζ = {}, drawn over two periods (amplitude {} × the unit-modal-mass shape)",
        Short(mode.frequency_hz),
        Short(mode.damping_ratio),
        Short(mode_shape::amplitude(&names, &u, mode))
    );
    Ok(mode_shape::frames(&names, &u, mode))
}

/// Writes each output asked for, of the frames `run`.
fn render(
    args: &AnimateArgs,
    (figure, model3d): (Box<dyn Figure>, Option<Spatial3d>),
    run: &Results,
) -> Result<()> {
    let scene = Scene::new(figure, &run.states);
    let view = View::fit(scene.bounds(&run.states), args.size.width, args.size.height);
    let canvas = Canvas {
        scene: &scene,
        view,
    };
    if args.gif.is_some() {
        let (t0, t1) = run.span();
        GifPlan::new(t1 - t0, args).check(view.width, view.height)?;
    }
    if let Some(path) = &args.html {
        write_html(path, args, &canvas, model3d.as_ref(), run)?;
    }
    if let Some(path) = &args.png {
        let (t0, t1) = run.span();
        let t = args.at.unwrap_or(t0);
        if !(t0..=t1).contains(&t) {
            bail!(
                "--at {}: the run goes from t = {} to {} s",
                Short(t),
                Short(t0),
                Short(t1)
            );
        }
        picture::write_png(path, &canvas, t, &run.at(t))?;
        say!(
            "wrote {} (t = {t:.3} s, {}×{})",
            path.display(),
            view.width,
            view.height
        );
    }
    if let Some(path) = &args.gif {
        write_gif(path, args, &canvas, run)?;
    }
    Ok(())
}

fn file_name(path: &Path) -> String {
    path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}

fn write_html(
    path: &Path,
    args: &AnimateArgs,
    canvas: &Canvas<'_>,
    model3d: Option<&Spatial3d>,
    run: &Results,
) -> Result<()> {
    let frames = run.at_most(html::MAX_FRAMES);
    let (t0, t1) = run.span();
    let what = match (&args.results, args.mode) {
        (Some(results), _) => file_name(results),
        (None, mode) => format!("mode {}", mode.unwrap_or(1)),
    };
    let title = format!(
        "mstar animate: {} with {what} (t = {} … {} s, {} frames)",
        file_name(&args.model),
        Short(t0),
        Short(t1),
        frames.times.len()
    );
    let page = match model3d {
        Some(m) => {
            let model = Model3d {
                sketch: &m.sketch,
                solids: &m.solids,
                projection: m.projection,
            };
            page3d::page(&model, canvas.scene, &canvas.view, &frames, &title)
        }
        None => html::page(canvas.scene, &canvas.view, &frames, &title),
    };
    mstar::csv::write_atomically(path, page.as_bytes())?;
    say!(
        "wrote {} ({} frames, {} kB)",
        path.display(),
        frames.times.len(),
        page.len().div_ceil(1000)
    );
    Ok(())
}

fn write_gif(path: &Path, args: &AnimateArgs, canvas: &Canvas<'_>, run: &Results) -> Result<()> {
    let (t0, t1) = run.span();
    let plan = GifPlan::new(t1 - t0, args);
    if let Some(note) = &plan.note {
        note!("note: {note}");
    }
    let frames: Vec<(f64, Vec<f64>)> = (0..plan.count)
        .map(|k| {
            let t = (t0 + plan.step * k as f64).min(t1);
            (t, run.at(t))
        })
        .collect();
    // A bar on a terminal for GIFs that take a while (indicatif draws
    // nothing elsewhere).
    let progress = if frames.len() > 100 {
        indicatif::ProgressBar::new(frames.len() as u64)
    } else {
        indicatif::ProgressBar::hidden()
    };
    let written = picture::write_gif(path, canvas, &frames, plan.delay_cs, &progress);
    progress.finish_and_clear();
    written?;
    say!(
        "wrote {} ({} frames, {}×{})",
        path.display(),
        frames.len(),
        canvas.view.width,
        canvas.view.height
    );
    Ok(())
}

/// The GIF's frames in time: how long each is shown and how much simulated
/// time lies between them.
#[derive(Clone, Debug, PartialEq)]
struct GifPlan {
    /// Each frame's delay, 1/100 s (GIF's unit).
    delay_cs: u32,
    /// Simulated time between frames, s.
    step: f64,
    /// Number of frames.
    count: usize,
    /// Why the speed differs from the one asked for, if it does.
    note: Option<String>,
}

impl GifPlan {
    /// The plan for a run lasting `span` s: real time, or over 1 s for a
    /// shorter run (or `--speed`, or the whole run in `--duration`) at
    /// `--fps`, at most `--max-frames`. A run's first and last states are
    /// both drawn; a `--mode`'s motion is periodic, and its last state (the
    /// first again) is left out so that the GIF loops without a pause: its
    /// frames split the span evenly, as many as the speed asks for, rounded.
    fn new(span: f64, args: &AnimateArgs) -> Self {
        let delay_cs = (100.0 / f64::from(args.fps)).round().max(2.0) as u32;
        let shown = f64::from(delay_cs) / 100.0;
        let speed = match (args.duration, args.speed) {
            (Some(d), _) if span > 0.0 => span / d,
            (_, Some(speed)) => speed,
            // A fast mechanism (Andrews' lasts 0.03 s) in slow motion.
            _ if span > 0.0 && span < 1.0 => span,
            _ => 1.0,
        };
        let step = speed * shown;
        let looping = args.mode.is_some() && span > 0.0;
        let count = if looping {
            ((span / step).round() as usize).max(2)
        } else if span > 0.0 {
            (span / step + 1e-9).floor() as usize + 1
        } else {
            1
        };
        let max = args.max_frames.max(1) as usize;
        if count <= max || max < 2 {
            let count = count.min(max);
            return Self {
                delay_cs,
                step: if looping { span / count as f64 } else { step },
                count,
                note: None,
            };
        }
        let step = span / (max - usize::from(!looping)) as f64;
        let note = format!(
            "{count} frames would be more than --max-frames {max}: drawing {max}, the run plays at {:.3}× real time",
            step / shown
        );
        Self {
            delay_cs,
            step,
            count: max,
            note: Some(note),
        }
    }
}

/// The most pixels a GIF may draw (frames × width × height): 10¹¹ are
/// about 330 000 frames of 640×480, hours of drawing and, uncompressed,
/// 100 GB; a request for more is a mistake in `--speed` or `--max-frames`.
const MAX_GIF_PIXELS: f64 = 1e11;

impl GifPlan {
    /// Refuses a GIF of more than [`MAX_GIF_PIXELS`] at `width`×`height`.
    ///
    /// # Errors
    /// With the estimate and a `--max-frames` that passes.
    fn check(&self, width: u32, height: u32) -> Result<()> {
        let picture = f64::from(width) * f64::from(height);
        let pixels = self.count as f64 * picture;
        if pixels <= MAX_GIF_PIXELS {
            return Ok(());
        }
        bail!(
            "the GIF would have {} frames of {width}×{height}, {} pixels (about {} uncompressed), \
             more than the {MAX_GIF_PIXELS:e} that mstar draws: use --max-frames {} or fewer, \
             a larger --speed, or a smaller --size",
            self.count,
            Short(pixels),
            crate::limits::bytes(pixels),
            (MAX_GIF_PIXELS / picture).floor()
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        args: AnimateArgs,
    }

    fn args(extra: &[&str]) -> AnimateArgs {
        let mut all = vec!["mstar", "m.toml", "r.csv", "--gif", "o.gif"];
        all.extend_from_slice(extra);
        Cli::try_parse_from(all).expect("valid arguments").args
    }

    #[test]
    fn gif_frames_follow_the_time_asked_for() {
        // 30 fps is stored as 3/100 s: a frame every 0.03 s of the run.
        let real = GifPlan::new(1.0, &args(&[]));
        assert_eq!(
            (real.delay_cs, real.count, real.note.is_none()),
            (3, 34, true)
        );
        assert!((real.step - 0.03).abs() < 1e-12);
        let slow = GifPlan::new(1.0, &args(&["--fps", "10", "--speed", "0.5"]));
        assert_eq!((slow.delay_cs, slow.count), (10, 21));
        let fit = GifPlan::new(4.0, &args(&["--fps", "10", "--duration", "2"]));
        assert_eq!(fit.count, 21);
        assert!((fit.step - 0.2).abs() < 1e-12);
        // A run of 0.03 s plays over 1 s: 34 frames, 0.03/33.3 s apart.
        let short = GifPlan::new(0.03, &args(&[]));
        assert_eq!(short.count, 34);
        assert!((short.step - 0.03 * 0.03).abs() < 1e-15);
        let capped = GifPlan::new(100.0, &args(&[]));
        assert_eq!(capped.count, 600);
        assert!((capped.step * 599.0 - 100.0).abs() < 1e-9);
        assert!(
            capped
                .note
                .as_deref()
                .unwrap_or_default()
                .contains("5.565× real time"),
            "{:?}",
            capped.note
        );
    }

    /// An absurd GIF is refused, and the `--max-frames` the refusal
    /// advises passes.
    #[test]
    fn absurd_gifs_are_refused_with_advice_that_passes() {
        let huge = GifPlan::new(
            1.0,
            &args(&["--max-frames", "100000000", "--speed", "1e-9"]),
        );
        let e = huge.check(640, 480).expect_err("refused").to_string();
        assert!(e.contains("--max-frames 325520 or fewer"), "{e}");
        let fits = GifPlan::new(1.0, &args(&["--max-frames", "325520", "--speed", "1e-9"]));
        assert_eq!(fits.count, 325_520);
        assert!(fits.check(640, 480).is_ok());
        assert!(GifPlan::new(1.0, &args(&[])).check(640, 480).is_ok());
    }

    #[test]
    fn sizes_and_numbers_are_checked() {
        assert_eq!(
            size("320x200"),
            Ok(Size {
                width: 320,
                height: 200
            })
        );
        assert!(size("320").is_err() && size("8x8").is_err() && size("axb").is_err());
        assert!(positive("0").is_err() && positive("nan").is_err() && positive("-1").is_err());
        let both = Cli::try_parse_from([
            "mstar",
            "m",
            "r",
            "--gif",
            "g",
            "--speed",
            "2",
            "--duration",
            "3",
        ]);
        assert!(both.is_err());
        let none = Cli::try_parse_from(["mstar", "m", "r"])
            .err()
            .map(|e| e.to_string());
        assert!(none.unwrap_or_default().contains("--gif"));
    }
}
