//! The spherical joint written out by hand (the chains' only joint, at every
//! Newton iteration): `Φ = x_A − x_B` with `x = r + A(p) s`.
//!
//! With `A(p) s` a homogeneous quadratic in `p` (`rotation.rs`), row `k` of
//! `∂(A s)/∂p` is `point_jt(p, s, e_k)`, the contracted Hessian
//! `Σ_k μ_k ∂²(A s)_k/∂p²` is the constant
//! `H(μ, s) = 2 [μ·s, (s × μ)ᵀ; s × μ, μ sᵀ + s μᵀ − (μ·s) I]`, and
//! `ṗᵀ H(e_k, s) ṗ = 2 (A(ṗ) s)_k`. The generic path (jets) gives the same
//! values; `tests` compares them.

use super::evaluate::SIDE;
use super::hessian::contracted_rotation;
use super::rotation::{point_jt, rotate};

/// Side `s`'s coordinates in `u`, or `None` for the ground.
pub(crate) type Side<'a> = Option<&'a [f64]>;

/// `Φ` and the dense local gradient (3 rows × 14 local variables).
pub(crate) fn phi_grad(
    points: &[[f64; 3]; 2],
    q: [Side<'_>; 2],
    phi: &mut [f64],
    grad: &mut [[f64; 2 * SIDE]; 3],
) {
    *grad = [[0.0; 2 * SIDE]; 3];
    phi[..3].fill(0.0);
    for (side, sign) in [(0, 1.0), (1, -1.0)] {
        let s = points[side];
        let Some(q) = q[side] else {
            for k in 0..3 {
                phi[k] += sign * s[k];
            }
            continue;
        };
        let x = point(q, s);
        for k in 0..3 {
            phi[k] += sign * x[k];
            grad[k][SIDE * side + k] = sign;
            if q.len() == SIDE {
                let p = [q[3], q[4], q[5], q[6]];
                let mut e = [0.0; 3];
                e[k] = 1.0;
                let row = point_jt(&p, s, e);
                for c in 0..4 {
                    grad[k][SIDE * side + 3 + c] = sign * row[c];
                }
            }
        }
    }
}

fn point(q: &[f64], s: [f64; 3]) -> [f64; 3] {
    if q.len() == SIDE {
        let a = rotate(&[q[3], q[4], q[5], q[6]], s);
        [q[0] + a[0], q[1] + a[1], q[2] + a[2]]
    } else {
        [q[0], q[1], q[2]]
    }
}

/// `H(μ, s)` times `sign`, into the local Hessian's block of a side.
pub(crate) fn hessian(
    points: &[[f64; 3]; 2],
    rigid: [bool; 2],
    mu: [f64; 3],
    h: &mut [[f64; 2 * SIDE]; 2 * SIDE],
) {
    for (side, sign) in [(0, 1.0), (1, -1.0)] {
        if !rigid[side] {
            continue;
        }
        let block = contracted_rotation(mu, points[side], sign);
        let o = SIDE * side + 3;
        for (i, row) in block.iter().enumerate() {
            h[o + i][o..o + 4].copy_from_slice(row);
        }
    }
}

/// The acceleration right-hand side `c = −2 A(ṗ_A) s_A + 2 A(ṗ_B) s_B`.
pub(crate) fn accel_rhs(points: &[[f64; 3]; 2], rates: [Side<'_>; 2], c: &mut [f64]) {
    c[..3].fill(0.0);
    for (side, sign) in [(0, 1.0), (1, -1.0)] {
        if let Some(v) = rates[side].filter(|v| v.len() == SIDE) {
            let a = rotate(&[v[3], v[4], v[5], v[6]], points[side]);
            for k in 0..3 {
                c[k] -= 2.0 * sign * a[k];
            }
        }
    }
}
