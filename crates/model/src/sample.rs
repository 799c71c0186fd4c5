//! One sample of a solution: the state of a system at a time, with the
//! integrator's diagnostics. Integrators and reference solutions both produce
//! [`Sample`]s, so one writer serves every output.

/// The state of a system at time `t` and how it was obtained.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Sample {
    /// Time, s.
    pub t: f64,
    /// Coordinates `u`.
    pub u: Vec<f64>,
    /// Velocities `u̇`.
    pub v: Vec<f64>,
    /// Accelerations `ü`.
    pub a: Vec<f64>,
    /// Lagrange multipliers `λ`.
    pub lambda: Vec<f64>,
    /// Kinetic energy `½ u̇ᵀ M u̇`.
    pub kinetic: f64,
    /// Potential energy.
    pub potential: f64,
    /// Newton iterations spent on this sample (0 for the initial state and for
    /// reference solutions).
    pub iterations: usize,
    /// Final `‖r‖∞` of the equations of motion (eq. 3).
    pub residual: f64,
    /// Final `‖Φ‖∞` of the constraints (eq. 4).
    pub constraint: f64,
}

impl Sample {
    /// Total energy, kinetic plus potential.
    #[must_use]
    pub fn energy(&self) -> f64 {
        self.kinetic + self.potential
    }
}

/// The point at which a system is evaluated: time, coordinates, velocities,
/// accelerations and multipliers (`algorithm.md` §2: the arguments of the
/// residual (3) and its Jacobians (6)-(7)), borrowed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StateRef<'a> {
    /// Time, s.
    pub t: f64,
    /// Coordinates `u`.
    pub u: &'a [f64],
    /// Velocities `u̇`.
    pub v: &'a [f64],
    /// Accelerations `ü`.
    pub a: &'a [f64],
    /// Lagrange multipliers `λ`.
    pub lambda: &'a [f64],
}

/// A [`Sample`] borrowed from where it lives (an integrator's state): what
/// an observer sees at every step, without copying the vectors.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampleRef<'a> {
    /// Time, s.
    pub t: f64,
    /// Coordinates `u`.
    pub u: &'a [f64],
    /// Velocities `u̇`.
    pub v: &'a [f64],
    /// Accelerations `ü`.
    pub a: &'a [f64],
    /// Lagrange multipliers `λ`.
    pub lambda: &'a [f64],
    /// Kinetic energy `½ u̇ᵀ M u̇`.
    pub kinetic: f64,
    /// Potential energy.
    pub potential: f64,
    /// Newton iterations spent on this sample.
    pub iterations: usize,
    /// Final `‖r‖∞` of the equations of motion (eq. 3).
    pub residual: f64,
    /// Final `‖Φ‖∞` of the constraints (eq. 4).
    pub constraint: f64,
}

impl<'a> SampleRef<'a> {
    /// Its state, without the diagnostics.
    #[must_use]
    pub fn state(&self) -> StateRef<'a> {
        StateRef {
            t: self.t,
            u: self.u,
            v: self.v,
            a: self.a,
            lambda: self.lambda,
        }
    }

    /// Total energy, kinetic plus potential.
    #[must_use]
    pub fn energy(&self) -> f64 {
        self.kinetic + self.potential
    }

    /// An owned copy.
    #[must_use]
    pub fn to_sample(&self) -> Sample {
        Sample {
            t: self.t,
            u: self.u.to_vec(),
            v: self.v.to_vec(),
            a: self.a.to_vec(),
            lambda: self.lambda.to_vec(),
            kinetic: self.kinetic,
            potential: self.potential,
            iterations: self.iterations,
            residual: self.residual,
            constraint: self.constraint,
        }
    }
}

impl Sample {
    /// A borrowed view of this sample.
    #[must_use]
    pub fn view(&self) -> SampleRef<'_> {
        SampleRef {
            t: self.t,
            u: &self.u,
            v: &self.v,
            a: &self.a,
            lambda: &self.lambda,
            kinetic: self.kinetic,
            potential: self.potential,
            iterations: self.iterations,
            residual: self.residual,
            constraint: self.constraint,
        }
    }
}
