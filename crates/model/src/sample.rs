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
