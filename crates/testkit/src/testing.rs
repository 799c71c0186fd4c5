//! For authors of models: check every analytic derivative of a [`System`]
//! against finite differences before integrating it.
//!
//! ```
//! use mstar_testkit::testing::check_derivatives;
//! use mstar::{PendulumChain, StateRef};
//!
//! let sys = PendulumChain::paper(1.0, 1.0, 9.81);
//! let u = sys.position(&[0.4]);
//! let e = check_derivatives(&sys, &StateRef { t: 0.0, u: &u, v: &[0.3, -0.2, 0.5], a: &[0.0; 3], lambda: &[1.0, -2.0] });
//! assert!(e.max() < 1e-6, "{e:?}"); // NaN fails too
//! ```
//!
//! [`System`]: mstar::System

pub use mstar::linearize::{DerivativeErrors, check_derivatives};
