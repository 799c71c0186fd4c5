//! What the planar and the spatial libraries share, written once for both
//! dimensions (as rapier builds its 2-D and 3-D engines from one source):
//! how many coordinates a body has, the initial state assembled body by
//! body, the look-up of bodies by name, and the builders' common checks
//! (the model error, an empty model, names used twice).
//!
//! Each dimension keeps its own physics (`planar`, `spatial`); this module
//! names neither, so both may use it.

use std::collections::{HashMap, HashSet};

/// Errors in a planar or spatial model.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ModelError {
    /// Two bodies or two elements share a name.
    #[error("the name '{0}' is used twice")]
    DuplicateName(String),
    /// A parameter is out of range.
    #[error("{element}: {what}")]
    Invalid {
        /// The element's name.
        element: String,
        /// What is wrong.
        what: String,
    },
}

/// A dimension: how many coordinates a body has in it.
pub(crate) trait Dimension {
    /// A rigid body's coordinates: `(x, y, θ)` in the plane, `(x, y, z, e0,
    /// e1, e2, e3)` in space.
    const RIGID: usize;
    /// A point mass's coordinates: `(x, y)` or `(x, y, z)`.
    const POINT: usize;

    /// The coordinates of a rigid body (`rigid`) or a point mass.
    fn count(rigid: bool) -> usize {
        if rigid { Self::RIGID } else { Self::POINT }
    }
}

/// The plane.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Planar;

/// Space.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Spatial;

impl Dimension for Planar {
    const RIGID: usize = 3;
    const POINT: usize = 2;
}

impl Dimension for Spatial {
    const RIGID: usize = 7;
    const POINT: usize = 3;
}

/// A body as an assembled system holds it: its name, its place in `u` and
/// its initial state (`N` values, of which the body's count are used).
pub(crate) trait Placed<const N: usize> {
    /// The dimension it moves in.
    type Dim: Dimension;
    /// Its name.
    fn name(&self) -> &str;
    /// Its first coordinate.
    fn first(&self) -> usize;
    /// Whether it is a rigid body (not a point mass).
    fn is_rigid(&self) -> bool;
    /// Its initial coordinates.
    fn u0(&self) -> [f64; N];
    /// Its initial velocities.
    fn v0(&self) -> [f64; N];

    /// Its number of coordinates.
    fn count(&self) -> usize {
        Self::Dim::count(self.is_rigid())
    }
}

/// Which half of the initial state.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Initial {
    /// `u₀`.
    Position,
    /// `u̇₀`.
    Velocity,
}

/// The initial coordinates or velocities of `n` coordinates, body by body.
pub(crate) fn initial<B: Placed<N>, const N: usize>(
    n: usize,
    bodies: &[B],
    which: Initial,
) -> Vec<f64> {
    let mut u = vec![0.0; n];
    for b in bodies {
        let values = match which {
            Initial::Position => b.u0(),
            Initial::Velocity => b.v0(),
        };
        let (x, count) = (b.first(), b.count());
        u[x..x + count].copy_from_slice(&values[..count]);
    }
    u
}

/// Each item's index by name (bodies, joints, …).
pub(crate) fn index_by_name<'a>(names: impl Iterator<Item = &'a str>) -> HashMap<String, usize> {
    names.enumerate().map(|(i, n)| (n.to_string(), i)).collect()
}

/// What every builder checks first: the first misuse found while adding,
/// then a model without bodies.
pub(crate) fn check_start(problems: &[ModelError], bodies: usize) -> Result<(), ModelError> {
    if let Some(problem) = problems.first() {
        return Err(problem.clone());
    }
    if bodies == 0 {
        return Err(ModelError::Invalid {
            element: "the model".to_string(),
            what: "no body or point mass: add a [[body]] or [[point_mass]]".to_string(),
        });
    }
    Ok(())
}

/// Every body and element has its own name (`count` of them), and none is
/// `reserved` (the fixed frame's name, where a builder keeps it).
pub(crate) fn check_names<'a>(
    names: impl Iterator<Item = &'a String>,
    count: usize,
    reserved: Option<&str>,
) -> Result<(), ModelError> {
    let mut seen = HashSet::with_capacity(count);
    for name in names {
        if Some(name.as_str()) == reserved || !seen.insert(name.as_str()) {
            return Err(ModelError::DuplicateName(name.clone()));
        }
    }
    Ok(())
}
