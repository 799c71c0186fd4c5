//! # mstar-rk4 — independent reference solutions
//!
//! Classic fourth-order Runge-Kutta on the *minimal-coordinate* equations of
//! motion, sharing no code with the DAE path of `mstar-newmark`: an oracle for
//! every curve the integrators produce.
//!
//! [`ChainOracle`] integrates a [`PendulumChain`] in its absolute link angles
//! `θ_k`. For one link (the paper's pendulum) its equation is exactly
//! `θ̈ = −(g₀/l) sin θ`; from `θ, θ̇, θ̈` it reconstructs `x, y, ẋ, ẏ, ẍ, ÿ` and the
//! multipliers (for one link the rod tension `T = m(g₀ cos θ + l θ̇²)` gives
//! `λ₁ = T sin θ`, `λ₂ = −T cos θ`, `algorithm.md` §5), so every curve of the
//! paper's Figs. 4-13 has a reference.
//!
//! ```
//! use mstar_model::PendulumChain;
//! use mstar_rk4::ChainOracle;
//!
//! let sys = PendulumChain::paper(1.0, 1.0, 10.0);
//! let oracle = ChainOracle::new(&sys);
//! let samples = oracle.solve(&[0.1], &[0.0], &[0.0, 0.5, 1.0]);
//! // Tension at rest at θ = 0.1: T = m g₀ cos θ.
//! let t0 = &samples[0];
//! let tension = (t0.lambda[0].powi(2) + t0.lambda[1].powi(2)).sqrt();
//! assert!((tension - 10.0 * 0.1f64.cos()).abs() < 1e-12);
//! ```
//!
//! [`Index1Rk4`] is the general reference for any [`System`](mstar_model::System):
//! RK4 on the index-1 form, the acceleration-level KKT system solved at every
//! stage and the state projected onto the constraints after every step.
#![deny(missing_docs)]

mod index1;
/// Closed-form references for spatial rigid-body validation: the torque-free
/// asymmetric body and the heavy symmetric top, with their textbook sources.
pub mod rigid;

pub use index1::{Index1Error, Index1Rk4, State};

use mstar_model::{PendulumChain, Sample};
use nalgebra::{DMatrix, DVector};

/// RK4 in the absolute link angles of a [`PendulumChain`].
///
/// With `μ_jk = Σ_{i ≥ max(j,k)} m_i` the equations of motion are
///
/// ```text
/// Σ_k μ_jk l_j l_k [cos(θ_j − θ_k) θ̈_k + sin(θ_j − θ_k) θ̇_k²] + (Σ_{i≥j} m_i) g₀ l_j sin θ_j = 0
/// ```
///
/// (one link: `m l² θ̈ + m g₀ l sin θ = 0`).
#[derive(Clone, Debug)]
pub struct ChainOracle<'a> {
    sys: &'a PendulumChain,
    chain: AngleChain,
    /// Largest RK4 step, s (default 1e-3: RK4's error is then ~1e-12 on the
    /// paper's pendulum, far below any integrator error studied here).
    pub max_step: f64,
}

impl<'a> ChainOracle<'a> {
    /// An oracle for `sys` with the default `max_step`.
    #[must_use]
    pub fn new(sys: &'a PendulumChain) -> Self {
        let links = sys
            .links
            .iter()
            .map(|l| AngleLink {
                m: l.m,
                j: 0.0,
                l: l.l,
                c: l.l,
            })
            .collect();
        Self {
            sys,
            chain: AngleChain::new(links, sys.g0),
            max_step: 1e-3,
        }
    }

    /// Angular accelerations `θ̈` for angles `theta` and rates `omega`.
    #[must_use]
    pub fn angular_acceleration(&self, theta: &[f64], omega: &[f64]) -> Vec<f64> {
        // θ is measured from the downward vertical: φ = θ − π/2 from +x.
        let phi: Vec<f64> = theta
            .iter()
            .map(|t| t - std::f64::consts::FRAC_PI_2)
            .collect();
        self.chain.angular_acceleration(&phi, omega)
    }

