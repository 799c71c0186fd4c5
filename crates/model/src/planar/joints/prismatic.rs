//! The prismatic joint: point B stays on the line through point A with the
//! normal `n_A = A(θ_A) n'`, `Φ = −n_A · (p_A − p_B)`; a rigid body B also
//! keeps its initial angle relative to A (`θ_B − θ_A − angle`, a second row).

use std::sync::Arc;

use super::{JointElement, JointKind, LocalPatterns, Place, angle_sign, theta_slot};
use crate::planar::geometry::{Anchor, Kind, Slots};

/// `n_A · (p_B − p_A) = 0`, and `θ_B − θ_A − angle = 0` for a rigid B.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Prismatic {
    /// The unit normal of the sliding direction in A's frame.
    pub(crate) normal: [f64; 2],
    /// The relative angle held, rad.
    pub(crate) angle: f64,
}

pub(crate) const KIND: JointKind = JointKind {
    name: "prismatic",
    example: |p| {
        let (s, c) = (0.7 + p[0]).sin_cos();
        Arc::new(Prismatic {
            normal: [-s, c],
            angle: p[1],
        })
    },
};

impl Prismatic {
    /// `n_A` and `∂n_A/∂θ_A` (zero when A is not a rigid body).
    fn normal(&self, x: &Place<'_>) -> ([f64; 2], [f64; 2]) {
        let n0 = self.normal;
        match x.anchors[0] {
            Anchor::Rigid { x: i, .. } => {
                let (s, c) = x.u[i + 2].sin_cos();
                let n = [c * n0[0] - s * n0[1], s * n0[0] + c * n0[1]];
                (n, [-n[1], n[0]])
            }
            _ => (n0, [0.0, 0.0]),
        }
    }
}

impl JointElement for Prismatic {
    fn kind(&self) -> &'static str {
        KIND.name
    }

    fn axis(&self) -> Option<[f64; 2]> {
        // normal = (−a_y, a_x) of the unit axis a.
        Some([self.normal[1], -self.normal[0]])
    }

    fn problem(&self, anchors: &[Anchor; 2]) -> Option<String> {
        if !self.normal.iter().all(|x| x.is_finite()) {
            Some("the prismatic axis must be a non-zero vector".to_string())
        } else if matches!(anchors[1], Anchor::Ground(_)) {
            Some("the sliding side (b) must be a body".to_string())
        } else {
            None
        }
    }

    fn row_names(&self, slots: &Slots) -> Vec<&'static str> {
        if theta_slot(slots, 1).is_some() {
            vec![".line", ".theta"]
        } else {
            vec![".line"]
        }
    }

    /// The line row: every slot, the Hessian on `θ_A`'s row and column and on
    /// `θ_B`'s diagonal; the angle row for a rigid B.
    fn patterns(&self, slots: &Slots) -> LocalPatterns {
        let (ta, tb) = (theta_slot(slots, 0), theta_slot(slots, 1));
        let mut p = LocalPatterns::default();
        let n = slots.len();
        for a in 0..n {
            p.grad.push((0, a));
            for b in 0..n {
                let with_ta = Some(a) == ta || Some(b) == ta;
                let tb_diag = a == b && Some(a) == tb;
                if with_ta || tb_diag {
                    p.hess.push((0, a, b));
                }
            }
        }
        if tb.is_some() {
            p.angle_row(slots, 1);
        }
        p
    }

    fn phi(&self, x: &Place<'_>, out: &mut [f64]) {
        let ((n, _), d) = (self.normal(x), x.d());
        out[0] = -(n[0] * d[0] + n[1] * d[1]);
        if out.len() == 2 {
            out[1] = x.theta(1) - x.theta(0) - self.angle;
        }
    }

    fn grad(&self, x: &Place<'_>, pattern: &[(usize, usize)], out: &mut [f64]) {
        let ((n, dn), d, s) = (self.normal(x), x.d(), x.slots);
        for (v, &(row, a)) in out.iter_mut().zip(pattern) {
            *v = if row == 1 {
                angle_sign(s, a)
            } else {
                let mut g = n[0] * s.d_grad(a, 0, &x.pts) + n[1] * s.d_grad(a, 1, &x.pts);
                if s.kind[a] == Kind::Theta && s.side[a] == 0 {
                    g += dn[0] * d[0] + dn[1] * d[1];
                }
                -g
            };
        }
    }

    fn hess(&self, x: &Place<'_>, pattern: &[(usize, usize, usize)], out: &mut [f64]) {
        let ((n, dn), d, s, pts) = (self.normal(x), x.d(), x.slots, &x.pts);
        let ta = |i: usize| s.kind[i] == Kind::Theta && s.side[i] == 0 && dn != [0.0, 0.0];
        for (v, &(_, a, b)) in out.iter_mut().zip(pattern) {
            let mut h: f64 = (0..2).map(|k| n[k] * s.d_hess(a, b, k, pts)).sum();
            if ta(a) {
                h += (0..2).map(|k| dn[k] * s.d_grad(b, k, pts)).sum::<f64>();
            }
            if ta(b) {
                h += (0..2).map(|k| dn[k] * s.d_grad(a, k, pts)).sum::<f64>();
            }
            if ta(a) && a == b {
                // ∂²n/∂θ² = −n
                h -= n[0] * d[0] + n[1] * d[1];
            }
            *v = -h;
        }
    }
}
