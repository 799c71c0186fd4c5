//! Bars described by their proximal joint: a chain whose mass matrix depends
//! on the configuration and is not diagonal.

use mstar::model::{Pattern, System};

/// One bar of a [`JointFrameChain`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointFrameBar {
    /// Mass, kg.
    pub mass: f64,
    /// Inertia about the centre of mass, kg m².
    pub inertia: f64,
    /// Distance from the joint to the next joint, m.
    pub length: f64,
    /// Distance from the joint to the centre of mass, along the bar, m.
    pub centre: f64,
}

/// A planar chain of bars hinged to the ground at the origin, each bar `k`
/// described by `u_k = [x_k, y_k, θ_k]`: the position of its proximal joint
/// `P_k` and its angle from `+x` (not its centre of mass). Its centre is
/// `c_k = P_k + a_k e(θ_k)`, `e(θ) = (cos θ, sin θ)`, so the kinetic energy
/// `½ m |Ṗ + a θ̇ e⊥|² + ½ J θ̇²` gives the configuration-dependent,
/// non-diagonal block
///
/// ```text
/// M_k(θ) = [[m, 0, −m a sin θ], [0, m, m a cos θ], [−m a sin θ, m a cos θ, J + m a²]]
/// ```
///
/// and Lagrange's equations move `Ṁ u̇ − ∂T/∂u = −m a θ̇² e(θ)` (on `x`, `y`) to
/// the forces as the centripetal term: `g_k = [m a θ̇² cos θ, −m g₀ + m a θ̇²
/// sin θ, −m g₀ a cos θ]` (gravity `−g₀ ŷ`). Joint `k` is `P_k − P_{k−1} −
/// l_{k−1} e(θ_{k−1}) = 0` (`P_0` the origin). Every derivative is written
/// out, `∂(M w)/∂u`, `∂g/∂u` and `∂g/∂u̇` included; the motion is that of a
/// bar chain in the centre-of-mass coordinates of the planar builder.
#[derive(Clone, Debug, PartialEq)]
pub struct JointFrameChain {
    bars: Vec<JointFrameBar>,
    g0: f64,
}

impl JointFrameChain {
    /// The chain of `bars` under gravity `g0` (along `−y`).
    #[must_use]
    pub fn new(bars: Vec<JointFrameBar>, g0: f64) -> Self {
        Self { bars, g0 }
    }

    /// Coordinates for the bar angles `theta` (joints placed on the chain).
    #[must_use]
    pub fn position(&self, theta: &[f64]) -> Vec<f64> {
        let mut joint = [0.0, 0.0];
        let mut u = Vec::with_capacity(3 * self.bars.len());
        for (bar, &th) in self.bars.iter().zip(theta) {
            u.extend_from_slice(&[joint[0], joint[1], th]);
            joint = [
                joint[0] + bar.length * th.cos(),
                joint[1] + bar.length * th.sin(),
            ];
        }
        u
    }

    /// Velocities for the angles `theta` and rates `omega`.
    #[must_use]
    pub fn velocity(&self, theta: &[f64], omega: &[f64]) -> Vec<f64> {
        let mut joint = [0.0, 0.0];
        let mut v = Vec::with_capacity(3 * self.bars.len());
        for ((bar, &th), &w) in self.bars.iter().zip(theta).zip(omega) {
            v.extend_from_slice(&[joint[0], joint[1], w]);
            let (s, c) = th.sin_cos();
            joint = [joint[0] - bar.length * s * w, joint[1] + bar.length * c * w];
        }
        v
    }

    /// `(m, J, l, a, sin θ, cos θ)` of bar `k` at `u`.
    fn at(&self, k: usize, u: &[f64]) -> (f64, f64, f64, f64, f64, f64) {
        let bar = &self.bars[k];
        let (s, c) = u[3 * k + 2].sin_cos();
        (bar.mass, bar.inertia, bar.length, bar.centre, s, c)
    }

    /// One entry per bar for its angle column (the shape of `∂g/∂u`,
    /// `∂g/∂u̇` and `∂(M w)/∂u`): rows `x`, `y`, `θ` of the bar.
    fn angle_columns(&self) -> Pattern {
        let n = self.n_coords();
        Pattern::from_entries(
            n,
            n,
            (0..self.bars.len())
                .flat_map(|k| (0..3).map(move |r| (3 * k + r, 3 * k + 2)))
                .collect(),
        )
    }
}

impl System for JointFrameChain {
    fn n_coords(&self) -> usize {
        3 * self.bars.len()
    }

    fn n_constraints(&self) -> usize {
        2 * self.bars.len()
    }

    fn coord_name(&self, i: usize) -> String {
        format!("bar{}.{}", i / 3 + 1, ["x", "y", "theta"][i % 3])
    }

    fn constraint_name(&self, i: usize) -> String {
        format!("joint{}.{}", i / 2 + 1, ["x", "y"][i % 2])
    }

    fn mass_pattern(&self) -> Pattern {
        let n = self.n_coords();
        let local = [(0, 0), (1, 1), (0, 2), (2, 0), (1, 2), (2, 1), (2, 2)];
        Pattern::from_entries(
            n,
            n,
            (0..self.bars.len())
                .flat_map(|k| local.iter().map(move |&(i, j)| (3 * k + i, 3 * k + j)))
                .collect(),
        )
    }

