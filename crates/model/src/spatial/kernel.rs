//! The hot path of spatial chains: a spherical joint's `Φ`, `B`, Hessian and
//! acceleration right-hand side written straight into the value buffers,
//! like the planar `RevoluteKernel`: the joint's coordinates, points and
//! offsets in one small record (no frames, no per-joint tables of local
//! entries, no dynamic dispatch), its structural entries as bit masks.
//!
//! The values are those of the generic path (`spherical.rs` through the
//! joint's local tables), computed by the same functions in the same order:
//! `Φ = x_A − x_B` with `x = r + A(p) s`, row `k` of `∂(A s)/∂p` is
//! `point_jt(p, s, e_k)` (as `point_jacobian`, the same values), the
//! contracted Hessian on a rigid side is
//! `±H(μ, s)` (see `spherical.rs`), and `c = −2 A(ṗ_A) s_A + 2 A(ṗ_B) s_B`
//! (algorithm.md, the acceleration-level constraint `B ü = c`).

use super::evaluate::SIDE;
use super::hessian::contracted_rotation;
use super::rotation::{point_jacobian, rotate};

/// One side of a spherical joint in the kernel.
#[derive(Clone, Copy, Debug)]
struct KernelSide {
    /// The body's first coordinate; `None` for the ground.
    x: Option<usize>,
    /// Whether the body has Euler parameters (7 coordinates), else a point
    /// mass (3).
    rigid: bool,
    /// The joint point: body axes, or global for the ground.
    s: [f64; 3],
    /// Per row `k`, the side's local coordinates (bits 0..7) with an entry in
    /// `B`, in value order.
    b_mask: [u8; 3],
    /// The entries `(i, j)` of the side's 4 × 4 Euler-parameter block in the
    /// Hessian, `4 i + j` ascending (the first `h_count`), in value order
    /// (row-major): the Hessian is written by this list.
    h_order: [u8; 16],
    h_count: u8,
}

/// A spherical joint's evaluations on precomputed offsets (see the module
/// documentation).
#[derive(Clone, Copy, Debug)]
pub(crate) struct SphericalKernel {
    sides: [KernelSide; 2],
    /// First global constraint row (rows `row0..row0 + 3`).
    row0: usize,
    /// Offsets of its entries in the `B` and Hessian value buffers.
    b_off: usize,
    h_off: usize,
    /// Whether every side's `B` entries are the usual ones ([`standard`]):
    /// then `B` is written without walking the masks.
    standard: bool,
}

/// What [`SphericalKernel::new`] needs of a joint: its sides (first
/// coordinate, count 3 or 7; `None` for the ground), points, first row,
/// value offsets and its structural entries as local pairs (row-major).
pub(crate) struct JointLayout<'a> {
    pub(crate) sides: [Option<(usize, usize)>; 2],
    pub(crate) points: &'a [[f64; 3]; 2],
    pub(crate) row0: usize,
    pub(crate) b_off: usize,
    pub(crate) h_off: usize,
    pub(crate) b_local: &'a [(usize, usize)],
    pub(crate) h_local: &'a [(usize, usize)],
}

impl SphericalKernel {
    /// The kernel of a spherical joint, or `None` when its structural entries
    /// are not in the layout the kernel writes (then the generic path runs).
    pub(crate) fn new(j: &JointLayout<'_>) -> Option<Self> {
        let mut sides = [0, 1].map(|s| KernelSide {
            x: j.sides[s].map(|(x, _)| x),
            rigid: j.sides[s].is_some_and(|(_, count)| count == SIDE),
            s: j.points[s],
            b_mask: [0; 3],
            h_order: [0; 16],
            h_count: 0,
        });
        for &(r, a) in j.b_local {
            let side = sides.get_mut(a / SIDE)?;
            *side.b_mask.get_mut(r)? |= 1 << (a % SIDE);
        }
        // Per side, bit `4 i + j` for the Hessian entry `(i, j)`.
        let mut h_masks = [0u16; 2];
        for &(a, b) in j.h_local {
            let (i, k) = ((a % SIDE).checked_sub(3)?, (b % SIDE).checked_sub(3)?);
            let side = h_masks.get_mut(a / SIDE).filter(|_| a / SIDE == b / SIDE)?;
            *side |= 1 << (4 * i + k);
        }
        for (side, &mask) in sides.iter_mut().zip(&h_masks) {
            for (slot, bit) in side.h_order.iter_mut().zip(bits(mask)) {
                // (`bit` < 16.)
                *slot = bit as u8;
                side.h_count += 1;
            }
        }
        let kernel = Self {
            sides,
            row0: j.row0,
            b_off: j.b_off,
            h_off: j.h_off,
            standard: sides.iter().all(standard),
        };
        // The masks give the entries in this order; any other order (or a
        // bit outside a side) keeps the joint on the generic path.
        (kernel.b_entries() == j.b_local && kernel.h_entries() == j.h_local).then_some(kernel)
    }

