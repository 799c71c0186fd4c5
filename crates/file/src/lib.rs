//! Model files: a mechanism and its simulation settings written down, in TOML
//! or JSON with the same keys (`docs/model-format.md`).
//!
//! ```
//! use mstar_file::ModelFile;
//! use mstar_model::System;
//!
//! let text = r#"
//! format = "mstar.planar/1"
//!
//! [[body]]
//! name = "bar"
//! mass = 1.0
//! inertia = 0.0833
//! pose = [0.5, 0.0, 0.0]
//!
//! [[joint]]
//! name = "hinge"
//! type = "revolute"
//! bodies = ["ground", "bar"]
//! at = [0.0, 0.0]
//!
//! [simulation]
//! t_end = 2.0
//! "#;
//! let model = ModelFile::parse(text, "bar.toml", mstar_file::Format::Toml)?;
//! assert_eq!(model.system.n_coords(), 3);
//! assert_eq!(model.simulation.t_end, Some(2.0));
//! # Ok::<(), mstar_file::FileError>(())
//! ```
//!
//! Every error names the file, the key and the element, with the line and
//! column where the format tells them (every TOML value; JSON syntax errors):
//! `bar.toml:7:8: body 'bar': mass: must be positive, in kg (got -1)`.
//!
//! URDF robots (`.urdf`, [`Format::Urdf`]) are read as the
//! `mstar.spatial/1` document they mean ([`convert_urdf`] writes it), and a
//! spatial file may start from one (`urdf = "arm.urdf"`); errors in the
//! URDF name its line and column too.

mod bodies;
mod document;
mod fields;
mod functions;
mod keys;
mod node;
mod planar;
pub mod pose;
mod sensors;
mod settings;
mod spatial;
mod urdf;

use std::path::Path;

pub use document::ModelDocument;
pub use fields::MAX_MAGNITUDE;
pub use planar::FORMAT;
pub use settings::{
    ErrorControlChoice, IntegratorChoice, NewtonChoice, Output, RedundantChoice, SettingPlaces,
    Simulation,
};
pub use spatial::FORMAT as SPATIAL_FORMAT;

use fields::Doc;
use mstar_model::planar::PlanarSystem;
use mstar_model::spatial::SpatialSystem;
use node::Node;

/// An error in a model file: where (when known) and what.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
#[error("{}{}: {message}", .origin, .place.map(|(l, c)| format!(":{l}:{c}")).unwrap_or_default())]
pub struct FileError {
    /// The file (or what stands for it).
    pub origin: String,
    /// Line and column, from 1, when known.
    pub place: Option<(usize, usize)>,
    /// What is wrong.
    pub message: String,
    /// The error is in a command-line override (`--set KEY=VALUE`) rather
    /// than in the model: a malformed assignment, a path through an element
    /// or key the file does not have, or a key the reader does not know.
    /// (A value out of range is the model's error even when an override gave
    /// it.) A sweep refuses such overrides before it runs anything.
    pub in_override: bool,
}

impl FileError {
    /// An error at byte `offset` of `text`, when known.
    fn at(origin: &str, text: &str, offset: Option<usize>, message: String) -> Self {
        Self {
            origin: origin.to_string(),
            place: offset.map(|o| node::line_column(text, o)),
            message,
            in_override: false,
        }
    }

    /// An error of the file `origin` with no place.
    fn unplaced(origin: &str, message: String) -> Self {
        Self::at(origin, "", None, message)
    }

    /// The error marked as one of an override ([`in_override`](Self::in_override)).
    #[must_use]
    pub(crate) fn of_override(self) -> Self {
        Self {
            in_override: true,
            ..self
        }
    }
}

/// The syntax of a model file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// TOML (`.toml`).
    Toml,
    /// JSON (`.json`).
    Json,
    /// A URDF robot description (`.urdf`, XML), read as the
    /// `mstar.spatial/1` model it means ([`convert_urdf`]).
    Urdf,
}

impl Format {
    /// The format of `path` from its extension: `.json` is JSON, `.urdf`
    /// URDF, anything else TOML.
    #[must_use]
    pub fn of(path: &Path) -> Self {
        match path.extension().and_then(|e| e.to_str()) {
            Some(e) if e.eq_ignore_ascii_case("json") => Self::Json,
            Some(e) if e.eq_ignore_ascii_case("urdf") => Self::Urdf,
            _ => Self::Toml,
        }
    }
}

