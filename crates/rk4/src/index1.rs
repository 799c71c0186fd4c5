//! The general reference integrator that `architecture.md` promises: RK4 on
//! the index-1 form of any [`System`], for models without a
//! minimal-coordinate oracle.
//!
//! At every stage the accelerations come from the acceleration-level KKT
//! system `[M Bᵀ; B 0][ü; λ] = [g; c]` with `c = −(B u̇)_u u̇ − 2 B_t u̇ − Φ_tt`
//! (`System::accel_rhs_into`), solved densely (full-pivoting LU: `M` may be
//! singular where `B` fixes the motion, as in the paper's pendulum). After
//! every step the state is projected back onto `Φ = 0` (minimum-norm Gauss-
//! Newton) and `B u̇ + Φ_t = 0`, which keeps the drift of the index-1 form
//! at round-off without changing RK4's order. Dense and `O((n + m)³)` per
//! stage: a reference for small models. It shares no code with the
//! linearize / kkt / newmark path.

use mstar_model::System;
use nalgebra::{DMatrix, DVector};

/// Why [`Index1Rk4`] could not integrate.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Index1Error {
    /// A requested time is NaN, negative, or before the one asked for
    /// previously.
    #[error("times must be non-negative and increasing (got {got} after {after})")]
    TimesOutOfOrder {
        /// The time asked for.
        got: f64,
        /// The time reached before it.
        after: f64,
    },
    /// The acceleration-level KKT matrix `[M Bᵀ; B 0]` has no inverse.
    #[error("the acceleration-level KKT matrix is singular at t = {t}")]
    SingularKkt {
        /// Where.
        t: f64,
    },
    /// `B Bᵀ` has no inverse in the projection: redundant constraints or a
    /// singular position.
    #[error("B Bᵀ is singular at t = {t}: redundant constraints or a singular position")]
    SingularProjection {
        /// Where.
        t: f64,
    },
}

/// RK4 on the index-1 form of `sys` with projection (module documentation).
#[derive(Debug)]
pub struct Index1Rk4<'a, S: System + ?Sized> {
    sys: &'a S,
    /// Largest step, s (default 1e-4).
    pub max_step: f64,
}

/// A state: coordinates and velocities.
pub type State = (Vec<f64>, Vec<f64>);

impl<'a, S: System + ?Sized> Index1Rk4<'a, S> {
    /// The reference for `sys` with the default step.
    #[must_use]
    pub fn new(sys: &'a S) -> Self {
        Self {
            sys,
            max_step: 1e-4,
        }
    }

    /// Integrates from `(u₀, u̇₀)` at `t = 0` (projected onto the position
    /// and velocity constraints first) and returns the state at every time of
    /// `times` (non-negative, non-decreasing).
    ///
    /// # Errors
    /// [`Index1Error`]: the KKT matrix or `B Bᵀ` is singular (redundant
    /// constraints, a singular position), or a time is negative or out of order.
    pub fn solve(&self, u0: &[f64], v0: &[f64], times: &[f64]) -> Result<Vec<State>, Index1Error> {
        let (mut t, mut u, mut v) = (0.0, u0.to_vec(), v0.to_vec());
        // An inconsistent start is projected before the first step: else the
        // projection after it would move the state by O(1), differently for
        // every step size (a first-order error).
        self.project(t, &mut u, &mut v)?;
        let mut out = Vec::with_capacity(times.len());
        for &target in times {
            if target.is_nan() || target < t {
                return Err(Index1Error::TimesOutOfOrder {
                    got: target,
                    after: t,
                });
            }
            while target - t > 1e-14 * target.max(1.0) {
                let h = self.max_step.min(target - t);
                (u, v) = self.step(t, &u, &v, h)?;
                t = if target - t - h <= 1e-14 * target.max(1.0) {
                    target
                } else {
                    t + h
                };
                self.project(t, &mut u, &mut v)?;
            }
            out.push((u.clone(), v.clone()));
        }
        Ok(out)
    }

