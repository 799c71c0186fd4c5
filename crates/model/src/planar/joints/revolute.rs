//! The revolute joint: two points coincide, `Φ = p_A − p_B` (2 rows).

use std::sync::Arc;

use super::{JointElement, JointKind, LocalPatterns, Place, point_grad};
use crate::planar::geometry::Slots;

/// `p_A − p_B = 0`.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Revolute;

pub(crate) const KIND: JointKind = JointKind {
    name: "revolute",
    example: |_| Arc::new(Revolute),
};

impl JointElement for Revolute {
    fn kind(&self) -> &'static str {
        KIND.name
    }

    fn row_names(&self, _: &Slots) -> Vec<&'static str> {
        vec![".x", ".y"]
    }

    fn patterns(&self, slots: &Slots) -> LocalPatterns {
        let mut p = LocalPatterns::default();
        p.point_rows(slots);
        p
    }

    fn phi(&self, x: &Place<'_>, out: &mut [f64]) {
        out[..2].copy_from_slice(&x.d());
    }

    fn grad(&self, x: &Place<'_>, pattern: &[(usize, usize)], out: &mut [f64]) {
        point_grad(x, pattern, out);
    }

    fn hess(&self, x: &Place<'_>, pattern: &[(usize, usize, usize)], out: &mut [f64]) {
        for (v, &(row, a, b)) in out.iter_mut().zip(pattern) {
            *v = x.slots.d_hess(a, b, row, &x.pts);
        }
    }

    fn is_revolute(&self) -> bool {
        true
    }
}
