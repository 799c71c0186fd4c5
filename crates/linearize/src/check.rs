//! Finite-difference checks of every derivative a [`System`] provides.

use mstar_model::System;

/// Largest relative errors of a system's analytic derivatives against central
/// finite differences, each `max|analytic − fd| / max(1, max|fd|)`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DerivativeErrors {
    /// `B = ∂Φ/∂u` against differences of `Φ`.
    pub b: f64,
    /// `K_T = −∂r/∂u` (eq. 6) against differences of the residual `r`.
    pub k_t: f64,
    /// `C_T = −∂r/∂u̇` (eq. 7) against differences of the residual `r`.
    pub c_t: f64,
    /// `Φ_t` against differences of `Φ` in time.
    pub phi_t: f64,
    /// The acceleration right-hand side `c` against
    /// `−d²/ds² Φ(u + s u̇, t + s)` at `s = 0`.
    pub accel_rhs: f64,
    /// The fused [`System::phi_b_into`] against `phi_into` and `b_into`
    /// (relative to `max(1, |value|)`; round-off level when they agree).
    pub fused: f64,
}

impl DerivativeErrors {
    /// The largest of all errors.
    #[must_use]
    pub fn max(&self) -> f64 {
        self.b
            .max(self.k_t)
            .max(self.c_t)
            .max(self.phi_t)
            .max(self.accel_rhs)
            .max(self.fused)
    }
}

/// The residual `r = g − Bᵀλ − M ü` (eq. 3), freshly allocated.
fn residual<S: System + ?Sized>(
    sys: &S,
    t: f64,
    u: &[f64],
    v: &[f64],
    a: &[f64],
    lambda: &[f64],
) -> Vec<f64> {
    let (mp, bp) = (sys.mass_pattern(), sys.b_pattern());
    let mut mass = vec![0.0; mp.len()];
    let mut b = vec![0.0; bp.len()];
    let mut r = vec![0.0; sys.n_coords()];
    sys.mass_into(t, u, &mut mass);
    sys.b_into(t, u, &mut b);
    sys.forces_into(t, u, v, &mut r);
    let mut bt_lambda = vec![0.0; r.len()];
    bp.mul_transpose_add(&b, lambda, &mut bt_lambda);
    let mut m_a = vec![0.0; r.len()];
    mp.mul_add(&mass, a, &mut m_a);
    for i in 0..r.len() {
        r[i] -= bt_lambda[i] + m_a[i];
    }
    r
}

fn phi<S: System + ?Sized>(sys: &S, t: f64, u: &[f64]) -> Vec<f64> {
    let mut out = vec![0.0; sys.n_constraints()];
    sys.phi_into(t, u, &mut out);
    out
}

/// Central-difference Jacobian of `f` at `x` (row-major, `f.len() × x.len()`).
fn fd_jacobian(x: &[f64], f: impl Fn(&[f64]) -> Vec<f64>) -> Vec<Vec<f64>> {
    let rows = f(x).len();
    let mut jac = vec![vec![0.0; x.len()]; rows];
    let mut xp = x.to_vec();
    for j in 0..x.len() {
        let d = 1e-6 * x[j].abs().max(1.0);
        xp[j] = x[j] + d;
        let fp = f(&xp);
        xp[j] = x[j] - d;
        let fm = f(&xp);
        xp[j] = x[j];
        for i in 0..rows {
            jac[i][j] = (fp[i] - fm[i]) / (2.0 * d);
        }
    }
    jac
}

fn rel_err(analytic: &[Vec<f64>], fd: &[Vec<f64>]) -> f64 {
    let scale = fd.iter().flatten().fold(1.0f64, |acc, &x| acc.max(x.abs()));
    analytic
        .iter()
        .flatten()
        .zip(fd.iter().flatten())
        .fold(0.0f64, |acc, (&x, &y)| acc.max((x - y).abs()))
        / scale
}

fn negated(a: Vec<Vec<f64>>) -> Vec<Vec<f64>> {
    a.into_iter()
        .map(|row| row.into_iter().map(|x| -x).collect())
        .collect()
}

