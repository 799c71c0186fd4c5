//! Model files: a mechanism and its simulation settings written down, in TOML
//! or JSON with the same keys (`docs/model-format.md`).
//!
//! ```
//! use mstar_model::file::ModelFile;
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
//! let model = ModelFile::parse(text, "bar.toml", mstar_model::file::Format::Toml)?;
//! assert_eq!(model.system.n_coords(), 3);
//! assert_eq!(model.simulation.t_end, Some(2.0));
//! # Ok::<(), mstar_model::file::FileError>(())
//! ```
//!
//! Every error names the file, the key and the element, with the line and
//! column where the format tells them (every TOML value; JSON syntax errors):
//! `bar.toml:7:8: body 'bar': mass: must be positive, in kg (got -1)`.

mod fields;
mod functions;
mod node;
mod planar;
mod settings;

use std::path::Path;

pub use planar::FORMAT;
pub use settings::{
    ErrorControlChoice, IntegratorChoice, NewtonChoice, Output, RedundantChoice, Simulation,
};

use crate::planar::PlanarSystem;
use fields::Doc;
use node::Node;

/// An error in a model file: where (when known) and what.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{}{}: {message}", .origin, .place.map(|(l, c)| format!(":{l}:{c}")).unwrap_or_default())]
pub struct FileError {
    /// The file (or what stands for it).
    pub origin: String,
    /// Line and column, from 1, when known.
    pub place: Option<(usize, usize)>,
    /// What is wrong.
    pub message: String,
}

impl FileError {
    /// An error at byte `offset` of `text`, when known.
    fn at(origin: &str, text: &str, offset: Option<usize>, message: String) -> Self {
        Self {
            origin: origin.to_string(),
            place: offset.map(|o| node::line_column(text, o)),
            message,
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
}

impl Format {
    /// The format of `path` from its extension: `.json` is JSON, anything
    /// else TOML.
    #[must_use]
    pub fn of(path: &Path) -> Self {
        match path.extension().and_then(|e| e.to_str()) {
            Some(e) if e.eq_ignore_ascii_case("json") => Self::Json,
            _ => Self::Toml,
        }
    }
}

/// A model file read and checked: the mechanism, ready to integrate, and its
/// settings.
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
        let origin = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| FileError {
            origin: origin.clone(),
            place: None,
            message: format!("cannot read the model file: {e}"),
        })?;
        Self::parse_with(&text, &origin, Format::of(path), overrides)
    }

    /// Reads and checks a model from `text`; `origin` names it in errors.
    ///
    /// # Errors
    /// As [`load`](Self::load).
    pub fn parse(text: &str, origin: &str, format: Format) -> Result<Self, FileError> {
        Self::parse_with(text, origin, format, &[])
    }

    /// [`parse`](Self::parse) with overrides `path=value`, each a dotted path
    /// of table keys (`simulation.h`, `output.every`) and a TOML value
    /// (`1e-4`, `"hht"`, or a bare word, taken as a string). Overridden
    /// values have no line in errors.
    ///
    /// # Errors
    /// As [`load`](Self::load), and for an override without `=` or with a path
    /// through something that is not a table.
    pub fn parse_with(
        text: &str,
        origin: &str,
        format: Format,
        overrides: &[String],
    ) -> Result<Self, FileError> {
        let mut root = match format {
            Format::Toml => node::parse_toml(text, origin)?,
            Format::Json => node::parse_json(text, origin)?,
        };
        for o in overrides {
            settings::apply_override(&mut root, o).map_err(|why| FileError {
                origin: origin.to_string(),
                place: None,
                message: format!("--set {o}: {why}"),
            })?;
        }
        let doc = Doc { origin, text };
        read(doc, &root)
    }
}

/// The mechanism and the settings of a parsed document.
fn read(doc: Doc<'_>, root: &Node) -> Result<ModelFile, FileError> {
    let system = planar::read(doc, root)?;
    let (simulation, output) = settings::read(doc, root)?;
    Ok(ModelFile {
        system,
        simulation,
        output,
    })
}