/// A planar model file (`format = "mstar.planar/1"`) read and checked: the
/// mechanism, ready to integrate, and its settings. [`MechanismFile`] reads
/// planar and spatial files alike.
#[derive(Clone, Debug)]
pub struct ModelFile {
    /// The mechanism.
    pub system: PlanarSystem,
    /// `[simulation]`: every key optional.
    pub simulation: Simulation,
    /// `[output]`.
    pub output: Output,
}

impl ModelFile {
    /// Reads and checks the model file at `path`.
    ///
    /// # Errors
    /// [`FileError`] for a file that cannot be read, a syntax error, or any
    /// key that is unknown, missing, of the wrong type or out of range.
    pub fn load(path: &Path) -> Result<Self, FileError> {
        Self::load_with(path, &[])
    }

    /// [`load`](Self::load) with overrides `key=value` applied first (the
    /// command line's `--set simulation.h=1e-4`; see [`parse_with`](Self::parse_with)).
    ///
    /// # Errors
    /// As [`load`](Self::load), and for a malformed override.
    pub fn load_with(path: &Path, overrides: &[String]) -> Result<Self, FileError> {
        Self::planar(
            MechanismFile::load_with(path, overrides)?,
            &path.display().to_string(),
        )
    }

    /// Reads and checks a model from `text`; `origin` names it in errors.
    ///
    /// # Errors
    /// As [`load`](Self::load).
    pub fn parse(text: &str, origin: &str, format: Format) -> Result<Self, FileError> {
        Self::parse_with(text, origin, format, &[])
    }

    /// [`parse`](Self::parse) with overrides `path=value`, each a dotted path
    /// of keys — table keys, and in an array of named elements the element's
    /// `name` (`simulation.h`, `output.every`, `body.upper.mass`,
    /// `force.drive.function.constant`) — and a TOML value (`1e-4`, `"hht"`,
    /// or a bare word, taken as a string). An error about a value an
    /// override gave names the override (`--set body.upper.mass=-1: …`)
    /// instead of a line of the file.
    ///
    /// # Errors
    /// As [`load`](Self::load), and for an override without `=`, with a path
    /// through something that is not a table, an element or key the file does
    /// not have, or a last key the reader does not know (these errors have
    /// [`FileError::in_override`] set).
    pub fn parse_with(
        text: &str,
        origin: &str,
        format: Format,
        overrides: &[String],
    ) -> Result<Self, FileError> {
        Self::planar(
            MechanismFile::parse_with(text, origin, format, overrides)?,
            origin,
        )
    }

    /// The planar model of `file`; an error naming `origin` for a spatial one.
    fn planar(file: MechanismFile, origin: &str) -> Result<Self, FileError> {
        match file.mechanism {
            Mechanism::Planar(system) => Ok(Self {
                system,
                simulation: file.simulation,
                output: file.output,
            }),
            Mechanism::Spatial(_) => Err(FileError::unplaced(
                origin,
                format!(
                    "a spatial model ('{SPATIAL_FORMAT}'), where a planar one ('{FORMAT}') is expected"
                ),
            )),
        }
    }
}

/// The mechanism of a model file: planar or spatial, by its `format`.
#[derive(Clone, Debug)]
pub enum Mechanism {
    /// `format = "mstar.planar/1"`.
    Planar(PlanarSystem),
    /// `format = "mstar.spatial/1"`.
    Spatial(SpatialSystem),
}

impl Mechanism {
    /// The mechanism as a [`System`](mstar_model::System).
    #[must_use]
    pub fn system(&self) -> &(dyn mstar_model::System + 'static) {
        match self {
            Self::Planar(s) => s,
            Self::Spatial(s) => s,
        }
    }
}

