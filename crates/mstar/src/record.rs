//! What a run of a model file writes and measures as it goes: the rows of its
//! CSV file (`[output] every` or `every_time`, the model's extra columns, the
//! last state reached) and the figures of its summary (the largest
//! constraint violation, the energy drift, the last state). `mstar run --out`
//! and `mstar sweep` write their CSV files through [`Recorder`], so a sweep's
//! run is byte for byte the file `mstar run --set …` writes.

use mstar_model::SampleRef;
use mstar_newmark::Observer;

use crate::columns::Columns;
use crate::csv::CsvStream;

/// A Δt for `[output] every_time` / `--output-every` that is not a positive,
/// finite number of seconds.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[error("--output-every must be a positive number of seconds (got {0})")]
pub struct BadInterval(pub f64);

/// The rows of a run's CSV file: every step, or with `--output-every` /
/// `[output] every_time` the state at every multiple of Δt, interpolated
/// within the steps ([`crate::Resample`]), and the last state reached.
#[derive(Debug)]
pub struct Grid(Option<crate::Resample<crate::Trajectory>>);

impl Grid {
    /// Every step (`None`) or every `every_time` seconds.
    ///
    /// # Errors
    /// [`BadInterval`] for a Δt that is not positive and finite.
    pub fn new(every_time: Option<f64>) -> Result<Self, BadInterval> {
        match every_time {
            None => Ok(Self(None)),
            Some(dt) if dt > 0.0 && dt.is_finite() => Ok(Self(Some(crate::Resample::new(
                dt,
                crate::Trajectory::default(),
            )))),
            Some(dt) => Err(BadInterval(dt)),
        }
    }

    /// Every step.
    #[must_use]
    pub fn every_step() -> Self {
        Self(None)
    }

    /// Hands `row` the rows that the state `s` completes.
    pub fn rows(&mut self, s: &SampleRef<'_>, row: &mut dyn FnMut(&SampleRef<'_>)) {
        match &mut self.0 {
            None => row(s),
            Some(grid) => {
                grid.observe(s);
                for sample in grid.inner_mut().samples.drain(..) {
                    row(&sample.view());
                }
            }
        }
    }

    /// Hands `row` the last state reached when it is not on the grid (at the
    /// end of a run, also of one that stopped early).
    pub fn finish(self, row: &mut dyn FnMut(&SampleRef<'_>)) {
        if let Some(grid) = self.0 {
            for sample in grid.finish().samples {
                row(&sample.view());
            }
        }
    }
}

/// Which states a [`Recorder`] writes: every `every`-th step (default 1) and
/// the last, or the rows of a [`Grid`].
#[derive(Debug)]
pub struct Rows {
    /// Write every n-th step (≥ 1; `[output] every`).
    pub every: usize,
    /// The grid of `[output] every_time` (every step when not given).
    pub grid: Grid,
}

/// An [`Observer`] of a run that writes its CSV rows (when it has a stream)
/// and keeps the figures of its summary. The state observed a second time
/// at the end of a run that stopped early is written if `every` skipped it,
/// so nothing the run computed is lost.
pub struct Recorder<'a> {
    stream: Option<CsvStream>,
    /// The model's extra columns and a buffer for their values.
    columns: Option<&'a dyn Columns>,
    extra: Vec<f64>,
    every: usize,
    grid: Grid,
    seen: usize,
    /// The time of the last state observed, and of the last one written.
    last_seen: f64,
    last_written: Option<f64>,
    t_end: f64,
    energy0: Option<f64>,
    drift: f64,
    max_constraint: f64,
    last_u: Vec<f64>,
    /// The whole last state observed, when asked to keep it.
    last_state: Option<mstar_model::Sample>,
    /// Which extra columns the stream writes (worked out at the first row;
    /// inner `None`: all).
    wanted: Option<Option<Vec<bool>>>,
}

impl std::fmt::Debug for Recorder<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Recorder")
            .field("seen", &self.seen)
            .field("t_end", &self.t_end)
            .finish_non_exhaustive()
    }
}

impl<'a> Recorder<'a> {
    /// A recorder of a run to `t_end` that writes `rows` of each state to
    /// `stream` (none: only the figures), with the model's extra `columns`.
    #[must_use]
    pub fn new(
        stream: Option<CsvStream>,
        columns: Option<&'a dyn Columns>,
        rows: Rows,
        t_end: f64,
    ) -> Self {
        Self {
            stream,
            columns,
            extra: Vec::new(),
            every: rows.every.max(1),
            grid: rows.grid,
            seen: 0,
            last_seen: f64::NAN,
            last_written: None,
            t_end,
            energy0: None,
            drift: 0.0,
            max_constraint: 0.0,
            last_u: Vec::new(),
            last_state: None,
            wanted: None,
        }
    }

