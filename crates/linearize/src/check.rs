//! Finite-difference checks of every derivative a [`System`] provides.

use mstar_kkt::MaxAbs;
use mstar_model::{Pattern, StateRef, System};

/// Largest relative errors of a system's analytic derivatives against central
/// finite differences, each `max|analytic − fd| / max(1, max|fd|)`; NaN (or
/// infinite) when either side has a NaN or an infinity, so that a check
/// `e.max() < tol` fails on it.
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
    /// The largest of all errors: NaN or infinite when one of them is.
    #[must_use]
    pub fn max(&self) -> f64 {
        let mut m = MaxAbs::new();
        for e in [
            self.b,
            self.k_t,
            self.c_t,
            self.phi_t,
            self.accel_rhs,
            self.fused,
        ] {
            m.push(e);
        }
        m.value()
    }
}

/// A dense row-major matrix.
type Dense = Vec<Vec<f64>>;

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
    let mut r = vec![0.0; sys.n_coords()];
    sys.forces_into(t, u, v, &mut r);
    let mut bt_lambda = vec![0.0; r.len()];
    bp.mul_transpose_add(
        &values(sys.b_pattern(), |b| sys.b_into(t, u, b)),
        lambda,
        &mut bt_lambda,
    );
    let mut m_a = vec![0.0; r.len()];
    mp.mul_add(
        &values(sys.mass_pattern(), |m| sys.mass_into(t, u, m)),
        a,
        &mut m_a,
    );
    for i in 0..r.len() {
        r[i] -= bt_lambda[i] + m_a[i];
    }
    r
}

/// The values that `fill` writes on `pattern`.
fn values(pattern: Pattern, fill: impl FnOnce(&mut [f64])) -> Vec<f64> {
    let mut v = vec![0.0; pattern.len()];
    fill(&mut v);
    v
}

/// The dense matrix that `fill` writes on `pattern`.
fn dense(pattern: Pattern, fill: impl FnOnce(&mut [f64])) -> Dense {
    let v = values(pattern.clone(), fill);
    pattern.to_dense(&v)
}

fn phi<S: System + ?Sized>(sys: &S, t: f64, u: &[f64]) -> Vec<f64> {
    let mut out = vec![0.0; sys.n_constraints()];
    sys.phi_into(t, u, &mut out);
    out
}

