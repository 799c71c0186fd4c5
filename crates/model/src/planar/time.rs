//! Prescribed functions of time for drivers, forces and torques.

/// A function of time `f(t)` with its first two derivatives.
#[derive(Clone, Debug, PartialEq)]
pub enum TimeFunction {
    /// `f(t) = c`.
    Constant(f64),
    /// `f(t) = value + rate · t`.
    Linear {
        /// Value at `t = 0`.
        value: f64,
        /// Slope.
        rate: f64,
    },
    /// `f(t) = offset + amplitude · sin(ω t + phase)`.
    Sine {
        /// Mean value.
        offset: f64,
        /// Amplitude.
        amplitude: f64,
        /// Angular frequency ω, rad/s.
        omega: f64,
        /// Phase, rad.
        phase: f64,
    },
    /// Piecewise linear through the points `(tᵢ, vᵢ)` (times strictly
    /// increasing), constant before the first and after the last. Its
    /// derivative is the slope of the segment `t` is in (at a breakpoint, the
    /// segment that starts there), its second derivative zero: a driver
    /// following a table has velocity jumps at the breakpoints.
    Table(Vec<(f64, f64)>),
}

impl TimeFunction {
    /// `(f(t), f'(t), f''(t))`.
    #[must_use]
    pub fn eval(&self, t: f64) -> (f64, f64, f64) {
        match *self {
            Self::Table(ref points) => table(points, t),
            Self::Constant(c) => (c, 0.0, 0.0),
            Self::Linear { value, rate } => (value + rate * t, rate, 0.0),
            Self::Sine {
                offset,
                amplitude,
                omega,
                phase,
            } => {
                let (s, c) = (omega * t + phase).sin_cos();
                (
                    offset + amplitude * s,
                    amplitude * omega * c,
                    -amplitude * omega * omega * s,
                )
            }
        }
    }

    /// `true` when every value is finite.
    #[must_use]
    pub fn is_finite(&self) -> bool {
        match *self {
            Self::Constant(c) => c.is_finite(),
            Self::Linear { value, rate } => value.is_finite() && rate.is_finite(),
            Self::Sine {
                offset,
                amplitude,
                omega,
                phase,
            } => [offset, amplitude, omega, phase]
                .iter()
                .all(|x| x.is_finite()),
            Self::Table(ref points) => points.iter().all(|(t, v)| t.is_finite() && v.is_finite()),
        }
    }

    /// Why the function cannot be used, if it cannot: a non-finite value, or
    /// a table without points or with times that do not increase.
    #[must_use]
    pub fn problem(&self) -> Option<String> {
        if !self.is_finite() {
            return Some("every value of the function must be finite".to_string());
        }
        match self {
            Self::Table(points) if points.is_empty() => {
                Some("a table needs at least one point [t, value]".to_string())
            }
            Self::Table(points) => points.windows(2).position(|w| w[1].0 <= w[0].0).map(|k| {
                format!(
                    "the times of a table must increase: point {} (t = {}) is not after point {} (t = {})",
                    k + 1,
                    points[k + 1].0,
                    k,
                    points[k].0
                )
            }),
            _ => None,
        }
    }
}

/// `(f, f', f'')` of the piecewise-linear table `points` at `t`.
fn table(points: &[(f64, f64)], t: f64) -> (f64, f64, f64) {
    let (Some(&(t0, v0)), Some(&(t1, v1))) = (points.first(), points.last()) else {
        return (0.0, 0.0, 0.0);
    };
    if t < t0 {
        return (v0, 0.0, 0.0);
    }
    if t >= t1 {
        return (v1, 0.0, 0.0);
    }
    // The segment [t_k, t_{k+1}) that holds t.
    let k = points.partition_point(|&(tk, _)| tk <= t) - 1;
    let ((ta, va), (tb, vb)) = (points[k], points[k + 1]);
    let slope = (vb - va) / (tb - ta);
    (va + slope * (t - ta), slope, 0.0)
}