/// Compares every analytic derivative of `sys` at the given state with central
/// finite differences. Expect errors of order 1e-8 for a correct system.
#[must_use]
pub fn check_derivatives<S: System + ?Sized>(
    sys: &S,
    t: f64,
    u: &[f64],
    v: &[f64],
    a: &[f64],
    lambda: &[f64],
) -> DerivativeErrors {
    let n = sys.n_coords();
    let m = sys.n_constraints();
    let dense = |p: mstar_model::Pattern, vals: &[f64]| p.to_dense(vals);

    // B
    let mut b = vec![0.0; sys.b_pattern().len()];
    sys.b_into(t, u, &mut b);
    let b_err = rel_err(
        &dense(sys.b_pattern(), &b),
        &fd_jacobian(u, |x| phi(sys, t, x)),
    );

    // K_T = H(λ) − ∂g/∂u + ∂(Mü)/∂u
    let mut h = vec![0.0; sys.hessian_pattern().len()];
    sys.hessian_into(t, u, lambda, &mut h);
    let mut g_u = vec![0.0; sys.forces_du_pattern().len()];
    sys.forces_du_into(t, u, v, &mut g_u);
    let mut m_du = vec![0.0; sys.mass_du_pattern().len()];
    sys.mass_du_into(t, u, a, &mut m_du);
    let mut k_t = dense(sys.hessian_pattern(), &h);
    let g_u = dense(sys.forces_du_pattern(), &g_u);
    let m_du = dense(sys.mass_du_pattern(), &m_du);
    for i in 0..n {
        for j in 0..n {
            k_t[i][j] += m_du[i][j] - g_u[i][j];
        }
    }
    let k_fd = negated(fd_jacobian(u, |x| residual(sys, t, x, v, a, lambda)));
    let k_err = rel_err(&k_t, &k_fd);

    // C_T = −∂g/∂u̇
    let mut g_v = vec![0.0; sys.forces_dv_pattern().len()];
    sys.forces_dv_into(t, u, v, &mut g_v);
    let c_t = negated(dense(sys.forces_dv_pattern(), &g_v));
    let c_fd = negated(fd_jacobian(v, |x| residual(sys, t, u, x, a, lambda)));
    let c_err = rel_err(&c_t, &c_fd);

    // Φ_t
    let mut phi_t = vec![0.0; m];
    sys.phi_t_into(t, u, &mut phi_t);
    let phi_t_fd = fd_jacobian(&[t], |s| phi(sys, s[0], u));
    let phi_t_err = rel_err(
        &phi_t.iter().map(|&x| vec![x]).collect::<Vec<_>>(),
        &phi_t_fd,
    );

    // c = −d²/ds² Φ(u + s v, t + s)
    let mut c = vec![0.0; m];
    sys.accel_rhs_into(t, u, v, &mut c);
    let d = 1e-4;
    let at = |s: f64| {
        let x: Vec<f64> = u.iter().zip(v).map(|(&ui, &vi)| ui + s * vi).collect();
        phi(sys, t + s, &x)
    };
    let (p_plus, p0, p_minus) = (at(d), at(0.0), at(-d));
    let c_fd: Vec<Vec<f64>> = (0..m)
        .map(|i| vec![-(p_plus[i] - 2.0 * p0[i] + p_minus[i]) / (d * d)])
        .collect();
    let accel_err = rel_err(&c.iter().map(|&x| vec![x]).collect::<Vec<_>>(), &c_fd);

    // The fused evaluation against the separate ones.
    let (mut phi_f, mut b_f) = (vec![0.0; m], vec![0.0; b.len()]);
    sys.phi_b_into(t, u, &mut phi_f, &mut b_f);
    let fused = phi_f
        .iter()
        .zip(&phi(sys, t, u))
        .chain(b_f.iter().zip(&b))
        .fold(0.0f64, |e, (x, y)| {
            let d = (x - y).abs() / y.abs().max(1.0);
            if d.is_nan() { f64::INFINITY } else { e.max(d) }
        });

    DerivativeErrors {
        fused,
        b: b_err,
        k_t: k_err,
        c_t: c_err,
        phi_t: phi_t_err,
        accel_rhs: accel_err,
    }
}
