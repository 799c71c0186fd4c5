//! The spatial bar chain of `mstar chain --kind spatial-bars`.

use super::builder::{Attach, JointSpec, JointType, RotationalMass, SpatialBuilder};
use super::{SpatialBody, SpatialInertia, SpatialSystem};

/// `n` solid cylinders (1 kg, 1 m, radius 0.02 m) on spherical joints, the
/// first to the ground at the origin, along +x at rest, gravity `−9.81 z`:
/// bar `k` (from 1) has its centre at `(k − ½, 0, 0)`. The iteration matrix
/// is exact: its bodies' 4 × 4 gyroscopic blocks are not symmetric, so the
/// automatic KKT choice takes the `schur-lu` backend, and full Newton
/// converges in one iteration a step (docs/theory.md, "Spatial bodies").
/// [`SpatialSystem::with_symmetric_tangent`] gives the symmetrized matrix
/// for the symmetric backends (`schur`, `ldlt`), at about two iterations a
/// step.
///
/// # Panics
/// Never for `n ≥ 1` (the model is valid by construction); `n = 0` gives an
/// empty model.
#[must_use]
pub fn spatial_bar_chain(n: usize, rotational_mass: RotationalMass) -> SpatialSystem {
    let (m, l, r) = (1.0, 1.0, 0.02);
    let axial = 0.5 * m * r * r;
    let transverse = m * (3.0 * r * r + l * l) / 12.0;
    let mut b = SpatialBuilder::new();
    b.rotational_mass(rotational_mass);
    let mut prev = Attach::Ground;
    for k in 0..n {
        let id = b.body(
            &format!("bar{}", k + 1),
            SpatialBody {
                mass: m,
                inertia: SpatialInertia::Principal([axial, transverse, transverse]),
                position: [k as f64 + 0.5, 0.0, 0.0],
                orientation: [1.0, 0.0, 0.0, 0.0],
                velocity: [0.0; 3],
                angular_velocity: [0.0; 3],
            },
        );
        let first = if k == 0 {
            [0.0; 3]
        } else {
            [0.5 * l, 0.0, 0.0]
        };
        b.joint(
            &format!("joint{}", k + 1),
            JointSpec {
                kind: JointType::Spherical,
                bodies: [prev, Attach::Body(id)],
                points: [first, [-0.5 * l, 0.0, 0.0]],
                axes: [[0.0, 0.0, 1.0]; 2],
                length: None,
            },
        );
        prev = Attach::Body(id);
    }
    match b.build() {
        Ok(sys) => sys,
        Err(e) => unreachable!("the spatial chain is valid by construction: {e}"),
    }
}
