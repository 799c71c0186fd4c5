//! # mstar — time integration of constrained multibody systems
//!
//! The facade of the mstar workspace: it re-exports the stages of the algorithm
//! (`algorithm.md`; the paper's eqs. 1-17) and holds what every front end
//! shares: run settings, records, output sinks, sweeps. The `mstar`
//! command-line program is the crate `mstar-cli` (`crates/cli`) on top of it.
//!
//! - [`model`]: the [`System`] trait and models ([`PendulumChain`]);
//! - [`linearize`]: residual, `K_T`, `C_T` and the KKT matrix on a fixed pattern;
//! - [`kkt`]: sparse (faer) and dense KKT solvers;
//! - [`newmark`]: Newmark / HHT-α / generalized-α with Newton-Raphson
//!   ([`Integrator`], [`Config`]);
//! - [`rk4`]: independent minimal-coordinate references ([`ChainOracle`]);
//! - [`csv`]: the output format; [`pendulum`]: the paper's presets;
//!   [`analysis`]: errors, fitted orders, the period-2h amplitude;
//! - [`equilibrium`]: static equilibrium; [`linear`]: linear state-space
//!   models about it;
//! - [`run`]: model files' settings as an integrator configuration, and
//!   `mstar check`'s report; [`record`]: what a run writes (its CSV rows) and
//!   measures; [`sweep`]: many runs of a model file over parameter values,
//!   on all cores, sharded, resumable.
//!
//! A model's derivatives are checked against finite differences by
//! [`linearize::check_derivatives`]. The test models and validation cases
//! are in the crate `mstar-testkit` (`crates/testkit`, not published).
//!
//! ```
//! use mstar::pendulum::PendulumRun;
//!
//! let mut run = PendulumRun::standard();
//! run.t_end = 0.5;
//! let (samples, result) = run.run();
//! let stats = result?;
//! assert_eq!(stats.steps, 50);
//! let reference = run.reference(&[samples[50].t]);
//! let err = (samples[50].u[2] - reference[0].u[2]).abs();
//! assert!(err < 1e-3, "{err}");
//! # Ok::<(), mstar::IntegrationError>(())
//! ```
#![deny(missing_docs)]

pub mod accuracy;
pub mod analysis;
pub mod columns;
pub mod csv;
mod decimal;
pub mod equilibrium;
pub mod linear;
pub mod modes;
pub mod npz;
pub mod pendulum;
pub mod placed;
pub mod record;
pub mod redundant;
pub mod run;
pub mod sensitivity;
pub mod sweep;

pub use mstar_file as file;
pub use mstar_kkt as kkt;
pub use mstar_linearize as linearize;
pub use mstar_model as model;
pub use mstar_newmark as newmark;
pub use mstar_rk4 as rk4;

pub use mstar_model::planar;
pub use mstar_model::{
    FnSystem, Link, Pattern, PendulumChain, Sample, SampleRef, StateRef, System,
};
pub use mstar_newmark::{
    AlphaParams, Config, EnergyReport, ErrorControl, ErrorReport, IntegrationError, Integrator,
    Newton, Observer, Predictor, Resample, RunStats, Scheme, Start, StartReport, StepMode,
    Trajectory,
};
pub use mstar_rk4::{ChainOracle, pendulum_period};
