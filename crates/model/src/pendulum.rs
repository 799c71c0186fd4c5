//! The paper's pendulum in `u = [x, y, θ]` (`algorithm.md` §5, paper §3), and its
//! generalization to a chain of point masses on massless rods.

use crate::{Pattern, System};

/// One link of a [`PendulumChain`]: a point mass `m` at the end of a massless rod
/// of length `l`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Link {
    /// Mass of the point at the end of the rod, kg (default 1).
    pub m: f64,
    /// Length of the rod, m (default 1).
    pub l: f64,
}

impl Default for Link {
    fn default() -> Self {
        Self { m: 1.0, l: 1.0 }
    }
}

/// A chain of point masses on massless rods, hanging from a pivot at the origin,
/// in the paper's redundant coordinates: link `k` has `[x_k, y_k, θ_k]`.
///
/// Convention (`algorithm.md` §5): `y` up, gravity `−g₀ ŷ`, `θ_k` measured from
/// the downward vertical, and for link `k` (pivot at the previous mass, or the
/// origin for the first link)
///
/// $$\Phi_{2k} = x_k - x_{k-1} - l_k\sin\theta_k,\qquad
///   \Phi_{2k+1} = y_k - y_{k-1} + l_k\cos\theta_k .$$
///
/// The mass matrix is `diag(m, m, 0)` per link: the angle carries no inertia, so
/// `M` is singular — the paper's situation (eqs. 10-11). With one link this is
/// exactly the paper's example; see [`PendulumChain::paper`].
#[derive(Clone, Debug, PartialEq)]
pub struct PendulumChain {
    /// The links, from the pivot outwards.
    pub links: Vec<Link>,
    /// Gravitational acceleration `g₀`, m/s² (acts along `−y`).
    pub g0: f64,
    names: Vec<String>,
    constraint_names: Vec<String>,
}

impl PendulumChain {
    /// A chain of the given links. Coordinates are named `link<k>.x`,
    /// `link<k>.y`, `link<k>.theta` (`k` from 1 at the pivot); a single link uses
    /// the paper's names `x`, `y`, `theta`.
    #[must_use]
    pub fn new(links: Vec<Link>, g0: f64) -> Self {
        let single = links.len() == 1;
        let mut names = Vec::with_capacity(3 * links.len());
        let mut constraint_names = Vec::with_capacity(2 * links.len());
        for k in 1..=links.len() {
            let prefix = if single {
                String::new()
            } else {
                format!("link{k}.")
            };
            for c in ["x", "y", "theta"] {
                names.push(format!("{prefix}{c}"));
            }
            let rod = if single {
                "rod".to_string()
            } else {
                format!("rod{k}")
            };
            constraint_names.push(format!("{rod}.x"));
            constraint_names.push(format!("{rod}.y"));
        }
        Self {
            links,
            g0,
            names,
            constraint_names,
        }
    }

    /// The paper's pendulum: one link of mass `m` and length `l` under gravity `g0`.
    #[must_use]
    pub fn paper(m: f64, l: f64, g0: f64) -> Self {
        Self::new(vec![Link { m, l }], g0)
    }

    /// Coordinates `u` for the given link angles `θ_k` (a consistent position).
    ///
    /// # Panics
    /// If `theta.len()` differs from the number of links.
    #[must_use]
    pub fn position(&self, theta: &[f64]) -> Vec<f64> {
        assert_eq!(theta.len(), self.links.len(), "one angle per link");
        let (mut x, mut y) = (0.0, 0.0);
        let mut u = Vec::with_capacity(3 * theta.len());
        for (link, &th) in self.links.iter().zip(theta) {
            x += link.l * th.sin();
            y -= link.l * th.cos();
            u.extend_from_slice(&[x, y, th]);
        }
        u
    }

    /// Velocities `u̇` for link angles `θ_k` and rates `θ̇_k` (consistent with
    /// `B u̇ = 0`).
    ///
    /// # Panics
    /// If the slices' lengths differ from the number of links.
    #[must_use]
    pub fn velocity(&self, theta: &[f64], omega: &[f64]) -> Vec<f64> {
        assert_eq!(theta.len(), self.links.len(), "one angle per link");
        assert_eq!(omega.len(), self.links.len(), "one rate per link");
        let (mut vx, mut vy) = (0.0, 0.0);
        let mut v = Vec::with_capacity(3 * theta.len());
        for ((link, &th), &w) in self.links.iter().zip(theta).zip(omega) {
            vx += link.l * th.cos() * w;
            vy += link.l * th.sin() * w;
            v.extend_from_slice(&[vx, vy, w]);
        }
        v
    }
}

