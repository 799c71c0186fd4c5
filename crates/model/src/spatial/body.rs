//! A rigid body's rotational inertia in Euler parameters, written out by
//! hand (it runs for every body at every Newton iteration): the mass block,
//! the quadratic-velocity forces and their derivatives (`docs/theory.md`,
//! "Spatial bodies"; Haug 1989, eq. 11.2.24; Nikravesh 1988, §11.4).
//!
//! From the kinetic energy `T = 2 ṗᵀ Gᵀ J' G ṗ` (`ω' = 2 G ṗ`) Lagrange's
//! equations give
//!
//! ```text
//! M_p p̈ = g_p,   M_p = 4 Gᵀ J' G (+ κ p pᵀ),   g_p = 8 Ġᵀ J' Ġ p  (+ loads),
//! ```
//!
//! with `Ġ = G(ṗ)`. `M_p` has rank 3 (`G p = 0`): the paper's singular mass
//! matrix. The optional `κ p pᵀ` makes it regular without changing the motion:
//! it is parallel to the normalization constraint's gradient `2 pᵀ`, so its
//! force is absorbed into that constraint's multiplier, exactly, also in the
//! discrete equations of every step.
//!
//! `H(c)` below is the 4 × 4 matrix with `G(x)ᵀ c = H(c) x`.

/// `G(x)`, 3 × 4.
#[inline]
pub(crate) fn g_of(x: &[f64]) -> [[f64; 4]; 3] {
    [
        [-x[1], x[0], x[3], -x[2]],
        [-x[2], -x[3], x[0], x[1]],
        [-x[3], x[2], -x[1], x[0]],
    ]
}

/// `H(c)`: `G(x)ᵀ c = H(c) x`.
#[inline]
fn h_of(c: [f64; 3]) -> [[f64; 4]; 4] {
    [
        [0.0, -c[0], -c[1], -c[2]],
        [c[0], 0.0, c[2], -c[1]],
        [c[1], -c[2], 0.0, c[0]],
        [c[2], c[1], -c[0], 0.0],
    ]
}

#[inline]
fn mat_vec(a: &[[f64; 4]; 3], x: &[f64]) -> [f64; 3] {
    let r = |i: usize| a[i][0] * x[0] + a[i][1] * x[1] + a[i][2] * x[2] + a[i][3] * x[3];
    [r(0), r(1), r(2)]
}

/// The rotational inertia of one body.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Inertia {
    /// `J'`, the inertia tensor about the centre of mass in body axes.
    pub(crate) j: [[f64; 3]; 3],
    /// The regularization `κ` of the mass block (0: the singular `4 Gᵀ J' G`).
    pub(crate) kappa: f64,
}

impl Inertia {
    /// Whether `J'` is diagonal (body axes along the principal axes).
    #[inline]
    fn diagonal(&self) -> bool {
        let j = &self.j;
        j[0][1] == 0.0
            && j[0][2] == 0.0
            && j[1][0] == 0.0
            && j[1][2] == 0.0
            && j[2][0] == 0.0
            && j[2][1] == 0.0
    }

    #[inline]
    fn j_times(&self, w: [f64; 3]) -> [f64; 3] {
        let r = |i: usize| self.j[i][0] * w[0] + self.j[i][1] * w[1] + self.j[i][2] * w[2];
        [r(0), r(1), r(2)]
    }

    /// `k Aᵀ J' B` for 3 × 4 matrices `A`, `B`, added to `out` (row-major).
    /// `J' B` is formed once (3 × 4), and `out` taken as a fixed 16 values so
    /// that the loops unroll without bounds checks (it runs four times per
    /// body and Newton iteration); the sums are in the same order as
    /// `j_times`, so the values do not depend on this layout.
    #[inline]
    fn add_gjg(&self, a: &[[f64; 4]; 3], b: &[[f64; 4]; 3], k: f64, out: &mut [f64]) {
        let Some(out) = out.first_chunk_mut::<16>() else {
            unreachable!("a 4 × 4 block has 16 values");
        };
        let j = &self.j;
        // Bodies given by their principal moments (the usual case) have a
        // diagonal `J'`: its products with zero are left out (the same
        // values, but for the sign of a zero).
        let jb: [[f64; 4]; 3] = if self.diagonal() {
            std::array::from_fn(|i| b[i].map(|x| j[i][i] * x))
        } else {
            std::array::from_fn(|i| {
                std::array::from_fn(|c| j[i][0] * b[0][c] + j[i][1] * b[1][c] + j[i][2] * b[2][c])
            })
        };
        for r in 0..4 {
            for c in 0..4 {
                out[4 * r + c] +=
                    k * (a[0][r] * jb[0][c] + a[1][r] * jb[1][c] + a[2][r] * jb[2][c]);
            }
        }
    }

