//! The pendulum's summary, gathered sample by sample so that no run keeps its
//! samples in memory: the last state, the energy drift, the largest
//! constraint violation, and the period-2h mode of λ in the first and the
//! last second (their windows only).

use std::collections::VecDeque;

use mstar::SampleRef;
use mstar::kkt::MaxAbs;

/// Samples a second beyond which the period-2h check is skipped: its window
/// of the last second would hold more than this many numbers (8 MB).
const MAX_WINDOW: usize = 1_000_000;

/// Running figures of a run.
pub struct Summary {
    /// t, θ, θ̇ and λ of the last sample.
    last: Option<(f64, f64, f64, Vec<f64>)>,
    t0: f64,
    e0: f64,
    drift: MaxAbs,
    constraint: MaxAbs,
    scale: MaxAbs,
    /// λ of the two samples before the current one.
    before: [Vec<f64>; 2],
    count: usize,
    /// Samples in the first second (known once a sample reaches t0 + 1).
    per_second: Option<usize>,
    /// The period-2h amplitude within the first second.
    early: f64,
    /// Each sample's second difference of λ, over the last second.
    recent: VecDeque<f64>,
    /// The first second holds more than [`MAX_WINDOW`] samples.
    too_dense: bool,
}

impl Summary {
    /// An empty summary.
    pub fn new() -> Self {
        Self {
            last: None,
            t0: 0.0,
            e0: 0.0,
            drift: MaxAbs::new(),
            constraint: MaxAbs::new(),
            scale: MaxAbs::new(),
            before: [Vec::new(), Vec::new()],
            count: 0,
            per_second: None,
            early: 0.0,
            recent: VecDeque::new(),
            too_dense: false,
        }
    }

    /// Takes in one sample (the pendulum's: θ = u[2], two multipliers).
    pub fn push(&mut self, s: &SampleRef<'_>) {
        let e = s.energy();
        if self.count == 0 {
            (self.t0, self.e0) = (s.t, e);
        }
        self.drift.push(e - self.e0);
        self.constraint.push(s.constraint);
        s.lambda.iter().for_each(|&l| self.scale.push(l));
        let k = self.count;
        if self.per_second.is_none() && s.t >= self.t0 + 1.0 {
            self.per_second = Some(k);
        }
        if k >= 2 && !self.too_dense {
            self.window(s.lambda);
        }
        self.before.swap(0, 1);
        self.before[1].clear();
        self.before[1].extend_from_slice(s.lambda);
        self.count += 1;
        let at = |i: usize| s.u.get(i).copied().unwrap_or(f64::NAN);
        let theta_dot = s.v.get(2).copied().unwrap_or(f64::NAN);
        self.last = Some((s.t, at(2), theta_dot, s.lambda.to_vec()));
    }

    /// The second difference `max_i |λ_i(k) − 2λ_i(k−1) + λ_i(k−2)| / 4`
    /// of the current sample, into the first second's amplitude and the
    /// window of the last second.
    fn window(&mut self, lambda: &[f64]) {
        let w = lambda
            .iter()
            .zip(&self.before[1])
            .zip(&self.before[0])
            .map(|((a, b), c)| ((a - 2.0 * b + c) / 4.0).abs())
            .fold(0.0, f64::max);
        if self.per_second.is_none() {
            self.early = self.early.max(w);
        }
        self.recent.push_back(w);
        let keep = self.per_second.map_or(MAX_WINDOW, |p| p.saturating_sub(2));
        while self.recent.len() > keep {
            self.recent.pop_front();
        }
        if self.per_second.is_none() && self.recent.len() >= MAX_WINDOW {
            self.too_dense = true;
            self.recent = VecDeque::new();
        }
    }

    /// The period-2h amplitudes in the first and the last second, when the
    /// run is at least two seconds of at least three samples each.
    fn amplitudes(&self) -> Option<(f64, f64)> {
        let p = self.per_second?;
        (!self.too_dense && self.count >= 2 * p && p >= 3)
            .then(|| (self.early, self.recent.iter().copied().fold(0.0, f64::max)))
    }

    /// Prints it; `damped`: whether the run's scheme damps the period-2h
    /// mode (γ > 1/2), which decides the advice of a growing one.
    pub fn print(&self, damped: bool) {
        let Some((t, theta, theta_dot, lambda)) = &self.last else {
            return;
        };
        let l = |i: usize| lambda.get(i).copied().unwrap_or(f64::NAN);
        say!(
            "t reached: {t} s; θ = {theta:.9} rad, θ̇ = {theta_dot:.9} rad/s, λ = [{:.6}, {:.6}]",
            l(0),
            l(1)
        );
        say!(
            "energy: E₀ = {:.6} J, max |E − E₀| = {:.3e} J; max ‖Φ‖∞ = {:.3e} m",
            self.e0,
            self.drift.value(),
            self.constraint.value()
        );
        // The trapezoidal rule's period-2h mode of λ grows silently: warn
        // when the last second's amplitude is far above the first second's.
        if let Some((early, late)) = self.amplitudes()
            && late > 10.0 * early
            && late > 1e-3 * self.scale.value()
        {
            let advice = if damped {
                "the scheme damps it, so the step is too large for the motion: see the accuracy \
                 warning for a smaller --h"
            } else {
                "an undamped scheme on an index-3 system lets it grow: use generalized-α with ρ∞ < 1 \
                 (--integrator generalized-alpha --rho 0.9)"
            };
            say!(
                "warning: the period-2h oscillation of λ grew from {early:.3e} in the first second to {late:.3e} in the last: \
                 the multipliers are not trustworthy; {advice}"
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mstar::Sample;

    /// The streamed amplitudes equal the ones over the stored windows
    /// (`analysis::nyquist_amplitude` over the first and the last second).
    #[test]
    fn windows_match_the_stored_samples() {
        let h = 0.01;
        let samples: Vec<Sample> = (0..=350)
            .map(|k| {
                let t = k as f64 * h;
                let alt = if k % 2 == 0 { 1.0 } else { -1.0 };
                Sample {
                    t,
                    u: vec![0.0; 3],
                    v: vec![0.0; 3],
                    a: vec![0.0; 3],
                    lambda: vec![
                        (3.0 * t).sin() + 1e-3 * t * t * alt,
                        0.5 * alt * (t - 2.0).max(0.0),
                    ],
                    ..Sample::default()
                }
            })
            .collect();
        let mut summary = Summary::new();
        samples.iter().for_each(|s| summary.push(&s.view()));
        let per_second = samples.iter().position(|s| s.t >= 1.0).unwrap_or(0);
        let amplitude = |part: &[Sample]| {
            (0..2)
                .map(|i| {
                    let x: Vec<f64> = part.iter().map(|s| s.lambda[i]).collect();
                    mstar::analysis::nyquist_amplitude(&x)
                })
                .fold(0.0, f64::max)
        };
        let early = amplitude(&samples[..per_second]);
        let late = amplitude(&samples[samples.len() - per_second..]);
        let (got_early, got_late) = summary.amplitudes().unwrap_or((f64::NAN, f64::NAN));
        assert!(
            (got_early - early).abs() <= 1e-15 * early.abs().max(1.0),
            "{got_early} {early}"
        );
        assert!(
            (got_late - late).abs() <= 1e-15 * late.abs().max(1.0),
            "{got_late} {late}"
        );
        assert!(late > 0.1, "{late}");
    }
}