/// A model file of either format read and checked: the mechanism, its
/// settings and the warnings about it.
///
/// ```
/// use mstar_file::{Format, Mechanism, MechanismFile};
///
/// let text = r#"
/// format = "mstar.spatial/1"
///
/// [[body]]
/// name = "top"
/// mass = 2.0
/// inertia = [0.05, 0.05, 0.08]
/// position = [0.0, 0.0, 0.25]
/// orientation = [2.0, 0.0, 0.0, 0.0]
///
/// [[joint]]
/// name = "tip"
/// type = "spherical"
/// bodies = ["ground", "top"]
/// points = [[0.0, 0.0, 0.0], [0.0, 0.0, -0.25]]
/// "#;
/// let file = MechanismFile::parse(text, "top.toml", Format::Toml)?;
/// assert!(matches!(file.mechanism, Mechanism::Spatial(_)));
/// assert_eq!(file.mechanism.system().n_coords(), 7);
/// // The orientation was normalized, with a warning that says where.
/// assert!(file.warnings[0].starts_with("top.toml:9:15: body 'top': orientation"));
/// # Ok::<(), mstar_file::FileError>(())
/// ```
#[derive(Clone, Debug)]
pub struct MechanismFile {
    /// The mechanism.
    pub mechanism: Mechanism,
    /// `[simulation]`: every key optional.
    pub simulation: Simulation,
    /// `[output]`.
    pub output: Output,
    /// Warnings about values the reader changed (an orientation normalized),
    /// each `FILE:LINE:COLUMN: element: key: what`.
    pub warnings: Vec<String>,
}

impl MechanismFile {
    /// Reads and checks the model file at `path`, planar or spatial.
    ///
    /// # Errors
    /// As [`ModelFile::load`].
    pub fn load(path: &Path) -> Result<Self, FileError> {
        Self::load_with(path, &[])
    }

    /// [`load`](Self::load) with overrides (as [`ModelFile::load_with`]).
    ///
    /// # Errors
    /// As [`ModelFile::load_with`].
    pub fn load_with(path: &Path, overrides: &[String]) -> Result<Self, FileError> {
        let origin = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| {
            FileError::unplaced(&origin, format!("cannot read the model file: {e}"))
        })?;
        Self::parse_with(&text, &origin, Format::of(path), overrides)
    }

    /// Reads and checks a model from `text`; `origin` names it in errors.
    ///
    /// # Errors
    /// As [`ModelFile::load`].
    pub fn parse(text: &str, origin: &str, format: Format) -> Result<Self, FileError> {
        Self::parse_with(text, origin, format, &[])
    }

    /// [`parse`](Self::parse) with overrides (as [`ModelFile::parse_with`]).
    ///
    /// # Errors
    /// As [`ModelFile::parse_with`].
    pub fn parse_with(
        text: &str,
        origin: &str,
        format: Format,
        overrides: &[String],
    ) -> Result<Self, FileError> {
        let (root, notes, places) = document(text, origin, format, overrides)?;
        let doc = Doc {
            origin,
            text,
            overrides,
        };
        // An error in a URDF's body or joint: at the URDF's element (unless
        // an override may have given the value).
        let mut file = read(doc, &root).map_err(|e| match &places {
            Some(p) if overrides.is_empty() => p.locate(e),
            _ => e,
        })?;
        // The URDF's notes first: they are about what the model is made of.
        file.warnings.splice(0..0, notes);
        Ok(file)
    }
}

impl MechanismFile {
    /// The value of the model parameter at the dotted key `key` of the model
    /// file at `path`, with `overrides` applied first: a key of a table or an
    /// element's name then its key, as `--set KEY=VALUE` names them
    /// (`body.crank.mass`, `joint.rod.length`).
    ///
    /// # Errors
    /// [`FileError`] as [`load_with`](Self::load_with) for the document, and
    /// for a key that names nothing or a value that is not a number, with the
    /// closest numeric keys of the file, or a key of `[simulation]` or
    /// `[output]` (settings of the run, not of the model).
    pub fn parameter(path: &Path, overrides: &[String], key: &str) -> Result<f64, FileError> {
        ModelDocument::load(path, overrides)?.parameter(key)
    }
}

/// What a model document reads as: its tree (a URDF, or a spatial file
/// that starts from one, expanded), the URDF's notes and places, with
/// `overrides` applied.
fn document(
    text: &str,
    origin: &str,
    format: Format,
    overrides: &[String],
) -> Result<(node::Node, Vec<String>, Option<urdf::Places>), FileError> {
    let doc = Doc {
        origin,
        text,
        overrides,
    };
    let (mut root, mut notes, mut places) = match format {
        Format::Toml => (node::parse_toml(text, origin)?, Vec::new(), None),
        Format::Json => (node::parse_json(text, origin)?, Vec::new(), None),
        Format::Urdf => {
            let read = urdf::read(text, origin)?;
            (read.root, read.notes, Some(read.places))
        }
    };
    // A spatial file that starts from a URDF (`urdf = "arm.urdf"`):
    // expanded first, so that overrides reach the URDF's bodies too.
    if is_spatial(&root)
        && let Some(read) = urdf::expand(doc, &root)?
    {
        (root, notes, places) = (read.root, read.notes, Some(read.places));
    }
    for (k, o) in overrides.iter().enumerate() {
        settings::apply_override(&mut root, o, k).map_err(|why| {
            FileError::unplaced(origin, format!("--set {o}: {why}")).of_override()
        })?;
    }
    Ok((root, notes, places))
}

