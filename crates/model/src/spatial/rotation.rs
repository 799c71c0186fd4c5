//! Rotations in Euler parameters `p = [e0, e1, e2, e3]` (`docs/theory.md`,
//! "Spatial bodies"; Haug, *Computer-Aided Kinematics and Dynamics of
//! Mechanical Systems*, 1989, §6.3 and §11.2; Nikravesh, *Computer-Aided
//! Analysis of Mechanical Systems*, 1988, §6.3).
//!
//! With `e = [e1, e2, e3]`,
//! `E(p) = [−e, e0 I + ẽ]` and `G(p) = [−e, e0 I − ẽ]` (3 × 4), the rotation
//! matrix (body to global) is `A = E Gᵀ = (e0² − eᵀe) I + 2 e eᵀ + 2 e0 ẽ`,
//! a homogeneous quadratic in `p` (a rotation times `|p|²`: the normalization
//! constraint `pᵀp = 1` makes it one), and the angular velocity is
//! `ω = 2 E ṗ` in global axes, `ω' = 2 G ṗ` in body axes.

use super::real::Real;

/// A 3-vector of numbers.
pub(crate) type V3<T> = [T; 3];

pub(crate) fn add<T: Real>(a: V3<T>, b: V3<T>) -> V3<T> {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

pub(crate) fn sub<T: Real>(a: V3<T>, b: V3<T>) -> V3<T> {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

pub(crate) fn dot<T: Real>(a: V3<T>, b: V3<T>) -> T {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

pub(crate) fn cross<T: Real>(a: V3<T>, b: V3<T>) -> V3<T> {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

pub(crate) fn scale<T: Real>(a: V3<T>, k: T) -> V3<T> {
    [a[0] * k, a[1] * k, a[2] * k]
}

/// A constant vector as numbers.
pub(crate) fn cst3<T: Real>(s: [f64; 3]) -> V3<T> {
    [T::cst(s[0]), T::cst(s[1]), T::cst(s[2])]
}

/// `A(p) s`: the body vector `s` in global axes.
pub(crate) fn rotate<T: Real>(p: &[T; 4], s: V3<T>) -> V3<T> {
    let e = [p[1], p[2], p[3]];
    let k = p[0] * p[0] - dot(e, e);
    let es = dot(e, s).scale(2.0);
    let exs = cross(e, s);
    let e0 = p[0].scale(2.0);
    [
        s[0] * k + e[0] * es + exs[0] * e0,
        s[1] * k + e[1] * es + exs[1] * e0,
        s[2] * k + e[2] * es + exs[2] * e0,
    ]
}

/// `A(p)` row by row, `(e0² − eᵀe) I + 2 e eᵀ + 2 e0 ẽ` (module
/// documentation): ten products of numbers, after which each body vector
/// costs [`apply`]'s scalings instead of [`rotate`]'s 22 products (with
/// second-order dual numbers a product costs four times a scaling).
pub(crate) fn matrix<T: Real>(p: &[T; 4]) -> [[T; 3]; 3] {
    let e = [p[1], p[2], p[3]];
    let sq = [e[0] * e[0], e[1] * e[1], e[2] * e[2]];
    let k = p[0] * p[0] - (sq[0] + sq[1] + sq[2]);
    let diag = |i: usize| k + sq[i].scale(2.0);
    let (xy, xz, yz) = (
        (e[0] * e[1]).scale(2.0),
        (e[0] * e[2]).scale(2.0),
        (e[1] * e[2]).scale(2.0),
    );
    let e0 = p[0].scale(2.0);
    let (x, y, z) = (e0 * e[0], e0 * e[1], e0 * e[2]);
    [
        [diag(0), xy - z, xz + y],
        [xy + z, diag(1), yz - x],
        [xz - y, yz + x, diag(2)],
    ]
}

/// `A s` for a constant body vector `s`, `A` from [`matrix`]: scalings of
/// its entries, none for the zero entries of `s` (an axis of a frame).
pub(crate) fn apply<T: Real>(a: &[[T; 3]; 3], s: [f64; 3]) -> V3<T> {
    let row = |i: usize| {
        let mut terms = (0..3).filter(|&j| s[j] != 0.0).map(|j| a[i][j].scale(s[j]));
        let first = terms.next().unwrap_or_else(|| T::cst(0.0));
        terms.fold(first, |acc, t| acc + t)
    };
    [row(0), row(1), row(2)]
}

/// `J(p, s)ᵀ f`, `J = ∂(A(p) s)/∂p`: the generalized force on `p` of a force
/// `f` at the body point `s` (relative to the centre of mass).
/// `J = 2 [e0 s + e × s,  (eᵀs) I + e sᵀ − s eᵀ − e0 s̃]`.
pub(crate) fn point_jt<T: Real>(p: &[T; 4], s: V3<T>, f: V3<T>) -> [T; 4] {
    let e = [p[1], p[2], p[3]];
    let c0 = dot(add(scale(s, p[0]), cross(e, s)), f).scale(2.0);
    let (es, ef, sf) = (dot(e, s), dot(e, f), dot(s, f));
    let sxf = cross(s, f);
    let r = |i: usize| (f[i] * es + s[i] * ef - e[i] * sf + sxf[i] * p[0]).scale(2.0);
    [c0, r(0), r(1), r(2)]
}

/// The three rows `J(p, s)ᵀ e_k` of `J = ∂(A(p) s)/∂p` ([`point_jt`] for
/// the unit vectors `e_k`), with the products by the zeros and ones of `e_k`
/// left out: the same values (but for the sign of a zero) at a third of the
/// operations. The spherical kernel's `B` rows.
pub(crate) fn point_jacobian(p: &[f64; 4], s: V3<f64>) -> [[f64; 4]; 3] {
    let e = [p[1], p[2], p[3]];
    let v = add(scale(s, p[0]), cross(e, s));
    let es = dot(e, s);
    // `((f_i (eᵀs) + s_i (eᵀf)) − e_i (sᵀf)) + (s × f)_i e0` of `point_jt`
    // for `f = e_k`, in its order: `t` is the first sum, `x` the `i`-th
    // entry of `s × e_k` (none on the diagonal, where it is zero).
    let r = |k: usize, i: usize, t: f64| (t - e[i] * s[k]) * 2.0;
    let rx = |k: usize, i: usize, t: f64, x: f64| ((t - e[i] * s[k]) + x * p[0]) * 2.0;
    [
        [
            v[0] * 2.0,
            r(0, 0, es + s[0] * e[0]),
            rx(0, 1, s[1] * e[0], s[2]),
            rx(0, 2, s[2] * e[0], -s[1]),
        ],
        [
            v[1] * 2.0,
            rx(1, 0, s[0] * e[1], -s[2]),
            r(1, 1, es + s[1] * e[1]),
            rx(1, 2, s[2] * e[1], s[0]),
        ],
        [
            v[2] * 2.0,
            rx(2, 0, s[0] * e[2], s[1]),
            rx(2, 1, s[1] * e[2], -s[0]),
            r(2, 2, es + s[2] * e[2]),
        ],
    ]
}

/// `2 E(p)ᵀ n`: the generalized force on `p` of a torque `n` in global axes.
pub(crate) fn torque_global<T: Real>(p: &[T; 4], n: V3<T>) -> [T; 4] {
    let e = [p[1], p[2], p[3]];
    let exn = cross(e, n);
    let r = |i: usize| (n[i] * p[0] - exn[i]).scale(2.0);
    [-dot(e, n).scale(2.0), r(0), r(1), r(2)]
}

/// `ω = 2 E(p) ṗ`, the angular velocity in global axes.
pub(crate) fn omega_global<T: Real>(p: &[T; 4], pd: &[T; 4]) -> V3<T> {
    let (e, ed) = ([p[1], p[2], p[3]], [pd[1], pd[2], pd[3]]);
    let exd = cross(e, ed);
    let r = |i: usize| (ed[i] * p[0] - e[i] * pd[0] + exd[i]).scale(2.0);
    [r(0), r(1), r(2)]
}

/// `ṗ = ½ E(p)ᵀ ω` for a unit `p`: the Euler-parameter rates of the angular
/// velocity `ω` (global axes).
#[must_use]
pub(crate) fn rates_of_omega(p: &[f64; 4], omega: [f64; 3]) -> [f64; 4] {
    let t = torque_global(p, omega);
    [0.25 * t[0], 0.25 * t[1], 0.25 * t[2], 0.25 * t[3]]
}

/// `A(p)ᵀ v` for unit `p`: the global vector `v` in body axes.
pub(crate) fn rotates_to_body(p: &[f64; 4], v: [f64; 3]) -> [f64; 3] {
    rotate(&[p[0], -p[1], -p[2], -p[3]], v)
}

/// Unit Euler parameters (`[1, 0, 0, 0]` for a zero vector).
pub(crate) fn normalized(p: [f64; 4]) -> [f64; 4] {
    let n = p.iter().map(|e| e * e).sum::<f64>().sqrt();
    if n > 0.0 && n.is_finite() {
        p.map(|e| e / n)
    } else {
        [1.0, 0.0, 0.0, 0.0]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const P: [f64; 4] = [0.8, -0.3, 0.45, 0.25];
    const PD: [f64; 4] = [0.2, 0.7, -0.4, 0.1];
    const S: [f64; 3] = [0.3, -1.2, 0.7];

    fn along(p: &[f64; 4], d: &[f64; 4], h: f64) -> [f64; 4] {
        std::array::from_fn(|k| p[k] + h * d[k])
    }

    /// `point_jacobian`'s rows are `point_jt` of the unit vectors: to the bit
    /// at a general state, and equal (zeros of either sign) at the identity
    /// with a point on an axis, where most terms vanish.
    #[test]
    fn point_jacobian_rows_are_point_jt_of_the_unit_vectors() {
        for (p, s, bits) in [
            (P, S, true),
            ([1.0, 0.0, 0.0, 0.0], [-0.5, 0.0, 0.0], false),
            ([0.6, 0.0, -0.8, 0.0], [0.0, 0.0, 0.25], false),
        ] {
            let rows = point_jacobian(&p, s);
            for (k, row) in rows.iter().enumerate() {
                let mut f = [0.0; 3];
                f[k] = 1.0;
                let expected = point_jt(&p, s, f);
                for (a, b) in row.iter().zip(expected) {
                    assert!(a.is_finite() && a == &b, "row {k}: {row:?} vs {expected:?}");
                    assert!(
                        !bits || a.to_bits() == b.to_bits(),
                        "row {k}: {row:?} vs {expected:?}"
                    );
                }
            }
        }
    }

    /// `matrix` and `apply` give `rotate`'s vector to round-off, for an
    /// Euler-parameter vector off unit length too (`A` is homogeneous).
    #[test]
    fn the_matrix_applied_is_the_rotation() {
        for p in [P, [1.0, 0.0, 0.0, 0.0], [0.3, 0.9, -0.2, 0.4]] {
            let a = matrix(&p);
            for s in [S, [0.0, 0.0, 1.0], [0.0, -2.0, 0.0], [0.0; 3]] {
                let (x, y) = (apply(&a, s), rotate(&p, s));
                for k in 0..3 {
                    assert!(
                        (x[k] - y[k]).abs() <= 1e-15 * 4.0,
                        "{p:?}, {s:?}: {x:?} vs {y:?}"
                    );
                }
            }
        }
    }

    /// `J(p, s)ᵀ f · δp = f · δ(A s)`: the force mapping is the transpose of
    /// the point's derivative (virtual work), checked by central differences.
    #[test]
    fn point_force_does_the_work_of_the_point_motion() {
        let f = [1.5, -0.4, 2.0];
        let h = 1e-6;
        let da = sub(
            rotate(&along(&P, &PD, h), S),
            rotate(&along(&P, &PD, -h), S),
        );
        let work = dot(f, da) / (2.0 * h);
        let q = point_jt(&P, S, f);
        let mapped: f64 = (0..4).map(|k| q[k] * PD[k]).sum();
        assert!((work - mapped).abs() < 1e-8, "{work} vs {mapped}");
    }

    /// The power of a torque: `2 Eᵀ n · ṗ = n · ω` with `ω = 2 E ṗ`.
    #[test]
    fn torques_do_the_work_of_the_rotation() {
        let n = [0.3, 1.1, -0.6];
        let q = torque_global(&P, n);
        let power: f64 = (0..4).map(|k| q[k] * PD[k]).sum();
        assert!((power - dot(n, omega_global(&P, &PD))).abs() < 1e-14);
    }

    /// A unit `p` rotates by the axis-angle it was made of: a quarter turn
    /// about z takes x to y; `Aᵀ A = I`.
    #[test]
    fn unit_parameters_rotate_rigidly() {
        let (s, c) = (std::f64::consts::FRAC_PI_4).sin_cos();
        let q = [c, 0.0, 0.0, s];
        let y = rotate(&q, [1.0, 0.0, 0.0]);
        assert!((y[0]).abs() < 1e-15 && (y[1] - 1.0).abs() < 1e-15 && y[2].abs() < 1e-15);
        let back = rotates_to_body(&q, y);
        assert!((back[0] - 1.0).abs() < 1e-15 && back[1].abs() < 1e-15);
        let norm = P.iter().map(|x| x * x).sum::<f64>().sqrt();
        let p = P.map(|x| x / norm);
        let a = rotate(&p, S);
        assert!((dot(a, a) - dot(S, S)).abs() < 1e-14);
    }

    /// `ṗ = ½ Eᵀ ω` inverts `ω = 2 E ṗ` for a unit `p`.
    #[test]
    fn rates_of_omega_invert_omega() {
        let norm = P.iter().map(|x| x * x).sum::<f64>().sqrt();
        let p = P.map(|x| x / norm);
        let w = [0.4, -2.0, 1.3];
        let back = omega_global(&p, &rates_of_omega(&p, w));
        for k in 0..3 {
            assert!((back[k] - w[k]).abs() < 1e-14);
        }
    }
}
