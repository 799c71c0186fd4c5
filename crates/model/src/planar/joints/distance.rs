//! The distance joint (a massless rod): the points stay `length` apart,
//! `Φ = ½(|p_A − p_B|² − L²)` (1 row).

use std::sync::Arc;

use super::{JointElement, JointKind, LocalPatterns, Place};
use crate::planar::geometry::{Kind, Slots};

/// `½(|p_A − p_B|² − L²) = 0`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Distance {
    /// `L`, m.
    pub(crate) length: f64,
}

pub(crate) const KIND: JointKind = JointKind {
    name: "distance",
    example: |p| {
        Arc::new(Distance {
            length: 1.0 + 0.5 * p[0],
        })
    },
};

impl JointElement for Distance {
    fn kind(&self) -> &'static str {
        KIND.name
    }

    fn problem(&self, _: &[crate::planar::geometry::Anchor; 2]) -> Option<String> {
        (!(self.length > 0.0 && self.length.is_finite()))
            .then(|| "the rod length must be positive".to_string())
    }

    fn row_names(&self, _: &Slots) -> Vec<&'static str> {
        vec![""]
    }

    /// Every slot, and the Hessian's products of `∂d/∂q` (no `x`·`y` pairs)
    /// and its `θθ` diagonal.
    fn patterns(&self, slots: &Slots) -> LocalPatterns {
        let mut p = LocalPatterns::default();
        let n = slots.len();
        for a in 0..n {
            p.grad.push((0, a));
            for b in 0..n {
                let theta_diag = a == b && slots.kind[a] == Kind::Theta;
                if slots.couples(a, b) || theta_diag {
                    p.hess.push((0, a, b));
                }
            }
        }
        p
    }

    fn phi(&self, x: &Place<'_>, out: &mut [f64]) {
        let d = x.d();
        out[0] = 0.5 * (d[0] * d[0] + d[1] * d[1] - self.length * self.length);
    }

    fn grad(&self, x: &Place<'_>, pattern: &[(usize, usize)], out: &mut [f64]) {
        let (d, s) = (x.d(), x.slots);
        for (v, &(_, a)) in out.iter_mut().zip(pattern) {
            *v = d[0] * s.d_grad(a, 0, &x.pts) + d[1] * s.d_grad(a, 1, &x.pts);
        }
    }

    fn hess(&self, x: &Place<'_>, pattern: &[(usize, usize, usize)], out: &mut [f64]) {
        let (d, s, pts) = (x.d(), x.slots, &x.pts);
        for (v, &(_, a, b)) in out.iter_mut().zip(pattern) {
            *v = (0..2)
                .map(|k| s.d_grad(a, k, pts) * s.d_grad(b, k, pts) + d[k] * s.d_hess(a, b, k, pts))
                .sum();
        }
    }
}