    /// Whether [`phi_b`](Self::phi_b) writes `B` in the usual layout.
    #[cfg(test)]
    pub(crate) fn is_standard(&self) -> bool {
        self.standard
    }

    /// The `B` entries the masks encode, as `(row, local variable)` in the
    /// order the kernel writes them.
    fn b_entries(&self) -> Vec<(usize, usize)> {
        let mut out = Vec::new();
        for r in 0..3 {
            for (s, side) in self.sides.iter().enumerate() {
                out.extend(bits(u16::from(side.b_mask[r])).map(|c| (r, SIDE * s + c)));
            }
        }
        out
    }

    /// The Hessian entries the masks encode, as local pairs in write order.
    fn h_entries(&self) -> Vec<(usize, usize)> {
        let mut out = Vec::new();
        for (s, side) in self.sides.iter().enumerate() {
            let o = SIDE * s + 3;
            let order = &side.h_order[..usize::from(side.h_count)];
            out.extend(
                order
                    .iter()
                    .map(|&b| (o + usize::from(b) / 4, o + usize::from(b) % 4)),
            );
        }
        out
    }

    /// `Φ` (3 rows) and its `B` entries. `phi` and `b` start at global row
    /// `base.0` and value `base.1` (a part of the buffers, for rayon).
    #[inline]
    pub(crate) fn phi_b(&self, u: &[f64], phi: &mut [f64], b: &mut [f64], base: (usize, usize)) {
        // Per side: the point (global) and the rows `±∂(A s)/∂p` (3 × 4).
        let mut point = [[0.0; 3]; 2];
        let mut rot = [[[0.0; 4]; 3]; 2];
        for (side, sign) in [(0, 1.0), (1, -1.0)] {
            let ks = &self.sides[side];
            let Some(x) = ks.x else {
                point[side] = ks.s;
                continue;
            };
            if ks.rigid {
                let q = &u[x..x + SIDE];
                let p = [q[3], q[4], q[5], q[6]];
                let a = rotate(&p, ks.s);
                point[side] = [q[0] + a[0], q[1] + a[1], q[2] + a[2]];
                let rows = point_jacobian(&p, ks.s);
                for (g, row) in rot[side].iter_mut().zip(rows) {
                    *g = row.map(|r| sign * r);
                }
            } else {
                point[side] = [u[x], u[x + 1], u[x + 2]];
            }
        }
        let row = self.row0 - base.0;
        for k in 0..3 {
            // As the generic path: 0 + x_A − x_B.
            phi[row + k] = 0.0 + point[0][k] - point[1][k];
        }
        let o = self.b_off - base.1;
        if self.standard {
            write_standard(&self.sides, &rot, &mut b[o..]);
        } else {
            self.write_masked(&rot, &mut b[o..]);
        }
    }

    /// The `B` entries in the masks' order: row `k`, side by side, the
    /// side's local coordinates ascending (`x_k`: `±1`, `p`: `rot`).
    fn write_masked(&self, rot: &[[[f64; 4]; 3]; 2], b: &mut [f64]) {
        let mut o = 0;
        for k in 0..3 {
            for (side, sign) in [(0, 1.0), (1, -1.0)] {
                for c in bits(u16::from(self.sides[side].b_mask[k])) {
                    b[o] = match c {
                        0..3 if c == k => sign,
                        0..3 => 0.0,
                        _ => rot[side][k][c - 3],
                    };
                    o += 1;
                }
            }
        }
    }