    /// The full redundant-coordinate [`Sample`] at `t` for angles and rates:
    /// positions, velocities, accelerations, multipliers and energies.
    #[must_use]
    pub fn sample(&self, t: f64, theta: &[f64], omega: &[f64]) -> Sample {
        let links = &self.sys.links;
        let n = links.len();
        let g0 = self.sys.g0;
        let alpha = self.angular_acceleration(theta, omega);
        let mut s = Sample {
            t,
            u: Vec::with_capacity(3 * n),
            v: Vec::with_capacity(3 * n),
            a: Vec::with_capacity(3 * n),
            lambda: vec![0.0; 2 * n],
            ..Sample::default()
        };
        let (mut x, mut y, mut vx, mut vy, mut ax, mut ay) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        for k in 0..n {
            let (l, th, w, al) = (links[k].l, theta[k], omega[k], alpha[k]);
            let (sn, cs) = th.sin_cos();
            x += l * sn;
            y -= l * cs;
            vx += l * cs * w;
            vy += l * sn * w;
            ax += l * (cs * al - sn * w * w);
            ay += l * (sn * al + cs * w * w);
            s.u.extend_from_slice(&[x, y, th]);
            s.v.extend_from_slice(&[vx, vy, w]);
            s.a.extend_from_slice(&[ax, ay, al]);
            s.kinetic += 0.5 * links[k].m * (vx * vx + vy * vy);
            s.potential += links[k].m * g0 * y;
        }
        // Multipliers from the tip inwards: m_i ẍ_i + λ_{2i} − λ_{2i+2} = 0,
        // m_i ÿ_i + λ_{2i+1} − λ_{2i+3} = −m_i g₀.
        let (mut lx, mut ly) = (0.0, 0.0);
        for k in (0..n).rev() {
            let m = links[k].m;
            lx -= m * s.a[3 * k];
            ly -= m * (s.a[3 * k + 1] + g0);
            s.lambda[2 * k] = lx;
            s.lambda[2 * k + 1] = ly;
        }
        s
    }

    /// Integrates from `(θ₀, θ̇₀)` at `t = 0` and returns the [`Sample`] at every
    /// time in `times` (non-negative, non-decreasing), stepping with RK4 at most
    /// [`max_step`](Self::max_step) between them.
    ///
    /// # Panics
    /// If the slices' lengths differ from the number of links or `times` is
    /// negative or decreasing.
    #[must_use]
    pub fn solve(&self, theta0: &[f64], omega0: &[f64], times: &[f64]) -> Vec<Sample> {
        // θ from the downward vertical is φ + π/2 with φ from +x.
        let half_pi = std::f64::consts::FRAC_PI_2;
        let phi0: Vec<f64> = theta0.iter().map(|t| t - half_pi).collect();
        let chain = AngleChain {
            max_step: self.max_step,
            ..self.chain.clone()
        };
        chain
            .solve(&phi0, omega0, times)
            .into_iter()
            .zip(times)
            .map(|((phi, omega), &t)| {
                let theta: Vec<f64> = phi.iter().map(|p| p + half_pi).collect();
                self.sample(t, &theta, &omega)
            })
            .collect()
    }
}

/// Classic RK4 for `ẏ = f(y)` from `y(0) = y0`, returning `y` at each time of
/// `times` (non-negative, non-decreasing), with steps of at most `max_step`.
///
/// # Panics
/// If `times` is negative or decreasing.
pub fn rk4_at(
    f: impl Fn(&[f64]) -> Vec<f64>,
    y0: Vec<f64>,
    times: &[f64],
    max_step: f64,
) -> Vec<Vec<f64>> {
    let mut y = y0;
    let mut t = 0.0;
    let mut out = Vec::with_capacity(times.len());
    for &target in times {
        assert!(target >= t, "times must be non-negative and non-decreasing");
        let span = target - t;
        let steps = (span / max_step).ceil() as usize;
        if steps > 0 {
            let h = span / steps as f64;
            for _ in 0..steps {
                let k1 = f(&y);
                let y2: Vec<f64> = y.iter().zip(&k1).map(|(a, k)| a + 0.5 * h * k).collect();
                let k2 = f(&y2);
                let y3: Vec<f64> = y.iter().zip(&k2).map(|(a, k)| a + 0.5 * h * k).collect();
                let k3 = f(&y3);
                let y4: Vec<f64> = y.iter().zip(&k3).map(|(a, k)| a + h * k).collect();
                let k4 = f(&y4);
                for i in 0..y.len() {
                    y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
                }
            }
        }
        t = target;
        out.push(y.clone());
    }
    out
}

/// One link of an [`AngleChain`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AngleLink {
    /// Mass, kg.
    pub m: f64,
    /// Inertia about the centre of mass, kg m².
    pub j: f64,
    /// Distance from this link's joint to the next joint, m.
    pub l: f64,
    /// Distance from this link's joint to its centre of mass (along the link), m.
    pub c: f64,
}

