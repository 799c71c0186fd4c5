//! The samples of a run in memory, column by column, and their hand-over to
//! Python as numpy arrays.

use std::time::Instant;

use mstar::System;
use mstar::columns::OutputColumns;
use mstar::csv::Columns;
use mstar::file::Mechanism;
use mstar::model::sensor::Sensor;
use mstar::{Observer, RunStats, SampleRef};
use numpy::{PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// Every sample of a run (the CSV's standard columns, `mstar::csv::header`),
/// row-major, and when the stepping began.
#[derive(Debug)]
pub(crate) struct Collect {
    n: usize,
    m: usize,
    t: Vec<f64>,
    u: Vec<f64>,
    v: Vec<f64>,
    a: Vec<f64>,
    lambda: Vec<f64>,
    energy: Vec<f64>,
    iterations: Vec<i64>,
    residual: Vec<f64>,
    constraint: Vec<f64>,
    /// The values of the model's further columns ([`Extra`]), row-major.
    extra: Vec<f64>,
    /// When the initial state was observed: the start of the stepping, as
    /// `mstar run` times it.
    started: Option<Instant>,
}

impl Collect {
    /// For a model of `n` coordinates and `m` constraint rows.
    pub(crate) fn new(n: usize, m: usize) -> Self {
        Self {
            n,
            m,
            t: Vec::new(),
            u: Vec::new(),
            v: Vec::new(),
            a: Vec::new(),
            lambda: Vec::new(),
            energy: Vec::new(),
            iterations: Vec::new(),
            residual: Vec::new(),
            constraint: Vec::new(),
            extra: Vec::new(),
            started: None,
        }
    }

    /// Makes room for `rows` samples up front, the large buffers advised for
    /// transparent huge pages: a 10⁴-bar chain's state is 880 KB a step,
    /// and faulting it in 4 KB pages cost a fifth of the stepping time
    /// (`python/benches/chain.py`); 2 MB pages cost almost nothing.
    pub(crate) fn reserve(&mut self, rows: usize) {
        for (buffer, width) in [
            (&mut self.u, self.n),
            (&mut self.v, self.n),
            (&mut self.a, self.n),
            (&mut self.lambda, self.m),
        ] {
            buffer.reserve_exact(rows.saturating_mul(width));
            advise_huge_pages(buffer);
        }
        for buffer in [
            &mut self.t,
            &mut self.energy,
            &mut self.residual,
            &mut self.constraint,
        ] {
            buffer.reserve_exact(rows);
        }
        self.iterations.reserve_exact(rows);
    }

    /// Seconds since the initial state was observed (0 before).
    pub(crate) fn wall(&self) -> f64 {
        self.started.map_or(0.0, |s| s.elapsed().as_secs_f64())
    }
}

/// Asks Linux to back the 2 MB-aligned part of `buffer`'s capacity with
/// huge pages (a hint: nothing happens where they are not available).
#[cfg(target_os = "linux")]
fn advise_huge_pages(buffer: &mut Vec<f64>) {
    const HUGE: usize = 2 << 20;
    let start = buffer.as_mut_ptr() as usize;
    let end = start + buffer.capacity() * std::mem::size_of::<f64>();
    let (from, to) = (start.next_multiple_of(HUGE), end / HUGE * HUGE);
    if to > from {
        // SAFETY: [from, to) lies within the buffer's allocation, which this
        // Vec owns; MADV_HUGEPAGE changes how its pages are backed, never its
        // contents.
        unsafe {
            libc::madvise(from as *mut libc::c_void, to - from, libc::MADV_HUGEPAGE);
        }
    }
}

#[cfg(not(target_os = "linux"))]
fn advise_huge_pages(_buffer: &mut Vec<f64>) {}

impl Observer for Collect {
    fn observe(&mut self, s: &SampleRef<'_>) {
        self.started.get_or_insert_with(Instant::now);
        self.t.push(s.t);
        self.u.extend_from_slice(s.u);
        self.v.extend_from_slice(s.v);
        self.a.extend_from_slice(s.a);
        self.lambda.extend_from_slice(s.lambda);
        self.energy.push(s.energy());
        self.iterations
            .push(i64::try_from(s.iterations).unwrap_or(i64::MAX));
        self.residual.push(s.residual);
        self.constraint.push(s.constraint);
    }
}

/// [`Collect`] with the model's further columns (reactions, efforts, ...):
/// their values at every sample, by whatever [`Columns`] gives them.
pub(crate) struct Extra<'c> {
    /// Where the samples go.
    pub(crate) collect: &'c mut Collect,
    /// The further columns ([`extra_columns`]).
    pub(crate) columns: &'c dyn Columns,
}

