//! A model's static equilibrium (`mstar equilibrium`) for Python: the state
//! at rest as one sample with every column `mstar run` writes, and the
//! model file rewritten to start there.

use mstar::Observer;
use mstar::equilibrium::{Equilibrium, EquilibriumOptions};
use mstar::file::Mechanism;
use mstar::model::sensor::Sensor;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::collect::{Collect, Extra};
use crate::{EquilibriumError, ModelError};

/// The equilibrium of `mechanism` from its initial pose, GIL released: a
/// dict as a run's (one sample at `t = 0`, velocities zero) with
/// `equilibrium` = `{iterations, damped, residual, constraint, redundant,
/// stable}` (`redundant`: the constraint rows left out of the solve, by
/// name; `stable`: `None` when not checked, above 600 coordinates).
///
/// # Errors
/// `mstar.EquilibriumError` with `kind`
/// `"not_found"` (and `unbalanced`) or `"neutral"` (and `direction` and
/// `equilibrium`, the pose found as such a dict); `ModelError` for sensors
/// the model cannot have.
pub(crate) fn solve<'py>(
    py: Python<'py>,
    mechanism: &Mechanism,
    sensors: &[Sensor],
    origin: &str,
) -> PyResult<Bound<'py, PyDict>> {
    crate::collect::extra_columns(mechanism, sensors)
        .map_err(|e| ModelError::new_err(format!("{origin}: {e}")))?;
    let sys = mstar::run::lookup(mechanism);
    let u0 = sys.initial_position();
    let found = py.detach(|| mstar::equilibrium::solve(sys, &u0, &EquilibriumOptions::default()));
    match found {
        Ok(eq) => at_rest(py, mechanism, sensors, &eq),
        Err(e) => Err(failure(py, mechanism, sensors, origin, e)),
    }
}

/// The equilibrium `eq` as a one-sample run's dict.
fn at_rest<'py>(
    py: Python<'py>,
    mechanism: &Mechanism,
    sensors: &[Sensor],
    eq: &Equilibrium,
) -> PyResult<Bound<'py, PyDict>> {
    let sys = mstar::run::lookup(mechanism);
    let columns = crate::collect::extra_columns(mechanism, sensors)
        .map_err(|e| ModelError::new_err(e.to_string()))?;
    let mut collect = Collect::new(sys.n_coords(), sys.n_constraints());
    let zeros = vec![0.0; eq.u.len()];
    let sample = eq.at_rest(0.0, &zeros, sys.potential_energy(0.0, &eq.u));
    Extra {
        collect: &mut collect,
        columns: &*columns,
    }
    .observe(&sample);
    let d = collect.into_dict(py, columns.names())?;
    d.set_item("coords", mstar::model::coord_names(sys))?;
    d.set_item("constraints", crate::collect::constraint_names(sys))?;
    d.set_item("header", mstar::csv::header(sys))?;
    let stats = PyDict::new(py);
    stats.set_item("steps", 0)?;
    stats.set_item("wall_time", 0.0)?;
    d.set_item("stats", stats)?;
    let found = PyDict::new(py);
    found.set_item("iterations", eq.iterations)?;
    found.set_item("damped", eq.damped)?;
    found.set_item("residual", eq.residual)?;
    found.set_item("constraint", eq.constraint)?;
    let left_out: Vec<String> = eq
        .left_out
        .iter()
        .map(|&k| sys.constraint_name(k))
        .collect();
    found.set_item("redundant", left_out)?;
    let stable = match eq.stability {
        mstar::equilibrium::Stability::Stable => Some(true),
        mstar::equilibrium::Stability::Unstable { .. } => Some(false),
        mstar::equilibrium::Stability::Unchecked => None,
    };
    found.set_item("stable", stable)?;
    d.set_item("equilibrium", found)?;
    Ok(d)
}

/// `mstar.EquilibriumError` for `e`, with its findings as attributes.
fn failure(
    py: Python<'_>,
    mechanism: &Mechanism,
    sensors: &[Sensor],
    origin: &str,
    e: mstar::equilibrium::EquilibriumError,
) -> PyErr {
    let err = EquilibriumError::new_err(format!("{origin}: {}", crate::message(&e)));
    match findings(err.value(py), mechanism, sensors, &e) {
        Ok(()) => err,
        Err(other) => other,
    }
}

/// Sets `kind` on the exception `value`, and `unbalanced` (not found) or
/// `direction` and `equilibrium` (neutral).
fn findings(
    value: &Bound<'_, pyo3::exceptions::PyBaseException>,
    mechanism: &Mechanism,
    sensors: &[Sensor],
    e: &mstar::equilibrium::EquilibriumError,
) -> PyResult<()> {
    match e {
        mstar::equilibrium::EquilibriumError::NotFound { unbalanced, .. } => {
            value.setattr("kind", "not_found")?;
            value.setattr("unbalanced", unbalanced.clone())
        }
        mstar::equilibrium::EquilibriumError::Neutral {
            equilibrium,
            direction,
        } => {
            value.setattr("kind", "neutral")?;
            value.setattr("direction", direction.clone())?;
            let found = at_rest(value.py(), mechanism, sensors, equilibrium)?;
            value.setattr("equilibrium", found)
        }
        _ => value.setattr("kind", "model"),
    }
}

/// The TOML text `text` (named `origin`) with the pose `u` as its initial
/// pose ([`mstar::equilibrium::model_text`]).
///
/// # Errors
/// `ModelError` with the reason nothing can be written.
pub(crate) fn model_text(
    mechanism: &Mechanism,
    text: &str,
    origin: &str,
    u: &[f64],
) -> PyResult<String> {
    let sys = mstar::run::lookup(mechanism);
    if u.len() != sys.n_coords() {
        return Err(ModelError::new_err(format!(
            "{origin}: the pose has {} values for {} coordinates",
            u.len(),
            sys.n_coords()
        )));
    }
    mstar::equilibrium::model_text(text, origin, sys, u)
        .map_err(|e| ModelError::new_err(format!("{origin}: {e}")))
}