    /// `k G(x)ᵀ J' G(x) + κ x xᵀ` into `out` (row-major 4 × 4) for principal
    /// moments, `J' = diag(J₁, J₂, J₃)`. Each row of `G(x)` is `x` permuted
    /// and signed, so the matrix is the ten products `x_a x_b` weighted by
    /// the moments: about 40 operations, where [`add_gjg`](Self::add_gjg)
    /// takes 170 (it runs for every body at every residual). The same matrix
    /// but for rounding, and exactly symmetric.
    #[inline]
    fn principal_gram(&self, x: &[f64], k: f64, kappa: f64, out: &mut [f64]) {
        let Some(out) = out.first_chunk_mut::<16>() else {
            unreachable!("a 4 × 4 block has 16 values");
        };
        let [x0, x1, x2, x3] = [x[0], x[1], x[2], x[3]];
        let (j1, j2, j3) = (k * self.j[0][0], k * self.j[1][1], k * self.j[2][2]);
        let (p00, p11, p22, p33) = (x0 * x0, x1 * x1, x2 * x2, x3 * x3);
        let (p01, p02, p03) = (x0 * x1, x0 * x2, x0 * x3);
        let (p12, p13, p23) = (x1 * x2, x1 * x3, x2 * x3);
        let diagonal = [
            j1 * p11 + j2 * p22 + j3 * p33 + kappa * p00,
            j1 * p00 + j2 * p33 + j3 * p22 + kappa * p11,
            j1 * p33 + j2 * p00 + j3 * p11 + kappa * p22,
            j1 * p22 + j2 * p11 + j3 * p00 + kappa * p33,
        ];
        let (a1, a2, a3) = (kappa - j1, kappa - j2, kappa - j3);
        let (d23, d31, d12) = (j2 - j3, j3 - j1, j1 - j2);
        // (r, c, value) above the diagonal.
        let upper = [
            (0, 1, a1 * p01 + d23 * p23),
            (0, 2, a2 * p02 + d31 * p13),
            (0, 3, a3 * p03 + d12 * p12),
            (1, 2, a3 * p12 + d12 * p03),
            (1, 3, a2 * p13 + d31 * p02),
            (2, 3, a1 * p23 + d23 * p01),
        ];
        for (r, d) in diagonal.into_iter().enumerate() {
            out[5 * r] = d;
        }
        for (r, c, v) in upper {
            out[4 * r + c] = v;
            out[4 * c + r] = v;
        }
    }

    /// `M_p(p)`, row-major 4 × 4.
    pub(crate) fn mass(&self, p: &[f64], out: &mut [f64]) {
        if self.diagonal() {
            self.principal_gram(p, 4.0, self.kappa, out);
            return;
        }
        out[..16].fill(0.0);
        let g = g_of(p);
        self.add_gjg(&g, &g, 4.0, out);
        for r in 0..4 {
            for c in 0..4 {
                out[4 * r + c] += self.kappa * p[r] * p[c];
            }
        }
    }

    /// `∂(M_p(p) w)/∂p = 4 H(J' G(p) w) − 4 G(p)ᵀ J' G(w) + κ (pᵀw I + p wᵀ)`,
    /// row-major 4 × 4.
    pub(crate) fn mass_du(&self, p: &[f64], w: &[f64], out: &mut [f64]) {
        let g = g_of(p);
        let h = h_of(self.j_times(mat_vec(&g, w)));
        let pw = p[0] * w[0] + p[1] * w[1] + p[2] * w[2] + p[3] * w[3];
        for r in 0..4 {
            for c in 0..4 {
                let diag = if r == c { pw } else { 0.0 };
                out[4 * r + c] = 4.0 * h[r][c] + self.kappa * (diag + p[r] * w[c]);
            }
        }
        self.add_gjg(&g, &g_of(w), -4.0, out);
    }

