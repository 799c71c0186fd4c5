//! The pendulum presets shared by the `mstar pendulum` command and the studies.

use mstar_model::{PendulumChain, Sample, SampleRef};
use mstar_newmark::{Config, IntegrationError, Integrator, RunStats, Trajectory};
use mstar_rk4::ChainOracle;

/// A pendulum run: the model, its initial state and the integrator settings.
#[derive(Clone, Debug, PartialEq)]
pub struct PendulumRun {
    /// Mass, kg.
    pub m: f64,
    /// Rod length, m.
    pub l: f64,
    /// Gravity, m/s².
    pub g0: f64,
    /// Initial angle from the downward vertical, rad.
    pub theta0: f64,
    /// Initial angular velocity, rad/s.
    pub omega0: f64,
    /// End time, s.
    pub t_end: f64,
    /// Integrator settings (the step size is `config.h`).
    pub config: Config,
}

impl PendulumRun {
    /// The paper's preset (§3, `algorithm.md` §5): m = 1, l = 1, g₀ = 10,
    /// h = 0.01, θ₀ = π/2 (released horizontally, at rest), λ₀ = (−10, 0),
    /// Newmark β = 1/4, γ = 1/2 with the paper's `M*` start, t_end = 10 s.
    #[must_use]
    pub fn paper() -> Self {
        Self {
            m: 1.0,
            l: 1.0,
            g0: 10.0,
            theta0: std::f64::consts::FRAC_PI_2,
            omega0: 0.0,
            t_end: 10.0,
            config: Config::paper(0.01, vec![-10.0, 0.0]),
        }
    }

    /// The default: g₀ = 9.81, θ₀ = π/2, h = 0.01, t_end = 10 s,
    /// generalized-α (ρ∞ = 0.9) with a consistent start.
    #[must_use]
    pub fn standard() -> Self {
        Self {
            g0: 9.81,
            config: Config::default(),
            ..Self::paper()
        }
    }

    /// The model.
    #[must_use]
    pub fn system(&self) -> PendulumChain {
        PendulumChain::paper(self.m, self.l, self.g0)
    }

    /// Integrates; returns every accepted sample and how the run ended. On an
    /// error, the samples up to the failure are still returned.
    pub fn run(&self) -> (Vec<Sample>, Result<RunStats, IntegrationError>) {
        self.run_observed(&mut |_: &SampleRef<'_>| {})
    }

    /// Like [`run`](Self::run), also handing each sample to `progress`.
    pub fn run_observed(
        &self,
        progress: &mut dyn FnMut(&SampleRef<'_>),
    ) -> (Vec<Sample>, Result<RunStats, IntegrationError>) {
        let sys = self.system();
        let u0 = sys.position(&[self.theta0]);
        let v0 = sys.velocity(&[self.theta0], &[self.omega0]);
        let mut traj = Trajectory::default();
        let result =
            Integrator::new(&sys, self.config.clone(), 0.0, &u0, &v0).and_then(|mut integ| {
                integ.run(self.t_end, &mut |s: &SampleRef<'_>| {
                    progress(s);
                    traj.samples.push(s.to_sample());
                })
            });
        (traj.samples, result)
    }

    /// The RK4 reference (minimal coordinates, from t = 0) at the given times.
    #[must_use]
    pub fn reference(&self, times: &[f64]) -> Vec<Sample> {
        let sys = self.system();
        ChainOracle::new(&sys).solve(&[self.theta0], &[self.omega0], times)
    }

    /// Integrates and pairs every sample with the RK4 reference at its time.
    ///
    /// # Errors
    /// The integration's error, if it stopped before `t_end`.
    pub fn run_with_reference(&self) -> Result<(Vec<Sample>, Vec<Sample>), IntegrationError> {
        let (samples, result) = self.run();
        result?;
        let times: Vec<f64> = samples.iter().map(|s| s.t).collect();
        let reference = self.reference(&times);
        Ok((samples, reference))
    }

    /// The RK4 reference on the grid `0, h, 2h, …, t_end`: it ends at `t_end`
    /// exactly, the last step shortened when `h` does not divide `t_end` (as
    /// the integrator's last step; a remainder below `1e-9 h` is dropped).
    /// The caller bounds `t_end / h`: every sample is kept in memory.
    #[must_use]
    pub fn reference_on_grid(&self) -> Vec<Sample> {
        self.reference(&self.grid())
    }

    /// The times of [`reference_on_grid`](Self::reference_on_grid).
    #[must_use]
    pub fn grid(&self) -> Vec<f64> {
        let h = self.config.h;
        let full = (self.t_end / h - 1e-9).ceil().max(1.0) as usize;
        (0..full)
            .map(|k| k as f64 * h)
            .chain(std::iter::once(self.t_end))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(h: f64, t_end: f64) -> Vec<f64> {
        let mut run = PendulumRun::standard();
        run.config.h = h;
        run.t_end = t_end;
        run.grid()
    }

    /// The grid ends at t_end exactly, the last step shortened.
    #[test]
    fn grid_ends_at_t_end() {
        assert_eq!(grid(0.03, 0.1), [0.0, 0.03, 0.06, 0.09, 0.1]);
        assert_eq!(grid(100.0, 10.0), [0.0, 10.0]);
        let g = grid(0.01, 0.1);
        assert_eq!(g.len(), 11);
        assert_eq!(g[10], 0.1);
        assert!((g[9] - 0.09).abs() < 1e-15);
        assert_eq!(grid(0.01, 10.0).len(), 1001);
    }
}