    /// The recorder keeping the whole last state observed
    /// ([`last_state`](Self::last_state)), not only its coordinates.
    #[must_use]
    pub fn keeping_last_state(mut self) -> Self {
        self.last_state = Some(mstar_model::Sample::default());
        self
    }

    /// The last state observed, when kept ([`keeping_last_state`](Self::keeping_last_state)).
    #[must_use]
    pub fn last_state(&self) -> Option<SampleRef<'_>> {
        self.last_state
            .as_ref()
            .filter(|_| self.seen > 0)
            .map(mstar_model::Sample::view)
    }

    /// The CSV stream, if any.
    #[must_use]
    pub fn stream(&self) -> Option<&CsvStream> {
        self.stream.as_ref()
    }

    /// The CSV stream, to finish or keep partial, once the rows are written
    /// ([`finish_rows`](Self::finish_rows)).
    #[must_use]
    pub fn into_stream(self) -> Option<CsvStream> {
        self.stream
    }

    /// The largest `‖Φ‖∞` of the states observed.
    #[must_use]
    pub fn max_constraint(&self) -> f64 {
        self.max_constraint
    }

    /// The energy drift `max |E − E₀|` of the states observed, J (NaN once
    /// the energy was NaN).
    #[must_use]
    pub fn energy_drift(&self) -> f64 {
        self.drift
    }

    /// The last state observed: its time and coordinates `u`.
    #[must_use]
    pub fn last(&self) -> Option<(f64, &[f64])> {
        (self.seen > 0).then_some((self.last_seen, &self.last_u[..]))
    }

    /// Writes the rows that the state `s` completes (`[output] every_time`),
    /// with the model's extra columns.
    fn write(&mut self, s: &SampleRef<'_>) {
        self.last_written = Some(s.t);
        let Some(stream) = self.stream.as_mut() else {
            return;
        };
        let columns = self.columns.filter(|_| stream.needs_extra());
        let wanted = self
            .wanted
            .get_or_insert_with(|| columns.and_then(|c| stream.extra_wanted(c.count())));
        let extra = &mut self.extra;
        self.grid.rows(s, &mut |row| {
            extra.clear();
            match (columns, wanted.as_deref()) {
                (Some(columns), Some(wanted)) => columns.values_wanted(row, wanted, extra),
                (Some(columns), None) => columns.values(row, extra),
                (None, _) => {}
            }
            stream.push_with(row, extra);
        });
    }

    /// Writes the last state reached when `[output] every_time` left it out.
    pub fn finish_rows(&mut self) {
        let grid = std::mem::replace(&mut self.grid, Grid::every_step());
        let (Some(stream), columns, extra) = (self.stream.as_mut(), self.columns, &mut self.extra)
        else {
            return;
        };
        let columns = columns.filter(|_| stream.needs_extra());
        let wanted = columns.and_then(|c| stream.extra_wanted(c.count()));
        grid.finish(&mut |row| {
            extra.clear();
            match (columns, wanted.as_deref()) {
                (Some(columns), Some(wanted)) => columns.values_wanted(row, wanted, extra),
                (Some(columns), None) => columns.values(row, extra),
                (None, _) => {}
            }
            stream.push_with(row, extra);
        });
    }
}

impl Observer for Recorder<'_> {
    fn observe(&mut self, s: &SampleRef<'_>) {
        // The last state observed again after a run that stopped early.
        if self.seen > 0 && s.t == self.last_seen {
            if self.last_written != Some(s.t) {
                self.write(s);
            }
            return;
        }
        let last = s.t >= self.t_end * (1.0 - 1e-12);
        if self.seen.is_multiple_of(self.every) || last {
            self.write(s);
        }
        self.seen += 1;
        self.last_seen = s.t;
        self.last_u.clear();
        self.last_u.extend_from_slice(s.u);
        if let Some(kept) = &mut self.last_state {
            kept.t = s.t;
            for (to, from) in [
                (&mut kept.u, s.u),
                (&mut kept.v, s.v),
                (&mut kept.a, s.a),
                (&mut kept.lambda, s.lambda),
            ] {
                to.clear();
                to.extend_from_slice(from);
            }
        }
        let e = s.energy();
        let e0 = *self.energy0.get_or_insert(e);
        self.drift = if (e - e0).abs() > self.drift || e.is_nan() {
            (e - e0).abs()
        } else {
            self.drift
        };
        self.max_constraint = self.max_constraint.max(s.constraint);
    }
}
