//! Jacobi's elliptic functions and the complete elliptic integral of the
//! first kind by the arithmetic-geometric mean (Abramowitz & Stegun,
//! *Handbook of Mathematical Functions*, 16.4 and 17.6; DLMF 22.20(ii)) —
//! the closed-form pendulum of IFToMM A01, written here so that the
//! reference shares no code with mstar.

/// The AGM sequences of A&S 16.4: `a_n`, `c_n` from `a₀ = 1`,
/// `b₀ = √(1 − m)`, `c₀ = √m`, until `c_N` is below round-off of `a_N`.
fn agm(m: f64) -> (Vec<f64>, Vec<f64>) {
    let (mut a, mut c) = (vec![1.0], vec![m.sqrt()]);
    let mut b = (1.0 - m).sqrt();
    // Quadratic convergence: a handful of means reach round-off.
    while c.len() < 40 && c[c.len() - 1].abs() > f64::EPSILON * a[a.len() - 1] {
        let an = a[a.len() - 1];
        c.push(0.5 * (an - b));
        a.push(0.5 * (an + b));
        b = (an * b).sqrt();
    }
    (a, c)
}

/// The complete elliptic integral of the first kind `K(m) = π / (2 a_N)`,
/// parameter `m = k²` in `[0, 1)` (A&S 17.6.1).
pub(super) fn complete_k(m: f64) -> f64 {
    let (a, _) = agm(m);
    std::f64::consts::FRAC_PI_2 / a[a.len() - 1]
}

/// `(sn, cn, dn)` of argument `u` and parameter `m = k²` in `[0, 1)` by
/// descending from `φ_N = 2ᴺ a_N u` with `φ_{n−1} = (φ_n + asin((c_n/a_n)
/// sin φ_n))/2`: `sn = sin φ₀`, `cn = cos φ₀` (A&S 16.4.3), and
/// `dn = √(1 − m sn²)` (positive for `m < 1`; A&S's `cos φ₀ / cos(φ₁ − φ₀)`
/// is 0/0 at `u = K`).
pub(super) fn jacobi(u: f64, m: f64) -> (f64, f64, f64) {
    let (a, c) = agm(m);
    let n = a.len() - 1;
    let mut phi = 2f64.powi(i32::try_from(n).unwrap_or(i32::MAX)) * a[n] * u;
    for i in (1..=n).rev() {
        phi = 0.5 * (phi + (c[i] / a[i] * phi.sin()).asin());
    }
    let sn = phi.sin();
    (sn, phi.cos(), (1.0 - m * sn * sn).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn at_m_zero_the_functions_are_sin_cos_and_one() {
        for u in [0.0, 0.3, 1.0, 2.5, -4.0, 100.0] {
            let (sn, cn, dn) = jacobi(u, 0.0);
            // One rounding of sin, cos of the same argument.
            assert!((sn - u.sin()).abs() <= 1e-15, "{u}: {sn}");
            assert!((cn - u.cos()).abs() <= 1e-15, "{u}: {cn}");
            assert_eq!(dn, 1.0);
        }
    }

    #[test]
    fn k_of_one_half_matches_the_table() {
        // A&S Table 17.1 (m = 0.5, 15 decimals): K = 1.854074677301372.
        assert!((complete_k(0.5) - 1.854_074_677_301_372).abs() <= 2e-15);
        assert!((complete_k(0.0) - std::f64::consts::FRAC_PI_2).abs() <= 1e-15);
    }

    #[test]
    fn the_identities_and_the_derivative_of_sn_hold() {
        let m = 0.5;
        let k = complete_k(m);
        let (sn, cn, dn) = jacobi(k, m);
        // sn(K) = 1, cn(K) = 0, dn(K) = √(1 − m) (A&S 16.5).
        assert!((sn - 1.0).abs() <= 1e-15 && cn.abs() <= 1e-15, "{sn} {cn}");
        assert!((dn - (1.0 - m).sqrt()).abs() <= 1e-15, "{dn}");
        let d = 1e-5;
        for u in [0.1, 0.7, 1.3, 2.9, -5.2, 40.0] {
            let (sn, cn, dn) = jacobi(u, m);
            assert!((sn * sn + cn * cn - 1.0).abs() <= 4e-16);
            // d sn/du = cn dn and d cn/du = −sn dn (A&S 16.16): the central
            // difference's error is d²/6 times the third derivative, e.g.
            // sn''' = cn dn (6m sn² − 1 − m), at most 1 + 7m = 4.5 (8e-11),
            // plus round-off ε / d (2e-11): within 1e-10.
            let (plus, minus) = (jacobi(u + d, m), jacobi(u - d, m));
            let slope = (plus.0 - minus.0) / (2.0 * d);
            assert!(
                (slope - cn * dn).abs() <= 1e-10,
                "{u}: {slope} vs {}",
                cn * dn
            );
            let slope = (plus.1 - minus.1) / (2.0 * d);
            assert!(
                (slope + sn * dn).abs() <= 1e-10,
                "{u}: {slope} vs {}",
                -sn * dn
            );
        }
    }
}