    fn mass_into(&self, _t: f64, u: &[f64], mass: &mut [f64]) {
        for k in 0..self.bars.len() {
            let (m, j, _, a, s, c) = self.at(k, u);
            let block = [
                m,
                m,
                -m * a * s,
                -m * a * s,
                m * a * c,
                m * a * c,
                j + m * a * a,
            ];
            mass[7 * k..7 * k + 7].copy_from_slice(&block);
        }
    }

    fn forces_into(&self, _t: f64, u: &[f64], v: &[f64], g: &mut [f64]) {
        for k in 0..self.bars.len() {
            let (m, _, _, a, s, c) = self.at(k, u);
            let w = v[3 * k + 2];
            g[3 * k] = m * a * w * w * c;
            g[3 * k + 1] = -m * self.g0 + m * a * w * w * s;
            g[3 * k + 2] = -m * self.g0 * a * c;
        }
    }

    fn forces_du_pattern(&self) -> Pattern {
        self.angle_columns()
    }

    fn forces_du_into(&self, _t: f64, u: &[f64], v: &[f64], g_u: &mut [f64]) {
        for k in 0..self.bars.len() {
            let (m, _, _, a, s, c) = self.at(k, u);
            let w = v[3 * k + 2];
            g_u[3 * k..3 * k + 3].copy_from_slice(&[
                -m * a * w * w * s,
                m * a * w * w * c,
                m * self.g0 * a * s,
            ]);
        }
    }

    fn forces_dv_pattern(&self) -> Pattern {
        self.angle_columns()
    }

    fn forces_dv_into(&self, _t: f64, u: &[f64], v: &[f64], g_v: &mut [f64]) {
        for k in 0..self.bars.len() {
            let (m, _, _, a, s, c) = self.at(k, u);
            let w = v[3 * k + 2];
            g_v[3 * k..3 * k + 3].copy_from_slice(&[2.0 * m * a * w * c, 2.0 * m * a * w * s, 0.0]);
        }
    }

    fn mass_du_pattern(&self) -> Pattern {
        self.angle_columns()
    }

    fn mass_du_into(&self, _t: f64, u: &[f64], w: &[f64], out: &mut [f64]) {
        for k in 0..self.bars.len() {
            let (m, _, _, a, s, c) = self.at(k, u);
            let (wx, wy, wt) = (w[3 * k], w[3 * k + 1], w[3 * k + 2]);
            out[3 * k..3 * k + 3].copy_from_slice(&[
                -m * a * c * wt,
                -m * a * s * wt,
                -m * a * (c * wx + s * wy),
            ]);
        }
    }

    fn phi_into(&self, _t: f64, u: &[f64], phi: &mut [f64]) {
        for k in 0..self.bars.len() {
            let (x, y) = (u[3 * k], u[3 * k + 1]);
            let previous = if k == 0 {
                [0.0, 0.0]
            } else {
                let (_, _, l, _, s, c) = self.at(k - 1, u);
                [u[3 * k - 3] + l * c, u[3 * k - 2] + l * s]
            };
            phi[2 * k] = x - previous[0];
            phi[2 * k + 1] = y - previous[1];
        }
    }

    fn b_pattern(&self) -> Pattern {
        let mut p = Pattern::new(self.n_constraints(), self.n_coords());
        for k in 0..self.bars.len() {
            p.push(2 * k, 3 * k);
            p.push(2 * k + 1, 3 * k + 1);
            if k > 0 {
                for (row, col) in [(0, 0), (0, 2), (1, 1), (1, 2)] {
                    p.push(2 * k + row, 3 * k - 3 + col);
                }
            }
        }
        p
    }

    fn b_into(&self, _t: f64, u: &[f64], b: &mut [f64]) {
        let mut at = 0;
        for k in 0..self.bars.len() {
            b[at] = 1.0;
            b[at + 1] = 1.0;
            at += 2;
            if k > 0 {
                let (_, _, l, _, s, c) = self.at(k - 1, u);
                b[at..at + 4].copy_from_slice(&[-1.0, l * s, -1.0, -l * c]);
                at += 4;
            }
        }
    }

    fn hessian_pattern(&self) -> Pattern {
        let n = self.n_coords();
        let angles = (1..self.bars.len())
            .map(|k| (3 * k - 1, 3 * k - 1))
            .collect();
        Pattern::from_entries(n, n, angles)
    }

    fn hessian_into(&self, _t: f64, u: &[f64], mu: &[f64], out: &mut [f64]) {
        for k in 1..self.bars.len() {
            let (_, _, l, _, s, c) = self.at(k - 1, u);
            out[k - 1] = mu[2 * k] * l * c + mu[2 * k + 1] * l * s;
        }
    }

    fn accel_rhs_into(&self, _t: f64, u: &[f64], v: &[f64], c_out: &mut [f64]) {
        c_out[..2].fill(0.0);
        for k in 1..self.bars.len() {
            let (_, _, l, _, s, c) = self.at(k - 1, u);
            let w = v[3 * k - 1];
            c_out[2 * k] = -l * c * w * w;
            c_out[2 * k + 1] = -l * s * w * w;
        }
    }

    fn mass_is_constant(&self) -> bool {
        false
    }

    fn tangent_is_symmetric(&self) -> bool {
        // ∂(M w)/∂u and the centripetal forces' ∂g/∂u, ∂g/∂u̇ live in the
        // angle columns only.
        false
    }

    fn potential_energy(&self, _t: f64, u: &[f64]) -> f64 {
        (0..self.bars.len())
            .map(|k| {
                let (m, _, _, a, s, _) = self.at(k, u);
                m * self.g0 * (u[3 * k + 1] + a * s)
            })
            .sum()
    }
}
