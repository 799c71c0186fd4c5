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
    /// Time reached.
    pub t: f64,
}
