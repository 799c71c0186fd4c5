//! Spatial multibody systems: rigid bodies in Euler parameters
//! `(x, y, z, e0, e1, e2, e3)`, point masses in `(x, y, z)`, joints, drivers
//! and forces, assembled into a [`System`](crate::System) (`docs/theory.md`, "Spatial
//! bodies").
//!
//! A rigid body's mass matrix `diag(m I₃, 4 Gᵀ J' G)` is singular (rank 3 in
//! its rotational block): the case the paper's `M* = M + BᵀB` (eq. 11) was
//! made for. Each rigid body carries the normalization constraint
//! `pᵀp − 1 = 0` (row `<body>.norm`). [`RotationalMass::Regularized`] adds
//! `κ p pᵀ` to the block instead, which leaves the motion unchanged (its force
//! is parallel to the normalization constraint's gradient) and makes `M`
//! regular, as backends that invert `M` block by block need.
//!
//! Joints and loads are written once over numbers that carry their
//! derivatives (module `real`), so their Jacobians and Hessians are exact; the
//! bodies' inertia terms (module `body`), the spherical joints of chains
//! (module `kernel`) and the joints' rows at each iteration (module
//! `hessian`) are written out by hand for speed.

mod body;
mod builder;
mod chain;
mod data;
mod evaluate;
mod examples;
mod frame;
mod hessian;
mod joints;
mod kernel;
mod loads;
pub(crate) mod real;
pub(crate) mod rotation;
mod sketch;
mod spherical;
mod system;

pub use builder::{
    Attach, Axes, DriverKind, JointSpec, JointType, RotationalMass, RotationalSpringDamper,
    SpatialBody, SpatialBuilder, SpatialInertia, SpatialPointMass, SpringDamper,
};
pub use chain::spatial_bar_chain;
pub use examples::element_examples;
pub use sketch::{SpatialAttachment, SpatialSketch, SpatialSketchBody, SpatialSketchElement};
pub use system::{SpatialReaction, SpatialSystem};

/// Handle of a body in the [`SpatialBuilder`] that made it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct SpatialBodyId(pub(crate) usize);

/// Unit Euler parameters of the rotation by `angle` (rad) about `axis`.
#[must_use]
pub fn euler_parameters(axis: [f64; 3], angle: f64) -> [f64; 4] {
    let n = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
    let (s, c) = (0.5 * angle).sin_cos();
    if n == 0.0 {
        return [1.0, 0.0, 0.0, 0.0];
    }
    [c, s * axis[0] / n, s * axis[1] / n, s * axis[2] / n]
}

/// The rotation matrix `A(p)` (body to global) of unit Euler parameters,
/// row by row.
#[must_use]
pub fn rotation_matrix(p: [f64; 4]) -> [[f64; 3]; 3] {
    let cols: [[f64; 3]; 3] = std::array::from_fn(|j| {
        let mut e = [0.0; 3];
        e[j] = 1.0;
        rotation::rotate(&p, e)
    });
    std::array::from_fn(|i| std::array::from_fn(|j| cols[j][i]))
}
