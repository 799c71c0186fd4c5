//! Per-step output: observers and the in-memory trajectory.

use mstar_model::{Sample, SampleRef};

/// Receives every accepted step (and the initial state) of an integration, as
/// a view of the integrator's state (copy what you keep:
/// [`SampleRef::to_sample`]).
pub trait Observer {
    /// Called with the converged state after every accepted step, and once with
    /// the initial state.
    fn observe(&mut self, sample: &SampleRef<'_>);

    /// Whether [`observe`](Self::observe) reads the energies (default: yes).
    /// An observer that does not (a progress report) saves their evaluation,
    /// a pass over the whole state, at every step; its views then carry NaN
    /// energies.
    fn reads_energy(&self) -> bool {
        true
    }
}

impl<F: FnMut(&SampleRef<'_>)> Observer for F {
    fn observe(&mut self, sample: &SampleRef<'_>) {
        self(sample);
    }
}

/// An observer that keeps every sample in memory.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Trajectory {
    /// The samples, in time order.
    pub samples: Vec<Sample>,
}

impl Observer for Trajectory {
    fn observe(&mut self, sample: &SampleRef<'_>) {
        self.samples.push(sample.to_sample());
    }
}

/// Counters of a run, for the summary.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RunStats {
    /// Accepted steps.
    pub steps: usize,
    /// Rejected step attempts (Newton failures retried with a smaller h).
    pub rejected: usize,
    /// Newton iterations over all attempts.
    pub iterations: usize,
    /// Largest number of Newton iterations of an accepted step.
    pub max_iterations: usize,
    /// Numeric factorizations of the KKT matrix.
    pub factorizations: usize,
    /// Smallest step size used.
    pub h_min_used: f64,
    /// Largest step size used (0 before the first step).
    pub h_max_used: f64,
    /// Time reached.
    pub t: f64,
    /// The local error estimate over the accepted steps.
    pub error: ErrorReport,
}

/// The local error estimate over a run's accepted steps, as a ratio to the
/// tolerance ([`ErrorControl`](crate::ErrorControl)): a step is within
/// tolerance when its ratio is at most 1.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ErrorReport {
    /// The largest ratio (NaN if an estimate was NaN).
    pub max_ratio: f64,
    /// When that step ended.
    pub t_max: f64,
    /// The step size of that step.
    pub h_max: f64,
    /// The coordinate where it was largest.
    pub coordinate: Option<usize>,
    /// Accepted steps whose ratio exceeded 1.
    pub exceeded: usize,
    /// When the first such step ended.
    pub first_exceeded: Option<f64>,
    /// Steps rejected (and retried smaller) because of the estimate.
    pub rejected: usize,
    /// Accepted steps whose converged constraint violation exceeded the
    /// tolerance (a Newton tolerance too loose for it; the step size cannot
    /// help).
    pub newton_exceeded: usize,
    /// The largest converged `‖Φ‖∞` over the tolerance.
    pub newton_max_ratio: f64,
}

impl ErrorReport {
    /// Records an accepted step's Newton ratio (converged `‖Φ‖∞` over the
    /// tolerance).
    pub(crate) fn record_newton(&mut self, ratio: f64) {
        if ratio > self.newton_max_ratio || ratio.is_nan() {
            self.newton_max_ratio = ratio;
        }
        if ratio.is_nan() || ratio > 1.0 {
            self.newton_exceeded += 1;
        }
    }

    /// Records an accepted step's ratio.
    pub(crate) fn record(&mut self, ratio: f64, t: f64, h: f64, coordinate: Option<usize>) {
        if ratio > self.max_ratio || ratio.is_nan() && !self.max_ratio.is_nan() {
            (self.max_ratio, self.t_max, self.h_max, self.coordinate) = (ratio, t, h, coordinate);
        }
        if ratio.is_nan() || ratio > 1.0 {
            self.exceeded += 1;
            self.first_exceeded.get_or_insert(t);
        }
    }

    /// Whether some accepted step exceeded the tolerance.
    #[must_use]
    pub fn exceeded_tolerance(&self) -> bool {
        self.exceeded > 0
    }

    /// A step size that would bring the worst step within tolerance: the
    /// local error is `O(h³)`, so `h · (0.5 / ratio)^(1/3)` (half the
    /// tolerance, for margin).
    #[must_use]
    pub fn suggested_h(&self) -> f64 {
        self.h_max * (0.5 / self.max_ratio).cbrt()
    }
}
