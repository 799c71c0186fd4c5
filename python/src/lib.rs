//! The `mstar` Python package's native module, `mstar._native`: model files
//! and planar builders as models, runs with the GIL released, results as
//! numpy arrays. The Python layer (`python/mstar/`) wraps it; the API is in
//! `docs/python.md`.
//!
//! Errors carry the messages the command line prints after `error: `
//! ([`mstar::run::error_message`]): `ModelError` for what `mstar run` exits
//! 2 on (a file that cannot be read, a key out of range, a setting no solver
//! has), `IntegrationError` for a run that fails (exit 1), with the samples
//! up to the failure attached as `partial`. Both derive from `Error`, and
//! all three are named `mstar.*` (the package re-exports them); the Python
//! layer (`python/mstar/_errors.py`) puts the options the messages name in
//! Python's words.

use pyo3::create_exception;
use pyo3::prelude::*;

mod builder;
mod cli;
mod collect;
mod equilibrium;
mod model;
mod modes;
mod spatial;
mod sweep;

create_exception!(
    mstar,
    Error,
    pyo3::exceptions::PyException,
    "The base of mstar's own exceptions."
);
create_exception!(
    mstar,
    ModelError,
    Error,
    "A model that cannot be read or built, or a setting out of range (`mstar run` exits 2)."
);
create_exception!(
    mstar,
    IntegrationError,
    Error,
    "A run that fails: its start, a step, or refused redundant constraints (`mstar run` exits 1). `partial` holds the samples so far."
);

create_exception!(
    mstar,
    EquilibriumError,
    Error,
    "No static equilibrium: none found (`kind` \"not_found\", `unbalanced` the coordinates with the largest unbalanced force), or a neutral one (`kind` \"neutral\", `direction`, `equilibrium`); `mstar equilibrium` exits 1."
);

/// The message of a library error as the command line prints it.
pub(crate) fn message(e: &(dyn std::error::Error + 'static)) -> String {
    mstar::run::error_message(e)
}

/// `mstar._native`.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("Error", py.get_type::<Error>())?;
    m.add("ModelError", py.get_type::<ModelError>())?;
    m.add("IntegrationError", py.get_type::<IntegrationError>())?;
    m.add("EquilibriumError", py.get_type::<EquilibriumError>())?;
    m.add_class::<model::NativeModel>()?;
    m.add_class::<builder::PlanarBuilder>()?;
    m.add_class::<builder::Body>()?;
    m.add_class::<builder::Point>()?;
    m.add_class::<builder::TimeFunction>()?;
    m.add_function(wrap_pyfunction!(model::load_path, m)?)?;
    m.add_function(wrap_pyfunction!(model::load_text, m)?)?;
    m.add_function(wrap_pyfunction!(builder::ground, m)?)?;
    m.add_function(wrap_pyfunction!(sweep::sweep, m)?)?;
    m.add_class::<spatial::SpatialBuilder>()?;
    m.add_class::<spatial::SpatialBody>()?;
    m.add_class::<spatial::SpatialPoint>()?;
    m.add_function(wrap_pyfunction!(spatial::spatial_ground, m)?)?;
    m.add_function(wrap_pyfunction!(cli::cli_main, m)?)?;
    Ok(())
}
