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
pub(crate) fn g_of(x: &[f64]) -> [[f64; 4]; 3] {
    [
        [-x[1], x[0], x[3], -x[2]],
        [-x[2], -x[3], x[0], x[1]],
        [-x[3], x[2], -x[1], x[0]],
    ]
}

/// `H(c)`: `G(x)ᵀ c = H(c) x`.
fn h_of(c: [f64; 3]) -> [[f64; 4]; 4] {
    [
        [0.0, -c[0], -c[1], -c[2]],
        [c[0], 0.0, c[2], -c[1]],
        [c[1], -c[2], 0.0, c[0]],
        [c[2], c[1], -c[0], 0.0],
    ]
}

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

    /// `M_p(p)`, row-major 4 × 4.
    pub(crate) fn mass(&self, p: &[f64], out: &mut [f64]) {
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
    pub(crate) fn quadratic_force(&self, p: &[f64], pd: &[f64]) -> [f64; 4] {
        let gd = g_of(pd);
        let c = self.j_times(mat_vec(&gd, p));
        std::array::from_fn(|k| 8.0 * (gd[0][k] * c[0] + gd[1][k] * c[1] + gd[2][k] * c[2]))
    }

    /// `∂/∂p` of the quadratic-velocity force: `8 G(ṗ)ᵀ J' G(ṗ)`.
    pub(crate) fn quadratic_du(&self, pd: &[f64], out: &mut [f64]) {
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
