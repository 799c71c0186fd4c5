//! Finite-difference defaults of the [`System`] trait's second-order terms.
//!
//! Central differences with the step `h = ε^{1/3} max(1, |x|)` balance the
//! truncation error `h² f‴/6` against the round-off `ε |f| / h`: about 1e-10
//! relative for smooth functions of order-one scale. The perturbed argument is
//! rounded first (`x ± h` then `h` recomputed from it), so that the divisor is
//! the step actually taken. Second differences in time use Richardson
//! extrapolation of two steps, `(4 D(h/2) − D(h)) / 3`, with `h = ε^{1/6}
//! max(1, |t|)`: error `O(h⁴) + O(ε/h²)`, also about 1e-10.

use crate::{Pattern, System};

/// `ε^{1/3}`, the relative step of central first differences.
fn first_step() -> f64 {
    f64::EPSILON.cbrt()
}

/// The points `x − h`, `x + h` and their distance, for a central difference.
fn around(x: f64, h: f64) -> (f64, f64, f64) {
    let (minus, plus) = (x - h, x + h);
    (minus, plus, plus - minus)
}

/// The step for a coordinate or time `x`.
fn step(x: f64) -> f64 {
    first_step() * x.abs().max(1.0)
}

/// `Φ_t` by central differences in `t`.
pub(crate) fn phi_t<S: System + ?Sized>(sys: &S, t: f64, u: &[f64], phi_t: &mut [f64]) {
    let m = phi_t.len();
    let (tm, tp, width) = around(t, step(t));
    let mut minus = vec![0.0; m];
    sys.phi_into(tm, u, &mut minus);
    sys.phi_into(tp, u, phi_t);
    for (d, &a) in phi_t.iter_mut().zip(&minus) {
        *d = (*d - a) / width;
    }
}

/// Every pair `(j, k)` of coordinates that share a row of `B`, once.
pub(crate) fn row_cliques(b: &Pattern) -> Pattern {
    let mut rows: Vec<Vec<usize>> = vec![Vec::new(); b.nrows];
    for &(i, j) in &b.entries {
        rows[i].push(j);
    }
    let mut entries: Vec<(usize, usize)> = rows
        .iter()
        .flat_map(|cols| cols.iter().flat_map(|&j| cols.iter().map(move |&k| (j, k))))
        .collect();
    entries.sort_unstable();
    entries.dedup();
    Pattern::from_entries(b.ncols, b.ncols, entries)
}

/// The dense `n × n` pattern, or the empty one when `constant`.
pub(crate) fn dense_unless(constant: bool, n: usize) -> Pattern {
    if constant {
        Pattern::new(n, n)
    } else {
        Pattern::from_entries(
            n,
            n,
            (0..n).flat_map(|i| (0..n).map(move |j| (i, j))).collect(),
        )
    }
}

/// Fills `out` (values on `pattern`) with the Jacobian `∂w/∂x` of `w = f(x)`
/// (length `pattern.nrows`) by central differences, one column of the pattern
/// at a time. A repeated entry gets the value once and zero in its repeats
/// (repeated entries are summed).
fn jacobian_on(
    pattern: &Pattern,
    x: &[f64],
    mut f: impl FnMut(&[f64], &mut [f64]),
    out: &mut [f64],
) {
    if pattern.is_empty() {
        return;
    }
    let mut by_column: Vec<Vec<usize>> = vec![Vec::new(); pattern.ncols];
    for (e, &(_, j)) in pattern.entries.iter().enumerate() {
        by_column[j].push(e);
    }
    let (mut xp, mut w_minus, mut w_plus) = (
        x.to_vec(),
        vec![0.0; pattern.nrows],
        vec![0.0; pattern.nrows],
    );
    let mut written = vec![usize::MAX; pattern.nrows];
    out.fill(0.0);
    for (j, entries) in by_column.iter().enumerate() {
        if entries.is_empty() {
            continue;
        }
        let (minus, plus, width) = around(x[j], step(x[j]));
        xp[j] = minus;
        f(&xp, &mut w_minus);
        xp[j] = plus;
        f(&xp, &mut w_plus);
        xp[j] = x[j];
        for &e in entries {
            let i = pattern.entries[e].0;
            if written[i] != j {
                written[i] = j;
                out[e] = (w_plus[i] - w_minus[i]) / width;
            }
        }
    }
}

/// `Σᵢ μᵢ ∂²Φᵢ/∂u²`: differences of `Bᵀμ`.
pub(crate) fn hessian<S: System + ?Sized>(sys: &S, t: f64, u: &[f64], mu: &[f64], out: &mut [f64]) {
    if out.is_empty() {
        return;
    }
    let bp = sys.b_pattern();
    let mut b = vec![0.0; bp.len()];
    let bt_mu = |x: &[f64], w: &mut [f64]| {
        sys.b_into(t, x, &mut b);
        w.fill(0.0);
        bp.mul_transpose_add(&b, mu, w);
    };
    jacobian_on(&sys.hessian_pattern(), u, bt_mu, out);
}

