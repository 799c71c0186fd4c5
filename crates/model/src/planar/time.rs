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

    #[test]
    fn derivatives_match_differences() {
        let f = TimeFunction::Sine {
            offset: 0.3,
            amplitude: 2.0,
            omega: 3.0,
            phase: 0.4,
        };
        let (t, d) = (0.7, 1e-5);
        let (f0, f1, f2) = f.eval(t);
        let (fp, fp1, _) = f.eval(t + d);
        let (fm, fm1, _) = f.eval(t - d);
        assert!(((fp - fm) / (2.0 * d) - f1).abs() < 1e-8);
        assert!(((fp1 - fm1) / (2.0 * d) - f2).abs() < 1e-7);
        assert!((fp - 2.0 * f0 + fm) / (d * d) - f2 < 1e-3);
    }
}
