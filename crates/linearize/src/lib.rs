//! # mstar-linearize — residual, constraints and the KKT iteration matrix
//!
//! Given a [`System`](mstar_model::System) and a state, [`Linearization`]
//! evaluates the residual `r = g − Bᵀλ − M ü` (the paper's eq. 3), the
//! constraints `Φ` (eq. 4), the tangent matrices `K_T`, `C_T` (eqs. 6-7) and fills
//! the values of the KKT matrix `[S_T Bᵀ; B 0]` (eqs. 16-17) on a compressed
//! sparse column structure computed once. [`check_derivatives`] compares every
//! analytic derivative with finite differences.
//!
//! ```
//! use mstar_linearize::{Coefficients, Linearization};
//! use mstar_model::{PendulumChain, StateRef};
//!
//! let sys = PendulumChain::paper(1.0, 1.0, 10.0);
//! let mut lin = Linearization::new(&sys).expect("valid patterns");
//! let u = sys.position(&[0.3]);
//! let (zeros, lambda) = ([0.0; 3], [0.0; 2]);
//! let x = StateRef { t: 0.0, u: &u, v: &zeros, a: &zeros, lambda: &lambda };
//! lin.eval_residual(&sys, &x);
//! lin.eval_jacobians(&sys, &x);
//! let (beta, gamma, h) = (0.25, 0.5, 0.01);
//! lin.assemble(&Coefficients {
//!     c_u: 1.0,
//!     c_v: gamma / (beta * h),
//!     c_a: 1.0 / (beta * h * h),
//!     c_bb: 1.0 / (beta * h * h),
//!     c_identity: 0.0,
//!     scale: 1.0,
//! });
//! assert_eq!(lin.kkt().n, 5);
//! assert!((lin.residual_norm() - 10.0).abs() < 1e-12); // r = g = [0, −m g₀, 0]
//! ```
#![deny(missing_docs)]

mod check;
mod csc;
mod fours;
mod layout;
mod linearization;

pub use check::{DerivativeErrors, check_derivatives};
pub use linearization::{Coefficients, Linearization, LinearizeError};
pub use mstar_kkt::{Csc, MaxAbs, Structure, max_abs};