    /// `Σ_k μ_k ∂²Φ_k/∂u²` on each rigid side's Euler parameters: `±H(μ, s)`;
    /// `out` starts at Hessian value `base`.
    #[inline]
    pub(crate) fn hessian(&self, mu: &[f64], out: &mut [f64], base: usize) {
        let m = [mu[self.row0], mu[self.row0 + 1], mu[self.row0 + 2]];
        let mut o = self.h_off - base;
        for (side, sign) in [(0, 1.0), (1, -1.0)] {
            let ks = &self.sides[side];
            if ks.h_count == 0 {
                continue;
            }
            let h = contracted_rotation(m, ks.s, sign);
            let h = h.as_flattened();
            let order = &ks.h_order[..usize::from(ks.h_count)];
            for (out, &bit) in out[o..o + order.len()].iter_mut().zip(order) {
                *out = h[usize::from(bit)];
            }
            o += order.len();
        }
    }

    /// The acceleration right-hand side `c = −2 A(ṗ_A) s_A + 2 A(ṗ_B) s_B`
    /// (3 rows, from global row `row0`).
    #[inline]
    pub(crate) fn accel_rhs(&self, v: &[f64], c: &mut [f64]) {
        let c = &mut c[self.row0..self.row0 + 3];
        c.fill(0.0);
        for (side, sign) in [(0, 1.0), (1, -1.0)] {
            let ks = &self.sides[side];
            if let (Some(x), true) = (ks.x, ks.rigid) {
                let a = rotate(&[v[x + 3], v[x + 4], v[x + 5], v[x + 6]], ks.s);
                for k in 0..3 {
                    c[k] -= 2.0 * sign * a[k];
                }
            }
        }
    }
}

/// Whether a side's `B` entries are the usual ones: none for the ground;
/// row `k` of a point mass has `x_k`; row `k` of a rigid body has `x_k` and
/// its four Euler parameters.
fn standard(side: &KernelSide) -> bool {
    (0..3).all(|k| {
        let expected = match side.x {
            None => 0,
            Some(_) => (1u8 << k) | if side.rigid { 0b111_1000 } else { 0 },
        };
        side.b_mask[k] == expected
    })
}

/// [`SphericalKernel::phi_b`]'s `B` entries for [`standard`] sides, in the
/// masks' order: row `k`, side by side, `±1` then a rigid side's `rot` row.
#[inline]
fn write_standard(sides: &[KernelSide; 2], rot: &[[[f64; 4]; 3]; 2], b: &mut [f64]) {
    let mut o = 0;
    for k in 0..3 {
        for (side, sign) in [(0, 1.0), (1, -1.0)] {
            if sides[side].x.is_none() {
                continue;
            }
            b[o] = sign;
            o += 1;
            if sides[side].rigid {
                b[o..o + 4].copy_from_slice(&rot[side][k]);
                o += 4;
            }
        }
    }
}

/// The positions of the set bits of `mask`, ascending.
#[inline]
fn bits(mut mask: u16) -> impl Iterator<Item = usize> {
    std::iter::from_fn(move || {
        (mask != 0).then(|| {
            let i = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            i
        })
    })
}

impl crate::parallel::KernelOffsets for SphericalKernel {
    fn offsets(&self) -> (usize, usize, usize) {
        (self.row0, self.b_off, self.h_off)
    }
}

#[cfg(test)]
mod tests {
    use crate::System;
    use crate::spatial::builder::{
        Attach, JointSpec, JointType, RotationalMass, SpatialBody, SpatialBuilder, SpatialPointMass,
    };
    use crate::spatial::{SpatialInertia, SpatialSystem, spatial_bar_chain};

    /// Deterministic values in `[−1, 1)`.
    fn values(len: usize, seed: u64) -> Vec<f64> {
        let mut s = seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1;
        (0..len)
            .map(|_| {
                s = s
                    .wrapping_mul(6_364_136_223_846_793_005)
                    .wrapping_add(1_442_695_040_888_963_407);
                2.0 * (s >> 11) as f64 / (1u64 << 53) as f64 - 1.0
            })
            .collect()
    }

    /// `Φ`, `B`, the contracted Hessian and `c` of `sys`.
    fn evaluations(sys: &SpatialSystem, seed: u64) -> [Vec<f64>; 4] {
        let (n, m, t) = (sys.n_coords(), sys.n_constraints(), 0.3);
        let (u, v, mu) = (values(n, seed), values(n, seed + 1), values(m, seed + 2));
        let mut phi = vec![f64::NAN; m];
        let mut b = vec![f64::NAN; sys.b_pattern().len()];
        sys.phi_b_into(t, &u, &mut phi, &mut b, &mut []);
        let mut h = vec![f64::NAN; sys.hessian_pattern().len()];
        sys.hessian_into(t, &u, &mu, &mut h);
        let mut c = vec![f64::NAN; m];
        sys.accel_rhs_into(t, &u, &v, &mut c);
        [phi, b, h, c]
    }

