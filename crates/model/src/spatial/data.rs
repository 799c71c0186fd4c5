//! The assembled elements that [`SpatialSystem`](super::SpatialSystem)
//! holds and `evaluate` reads: bodies with their first coordinate, joints and
//! loads with their rows and the places of their structural entries. Apart
//! from the system's file so that `evaluate` and `builder` depend on the data
//! and not on each other.

use std::sync::Arc;

use super::body::Inertia;
use super::joints::SpatialJoint;
use super::loads::SpatialLoad;
use crate::dims::Spatial;

/// A body as assembled.
pub(crate) type BodyData = crate::dims::Body<Spatial, Inertia>;

/// A joint or driver as assembled: its rows, its structural entries and where
/// its values go.
#[derive(Clone, Debug)]
pub(crate) struct JointData {
    pub(crate) name: String,
    pub(crate) sides: [Option<usize>; 2],
    pub(crate) element: Arc<dyn SpatialJoint>,
    pub(crate) row0: usize,
    /// `(row, local variable)` of its entries of `B`, in value order.
    pub(crate) b_local: Vec<(usize, usize)>,
    /// Local pairs of its Hessian entries, in value order.
    pub(crate) h_local: Vec<(usize, usize)>,
    pub(crate) b_off: usize,
    pub(crate) h_off: usize,
}

impl JointData {
    pub(crate) fn new(
        name: String,
        sides: [Option<usize>; 2],
        element: Arc<dyn SpatialJoint>,
    ) -> Self {
        Self {
            name,
            sides,
            element,
            row0: 0,
            b_local: Vec::new(),
            h_local: Vec::new(),
            b_off: 0,
            h_off: 0,
        }
    }

    pub(crate) fn rows(&self) -> usize {
        self.element.row_names().len()
    }
}

/// A load as assembled.
#[derive(Clone, Debug)]
pub(crate) struct LoadData {
    pub(crate) name: String,
    pub(crate) sides: [Option<usize>; 2],
    pub(crate) element: Arc<dyn SpatialLoad>,
}

impl LoadData {
    /// The number of coordinates of each side (0 for the ground).
    pub(crate) fn counts(&self, bodies: &[BodyData]) -> [usize; 2] {
        self.sides.map(|s| s.map_or(0, |i| bodies[i].count()))
    }
}