/// A planar serial chain hinged to the ground at the origin, in the absolute
/// link angles `φ_k` (from `+x`, counter-clockwise) — the minimal coordinates.
/// Centre of mass `k` is at `Σ_{i<k} l_i e(φ_i) + c_k e(φ_k)`, `e(φ) = (cos φ,
/// sin φ)`, so with the lever arms `a_ki = l_i (i < k), c_k (i = k), 0 (i > k)`
/// and `μ_ij = Σ_k m_k a_ki a_kj` the equations of motion are
///
/// ```text
/// Σ_i (μ_ji cos(φ_j − φ_i) + J_j δ_ji) φ̈_i + Σ_i μ_ji sin(φ_j − φ_i) φ̇_i² = −g₀ Σ_k m_k a_kj cos φ_j
/// ```
///
/// (gravity `−g₀ ŷ`). This covers point masses on rods (`J = 0`, `c = l`) and
/// chains of bars (`c = l/2`, `J = m l²/12`).
#[derive(Clone, Debug, PartialEq)]
pub struct AngleChain {
    links: Vec<AngleLink>,
    g0: f64,
    mu: Vec<f64>,
    /// `Σ_k m_k a_kj`, the gravity lever of each angle.
    weight: Vec<f64>,
    /// Largest RK4 step, s (default 1e-4).
    pub max_step: f64,
}

impl AngleChain {
    /// A chain of the given links under gravity `g0` (along `−y`).
    #[must_use]
    pub fn new(links: Vec<AngleLink>, g0: f64) -> Self {
        let n = links.len();
        let arm = |k: usize, i: usize| match i.cmp(&k) {
            std::cmp::Ordering::Less => links[i].l,
            std::cmp::Ordering::Equal => links[k].c,
            std::cmp::Ordering::Greater => 0.0,
        };
        let mut mu = vec![0.0; n * n];
        let mut weight = vec![0.0; n];
        for k in 0..n {
            for i in 0..=k {
                weight[i] += links[k].m * arm(k, i);
                for j in 0..=k {
                    mu[i * n + j] += links[k].m * arm(k, i) * arm(k, j);
                }
            }
        }
        Self {
            links,
            g0,
            mu,
            weight,
            max_step: 1e-4,
        }
    }

    /// `φ̈` for angles `phi` and rates `omega`.
    #[must_use]
    pub fn angular_acceleration(&self, phi: &[f64], omega: &[f64]) -> Vec<f64> {
        let n = self.links.len();
        let mut mass = DMatrix::<f64>::zeros(n, n);
        let mut rhs = DVector::<f64>::zeros(n);
        for j in 0..n {
            rhs[j] = -self.g0 * self.weight[j] * phi[j].cos();
            for i in 0..n {
                let mu = self.mu[j * n + i];
                let d = phi[j] - phi[i];
                mass[(j, i)] = mu * d.cos();
                rhs[j] -= mu * d.sin() * omega[i] * omega[i];
            }
            mass[(j, j)] += self.links[j].j;
        }
        // The chain's mass matrix is symmetric positive definite.
        match mass.cholesky() {
            Some(c) => c.solve(&rhs).iter().copied().collect(),
            None => vec![f64::NAN; n],
        }
    }

    /// Centres of mass `(x, y)` of every link for angles `phi`.
    #[must_use]
    pub fn centres(&self, phi: &[f64]) -> Vec<[f64; 2]> {
        let mut joint = [0.0, 0.0];
        self.links
            .iter()
            .zip(phi)
            .map(|(link, &p)| {
                let (s, c) = p.sin_cos();
                let centre = [joint[0] + link.c * c, joint[1] + link.c * s];
                joint = [joint[0] + link.l * c, joint[1] + link.l * s];
                centre
            })
            .collect()
    }

    /// Integrates from `(φ₀, φ̇₀)` at `t = 0` and returns `(φ, φ̇)` at each time.
    ///
    /// # Panics
    /// If the slices' lengths differ from the number of links or `times` is
    /// negative or decreasing.
    #[must_use]
    pub fn solve(&self, phi0: &[f64], omega0: &[f64], times: &[f64]) -> Vec<(Vec<f64>, Vec<f64>)> {
        let n = self.links.len();
        assert_eq!(phi0.len(), n, "one angle per link");
        assert_eq!(omega0.len(), n, "one rate per link");
        let f = |y: &[f64]| -> Vec<f64> {
            let (p, w) = y.split_at(n);
            let al = self.angular_acceleration(p, w);
            w.iter().chain(&al).copied().collect()
        };
        let y0: Vec<f64> = phi0.iter().chain(omega0).copied().collect();
        rk4_at(f, y0, times, self.max_step)
            .into_iter()
            .map(|y| (y[..n].to_vec(), y[n..].to_vec()))
            .collect()
    }
}

