//! The hot path of chains: a revolute joint's `Φ`, `B` and Hessian written
//! directly, without the generic element's slot tables (the same values in
//! the same entry order as [`Revolute`](super::Revolute) through
//! [`Constraint`]), each body's `sin θ, cos θ` read from a table.

use super::Constraint;
use crate::planar::geometry::Anchor;

/// The hot path of chains: a revolute joint's `Φ`, `B` and Hessian written
/// directly, without the generic element's slot tables (same values, same
/// entry order as [`Constraint::grad`] and [`Constraint::hess`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct RevoluteKernel {
    anchors: [Anchor; 2],
    /// For each rigid side, the position of its body's `(sin θ, cos θ)` pair
    /// in the table [`phi_b`](Self::phi_b) is given.
    trig: [u32; 2],
    /// First global constraint row.
    row0: usize,
    /// Offsets of the element's entries in the B and Hessian value buffers.
    b_off: usize,
    h_off: usize,
}

impl RevoluteKernel {
    /// The kernel of `c`, if it is a revolute joint; `trig_slot(θ)` is the
    /// position of `(sin θ, cos θ)` in the table of [`phi_b`](Self::phi_b)
    /// for the angle coordinate `θ`.
    pub(crate) fn of(
        c: &Constraint,
        b_off: usize,
        h_off: usize,
        trig_slot: impl Fn(usize) -> u32,
    ) -> Option<Self> {
        let slot = |a: &Anchor| match *a {
            Anchor::Rigid { x, .. } => trig_slot(x + 2),
            _ => 0,
        };
        c.element.is_revolute().then_some(Self {
            trig: [slot(&c.anchors[0]), slot(&c.anchors[1])],
            anchors: c.anchors,
            row0: c.row0,
            b_off,
            h_off,
        })
    }

    /// `Φ = p_A − p_B` and its gradient: per row `k`, `[±1 on x/y, ±∂p/∂θ]` of
    /// side A (when not the ground), then of side B.
    /// `phi` and `b` start at global row `base.0` and value `base.1`.
    #[inline]
    pub(crate) fn phi_b(
        &self,
        u: &[f64],
        trig: &[f64],
        phi: &mut [f64],
        b: &mut [f64],
        base: (usize, usize),
    ) {
        let (pa, pb) = (self.point_from(0, u, trig), self.point_from(1, u, trig));
        let row = self.row0 - base.0;
        phi[row] = pa.p[0] - pb.p[0];
        phi[row + 1] = pa.p[1] - pb.p[1];
        let mut o = self.b_off - base.1;
        for k in 0..2 {
            for (anchor, pt, sign) in [(&self.anchors[0], &pa, 1.0), (&self.anchors[1], &pb, -1.0)]
            {
                match anchor {
                    Anchor::Ground(_) => {}
                    Anchor::Point { .. } => {
                        b[o] = sign;
                        o += 1;
                    }
                    Anchor::Rigid { .. } => {
                        b[o] = sign;
                        b[o + 1] = sign * pt.dp[k];
                        o += 2;
                    }
                }
            }
        }
    }

    /// Side `k`'s point, its rigid body's `(sin θ, cos θ)` read from `trig`.
    #[inline]
    fn point_from(&self, k: usize, u: &[f64], trig: &[f64]) -> crate::planar::geometry::Pt {
        let a = &self.anchors[k];
        match a {
            Anchor::Rigid { .. } => {
                let at = 2 * self.trig[k] as usize;
                a.point_at(u, (trig[at], trig[at + 1]))
            }
            _ => a.point(u),
        }
    }

    /// `μ_k ∂²Φ_k/∂θ²` on each rigid side's angle (rows `k = 0, 1`); `out`
    /// starts at Hessian value `base`.
    #[inline]
    pub(crate) fn hessian(&self, u: &[f64], mu: &[f64], out: &mut [f64], base: usize) {
        let pts = [self.anchors[0].point(u), self.anchors[1].point(u)];
        self.write_hessian(&pts, mu, out, base);
    }

    /// [`hessian`](Self::hessian) with each body's `(sin θ, cos θ)` read
    /// from the table of [`phi_b`](Self::phi_b).
    #[inline]
    pub(crate) fn hessian_from(
        &self,
        u: &[f64],
        trig: &[f64],
        mu: &[f64],
        out: &mut [f64],
        base: usize,
    ) {
        let pts = [self.point_from(0, u, trig), self.point_from(1, u, trig)];
        self.write_hessian(&pts, mu, out, base);
    }

    /// The Hessian's values from the two sides' points.
    #[inline]
    fn write_hessian(
        &self,
        pts: &[crate::planar::geometry::Pt; 2],
        mu: &[f64],
        out: &mut [f64],
        base: usize,
    ) {
        let mut o = self.h_off - base;
        for k in 0..2 {
            let m = mu[self.row0 + k];
            for (side, sign) in [(0, 1.0), (1, -1.0)] {
                if let Anchor::Rigid { .. } = self.anchors[side] {
                    out[o] = m * sign * pts[side].ddp[k];
                    o += 1;
                }
            }
        }
    }
}

impl crate::parallel::KernelOffsets for RevoluteKernel {
    fn offsets(&self) -> (usize, usize, usize) {
        (self.row0, self.b_off, self.h_off)
    }
}
