//! # mstar-model — what a constrained system is
//!
//! The [`System`] trait describes the index-3 DAE of `algorithm.md` §1 (the
//! paper's eqs. 1-4),
//! `M ü + Bᵀλ = g(u, u̇, t)`, `Φ(u, t) = 0`, with every matrix declared once as
//! a sparse [`Pattern`] and written into caller-owned value buffers.
//!
//! [`PendulumChain`] is the paper's example (one link, `u = [x, y, θ]`, singular
//! `M = diag(m, m, 0)`) and its multi-link generalization.
//!
//! ```
//! use mstar_model::{PendulumChain, System};
//!
//! let pendulum = PendulumChain::paper(1.0, 1.0, 10.0);
//! let u = pendulum.position(&[std::f64::consts::FRAC_PI_2]); // released horizontally
//! let mut phi = vec![0.0; pendulum.n_constraints()];
//! pendulum.phi_into(0.0, &u, &mut phi);
//! assert!(phi.iter().all(|p| p.abs() < 1e-15));
//! assert_eq!(pendulum.coord_name(2), "theta");
//! ```
#![deny(missing_docs)]

mod dims;
mod fd;
mod fn_system;
mod parallel;
mod pattern;
mod pendulum;
pub mod planar;
mod sample;
pub mod sensor;
pub mod spatial;
pub mod subnormal;
mod subset;
mod system;

pub use dims::PointMass;
pub use fn_system::{FnSystem, NamesError};
pub use pattern::Pattern;
pub use pendulum::{Link, PendulumChain};
pub use sample::{Sample, SampleRef, StateRef};
pub use subnormal::FlushSubnormals;
pub use subset::RowSubset;
pub use system::{System, constraint_names, coord_names, kinetic_energy};
