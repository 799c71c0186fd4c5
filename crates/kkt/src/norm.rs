//! `‖x‖∞` and finiteness checks that never lose a NaN.
//!
//! `f64::max` returns the other operand when one is NaN, so a running maximum
//! folded with it forgets a NaN (a NaN residual would score zero), and its NaN
//! rules cost a blend in a loop's chain of dependent operations. [`MaxAbs`]
//! keeps the maximum with plain comparisons and carries non-finite entries in a
//! separate sum of `0 · x` (NaN for a NaN or an infinite `x`).

/// Whether every value seen was finite: a sum of `0 · x`, NaN once a NaN or
/// an infinite `x` was added (one add per value, no branch).
///
/// ```
/// use mstar_kkt::Finite;
///
/// let mut f = Finite::new();
/// f.push(1.0);
/// assert!(f.all());
/// f.push(f64::NEG_INFINITY);
/// f.push(2.0);
/// assert!(!f.all());
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Finite(f64);

impl Finite {
    /// Nothing seen yet.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// Takes `x` into account.
    #[inline]
    pub fn push(&mut self, x: f64) {
        self.0 += 0.0 * x;
    }

    /// Whether every value pushed so far was finite.
    #[inline]
    #[must_use]
    pub fn all(&self) -> bool {
        !self.0.is_nan()
    }

    /// Merges another check into this one.
    #[inline]
    pub fn merge(&mut self, other: Self) {
        self.0 += other.0;
    }
}

/// A running `‖·‖∞` that remembers NaN and infinity.
///
/// ```
/// use mstar_kkt::MaxAbs;
///
/// let mut m = MaxAbs::new();
/// for x in [1.0, -3.0, f64::NAN, 2.0] {
///     m.push(x);
/// }
/// assert!(m.value().is_nan());
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MaxAbs {
    max: f64,
    finite: Finite,
}

impl MaxAbs {
    /// An empty maximum (its value is 0).
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// Takes `|x|` into the maximum.
    #[inline]
    pub fn push(&mut self, x: f64) {
        let a = x.abs();
        self.max = if a > self.max { a } else { self.max };
        self.finite.push(x);
    }

    /// The maximum of the finite `|x|` pushed so far, ignoring non-finite
    /// entries (for callers that check [`is_finite`](Self::is_finite)).
    #[inline]
    #[must_use]
    pub fn finite_max(&self) -> f64 {
        self.max
    }

    /// Whether every entry pushed so far was finite.
    #[inline]
    #[must_use]
    pub fn is_finite(&self) -> bool {
        self.finite.all()
    }

    /// `max |x|` over the entries pushed: NaN when one was NaN and none was
    /// infinite, infinite when one was infinite, 0 when none was pushed.
    #[inline]
    #[must_use]
    pub fn value(&self) -> f64 {
        if self.is_finite() || !self.max.is_finite() {
            self.max
        } else {
            f64::NAN
        }
    }

    /// Merges another running maximum into this one.
    #[inline]
    pub fn merge(&mut self, other: Self) {
        self.max = if other.max > self.max {
            other.max
        } else {
            self.max
        };
        self.finite.merge(other.finite);
    }
}

/// `‖x‖∞` (NaN if an entry is NaN and none infinite, infinite if an entry is).
#[must_use]
pub fn max_abs(x: &[f64]) -> f64 {
    // Four independent lanes the compiler can vectorize.
    let mut lanes = [MaxAbs::new(); 4];
    let chunks = x.chunks_exact(4);
    let tail = chunks.remainder();
    for c in chunks {
        for k in 0..4 {
            lanes[k].push(c[k]);
        }
    }
    for (k, &v) in tail.iter().enumerate() {
        lanes[k].push(v);
    }
    let [mut m, b, c, d] = lanes;
    m.merge(b);
    m.merge(c);
    m.merge(d);
    m.value()
}

/// The index and magnitude of the largest `|xᵢ|`, a NaN winning over any
/// number (the first of equals; `(0, 0.0)` for an empty `x`): where a
/// residual or a violation is worst.
#[must_use]
pub fn argmax_abs(x: &[f64]) -> (usize, f64) {
    x.iter()
        .enumerate()
        .fold((0, 0.0f64), |(k, best), (i, &v)| {
            if v.abs() > best || (v.is_nan() && !best.is_nan()) {
                (i, v.abs())
            } else {
                (k, best)
            }
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn argmax_abs_finds_the_largest_magnitude_and_a_nan_first() {
        assert_eq!(argmax_abs(&[1.0, -3.0, 2.0, 3.0]), (1, 3.0));
        assert_eq!(argmax_abs(&[]), (0, 0.0));
        let (k, v) = argmax_abs(&[1.0, f64::NAN, 5.0, f64::NAN]);
        assert_eq!(k, 1);
        assert!(v.is_nan());
    }

    /// The reference: `‖x‖∞` by cases, NaN and infinity looked for first.
    fn by_cases(x: &[f64]) -> f64 {
        if x.iter().any(|v| v.is_infinite()) {
            f64::INFINITY
        } else if x.iter().any(|v| v.is_nan()) {
            f64::NAN
        } else {
            x.iter().map(|v| v.abs()).fold(0.0, f64::max)
        }
    }

    fn same(a: f64, b: f64) -> bool {
        a == b || (a.is_nan() && b.is_nan())
    }

    #[test]
    fn max_abs_finds_the_largest_magnitude_and_non_finite_entries() {
        for len in 0usize..11 {
            let mut x: Vec<f64> = (0..len).map(|i| i as f64 * 0.5 - 2.0).collect();
            assert_eq!(max_abs(&x), by_cases(&x), "len {len}");
            if len > 0 {
                x[len - 1] = -7.5;
                assert_eq!(max_abs(&x), 7.5);
                // A NaN anywhere, also after larger finite entries.
                for at in 0..len {
                    let mut y = x.clone();
                    y[at] = f64::NAN;
                    assert!(max_abs(&y).is_nan(), "NaN at {at} of {len}");
                    y[at] = f64::NEG_INFINITY;
                    assert_eq!(max_abs(&y), f64::INFINITY);
                }
            }
        }
    }

    #[test]
    fn the_running_maximum_never_forgets_a_nan() {
        // The f64::max fold this replaces forgets it: the test can fail.
        let x = [1.0, f64::NAN, 3.0, -2.0];
        assert_eq!(x.iter().fold(0.0f64, |m, v| m.max(v.abs())), 3.0);
        for order in [[0, 1, 2, 3], [1, 0, 3, 2], [3, 2, 1, 0]] {
            let mut m = MaxAbs::new();
            for k in order {
                m.push(x[k]);
            }
            assert!(m.value().is_nan() && !m.is_finite());
            assert_eq!(m.finite_max(), 3.0);
        }
        let mut m = MaxAbs::new();
        m.push(f64::INFINITY);
        m.push(f64::NAN);
        assert!(same(m.value(), by_cases(&[f64::INFINITY, f64::NAN])));
        let mut a = MaxAbs::new();
        a.push(-4.0);
        let mut b = MaxAbs::new();
        b.push(f64::NAN);
        a.merge(b);
        assert!(a.value().is_nan());
        assert_eq!(MaxAbs::new().value(), 0.0);
    }
}