    /// Every value of the kernel equals the generic path's to the bit (and
    /// is finite: a NaN left in a buffer fails).
    fn assert_same(sys: &SpatialSystem, kernels: usize) {
        assert_eq!(sys.kernel_joints(), kernels);
        let generic = sys.clone().with_generic_joints();
        assert_eq!(generic.kernel_joints(), 0);
        for seed in [1, 7, 42] {
            let (fast, slow) = (evaluations(sys, seed), evaluations(&generic, seed));
            for (what, (f, s)) in ["phi", "B", "hessian", "c"]
                .iter()
                .zip(fast.iter().zip(&slow))
            {
                assert_eq!(f.len(), s.len());
                for (i, (x, y)) in f.iter().zip(s).enumerate() {
                    assert!(
                        x.is_finite() && x.to_bits() == y.to_bits(),
                        "{what}[{i}]: {x} vs {y}"
                    );
                }
            }
        }
    }

    #[test]
    fn chain_kernels_equal_the_generic_joints() {
        let chain = spatial_bar_chain(6, RotationalMass::Regularized);
        assert_eq!(chain.usual_kernels(), 6, "the usual layout");
        assert_same(&chain, 6);
        assert_same(&spatial_bar_chain(3, RotationalMass::Singular), 3);
    }

    /// A point mass hanging from a tilted bar's end, and the bar's other end
    /// on the ground away from the origin: ground, rigid and point-mass sides
    /// with general joint points.
    #[test]
    fn mixed_sides_equal_the_generic_joints() {
        let mut b = SpatialBuilder::new();
        let bar = b.body(
            "bar",
            SpatialBody {
                mass: 2.0,
                inertia: SpatialInertia::Principal([0.1, 0.2, 0.3]),
                position: [0.3, 0.2, -0.1],
                orientation: [0.9, 0.1, -0.3, 0.2],
                velocity: [0.0; 3],
                angular_velocity: [0.0; 3],
            },
        );
        let point = b.point_mass(
            "bob",
            SpatialPointMass {
                mass: 1.0,
                position: [0.7, 0.4, -0.5],
                velocity: [0.0; 3],
            },
        );
        let joint = |bodies, points| JointSpec {
            kind: JointType::Spherical,
            bodies,
            points,
            axes: [[0.0, 0.0, 1.0]; 2],
            length: None,
        };
        b.joint(
            "base",
            joint(
                [Attach::Ground, Attach::Body(bar)],
                [[0.1, -0.2, 0.3], [-0.2, 0.1, 0.4]],
            ),
        );
        b.joint(
            "hook",
            joint(
                [Attach::Body(bar), Attach::Body(point)],
                [[0.25, -0.3, 0.15], [0.0; 3]],
            ),
        );
        let sys = b.build().expect("a valid model");
        assert_eq!(sys.usual_kernels(), 2, "ground, rigid and point-mass sides");
        assert_same(&sys, 2);
    }

    /// A joint at a body's centre of mass has no Euler-parameter entries on
    /// that side (`∂(A s)/∂p = 0` for `s = 0`): its entries are written by
    /// the masks, not the usual layout.
    #[test]
    fn a_joint_at_the_centre_equals_the_generic_joint() {
        let mut b = SpatialBuilder::new();
        let body = |position| SpatialBody {
            mass: 1.5,
            inertia: SpatialInertia::Principal([0.1, 0.2, 0.3]),
            position,
            orientation: [0.9, 0.1, -0.3, 0.2],
            velocity: [0.0; 3],
            angular_velocity: [0.0; 3],
        };
        let upper = b.body("upper", body([0.0, 0.0, 0.0]));
        let lower = b.body("lower", body([0.2, -0.1, -0.6]));
        b.joint(
            "centre",
            JointSpec {
                kind: JointType::Spherical,
                bodies: [Attach::Body(upper), Attach::Body(lower)],
                points: [[0.0; 3], [0.1, 0.2, 0.3]],
                axes: [[0.0, 0.0, 1.0]; 2],
                length: None,
            },
        );
        let sys = b.build().expect("a valid model");
        assert_eq!(
            sys.usual_kernels(),
            0,
            "the centre's side is not the usual one"
        );
        assert_same(&sys, 1);
    }
}
