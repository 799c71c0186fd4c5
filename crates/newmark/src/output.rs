//! Per-step output: observers and the in-memory trajectory.

use mstar_model::Sample;

/// Receives every accepted step (and the initial state) of an integration.
pub trait Observer {
    /// Called with the converged state after every accepted step, and once with
    /// the initial state.
    fn observe(&mut self, sample: &Sample);
}

impl<F: FnMut(&Sample)> Observer for F {
    fn observe(&mut self, sample: &Sample) {
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
    fn observe(&mut self, sample: &Sample) {
        self.samples.push(sample.clone());
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
    /// Time reached.
    pub t: f64,
}
