//! # mstar-newmark — Newmark, HHT-α and generalized-α for index-3 DAEs
//!
//! [`Integrator`] advances a [`System`](mstar_model::System) in time with the
//! paper's predictor-corrector Newton-Raphson scheme (eqs. 12-17, Fig. 2): the
//! predictor (14), the corrector (15) and the KKT system (16) with the iteration
//! matrix `S_T = K_T + γ/(βh) C_T + M*/(βh²)` (17), `M* = M + BᵀB` (11).
//! Beyond the paper: HHT-α and generalized-α ([`Scheme`]), consistent initial
//! conditions and projection ([`Start`], [`Config::project`]), scaling of the KKT
//! system, modified Newton and step control ([`Config`]).
//!
//! ```
//! use mstar_model::PendulumChain;
//! use mstar_newmark::{Config, Integrator, Trajectory};
//!
//! // The paper's setting: Newmark β = 1/4, γ = 1/2, start from M* and λ₀.
//! let sys = PendulumChain::paper(1.0, 1.0, 10.0);
//! let u0 = sys.position(&[std::f64::consts::FRAC_PI_2]);
//! let config = Config::paper(0.01, vec![-10.0, 0.0]);
//! let mut integ = Integrator::new(&sys, config, 0.0, &u0, &[0.0; 3])?;
//! let mut traj = Trajectory::default();
//! integ.run(0.5, &mut traj)?;
//! let last = traj.samples.last().expect("samples");
//! assert!((last.t - 0.5).abs() < 1e-12);
//! assert!(last.constraint < 1e-9);
//! # Ok::<(), mstar_newmark::IntegrationError>(())
//! ```
#![deny(missing_docs)]

mod error;
mod integrator;
mod output;
mod params;
mod resample;

pub use error::{IntegrationError, Short};
pub use integrator::{
    Column, DIFFERENCE_STEP, Gradient, Integrator, Memory, NewtonSwitch, Objective, Parameterized,
    Sensitivities, StartReport, Variant,
};
pub use output::{EnergyReport, ErrorReport, Observer, RunStats, Trajectory};
pub use params::{AlphaParams, Config, ErrorControl, Newton, Predictor, Scheme, Start, StepMode};
pub use resample::Resample;
