//! The weld: the points coincide and the relative angle stays at its initial
//! value, `Φ = [p_A − p_B; θ_B − θ_A − angle]` (3 rows).

use std::sync::Arc;

use super::{JointElement, JointKind, LocalPatterns, Place, angle_sign};
use crate::planar::geometry::Slots;

/// `p_A − p_B = 0`, `θ_B − θ_A − angle = 0`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Weld {
    /// The relative angle held, rad.
    pub(crate) angle: f64,
}

pub(crate) const KIND: JointKind = JointKind {
    name: "weld",
    example: |p| Arc::new(Weld { angle: p[0] }),
};

impl JointElement for Weld {
    fn kind(&self) -> &'static str {
        KIND.name
    }

    fn problem(&self, _: &[crate::planar::geometry::Anchor; 2]) -> Option<String> {
        (!self.angle.is_finite()).then(|| "the initial relative angle must be finite".to_string())
    }

    fn row_names(&self, _: &Slots) -> Vec<&'static str> {
        vec![".x", ".y", ".theta"]
    }

    fn patterns(&self, slots: &Slots) -> LocalPatterns {
        let mut p = LocalPatterns::default();
        p.point_rows(slots);
        p.angle_row(slots, 2);
        p
    }

    fn phi(&self, x: &Place<'_>, out: &mut [f64]) {
        out[..2].copy_from_slice(&x.d());
        out[2] = x.theta(1) - x.theta(0) - self.angle;
    }

    fn grad(&self, x: &Place<'_>, pattern: &[(usize, usize)], out: &mut [f64]) {
        for (v, &(row, a)) in out.iter_mut().zip(pattern) {
            *v = if row < 2 {
                x.slots.d_grad(a, row, &x.pts)
            } else {
                angle_sign(x.slots, a)
            };
        }
    }

    fn hess(&self, x: &Place<'_>, pattern: &[(usize, usize, usize)], out: &mut [f64]) {
        for (v, &(row, a, b)) in out.iter_mut().zip(pattern) {
            *v = x.slots.d_hess(a, b, row, &x.pts);
        }
    }
}