    /// One classic RK4 step of `(u, u̇)' = (u̇, ü(t, u, u̇))`.
    fn step(&self, t: f64, u: &[f64], v: &[f64], h: f64) -> Result<State, Index1Error> {
        let axpy = |x: &[f64], k: &[f64], c: f64| -> Vec<f64> {
            x.iter().zip(k).map(|(x, k)| x + c * k).collect()
        };
        let a1 = self.acceleration(t, u, v)?;
        let (u2, v2) = (axpy(u, v, 0.5 * h), axpy(v, &a1, 0.5 * h));
        let a2 = self.acceleration(t + 0.5 * h, &u2, &v2)?;
        let (u3, v3) = (axpy(u, &v2, 0.5 * h), axpy(v, &a2, 0.5 * h));
        let a3 = self.acceleration(t + 0.5 * h, &u3, &v3)?;
        let (u4, v4) = (axpy(u, &v3, h), axpy(v, &a3, h));
        let a4 = self.acceleration(t + h, &u4, &v4)?;
        let n = u.len();
        let mut u1 = u.to_vec();
        let mut v1 = v.to_vec();
        for i in 0..n {
            u1[i] += h / 6.0 * (v[i] + 2.0 * v2[i] + 2.0 * v3[i] + v4[i]);
            v1[i] += h / 6.0 * (a1[i] + 2.0 * a2[i] + 2.0 * a3[i] + a4[i]);
        }
        Ok((u1, v1))
    }

    /// `ü` from the acceleration-level KKT system at `(t, u, u̇)`.
    fn acceleration(&self, t: f64, u: &[f64], v: &[f64]) -> Result<Vec<f64>, Index1Error> {
        let n = self.sys.n_coords();
        Ok(self.kkt_solution(t, u, v)?[..n].to_vec())
    }

    /// The multipliers `λ` of the acceleration-level KKT system at
    /// `(t, u, u̇)`: the reference for a DAE's `λ` at a state of the
    /// reference solution.
    ///
    /// # Errors
    /// A message when the KKT matrix is singular (redundant constraints).
    pub fn multipliers(&self, t: f64, u: &[f64], v: &[f64]) -> Result<Vec<f64>, Index1Error> {
        let n = self.sys.n_coords();
        Ok(self.kkt_solution(t, u, v)?[n..].to_vec())
    }

    /// `[ü; λ]` from `[M Bᵀ; B 0][ü; λ] = [g; c]` at `(t, u, u̇)`.
    fn kkt_solution(&self, t: f64, u: &[f64], v: &[f64]) -> Result<Vec<f64>, Index1Error> {
        let (n, m) = (self.sys.n_coords(), self.sys.n_constraints());
        let mut kkt = DMatrix::<f64>::zeros(n + m, n + m);
        let pattern = self.sys.mass_pattern();
        let mut mass = vec![0.0; pattern.len()];
        self.sys.mass_into(t, u, &mut mass);
        for (&(i, j), &x) in pattern.entries.iter().zip(&mass) {
            kkt[(i, j)] += x;
        }
        let b = self.b(t, u);
        for r in 0..m {
            for c in 0..n {
                kkt[(n + r, c)] = b[(r, c)];
                kkt[(c, n + r)] = b[(r, c)];
            }
        }
        let mut rhs = DVector::<f64>::zeros(n + m);
        let mut g = vec![0.0; n];
        self.sys.forces_into(t, u, v, &mut g);
        let mut c = vec![0.0; m];
        self.sys.accel_rhs_into(t, u, v, &mut c);
        rhs.rows_mut(0, n).copy_from_slice(&g);
        rhs.rows_mut(n, m).copy_from_slice(&c);
        let x = kkt
            .full_piv_lu()
            .solve(&rhs)
            .ok_or(Index1Error::SingularKkt { t })?;
        Ok(x.iter().copied().collect())
    }

    /// `B(t, u)`, dense.
    fn b(&self, t: f64, u: &[f64]) -> DMatrix<f64> {
        let pattern = self.sys.b_pattern();
        let mut values = vec![0.0; pattern.len()];
        self.sys.b_into(t, u, &mut values);
        let mut b = DMatrix::zeros(self.sys.n_constraints(), self.sys.n_coords());
        for (&(i, j), &x) in pattern.entries.iter().zip(&values) {
            b[(i, j)] += x;
        }
        b
    }