impl System for PendulumChain {
    fn n_coords(&self) -> usize {
        3 * self.links.len()
    }

    fn n_constraints(&self) -> usize {
        2 * self.links.len()
    }

    fn coord_name(&self, i: usize) -> String {
        self.names[i].clone()
    }

    fn constraint_name(&self, i: usize) -> String {
        self.constraint_names[i].clone()
    }

    fn mass_pattern(&self) -> Pattern {
        let n = self.n_coords();
        let entries = (0..self.links.len())
            .flat_map(|k| [(3 * k, 3 * k), (3 * k + 1, 3 * k + 1)])
            .collect();
        Pattern::from_entries(n, n, entries)
    }

    fn mass_is_constant(&self) -> bool {
        true
    }

    fn mass_into(&self, _t: f64, _u: &[f64], mass: &mut [f64]) {
        for (k, link) in self.links.iter().enumerate() {
            mass[2 * k] = link.m;
            mass[2 * k + 1] = link.m;
        }
    }

    fn forces_are_constant(&self) -> bool {
        true
    }

    fn forces_into(&self, _t: f64, _u: &[f64], _v: &[f64], g: &mut [f64]) {
        for (k, link) in self.links.iter().enumerate() {
            g[3 * k] = 0.0;
            g[3 * k + 1] = -link.m * self.g0;
            g[3 * k + 2] = 0.0;
        }
    }

    fn phi_into(&self, _t: f64, u: &[f64], phi: &mut [f64]) {
        let (mut x0, mut y0) = (0.0, 0.0);
        for (k, link) in self.links.iter().enumerate() {
            let (x, y, th) = (u[3 * k], u[3 * k + 1], u[3 * k + 2]);
            phi[2 * k] = x - x0 - link.l * th.sin();
            phi[2 * k + 1] = y - y0 + link.l * th.cos();
            (x0, y0) = (x, y);
        }
    }

    fn b_pattern(&self) -> Pattern {
        let mut p = Pattern::new(self.n_constraints(), self.n_coords());
        for k in 0..self.links.len() {
            p.push(2 * k, 3 * k);
            p.push(2 * k, 3 * k + 2);
            p.push(2 * k + 1, 3 * k + 1);
            p.push(2 * k + 1, 3 * k + 2);
            if k > 0 {
                p.push(2 * k, 3 * k - 3);
                p.push(2 * k + 1, 3 * k - 2);
            }
        }
        p
    }

    fn b_into(&self, _t: f64, u: &[f64], b: &mut [f64]) {
        // Same order as `b_pattern`; eq. (18) of the paper for one link.
        let mut at = 0;
        for (k, link) in self.links.iter().enumerate() {
            let th = u[3 * k + 2];
            b[at] = 1.0;
            b[at + 1] = -link.l * th.cos();
            b[at + 2] = 1.0;
            b[at + 3] = -link.l * th.sin();
            at += 4;
            if k > 0 {
                b[at] = -1.0;
                b[at + 1] = -1.0;
                at += 2;
            }
        }
    }

    fn hessian_pattern(&self) -> Pattern {
        let n = self.n_coords();
        Pattern::from_entries(
            n,
            n,
            (0..self.links.len())
                .map(|k| (3 * k + 2, 3 * k + 2))
                .collect(),
        )
    }

    fn hessian_into(&self, _t: f64, u: &[f64], mu: &[f64], out: &mut [f64]) {
        for (k, link) in self.links.iter().enumerate() {
            let th = u[3 * k + 2];
            out[k] = link.l * (mu[2 * k] * th.sin() - mu[2 * k + 1] * th.cos());
        }
    }

    fn accel_rhs_into(&self, _t: f64, u: &[f64], v: &[f64], c: &mut [f64]) {
        for (k, link) in self.links.iter().enumerate() {
            let (th, w) = (u[3 * k + 2], v[3 * k + 2]);
            c[2 * k] = -link.l * th.sin() * w * w;
            c[2 * k + 1] = link.l * th.cos() * w * w;
        }
    }

    fn conserves_energy(&self) -> bool {
        true
    }

    fn potential_energy(&self, _t: f64, u: &[f64]) -> f64 {
        self.links
            .iter()
            .enumerate()
            .map(|(k, link)| link.m * self.g0 * u[3 * k + 1])
            .sum()
    }
}
