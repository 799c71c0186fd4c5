//! `mstar animate MODEL --mode K`: a vibration mode (`mstar::modes`) drawn
//! as a motion about the state it was found at,
//!
//! ```text
//! u(t) = u₀ + A Re(φ e^{i ω_d t}) = u₀ + A (φ_re cos ω_d t − φ_im sin ω_d t)
//! ```
//!
//! over two periods `2π/ω_d` (`ω_d = Im s`, the damped frequency), without
//! the decay `e^{Re(s) t}`, so that the shape stays visible. A mode that does
//! not oscillate (rigid, overdamped or unstable) swings as `A φ sin(2π t)`
//! over 2 s. The amplitude `A` moves the largest translational coordinate
//! by a tenth of the model's size (the largest distance of a body from the
//! origin or from another body, at least 0.1 m) or turns the largest angle
//! or Euler parameter by 0.3, whichever is smaller. Each spatial body's
//! Euler parameters are normalized again after the displacement.

use mstar::modes::{Mode, ModeKind};

use super::results::Results;

/// Frames per period.
const FRAMES_PER_PERIOD: usize = 48;
/// The share of the model's size the largest translation moves.
const TRANSLATION: f64 = 0.1;
/// The largest angle (rad) or Euler parameter change.
const ROTATION: f64 = 0.3;

/// Whether coordinate `name` is a translation (`.x`, `.y`, `.z`).
fn is_translation(name: &str) -> bool {
    name.ends_with(".x") || name.ends_with(".y") || name.ends_with(".z")
}

/// The size of the model at `u0`: the spread of its translational
/// coordinates, including the origin, at least 0.1 m.
fn size(names: &[String], u0: &[f64]) -> f64 {
    let (lo, hi) = names
        .iter()
        .zip(u0)
        .filter(|(n, _)| is_translation(n))
        .fold((0.0_f64, 0.0_f64), |(lo, hi), (_, &x)| {
            (lo.min(x), hi.max(x))
        });
    (hi - lo).max(0.1)
}

/// The amplitude `A` that scales `mode`'s shape for drawing (module doc).
pub fn amplitude(names: &[String], u0: &[f64], mode: &Mode) -> f64 {
    let largest = |translation: bool| {
        names
            .iter()
            .enumerate()
            .filter(|(_, n)| is_translation(n) == translation)
            .map(|(i, _)| mode.shape[i].hypot(mode.shape_imag[i]))
            .fold(0.0_f64, f64::max)
    };
    let by_translation = TRANSLATION * size(names, u0) / largest(true);
    let by_rotation = ROTATION / largest(false);
    let a = by_translation.min(by_rotation);
    if a.is_finite() { a } else { 0.0 }
}

/// The period of the drawn motion, s: `2π / Im s` for an oscillating mode,
/// 1 s otherwise.
pub fn period(mode: &Mode) -> f64 {
    match mode.kind {
        ModeKind::Oscillating if mode.s.1 > 0.0 => std::f64::consts::TAU / mode.s.1,
        _ => 1.0,
    }
}

/// Two periods of `mode` about `u0` (coordinates named `names`), as the
/// frames of a results file.
pub fn frames(names: &[String], u0: &[f64], mode: &Mode) -> Results {
    let a = amplitude(names, u0, mode);
    let t_period = period(mode);
    let count = 2 * FRAMES_PER_PERIOD + 1;
    let mut times = Vec::with_capacity(count);
    let mut states = Vec::with_capacity(count);
    for k in 0..count {
        let t = t_period * k as f64 / FRAMES_PER_PERIOD as f64;
        let phase = std::f64::consts::TAU * t / t_period;
        let (c, s) = match mode.kind {
            ModeKind::Oscillating => (phase.cos(), -phase.sin()),
            _ => (phase.sin(), 0.0),
        };
        let mut u: Vec<f64> = (0..u0.len())
            .map(|i| u0[i] + a * (c * mode.shape[i] + s * mode.shape_imag[i]))
            .collect();
        normalize_euler_parameters(names, &mut u);
        times.push(t);
        states.push(u);
    }
    Results { times, states }
}

/// Scales each body's `e0 … e3` back to unit length (a displaced Euler
/// parameter vector is no rotation otherwise).
fn normalize_euler_parameters(names: &[String], u: &mut [f64]) {
    for i in 0..names.len().saturating_sub(3) {
        if !names[i].ends_with(".e0") {
            continue;
        }
        let norm = u[i..i + 4].iter().map(|e| e * e).sum::<f64>().sqrt();
        if norm > 0.0 {
            u[i..i + 4].iter_mut().for_each(|e| *e /= norm);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mode(kind: ModeKind, s: (f64, f64), shape: Vec<f64>, imag: Vec<f64>) -> Mode {
        Mode {
            s,
            frequency_hz: s.0.hypot(s.1) / std::f64::consts::TAU,
            damping_ratio: 0.0,
            kind,
            shape,
            shape_imag: imag,
        }
    }

    fn names(list: &[&str]) -> Vec<String> {
        list.iter().map(|s| (*s).to_string()).collect()
    }

    /// A pendulum bob at (0, −1) swinging with shape (1, 0, 1): the model
    /// is 1 m across, so x moves ±0.1 m; θ would allow 0.3, so the
    /// translation decides. Two periods of 2π/ω, starting at the largest
    /// displacement, through the rest pose a quarter period later.
    #[test]
    fn an_oscillating_mode_swings_by_a_tenth_of_the_model() {
        let n = names(&["bob.x", "bob.y", "bob.theta"]);
        let u0 = [0.0, -1.0, 0.0];
        let omega = 3.0;
        let m = mode(
            ModeKind::Oscillating,
            (0.0, omega),
            vec![1.0, 0.0, 1.0],
            vec![0.0; 3],
        );
        let r = frames(&n, &u0, &m);
        assert_eq!(r.times.len(), 97);
        let last = *r.times.last().expect("frames");
        assert!((last - 2.0 * std::f64::consts::TAU / omega).abs() < 1e-12);
        assert!((r.states[0][0] - 0.1).abs() < 1e-12 && (r.states[0][2] - 0.1).abs() < 1e-12);
        let quarter = &r.states[FRAMES_PER_PERIOD / 4];
        assert!(quarter[0].abs() < 1e-12 && (quarter[1] + 1.0).abs() < 1e-12);
        let half = &r.states[FRAMES_PER_PERIOD / 2];
        assert!((half[0] + 0.1).abs() < 1e-12);
    }

    /// A spatial body turning about z: the Euler parameters stay unit.
    #[test]
    fn euler_parameters_stay_unit() {
        let n = names(&["b.x", "b.y", "b.z", "b.e0", "b.e1", "b.e2", "b.e3"]);
        let u0 = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0];
        let m = mode(
            ModeKind::Rigid,
            (0.0, 0.0),
            vec![0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0],
            vec![0.0; 7],
        );
        let r = frames(&n, &u0, &m);
        for u in &r.states {
            let norm: f64 = u[3..].iter().map(|e| e * e).sum();
            assert!((norm - 1.0).abs() < 1e-12, "{u:?}");
        }
        // A quarter of the 1 s swing: e3 displaced by 0.3, then normalized.
        let q = &r.states[FRAMES_PER_PERIOD / 4];
        assert!((q[6] - 0.3 / 1.09_f64.sqrt()).abs() < 1e-12, "{q:?}");
    }
}
