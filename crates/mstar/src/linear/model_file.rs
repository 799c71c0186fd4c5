//! A state-space model of a model file in one call ([`from_file`]): the
//! operating point, the inputs built from the file's keys, the outputs from
//! its columns. What `mstar linearize` does (and Python can).

use std::path::Path;

use mstar_file::MechanismFile;

use super::{Input, LinearError, OperatingPoint, StateSpace, at_rest, input, input_step};
use crate::equilibrium::{EquilibriumError, EquilibriumOptions};
use crate::run::ModelLookup;

pub use crate::modes::About;

/// What [`from_file`] forms.
#[derive(Clone, Copy, Debug, Default)]
pub struct Request<'a> {
    /// The operating point.
    pub about: About,
    /// Input keys (`force.push.fx`).
    pub inputs: &'a [String],
    /// Output columns or `*` patterns.
    pub outputs: &'a [String],
    /// `--set KEY=VALUE` overrides of the file.
    pub overrides: &'a [String],
}

/// A model formed by [`from_file`], and the warnings on the way (the
/// file's, a neutral equilibrium).
#[derive(Clone, Debug)]
pub struct FromFile {
    /// The model.
    pub model: StateSpace,
    /// Warnings, each a sentence.
    pub warnings: Vec<String>,
}

/// The state-space model of the model file at `path`
/// (`docs/analysis.md`, "Linear state-space models").
///
/// # Errors
/// [`LinearError`]: the file or a key ([`LinearError::is_usage`]), no
/// operating point, or no model there.
pub fn from_file(path: &Path, request: &Request<'_>) -> Result<FromFile, LinearError> {
    let file = MechanismFile::load_with(path, request.overrides)?;
    let mut warnings = file.warnings.clone();
    let sys = crate::run::lookup(&file.mechanism);
    let n = sys.n_coords();
    if n > super::MAX_COORDS {
        return Err(LinearError::TooLarge {
            n,
            max: super::MAX_COORDS,
        });
    }
    let u0 = sys.initial_position();
    let op = match request.about {
        About::Equilibrium => equilibrium(sys, &u0, &mut warnings)?,
        About::Initial => at_rest(sys, 0.0, &u0)?,
    };
    let inputs = request
        .inputs
        .iter()
        .map(|key| file_input(path, request.overrides, key, &op))
        .collect::<Result<Vec<_>, _>>()?;
    let model = super::state_space(sys, &op, &inputs, request.outputs, &file.output.sensors)?;
    Ok(FromFile { model, warnings })
}

/// The equilibrium from `u0`; a neutral one (its free direction a zero
/// eigenvalue pair of `A`) with a warning.
fn equilibrium(
    sys: &dyn ModelLookup,
    u0: &[f64],
    warnings: &mut Vec<String>,
) -> Result<OperatingPoint, LinearError> {
    let eq = match crate::equilibrium::solve(sys, u0, &EquilibriumOptions::default()) {
        Ok(eq) => eq,
        Err(EquilibriumError::Neutral {
            equilibrium,
            direction,
        }) => {
            let along: Vec<&str> = direction.iter().map(|(n, _)| n.as_str()).collect();
            warnings.push(format!(
                "the equilibrium is neutral along {}: nothing resists that motion, and A has a zero eigenvalue pair for it",
                along.join(", ")
            ));
            *equilibrium
        }
        Err(e) => return Err(LinearError::NoEquilibrium(Box::new(e))),
    };
    Ok(OperatingPoint {
        about: "equilibrium".into(),
        t: 0.0,
        a: vec![0.0; eq.u.len()],
        u: eq.u,
        lambda: eq.lambda,
    })
}

/// The input `key`: its value in the file (after `overrides`), and `∂g/∂p`
/// from the models built with it changed by `± h` ([`input_step`]).
fn file_input(
    path: &Path,
    overrides: &[String],
    key: &str,
    op: &OperatingPoint,
) -> Result<Input, LinearError> {
    if key.trim().starts_with("driver.") {
        return Err(LinearError::DriverInput {
            key: key.to_string(),
        });
    }
    let value = mstar_file::number_at(path, overrides, key)?;
    let h = input_step(value);
    let build = |p: f64| {
        let mut sets = overrides.to_vec();
        sets.push(format!("{key}={p:e}"));
        MechanismFile::load_with(path, &sets)
    };
    let (plus, minus) = (build(value + h)?, build(value - h)?);
    let systems = [plus.mechanism.system(), minus.mechanism.system()];
    input(key, value, h, systems, op)
}
