//! Small tools for comparing solutions: errors against a reference, fitted
//! convergence orders, the amplitude of the period-2h oscillation.

use mstar_kkt::MaxAbs;
use mstar_model::Sample;

/// `max |x|` over `values`, NaN-aware ([`MaxAbs`]): a NaN error is never
/// taken for a small one.
fn largest(values: impl IntoIterator<Item = f64>) -> f64 {
    let mut m = MaxAbs::new();
    for v in values {
        m.push(v);
    }
    m.value()
}

/// `max_k |f(samples[k]) − f(reference[k])|` over samples paired by index (the
/// reference must be sampled at the same times); NaN when a difference is.
///
/// # Panics
/// If the two slices differ in length or their times differ by more than 1e-9.
#[must_use]
pub fn max_error(samples: &[Sample], reference: &[Sample], f: impl Fn(&Sample) -> f64) -> f64 {
    assert_eq!(samples.len(), reference.len(), "paired samples");
    largest(samples.iter().zip(reference).map(|(s, r)| {
        assert!(
            (s.t - r.t).abs() <= 1e-9,
            "times differ: {} vs {}",
            s.t,
            r.t
        );
        f(s) - f(r)
    }))
}

/// Largest error of any multiplier, `max_k ‖λ_k − λ_ref,k‖∞`.
#[must_use]
pub fn max_lambda_error(samples: &[Sample], reference: &[Sample]) -> f64 {
    largest(
        (0..samples.first().map_or(0, |s| s.lambda.len()))
            .map(|i| max_error(samples, reference, |s| s.lambda[i])),
    )
}

/// The least-squares slope of `log(error)` against `log(h)`: the observed order
/// of convergence.
///
/// # Panics
/// If fewer than two points are given.
#[must_use]
pub fn fitted_order(h: &[f64], error: &[f64]) -> f64 {
    assert!(
        h.len() >= 2 && h.len() == error.len(),
        "two or more (h, error) points"
    );
    let x: Vec<f64> = h.iter().map(|v| v.ln()).collect();
    let y: Vec<f64> = error.iter().map(|v| v.ln()).collect();
    let n = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let sxy: f64 = x.iter().zip(&y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx) * (a - mx)).sum();
    sxy / sxx
}

/// Amplitude of the period-2h (Nyquist) component of a uniformly sampled
/// signal: `max_k |x_{k+1} − 2x_k + x_{k−1}| / 4`. For `x_k = A(−1)^k + smooth`
/// this is `A` plus `O(h² ẍ)` of the smooth part.
#[must_use]
pub fn nyquist_amplitude(x: &[f64]) -> f64 {
    largest(x.windows(3).map(|w| (w[2] - 2.0 * w[1] + w[0]) / 4.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn order_of_a_power_law() {
        let h = [0.1, 0.05, 0.025];
        let e: Vec<f64> = h.iter().map(|v| 3.0 * v * v).collect();
        assert!((fitted_order(&h, &e) - 2.0).abs() < 1e-12);
    }

    #[test]
    fn a_nan_error_is_never_small() {
        let sample = |t: f64, x: f64| Sample {
            t,
            u: vec![x],
            lambda: vec![x],
            ..Sample::default()
        };
        let got = [sample(0.0, 1.0), sample(1.0, f64::NAN), sample(2.0, 5.0)];
        let want = [sample(0.0, 1.0), sample(1.0, 2.0), sample(2.0, 5.5)];
        assert!(max_error(&got, &want, |s| s.u[0]).is_nan());
        assert!(max_lambda_error(&got, &want).is_nan());
        assert!(nyquist_amplitude(&[0.0, f64::NAN, 0.0, 1.0]).is_nan());
        assert_eq!(max_error(&want, &want, |s| s.u[0]), 0.0);
    }

    #[test]
    fn nyquist_amplitude_of_an_alternating_signal() {
        let x: Vec<f64> = (0..100)
            .map(|k| 0.5 * if k % 2 == 0 { 1.0 } else { -1.0 } + (0.01 * k as f64).sin())
            .collect();
        assert!((nyquist_amplitude(&x) - 0.5).abs() < 1e-4);
        let smooth: Vec<f64> = (0..100).map(|k| (0.01 * k as f64).sin()).collect();
        assert!(nyquist_amplitude(&smooth) < 1e-4);
    }
}