/// Central-difference Jacobian of `f` at `x` (row-major, `f.len() × x.len()`).
fn fd_jacobian(x: &[f64], f: impl Fn(&[f64]) -> Vec<f64>) -> Dense {
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

/// `max|analytic − fd| / max(1, max|fd|)`, NaN-aware.
fn rel_err(analytic: &[Vec<f64>], fd: &[Vec<f64>]) -> f64 {
    let (mut scale, mut err) = (MaxAbs::new(), MaxAbs::new());
    scale.push(1.0);
    for (a, d) in analytic.iter().flatten().zip(fd.iter().flatten()) {
        scale.push(*d);
        err.push(a - d);
    }
    err.value() / scale.value()
}

/// A column vector as a dense matrix.
fn column(x: &[f64]) -> Dense {
    x.iter().map(|&v| vec![v]).collect()
}

fn negated(a: Dense) -> Dense {
    a.into_iter()
        .map(|row| row.into_iter().map(|x| -x).collect())
        .collect()
}

/// Compares every analytic derivative of `sys` at the given state with central
/// finite differences. Expect errors of order 1e-8 for a correct system.
#[must_use]
pub fn check_derivatives<S: System + ?Sized>(sys: &S, x: &StateRef<'_>) -> DerivativeErrors {
    let StateRef { t, u, v, a, lambda } = *x;
    DerivativeErrors {
        b: rel_err(
            &dense(sys.b_pattern(), |b| sys.b_into(t, u, b)),
            &fd_jacobian(u, |x| phi(sys, t, x)),
        ),
        k_t: k_t_error(sys, t, u, v, a, lambda),
        c_t: rel_err(
            &negated(dense(sys.forces_dv_pattern(), |g_v| {
                sys.forces_dv_into(t, u, v, g_v);
            })),
            &negated(fd_jacobian(v, |x| residual(sys, t, u, x, a, lambda))),
        ),
        phi_t: phi_t_error(sys, t, u),
        accel_rhs: accel_rhs_error(sys, t, u, v),
        fused: fused_error(sys, t, u),
    }
}

/// `K_T = H(λ) − ∂g/∂u + ∂(Mü)/∂u` against `−∂r/∂u`.
fn k_t_error<S: System + ?Sized>(
    sys: &S,
    t: f64,
    u: &[f64],
    v: &[f64],
    a: &[f64],
    lambda: &[f64],
) -> f64 {
    let mut k_t = dense(sys.hessian_pattern(), |h| sys.hessian_into(t, u, lambda, h));
    let g_u = dense(sys.forces_du_pattern(), |g| sys.forces_du_into(t, u, v, g));
    let m_du = dense(sys.mass_du_pattern(), |m| sys.mass_du_into(t, u, a, m));
    for (i, row) in k_t.iter_mut().enumerate() {
        for (j, k) in row.iter_mut().enumerate() {
            *k += m_du[i][j] - g_u[i][j];
        }
    }
    let fd = negated(fd_jacobian(u, |x| residual(sys, t, x, v, a, lambda)));
    rel_err(&k_t, &fd)
}

/// `Φ_t` against differences of `Φ` in time.
fn phi_t_error<S: System + ?Sized>(sys: &S, t: f64, u: &[f64]) -> f64 {
    let mut phi_t = vec![0.0; sys.n_constraints()];
    sys.phi_t_into(t, u, &mut phi_t);
    rel_err(&column(&phi_t), &fd_jacobian(&[t], |s| phi(sys, s[0], u)))
}

/// `c` against `−d²/ds² Φ(u + s v, t + s)`.
fn accel_rhs_error<S: System + ?Sized>(sys: &S, t: f64, u: &[f64], v: &[f64]) -> f64 {
    let m = sys.n_constraints();
    let mut c = vec![0.0; m];
    sys.accel_rhs_into(t, u, v, &mut c);
    let at = |s: f64| {
        let x: Vec<f64> = u.iter().zip(v).map(|(&ui, &vi)| ui + s * vi).collect();
        phi(sys, t + s, &x)
    };
    let p0 = at(0.0);
    // The central second difference at step d, its O(d²) term removed by
    // Richardson extrapolation from d and d/2. Its round-off is about
    // ε |Φ| / d²: at a random state off the constraints |Φ| is of order 10
    // (a distance joint's squared lengths), and d = 1e-4 alone left errors
    // of 1e-6; d = 1e-3 with the extrapolation keeps both the round-off
    // (about 1e-9 |Φ|) and the truncation (O(d⁴)) far below the tolerance.
    let second = |d: f64| {
        let (p_plus, p_minus) = (at(d), at(-d));
        (0..m)
            .map(|i| -(p_plus[i] - 2.0 * p0[i] + p_minus[i]) / (d * d))
            .collect::<Vec<f64>>()
    };
    let (coarse, fine) = (second(2e-3), second(1e-3));
    let c_fd: Vec<f64> = fine
        .iter()
        .zip(&coarse)
        .map(|(f, c)| (4.0 * f - c) / 3.0)
        .collect();
    rel_err(&column(&c), &column(&c_fd))
}

/// The fused `Φ` and `B` against the separate ones, relative to
/// `max(1, |value|)`.
fn fused_error<S: System + ?Sized>(sys: &S, t: f64, u: &[f64]) -> f64 {
    let b = values(sys.b_pattern(), |b| sys.b_into(t, u, b));
    let (mut phi_f, mut b_f) = (vec![0.0; sys.n_constraints()], vec![0.0; b.len()]);
    let mut work = vec![0.0; sys.workspace_len()];
    sys.phi_b_into(t, u, &mut phi_f, &mut b_f, &mut work);
    let mut err = MaxAbs::new();
    for (x, y) in phi_f.iter().zip(&phi(sys, t, u)).chain(b_f.iter().zip(&b)) {
        err.push((x - y) / y.abs().max(1.0));
    }
    err.value()
}
