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
    /// The energy balance of a system that conserves energy
    /// ([`System::conserves_energy`](mstar_model::System::conserves_energy)).
    pub energy: EnergyReport,
}

/// The energy drift of a run of a system whose exact motion keeps
/// `E = ½ u̇ᵀ M u̇ + V` constant (`docs/theory.md`, "Energy drift"): a global
/// check that the local error estimate cannot make, since it sees one step at
/// a time. The drift is within tolerance when
/// `max |E − E₀| ≤ 2 rtol · T_max`, `T_max` the largest kinetic energy of the
/// run (the energy that the motion exchanges), with a round-off floor: an
/// oscillation's energy goes with its amplitude squared, so amplitudes
/// within `rtol` keep it within `2 rtol`. The floor is `1e-12` of the
/// energies' size, which includes the work `W = Σ|gᵢ| max(1, ‖u‖∞)` the
/// forces would do over the coordinates' own size: a structure at rest at
/// `y = 0` has `E₀ = T = 0`, and the round-off of its positions still moves
/// its potential energy by about `ε W`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EnergyReport {
    /// Whether the energy was tracked (the system conserves it).
    pub tracked: bool,
    /// `E₀`, J.
    pub e0: f64,
    /// `max |E − E₀|` over the accepted steps, J (NaN once `E` was NaN).
    pub drift: f64,
    /// When it was largest.
    pub t_drift: f64,
    /// The largest kinetic energy, J.
    pub kinetic_max: f64,
    /// The largest `W = Σ|gᵢ| max(1, ‖u‖∞)`, J: the scale of the potential
    /// energy's round-off.
    pub work_max: f64,
}

impl EnergyReport {
    /// Records the energy of a state at `t`, with `work`, the state's `W`.
    pub(crate) fn record(&mut self, t: f64, kinetic: f64, potential: f64, work: f64) {
        let e = kinetic + potential;
        if !self.tracked {
            (self.tracked, self.e0, self.drift, self.t_drift) = (true, e, 0.0, t);
        }
        let d = (e - self.e0).abs();
        if d > self.drift || d.is_nan() && !self.drift.is_nan() {
            (self.drift, self.t_drift) = (d, t);
        }
        self.kinetic_max = self.kinetic_max.max(kinetic);
        self.work_max = self.work_max.max(work);
    }

    /// The drift allowed with relative tolerance `rtol`: `2 rtol · T_max`,
    /// and never below the round-off of the energies (`1e-12` of `|E₀| +
    /// T_max + W_max`).
    #[must_use]
    pub fn limit(&self, rtol: f64) -> f64 {
        let round_off = 1e-12 * (self.e0.abs() + self.kinetic_max + self.work_max);
        (2.0 * rtol * self.kinetic_max).max(round_off)
    }

    /// Whether the drift exceeded [`limit`](Self::limit) (NaN exceeds).
    #[must_use]
    pub fn exceeded(&self, rtol: f64) -> bool {
        self.tracked && (self.drift.is_nan() || self.drift > self.limit(rtol))
    }
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

#[cfg(test)]
mod tests {
    use super::EnergyReport;

    #[test]
    fn the_drift_is_judged_against_twice_rtol_times_the_largest_kinetic_energy() {
        let mut e = EnergyReport::default();
        assert!(!e.exceeded(1e-3), "nothing tracked, nothing exceeded");
        e.record(0.0, 0.0, -10.0, 0.0);
        e.record(1.0, 10.0, -19.99, 0.0);
        // |E − E₀| = 0.01 J against 2 · 1e-3 · 10 J = 0.02 J.
        assert!((e.drift - 0.01).abs() < 1e-12 && e.t_drift == 1.0);
        assert!(!e.exceeded(1e-3));
        assert!(e.exceeded(1e-4));
        e.record(2.0, 5.0, f64::NAN, 0.0);
        assert!(e.drift.is_nan() && e.exceeded(1.0), "NaN never passes");
        e.record(3.0, 5.0, -15.0, 0.0);
        assert!(e.drift.is_nan(), "a NaN drift stays NaN");
    }

    #[test]
    fn a_body_at_rest_is_judged_at_round_off() {
        let mut e = EnergyReport::default();
        e.record(0.0, 0.0, 5.0, 0.0);
        e.record(1.0, 0.0, 5.0 + 1e-13, 0.0);
        assert!(!e.exceeded(1e-3), "round-off of E₀");
        e.record(2.0, 0.0, 5.0 + 1e-9, 0.0);
        assert!(e.exceeded(1e-3));
    }

    #[test]
    fn a_structure_at_rest_at_zero_potential_is_judged_at_the_forces_round_off() {
        // Two welded bars along y = 0 (3 kg, 1.4 m): E₀ = 0, a kinetic
        // energy of round-off (1e-40 J), and W = 3 · 9.81 N · 1.4 m.
        let work = 3.0 * 9.81 * 1.4;
        let mut e = EnergyReport::default();
        e.record(0.0, 0.0, 0.0, work);
        e.record(1.0, 7.6e-40, 2.8e-35, work);
        assert!(!e.exceeded(1e-3), "round-off of the positions");
        e.record(2.0, 7.6e-40, 1e-9, work);
        assert!(e.exceeded(1e-3), "1e-9 J is no round-off of 41 J");
    }
}
