//! # mstar-testkit — test models and validation cases
//!
//! What the tests, the studies (`xtask`) and the benchmarks share, kept out
//! of the public API of the facade `mstar` (`publish = false`):
//!
//! - [`catalogue`]: the test models, each with a consistent start and an
//!   independent reference, that one harness runs through every integrator;
//! - [`validation`]: the classic mechanisms of `models/` against independent
//!   references (`cargo xtask validate`, `docs/validation.md`);
//! - [`testing`]: the derivative checker, for the tests of a model.
#![deny(missing_docs)]

pub mod catalogue;
pub mod testing;
pub mod validation;
