//! `mstar.sweep`: a model file run for many values of its keys, the runs
//! spread over the cores with the GIL released (`mstar::sweep`, the library
//! behind `mstar sweep`; docs/sweeps.md).

use std::path::PathBuf;

use mstar::sweep::{Combine, Options, Param, Plan, Shard, SweepError, run_plan};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::ModelError;

/// A sweep's error as Python sees it: `OSError` for a file that cannot be
/// written, `ModelError` (what `mstar sweep` exits 2 on) for the rest, with
/// the command line's message.
fn sweep_error(e: &SweepError) -> PyErr {
    match e {
        SweepError::Io { .. } => pyo3::exceptions::PyOSError::new_err(crate::message(e)),
        _ => ModelError::new_err(crate::message(e)),
    }
}

/// Runs `model` for the values `params` (key, values written as `--set`
/// takes them) combined as a grid (every combination) or zipped, into the
/// directory `out`, as `mstar sweep` does: `jobs` runs at once (default one
/// per core), only the runs of `shard = (i, n)` when given. Returns the run
/// counts, the failed runs `(index, message)` and the summary file's path.
#[pyfunction]
#[pyo3(signature = (model, params, out, zip = false, jobs = None, shard = None))]
pub(crate) fn sweep(
    py: Python<'_>,
    model: PathBuf,
    params: Vec<(String, Vec<String>)>,
    out: PathBuf,
    zip: bool,
    jobs: Option<usize>,
    shard: Option<(usize, usize)>,
) -> PyResult<Py<PyDict>> {
    let params = params
        .into_iter()
        .map(|(key, values)| Param::new(&key, values))
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| sweep_error(&e))?;
    let combine = if zip { Combine::Zip } else { Combine::Grid };
    let plan = Plan::new(&model, params, combine).map_err(|e| sweep_error(&e))?;
    let mut options = Options::new(out);
    options.jobs = jobs;
    if let Some((i, n)) = shard {
        options.shard = Shard::parse(&format!("{i}/{n}")).map_err(|e| sweep_error(&e))?;
    }
    let report = py
        .detach(|| run_plan(&plan, &options, &()))
        .map_err(|e| sweep_error(&e))?;
    let dict = PyDict::new(py);
    dict.set_item("ran", report.ran)?;
    dict.set_item("skipped", report.skipped)?;
    dict.set_item("failed", report.failed)?;
    dict.set_item("beyond", report.beyond)?;
    dict.set_item("summary", report.summary)?;
    dict.set_item("runs", plan.len())?;
    Ok(dict.unbind())
}
