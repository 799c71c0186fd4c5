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

/// A point mass in `D` dimensions: mass, initial position and velocity
/// ([`planar::PointMass`](crate::planar::PointMass) in the plane,
/// [`spatial::SpatialPointMass`](crate::spatial::SpatialPointMass) in
/// space).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointMass<const D: usize> {
    /// Mass, kg (> 0).
    pub mass: f64,
    /// Position, global, m: `[x, y]` or `[x, y, z]`.
    pub position: [f64; D],
    /// Velocity, global, m/s (default: at rest).
    pub velocity: [f64; D],
}

/// A dimension: how many coordinates a body has in it ([`Planar`],
/// [`Spatial`]).
pub(crate) trait Dimension: Clone + std::fmt::Debug {
    /// A rigid body's coordinates: `(x, y, θ)` in the plane, `(x, y, z, e0,
    /// e1, e2, e3)` in space.
    const RIGID: usize;
    /// A point mass's coordinates: `(x, y)` or `(x, y, z)`.
    const POINT: usize;
    /// A body's coordinates or velocities, with room for a rigid body's
    /// (a point mass uses the first [`POINT`](Self::POINT)).
    type Coords: Copy + std::fmt::Debug + AsRef<[f64]>;

    /// The coordinates of a rigid body (`rigid`) or a point mass.
    fn count(rigid: bool) -> usize {
        if rigid { Self::RIGID } else { Self::POINT }
    }
}

/// The plane: rigid bodies in `(x, y, θ)`, point masses in `(x, y)`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Planar;

/// Space: rigid bodies in `(x, y, z, e0, e1, e2, e3)`, point masses in
/// `(x, y, z)`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Spatial;

impl Dimension for Planar {
    const RIGID: usize = 3;
    const POINT: usize = 2;
    type Coords = [f64; 3];
}

impl Dimension for Spatial {
    const RIGID: usize = 7;
    const POINT: usize = 3;
    type Coords = [f64; 7];
}

/// A body as an assembled system holds it, in either dimension; `I` is a
/// rigid body's rotational inertia as assembled.
#[derive(Clone, Debug)]
pub(crate) struct Body<D: Dimension, I> {
    pub(crate) name: String,
    pub(crate) mass: f64,
    /// `None` for a point mass.
    pub(crate) inertia: Option<I>,
    /// Its first coordinate.
    pub(crate) x: usize,
    /// Its initial coordinates.
    pub(crate) u0: D::Coords,
    /// Its initial velocities.
    pub(crate) v0: D::Coords,
}

impl<D: Dimension, I> Body<D, I> {
    /// Its number of coordinates: [`Dimension::RIGID`] for a rigid body,
    /// [`Dimension::POINT`] for a point mass.
    pub(crate) fn count(&self) -> usize {
        D::count(self.inertia.is_some())
    }

    /// Whether it is a rigid body (not a point mass).
    pub(crate) fn is_rigid(&self) -> bool {
        self.inertia.is_some()
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
pub(crate) fn initial<D: Dimension, I>(
    n: usize,
    bodies: &[Body<D, I>],
    which: Initial,
) -> Vec<f64> {
    let mut u = vec![0.0; n];
    for b in bodies {
        let values = match which {
            Initial::Position => b.u0,
            Initial::Velocity => b.v0,
        };
        let (x, count) = (b.x, b.count());
        u[x..x + count].copy_from_slice(&values.as_ref()[..count]);
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

/// The [`System`](crate::System) methods that only read the sizes and the
/// row names, the same in every assembled system: `n_coords` (`self.n`),
/// `n_constraints` (`self.m`) and `constraint_name`
/// (`self.constraint_names[i]`).
macro_rules! sizes_and_row_names {
    () => {
        fn n_coords(&self) -> usize {
            self.n
        }

        fn n_constraints(&self) -> usize {
            self.m
        }

        fn constraint_name(&self, i: usize) -> String {
            self.constraint_names[i].clone()
        }
    };
}
pub(crate) use sizes_and_row_names;

/// The inherent methods of an assembled system that read its bodies' initial
/// state ([`initial`]) and count them, documented per dimension: where the
/// system's module has `dims` and `dims::Initial` in scope.
macro_rules! initial_state {
    (position: $position:literal, velocity: $velocity:literal) => {
        #[doc = $position]
        #[must_use]
        pub fn initial_position(&self) -> Vec<f64> {
            dims::initial(self.n, &self.bodies, Initial::Position)
        }

        #[doc = $velocity]
        #[must_use]
        pub fn initial_velocity(&self) -> Vec<f64> {
            dims::initial(self.n, &self.bodies, Initial::Velocity)
        }

        /// Number of bodies.
        #[must_use]
        pub fn n_bodies(&self) -> usize {
            self.bodies.len()
        }
    };
}
pub(crate) use initial_state;