/// The number the dotted `key` (the `--set` syntax: `force.push.fx`,
/// `body.upper.mass`) holds in the model file at `path`, after the
/// `overrides`: what a key's value is before a command changes it (the
/// inputs of `mstar linearize`). TOML and JSON files; a URDF's keys are
/// those of the spatial document it means.
///
/// # Errors
/// [`FileError`] when the file cannot be read, a step of the path is not
/// there (naming the keys or elements that are), or the key holds something
/// other than a number (`FILE:LINE:COLUMN` of the value where known).
pub fn number_at(path: &Path, overrides: &[String], key: &str) -> Result<f64, FileError> {
    let origin = path.display().to_string();
    let text = std::fs::read_to_string(path)
        .map_err(|e| FileError::unplaced(&origin, format!("cannot read the model file: {e}")))?;
    let (mut root, _, _) = document(&text, &origin, Format::of(path), overrides)?;
    let node = settings::lookup(&mut root, key)
        .map_err(|why| FileError::unplaced(&origin, format!("{key}: {why}")))?;
    match node.value {
        node::Value::Num { value, .. } => Ok(value),
        ref other => Err(Doc {
            origin: &origin,
            text: &text,
            overrides,
        }
        .error(
            node.span.as_ref(),
            format!(
                "{key}: is {}, not a number (name the number itself, e.g. force.push.fx.constant or force.push.fx.harmonic.offset)",
                other.kind()
            ),
        )),
    }
}

impl Simulation {
    /// The `[simulation]` of a planar model made in code (no file): the
    /// defaults with the overrides `simulation.key=value` applied and checked
    /// as [`MechanismFile::parse_with`] checks a file's (the same messages;
    /// `origin` names the model in them).
    ///
    /// # Errors
    /// [`FileError`] for a malformed override, an unknown key or a value out
    /// of range.
    pub fn with_overrides(origin: &str, overrides: &[String]) -> Result<Self, FileError> {
        let mut root = node::parse_toml("", origin)?;
        for (k, o) in overrides.iter().enumerate() {
            settings::apply_override(&mut root, o, k).map_err(|why| {
                FileError::unplaced(origin, format!("--set {o}: {why}")).of_override()
            })?;
        }
        let doc = Doc {
            origin,
            text: "",
            overrides,
        };
        Ok(settings::read(doc, &root, false)?.0)
    }
}

/// The `mstar.spatial/1` model file of the URDF robot `text` (the file
/// `origin`, named in errors and in the document's first comment), and
/// one note for each kind of URDF element read and ignored (`<limit>`,
/// `<visual>`, …) and for each massless link left out, each
/// `FILE:LINE:COLUMN: what`. Reading the document gives the model
/// [`MechanismFile::load`] reads from the URDF, bit for bit.
///
/// # Errors
/// [`FileError`] for malformed XML (`FILE:LINE:COLUMN`), a joint type other
/// than revolute, continuous, prismatic or fixed, a joint naming a link the
/// file does not have, a cycle, two root links, a massless link between
/// moving joints, or a name given to a link and a joint.
pub fn convert_urdf(text: &str, origin: &str) -> Result<(String, Vec<String>), FileError> {
    urdf::convert(text, origin)
}

/// The files the model file at `path` reads besides itself: the URDF a
/// spatial file starts from (`urdf = "arm.urdf"`, relative to the file),
/// whether or not it exists. Empty when the file cannot be read or parsed
/// (loading it reports why): the CLI uses this to keep outputs off inputs
/// and to fingerprint a model with everything it reads.
pub fn included_files(path: &Path) -> Vec<std::path::PathBuf> {
    let Ok(text) = std::fs::read_to_string(path) else {
        return Vec::new();
    };
    let origin = path.display().to_string();
    let root = match Format::of(path) {
        Format::Toml => node::parse_toml(&text, &origin),
        Format::Json => node::parse_json(&text, &origin),
        Format::Urdf => return Vec::new(),
    };
    let Ok(root) = root else {
        return Vec::new();
    };
    let node::Value::Table(entries) = &root.value else {
        return Vec::new();
    };
    let urdf = entries.iter().find_map(|e| match &e.node.value {
        node::Value::Str(file) if e.key == "urdf" => Some(file),
        _ => None,
    });
    match urdf {
        Some(file) if is_spatial(&root) => {
            vec![path.parent().unwrap_or(Path::new("")).join(file)]
        }
        _ => Vec::new(),
    }
}

