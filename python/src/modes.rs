//! A model's vibration modes (`mstar modes`) for Python: the state at rest
//! `about` names, then `mstar::modes::modes`, as a dict of numpy arrays.

use mstar::file::Mechanism;
use mstar::modes::{About, Method, ModeKind, Modes, ModesError, ModesOptions};
use numpy::{PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::{EquilibriumError, ModelError};

/// `about` and `method` as Python gives them.
fn options(about: &str, method: &str) -> PyResult<(About, Method)> {
    let about = match about {
        "equilibrium" => About::Equilibrium,
        "initial" => About::Initial,
        other => {
            return Err(pyo3::exceptions::PyValueError::new_err(format!(
                "about: expected \"equilibrium\" or \"initial\", got {other:?}"
            )));
        }
    };
    let method = match method {
        "auto" => Method::Auto,
        "dense" => Method::Dense,
        "sparse" => Method::Sparse,
        other => {
            return Err(pyo3::exceptions::PyValueError::new_err(format!(
                "method: expected \"auto\", \"dense\" or \"sparse\", got {other:?}"
            )));
        }
    };
    Ok((about, method))
}

/// The lowest `count` modes (None: 10, or the degrees of freedom when
/// fewer, as `mstar modes` without `--count`) of `mechanism` about the state
/// `about` names, GIL released.
///
/// # Errors
/// `ValueError` for an unknown `about` or `method`; `mstar.EquilibriumError`
/// when there is no equilibrium to be about; `ModelError` for the
/// eigenproblem's failures (too many modes, a singular mass, the sparse
/// method on a damped model …).
pub(crate) fn solve<'py>(
    py: Python<'py>,
    mechanism: &Mechanism,
    origin: &str,
    count: Option<usize>,
    about: &str,
    method: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let (about, method) = options(about, method)?;
    let sys = mstar::run::lookup(mechanism);
    let found = py.detach(|| {
        let state = mstar::modes::rest_state(sys, &sys.initial_position(), about)?;
        let mut options = ModesOptions {
            count: count.unwrap_or(10),
            method,
            ..ModesOptions::default()
        };
        let modes = match mstar::modes::modes(sys, &state.u, &state.lambda, &options) {
            Err(ModesError::TooMany { dof, .. }) if count.is_none() => {
                options.count = dof;
                mstar::modes::modes(sys, &state.u, &state.lambda, &options)
            }
            other => other,
        };
        Ok::<_, mstar::modes::RestStateError>((state, modes))
    });
    let (state, modes) = found.map_err(|e| match e {
        mstar::modes::RestStateError::Equilibrium(_) => {
            EquilibriumError::new_err(format!("{origin}: {}", crate::message(&e)))
        }
        mstar::modes::RestStateError::Initial(_) => {
            ModelError::new_err(format!("{origin}: {}", crate::message(&e)))
        }
    })?;
    let modes =
        modes.map_err(|e| ModelError::new_err(format!("{origin}: {}", crate::message(&e))))?;
    to_dict(py, &modes, &state)
}

/// The modes as arrays: `s_re`, `s_im`, `frequency_hz`, `damping_ratio`
/// (K,), `shape`, `shape_imag` (K × n), `kind` (str each), and the state.
fn to_dict<'py>(
    py: Python<'py>,
    found: &Modes,
    state: &mstar::modes::RestState,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let column = |f: &dyn Fn(&mstar::modes::Mode) -> f64| -> Vec<f64> {
        found.modes.iter().map(f).collect()
    };
    d.set_item("s_re", PyArray1::from_vec(py, column(&|m| m.s.0)))?;
    d.set_item("s_im", PyArray1::from_vec(py, column(&|m| m.s.1)))?;
    d.set_item(
        "frequency_hz",
        PyArray1::from_vec(py, column(&|m| m.frequency_hz)),
    )?;
    d.set_item(
        "damping_ratio",
        PyArray1::from_vec(py, column(&|m| m.damping_ratio)),
    )?;
    let n = state.u.len();
    let rows = found.modes.len();
    let flat = |f: &dyn Fn(&mstar::modes::Mode) -> &[f64]| -> PyResult<Bound<'py, PyAny>> {
        let data: Vec<f64> = found
            .modes
            .iter()
            .flat_map(|m| f(m).iter().copied())
            .collect();
        Ok(PyArray1::from_vec(py, data).reshape([rows, n])?.into_any())
    };
    d.set_item("shape", flat(&|m| &m.shape)?)?;
    d.set_item("shape_imag", flat(&|m| &m.shape_imag)?)?;
    let kinds: Vec<&str> = found.modes.iter().map(|m| kind(m.kind)).collect();
    d.set_item("kind", kinds)?;
    d.set_item("dof", found.dof)?;
    d.set_item("damped", found.damped)?;
    d.set_item(
        "method",
        if found.method == Method::Sparse {
            "sparse"
        } else {
            "dense"
        },
    )?;
    d.set_item("u", PyArray1::from_vec(py, state.u.clone()))?;
    d.set_item("lam", PyArray1::from_vec(py, state.lambda.clone()))?;
    d.set_item("neutral", state.neutral)?;
    Ok(d)
}

/// A mode's kind as Python names it.
fn kind(k: ModeKind) -> &'static str {
    match k {
        ModeKind::Rigid => "rigid",
        ModeKind::Oscillating => "oscillating",
        ModeKind::Overdamped => "overdamped",
        ModeKind::Unstable => "unstable",
    }
}
