//! Prescribed functions of time for drivers, forces and torques.

/// A function of time `f(t)` with its first two derivatives.
#[derive(Clone, Copy, Debug, PartialEq)]
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
}

impl TimeFunction {
    /// `(f(t), f'(t), f''(t))`.
    #[must_use]
    pub fn eval(&self, t: f64) -> (f64, f64, f64) {
        match *self {
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
        }
    }
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