    /// The quadratic-velocity force `8 G(ṗ)ᵀ J' G(ṗ) p`.
    #[inline]
    pub(crate) fn quadratic_force(&self, p: &[f64], pd: &[f64]) -> [f64; 4] {
        let gd = g_of(pd);
        let c = self.j_times(mat_vec(&gd, p));
        std::array::from_fn(|k| 8.0 * (gd[0][k] * c[0] + gd[1][k] * c[1] + gd[2][k] * c[2]))
    }

    /// `∂/∂p` of the quadratic-velocity force: `8 G(ṗ)ᵀ J' G(ṗ)`.
    pub(crate) fn quadratic_du(&self, pd: &[f64], out: &mut [f64]) {
        if self.diagonal() {
            self.principal_gram(pd, 8.0, 0.0, out);
            return;
        }
        out[..16].fill(0.0);
        let gd = g_of(pd);
        self.add_gjg(&gd, &gd, 8.0, out);
    }

    /// `∂/∂ṗ` of the quadratic-velocity force: `8 H(J' G(ṗ) p) − 8 G(ṗ)ᵀ J' G(p)`.
    pub(crate) fn quadratic_dv(&self, p: &[f64], pd: &[f64], out: &mut [f64]) {
        let gd = g_of(pd);
        let h = h_of(self.j_times(mat_vec(&gd, p)));
        for r in 0..4 {
            for c in 0..4 {
                out[4 * r + c] = 8.0 * h[r][c];
            }
        }
        self.add_gjg(&gd, &g_of(p), -8.0, out);
    }
}

#[cfg(test)]
mod tests {
    use super::{Inertia, g_of};

    /// `k G(x)ᵀ J' G(x) + κ x xᵀ` entry by entry, from `G` as written.
    fn gram(j: [f64; 3], x: [f64; 4], k: f64, kappa: f64) -> [f64; 16] {
        let g = g_of(&x);
        std::array::from_fn(|e| {
            let (r, c) = (e / 4, e % 4);
            k * (0..3).map(|i| j[i] * g[i][r] * g[i][c]).sum::<f64>() + kappa * x[r] * x[c]
        })
    }

    /// The principal-moment path of `mass` and `quadratic_du` against the
    /// product `G(x)ᵀ J' G(x)` written out, to the rounding of its terms.
    #[test]
    fn principal_moments_give_the_gram_product() {
        let cases = [
            ([0.05, 0.05, 0.08], [0.9, -0.1, 0.3, 0.2958]),
            ([0.1, 0.2, 0.3], [0.5, 0.5, -0.5, 0.5]),
            ([2.0, 3.0, 4.5], [0.1, 0.7, -0.4, -0.58]),
        ];
        for (j, x) in cases {
            let inertia = Inertia {
                j: [[j[0], 0.0, 0.0], [0.0, j[1], 0.0], [0.0, 0.0, j[2]]],
                kappa: 4.0 * (j[0] + j[1] + j[2]) / 3.0,
            };
            let mut got = [f64::NAN; 16];
            inertia.mass(&x, &mut got);
            let want = gram(j, x, 4.0, inertia.kappa);
            let scale = want.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for e in 0..16 {
                assert!(
                    (got[e] - want[e]).abs() <= 8.0 * f64::EPSILON * scale,
                    "{e}: {got:?} {want:?}"
                );
            }
            inertia.quadratic_du(&x, &mut got);
            let want = gram(j, x, 8.0, 0.0);
            let scale = want.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for e in 0..16 {
                assert!(
                    (got[e] - want[e]).abs() <= 8.0 * f64::EPSILON * scale,
                    "{e}: {got:?} {want:?}"
                );
            }
        }
    }
}