impl Observer for Extra<'_> {
    fn observe(&mut self, s: &SampleRef<'_>) {
        self.collect.observe(s);
        self.columns.values(s, &mut self.collect.extra);
    }
}

/// A run's figures: `mstar run`'s summary (`wall_time`: the stepping, s).
pub(crate) fn stats_dict<'py>(
    py: Python<'py>,
    stats: Option<&RunStats>,
    wall: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    if let Some(s) = stats {
        d.set_item("steps", s.steps)?;
        d.set_item("rejected", s.rejected)?;
        d.set_item("newton_iterations", s.iterations)?;
        d.set_item("max_newton_iterations", s.max_iterations)?;
        d.set_item("factorizations", s.factorizations)?;
        d.set_item("h_min_used", s.h_min_used)?;
        d.set_item("h_max_used", s.h_max_used)?;
        d.set_item("t", s.t)?;
        d.set_item("max_error_ratio", s.error.max_ratio)?;
    }
    d.set_item("wall_time", wall)?;
    Ok(d)
}

/// A row-major `rows × cols` array of `data`.
fn matrix<'py>(
    py: Python<'py>,
    data: Vec<f64>,
    [rows, cols]: [usize; 2],
) -> PyResult<Bound<'py, PyAny>> {
    let flat = PyArray1::from_vec(py, data);
    Ok(flat.reshape([rows, cols])?.into_any())
}

impl Collect {
    /// The columns as a dict of numpy arrays (`t`, `u`, `v`, `a`, `lam`,
    /// `energy`, `iterations`, `residual`, `constraint`), moved, not copied,
    /// and the further columns: `extra_names` (their CSV names) and `extra`
    /// (samples × names).
    pub(crate) fn into_dict(
        self,
        py: Python<'_>,
        extra_names: Vec<String>,
    ) -> PyResult<Bound<'_, PyDict>> {
        let d = PyDict::new(py);
        let rows = self.t.len();
        d.set_item("t", PyArray1::from_vec(py, self.t))?;
        let (n, m) = ([rows, self.n], [rows, self.m]);
        d.set_item("u", matrix(py, self.u, n)?)?;
        d.set_item("v", matrix(py, self.v, n)?)?;
        d.set_item("a", matrix(py, self.a, n)?)?;
        d.set_item("lam", matrix(py, self.lambda, m)?)?;
        d.set_item("energy", PyArray1::from_vec(py, self.energy))?;
        d.set_item("iterations", PyArray1::from_vec(py, self.iterations))?;
        d.set_item("residual", PyArray1::from_vec(py, self.residual))?;
        d.set_item("constraint", PyArray1::from_vec(py, self.constraint))?;
        // A run stopped inside a sample's columns leaves no partial row.
        let width = extra_names.len();
        let mut extra = self.extra;
        extra.truncate(rows * width);
        extra.resize(rows * width, f64::NAN);
        d.set_item("extra", matrix(py, extra, [rows, width])?)?;
        d.set_item("extra_names", extra_names)?;
        Ok(d)
    }
}

/// The columns a run adds after the standard ones, as `mstar run --out`
/// writes them: the reactions and efforts of its joints and drivers, then
/// its sensors ([`OutputColumns`]). Results expose whatever these name,
/// generically.
pub(crate) fn extra_columns<'a>(
    mechanism: &'a Mechanism,
    sensors: &[Sensor],
) -> Result<Box<dyn Columns + 'a>, mstar::columns::SensorError> {
    Ok(Box::new(OutputColumns::new(
        mstar::run::lookup(mechanism),
        sensors,
    )?))
}

/// The constraint rows' names, in order.
pub(crate) fn constraint_names(sys: &dyn System) -> Vec<String> {
    (0..sys.n_constraints())
        .map(|i| sys.constraint_name(i))
        .collect()
}