    /// Minimum-norm corrections onto `Φ(u, t) = 0` (Gauss-Newton) and
    /// `B u̇ + Φ_t = 0`.
    fn project(&self, t: f64, u: &mut [f64], v: &mut [f64]) -> Result<(), Index1Error> {
        let m = self.sys.n_constraints();
        if m == 0 {
            return Ok(());
        }
        let mut phi = vec![0.0; m];
        for _ in 0..10 {
            self.sys.phi_into(t, u, &mut phi);
            if phi.iter().all(|x| x.abs() <= 1e-15 * (1.0 + x.abs())) {
                break;
            }
            let du = minimum_norm(&self.b(t, u), &phi, t)?;
            for (x, d) in u.iter_mut().zip(du.iter()) {
                *x -= d;
            }
        }
        let b = self.b(t, u);
        let mut phi_t = vec![0.0; m];
        self.sys.phi_t_into(t, u, &mut phi_t);
        let residual: Vec<f64> = (b.clone() * DVector::from_column_slice(v))
            .iter()
            .zip(&phi_t)
            .map(|(bv, pt)| bv + pt)
            .collect();
        let dv = minimum_norm(&b, &residual, t)?;
        for (x, d) in v.iter_mut().zip(dv.iter()) {
            *x -= d;
        }
        Ok(())
    }
}

/// `Bᵀ (B Bᵀ)⁻¹ r`: the least-norm `x` with `B x = r`.
fn minimum_norm(b: &DMatrix<f64>, r: &[f64], t: f64) -> Result<DVector<f64>, Index1Error> {
    let y = (b * b.transpose())
        .lu()
        .solve(&DVector::from_column_slice(r))
        .ok_or(Index1Error::SingularProjection { t })?;
    Ok(b.transpose() * y)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ChainOracle;
    use mstar_model::{Link, PendulumChain};

    /// A three-link pendulum chain (point masses, `M` singular in the
    /// angles) against the joint-angle RK4 oracle: RK4's order 4 survives
    /// the projection (errors fall by 16 when h halves: between 12 and 20),
    /// and the constraints hold to round-off.
    #[test]
    fn matches_the_minimal_coordinate_oracle_at_order_four() {
        let links = vec![
            Link { m: 1.0, l: 0.5 },
            Link { m: 2.0, l: 0.7 },
            Link { m: 0.5, l: 0.3 },
        ];
        let sys = PendulumChain::new(links, 9.81);
        let (theta0, omega0) = ([1.0, 2.0, -0.5], [0.3, -1.0, 2.0]);
        let (u0, v0) = (sys.position(&theta0), sys.velocity(&theta0, &omega0));
        let mut oracle = ChainOracle::new(&sys);
        oracle.max_step = 1e-5;
        let exact = oracle.solve(&theta0, &omega0, &[1.0]);
        let error = |h: f64| {
            let mut reference = Index1Rk4::new(&sys);
            reference.max_step = h;
            let states = reference.solve(&u0, &v0, &[1.0]).expect("solves");
            let (u, _) = &states[0];
            let mut phi = vec![0.0; sys.n_constraints()];
            sys.phi_into(1.0, u, &mut phi);
            assert!(phi.iter().all(|x| x.abs() < 1e-12), "{phi:?}");
            u.iter()
                .zip(&exact[0].u)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max)
        };
        let (coarse, fine) = (error(4e-3), error(2e-3));
        assert!(fine < 1e-6, "{fine:e}");
        let ratio = coarse / fine;
        assert!(
            (12.0..=20.0).contains(&ratio),
            "errors {coarse:e}, {fine:e}: ratio {ratio}"
        );
    }

    #[test]
    fn times_out_of_order_are_an_error() {
        let sys = PendulumChain::paper(1.0, 1.0, 9.81);
        let u0 = sys.position(&[1.0]);
        let reference = Index1Rk4::new(&sys);
        assert_eq!(
            reference.solve(&u0, &[0.0; 3], &[0.5, 0.2]),
            Err(Index1Error::TimesOutOfOrder {
                got: 0.2,
                after: 0.5
            })
        );
        assert!(matches!(
            reference.solve(&u0, &[0.0; 3], &[f64::NAN]),
            Err(Index1Error::TimesOutOfOrder { got, .. }) if got.is_nan()
        ));
    }
}