/// The exact period of a pendulum of length `l` released at rest from `θ₀`:
/// `T = 4 √(l/g₀) K(sin(θ₀/2))`, with the complete elliptic integral of the
/// first kind from the arithmetic-geometric mean, `K(k) = π / (2 AGM(1, √(1−k²)))`.
#[must_use]
pub fn pendulum_period(l: f64, g0: f64, theta0: f64) -> f64 {
    let k = (0.5 * theta0).sin();
    let (mut a, mut b) = (1.0f64, (1.0 - k * k).sqrt());
    for _ in 0..40 {
        (a, b) = (0.5 * (a + b), (a * b).sqrt());
    }
    4.0 * (l / g0).sqrt() * std::f64::consts::PI / (2.0 * a)
}

#[cfg(test)]
mod tests {
    use super::*;
    use mstar_model::{Link, System};

    #[test]
    fn pendulum_returns_after_the_exact_period() {
        // A closed form independent of RK4: the elliptic-integral period.
        let sys = PendulumChain::paper(1.0, 1.0, 10.0);
        let theta0 = std::f64::consts::FRAC_PI_2;
        let period = pendulum_period(1.0, 10.0, theta0);
        let s = ChainOracle::new(&sys).solve(&[theta0], &[0.0], &[0.0, 0.5 * period, period]);
        assert!(
            (s[1].u[2] + theta0).abs() < 1e-9,
            "half period: {}",
            s[1].u[2]
        );
        assert!(
            (s[2].u[2] - theta0).abs() < 1e-9,
            "full period: {}",
            s[2].u[2]
        );
        assert!(s[2].v[2].abs() < 1e-8);
    }

    #[test]
    fn reconstruction_satisfies_the_dae() {
        // M ü + Bᵀλ = g and B ü = c at a moving state of a 3-link chain.
        let sys = PendulumChain::new(
            vec![
                Link { m: 1.0, l: 1.0 },
                Link { m: 2.0, l: 0.5 },
                Link { m: 0.5, l: 0.8 },
            ],
            9.81,
        );
        let s = ChainOracle::new(&sys).sample(0.0, &[0.3, -0.7, 1.2], &[0.5, -1.0, 2.0]);
        let (n, m) = (sys.n_coords(), sys.n_constraints());
        let (mp, bp) = (sys.mass_pattern(), sys.b_pattern());
        let mut mass = vec![0.0; mp.len()];
        let mut b = vec![0.0; bp.len()];
        sys.mass_into(0.0, &s.u, &mut mass);
        sys.b_into(0.0, &s.u, &mut b);
        let mut lhs = vec![0.0; n];
        mp.mul_add(&mass, &s.a, &mut lhs);
        bp.mul_transpose_add(&b, &s.lambda, &mut lhs);
        let mut g = vec![0.0; n];
        sys.forces_into(0.0, &s.u, &s.v, &mut g);
        for i in 0..n {
            assert!(
                (lhs[i] - g[i]).abs() < 1e-12,
                "equation {i}: {} vs {}",
                lhs[i],
                g[i]
            );
        }
        let mut ba = vec![0.0; m];
        bp.mul_add(&b, &s.a, &mut ba);
        let mut c = vec![0.0; m];
        sys.accel_rhs_into(0.0, &s.u, &s.v, &mut c);
        for i in 0..m {
            assert!((ba[i] - c[i]).abs() < 1e-12);
        }
        let mut phi = vec![0.0; m];
        sys.phi_into(0.0, &s.u, &mut phi);
        assert!(phi.iter().all(|p| p.abs() < 1e-14));
    }

    #[test]
    fn one_link_tension_matches_the_closed_form() {
        let sys = PendulumChain::paper(2.0, 1.5, 9.81);
        let s = ChainOracle::new(&sys).sample(0.0, &[0.4], &[1.3]);
        let tension = 2.0 * (9.81 * 0.4f64.cos() + 1.5 * 1.3 * 1.3);
        assert!((s.lambda[0] - tension * 0.4f64.sin()).abs() < 1e-12);
        assert!((s.lambda[1] + tension * 0.4f64.cos()).abs() < 1e-12);
        assert!((s.a[2] + 9.81 / 1.5 * 0.4f64.sin()).abs() < 1e-12);
    }
}