/// Whether the document says `format = "mstar.spatial/1"`.
fn is_spatial(root: &Node) -> bool {
    let node::Value::Table(entries) = &root.value else {
        return false;
    };
    entries.iter().any(|e| {
        e.key == "format" && matches!(&e.node.value, node::Value::Str(s) if s == SPATIAL_FORMAT)
    })
}

/// The mechanism and the settings of a parsed document.
fn read(doc: Doc<'_>, root: &Node) -> Result<MechanismFile, FileError> {
    let (mechanism, simulation, output, warnings) = if is_spatial(root) {
        // The settings first: they say how to form the mass matrix.
        let (simulation, mut output) = settings::read(doc, root, true)?;
        let mode = simulation.rotational_mass.unwrap_or_default();
        let (system, warnings, sensors) = spatial::read(doc, root, mode)?;
        output.sensors = sensors;
        (Mechanism::Spatial(system), simulation, output, warnings)
    } else {
        let (system, sensors) = planar::read(doc, root)?;
        let (simulation, mut output) = settings::read(doc, root, false)?;
        output.sensors = sensors;
        (Mechanism::Planar(system), simulation, output, Vec::new())
    };
    Ok(MechanismFile {
        mechanism,
        simulation,
        output,
        warnings,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `included_files` names the URDF a spatial file starts from, beside
    /// the file, and nothing for a file that reads none or cannot be read.
    #[test]
    fn included_files_names_a_spatial_file_s_urdf() {
        let dir = std::env::temp_dir().join(format!("mstar-file-included-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("a scratch directory");
        let spatial = dir.join("arm.toml");
        std::fs::write(
            &spatial,
            "format = \"mstar.spatial/1\"\nurdf = \"arm.urdf\"\n",
        )
        .expect("written");
        assert_eq!(included_files(&spatial), vec![dir.join("arm.urdf")]);
        let planar = dir.join("bar.toml");
        std::fs::write(
            &planar,
            "format = \"mstar.planar/1\"\nurdf = \"arm.urdf\"\n",
        )
        .expect("written");
        assert!(included_files(&planar).is_empty());
        assert!(included_files(&dir.join("missing.toml")).is_empty());
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// `number_at` reads a key's number as the file (after the overrides)
    /// has it, and says where a key holds no number or is not there.
    #[test]
    fn number_at_reads_keys_and_places_errors() {
        let text = "format = \"mstar.planar/1\"\n\n[[body]]\nname = \"bar\"\nmass = 1.5\ninertia = 0.1\npose = [0.0, 0.0, 0.0]\n\n[[force]]\nname = \"push\"\ntype = \"force\"\nbody = \"bar\"\nfx = { constant = 0.25 }\n";
        let dir = std::env::temp_dir().join(format!("mstar-file-number-at-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("a scratch directory");
        let path = dir.join("bar.toml");
        std::fs::write(&path, text).expect("written");
        let at = |overrides: &[&str], key: &str| {
            let o: Vec<String> = overrides.iter().map(|s| (*s).to_string()).collect();
            number_at(&path, &o, key)
        };
        assert_eq!(at(&[], "body.bar.mass"), Ok(1.5));
        assert_eq!(at(&[], "force.push.fx.constant"), Ok(0.25));
        assert_eq!(
            at(&["force.push.fx.constant=2"], "force.push.fx.constant"),
            Ok(2.0)
        );
        let table = at(&[], "force.push.fx").expect_err("a table");
        assert_eq!(table.place, Some((13, 6)), "{table}");
        assert!(table.message.contains("not a number"), "{table}");
        let missing = at(&[], "force.pull.fx").expect_err("no such force");
        assert!(missing.message.contains("the names are: push"), "{missing}");
        let settings = at(&[], "simulation.h").expect_err("no [simulation]");
        assert!(settings.message.contains("no [simulation]"), "{settings}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