/// `∂g/∂u`: differences of `g`.
pub(crate) fn forces_du<S: System + ?Sized>(
    sys: &S,
    t: f64,
    u: &[f64],
    v: &[f64],
    out: &mut [f64],
) {
    let g = |x: &[f64], w: &mut [f64]| sys.forces_into(t, x, v, w);
    jacobian_on(&sys.forces_du_pattern(), u, g, out);
}

/// `∂g/∂u̇`: differences of `g`.
pub(crate) fn forces_dv<S: System + ?Sized>(
    sys: &S,
    t: f64,
    u: &[f64],
    v: &[f64],
    out: &mut [f64],
) {
    let g = |x: &[f64], w: &mut [f64]| sys.forces_into(t, u, x, w);
    jacobian_on(&sys.forces_dv_pattern(), v, g, out);
}

/// `∂(M w)/∂u`: differences of `M(u) w`.
pub(crate) fn mass_du<S: System + ?Sized>(sys: &S, t: f64, u: &[f64], w: &[f64], out: &mut [f64]) {
    if out.is_empty() {
        return;
    }
    let mp = sys.mass_pattern();
    let mut mass = vec![0.0; mp.len()];
    let m_w = |x: &[f64], y: &mut [f64]| {
        sys.mass_into(t, x, &mut mass);
        y.fill(0.0);
        mp.mul_add(&mass, w, y);
    };
    jacobian_on(&sys.mass_du_pattern(), u, m_w, out);
}

/// `c = −(B u̇)_u u̇ − 2 B_t u̇ − Φ_tt`: the first term from differences of `B`
/// along `u̇`, the second from differences of `B` in time, `Φ_tt` from second
/// differences of `Φ` in time (the last two are exactly zero when `Φ` does not
/// depend on `t`: the perturbed evaluations are then identical).
pub(crate) fn accel_rhs<S: System + ?Sized>(sys: &S, t: f64, u: &[f64], v: &[f64], c: &mut [f64]) {
    let (bp, m) = (sys.b_pattern(), c.len());
    let mut b = vec![0.0; bp.len()];
    let mut b_v = |t: f64, x: &[f64], out: &mut [f64]| {
        sys.b_into(t, x, &mut b);
        out.fill(0.0);
        bp.mul_add(&b, v, out);
    };
    let (mut minus, mut plus) = (vec![0.0; m], vec![0.0; m]);
    // (B u̇)_u u̇ = d/ds B(u + s u̇, t) u̇, with s scaled so that s u̇ is a
    // relative step of u.
    let v_max = v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    c.fill(0.0);
    if v_max > 0.0 {
        let u_max = u.iter().fold(1.0f64, |a, x| a.max(x.abs()));
        let (sm, sp, width) = around(0.0, first_step() * u_max / v_max);
        let at = |s: f64| -> Vec<f64> { u.iter().zip(v).map(|(x, y)| x + s * y).collect() };
        b_v(t, &at(sm), &mut minus);
        b_v(t, &at(sp), &mut plus);
        for ((ci, p), q) in c.iter_mut().zip(&plus).zip(&minus) {
            *ci -= (p - q) / width;
        }
    }
    // 2 B_t u̇.
    let (tm, tp, width) = around(t, step(t));
    b_v(tm, u, &mut minus);
    b_v(tp, u, &mut plus);
    for ((ci, p), q) in c.iter_mut().zip(&plus).zip(&minus) {
        *ci -= 2.0 * (p - q) / width;
    }
    // Φ_tt, Richardson-extrapolated second differences.
    let h = f64::EPSILON.powf(1.0 / 6.0) * t.abs().max(1.0);
    let (coarse, fine) = (
        second_in_time(sys, t, u, h),
        second_in_time(sys, t, u, 0.5 * h),
    );
    for ((ci, f), k) in c.iter_mut().zip(&fine).zip(&coarse) {
        *ci -= (4.0 * f - k) / 3.0;
    }
}

/// `(Φ(t + h) − 2Φ(t) + Φ(t − h)) / h²` at fixed `u`, with the steps taken.
fn second_in_time<S: System + ?Sized>(sys: &S, t: f64, u: &[f64], h: f64) -> Vec<f64> {
    let m = sys.n_constraints();
    let (tm, tp) = (t - h, t + h);
    let (hm, hp) = (t - tm, tp - t);
    let (mut a, mut b, mut c) = (vec![0.0; m], vec![0.0; m], vec![0.0; m]);
    sys.phi_into(tm, u, &mut a);
    sys.phi_into(t, u, &mut b);
    sys.phi_into(tp, u, &mut c);
    // The three-point second difference on the (slightly) uneven grid.
    (0..m)
        .map(|i| 2.0 * ((c[i] - b[i]) / hp - (b[i] - a[i]) / hm) / (hp + hm))
        .collect()
}