impl From<f64> for TimeFunction {
    fn from(c: f64) -> Self {
        Self::Constant(c)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The errors of `f'` and `f''` against central differences of `f` and
    /// `f'` at `t`, and of `f''` against the second difference of `f`.
    fn derivative_errors(f: impl Fn(f64) -> (f64, f64, f64), t: f64) -> [f64; 3] {
        let d = 1e-5;
        let (f0, f1, f2) = f(t);
        let (fp, fp1, _) = f(t + d);
        let (fm, fm1, _) = f(t - d);
        [
            ((fp - fm) / (2.0 * d) - f1).abs(),
            ((fp1 - fm1) / (2.0 * d) - f2).abs(),
            ((fp - 2.0 * f0 + fm) / (d * d) - f2).abs(),
        ]
    }

    /// Tolerances of [`derivative_errors`]: truncation `d² f‴/6` and
    /// round-off `ε |f| / d` (first differences), `ε |f| / d²` (second).
    const TOLERANCES: [f64; 3] = [1e-8, 1e-7, 1e-3];

    fn within(errors: [f64; 3]) -> bool {
        errors.iter().zip(TOLERANCES).all(|(e, tol)| *e <= tol)
    }

    #[test]
    fn derivatives_match_differences() {
        let sine = TimeFunction::Sine {
            offset: 0.3,
            amplitude: 2.0,
            omega: 3.0,
            phase: 0.4,
        };
        for f in [
            sine,
            TimeFunction::Constant(1.5),
            TimeFunction::Linear {
                value: -1.0,
                rate: 2.5,
            },
        ] {
            for t in [0.0, 0.7, 3.1] {
                let e = derivative_errors(|t| f.eval(t), t);
                assert!(within(e), "{f:?} at t = {t}: {e:?}");
            }
        }
    }

    #[test]
    fn a_table_interpolates_and_holds_its_ends() {
        let f = TimeFunction::Table(vec![(0.0, 1.0), (1.0, 3.0), (3.0, -1.0)]);
        assert_eq!(f.eval(-1.0), (1.0, 0.0, 0.0));
        assert_eq!(f.eval(0.5), (2.0, 2.0, 0.0));
        assert_eq!(f.eval(1.0), (3.0, -2.0, 0.0));
        assert_eq!(f.eval(2.0), (1.0, -2.0, 0.0));
        assert_eq!(f.eval(3.0), (-1.0, 0.0, 0.0));
        assert_eq!(f.eval(7.0), (-1.0, 0.0, 0.0));
        assert_eq!(f.problem(), None);
        let single = TimeFunction::Table(vec![(0.5, 2.0)]);
        assert_eq!(single.eval(0.0), (2.0, 0.0, 0.0));
        assert_eq!(single.eval(9.0), (2.0, 0.0, 0.0));
        assert!(TimeFunction::Table(vec![]).problem().is_some());
        let backwards = TimeFunction::Table(vec![(0.0, 1.0), (0.0, 2.0)]);
        assert!(backwards.problem().is_some_and(|p| p.contains("increase")));
        assert!(TimeFunction::Constant(f64::NAN).problem().is_some());
    }

    #[test]
    fn the_derivative_check_catches_a_wrong_sign_and_a_nan() {
        let f = TimeFunction::Sine {
            offset: 0.3,
            amplitude: 2.0,
            omega: 3.0,
            phase: 0.4,
        };
        // f'' of the wrong sign: the second-difference check must see it in
        // both directions (it once compared without |·|).
        for t in [0.2, 1.3] {
            let wrong = |t: f64| {
                let (a, b, c) = f.eval(t);
                (a, b, -c)
            };
            let e = derivative_errors(wrong, t);
            assert!(
                e[1] > TOLERANCES[1] && e[2] > TOLERANCES[2],
                "t = {t}: {e:?}"
            );
        }
        let nan = |t: f64| {
            let (a, b, _) = f.eval(t);
            (a, b, f64::NAN)
        };
        assert!(!within(derivative_errors(nan, 0.5)));
    }
}
