//! Small, self-contained formulas with their textbook sources, for checking
//! three-dimensional rigid-body integrators against numbers that come from no
//! integrator at all:
//!
//! * [`elliptic_k`](crate::rigid::elliptic_k), the complete elliptic integral
//!   of the first kind by the arithmetic-geometric mean;
//! * [`torque_free_period`](crate::rigid::torque_free_period), the period of
//!   the body-frame angular velocity of a torque-free asymmetric body (Euler's
//!   equations solved in Jacobi elliptic functions), and with it the interval
//!   between the flips of the Dzhanibekov (tennis-racket) effect;
//!   [`torque_free_omega_rk4`](crate::rigid::torque_free_omega_rk4) is a plain
//!   RK4 of Euler's equations used to cross-check it;
//! * [`top_steady_precession`](crate::rigid::top_steady_precession) and
//!   [`top_nutation_frequency`](crate::rigid::top_nutation_frequency), the two
//!   steady precession rates of a heavy symmetric top with a fixed tip and the
//!   frequency of small nutation about a steady precession.
//!
//! Angles are in radians, rates in rad/s, SI units throughout.

use std::f64::consts::PI;

/// The complete elliptic integral of the first kind,
///
/// ```text
/// K(m) = ∫₀^{π/2} dθ / √(1 − m sin²θ),
/// ```
///
/// with the *parameter* `m = k²` (`k` the modulus), from the
/// arithmetic-geometric mean:
///
/// ```text
/// K(m) = π / (2 AGM(1, √(1 − m)))
/// ```
///
/// (Abramowitz & Stegun, *Handbook of Mathematical Functions* (1964), §17.6,
/// "Arithmetic-geometric mean"; values checked against their Table 17.1).
/// The iteration converges quadratically, to a few ulps.
///
/// Defined for `m < 1` (negative `m` included); `K(1) = +∞`, and `m > 1` or
/// NaN give NaN.
#[must_use]
pub fn elliptic_k(m: f64) -> f64 {
    elliptic_k_complementary(1.0 - m)
}

/// `K` as a function of the complementary parameter `m₁ = 1 − m`, accurate
/// also where `m` is within rounding of 1 (near a separatrix `m₁` is computed
/// directly, not as `1 − m`).
fn elliptic_k_complementary(m1: f64) -> f64 {
    if m1.is_nan() || m1 < 0.0 {
        return f64::NAN;
    }
    if m1 == 0.0 {
        return f64::INFINITY;
    }
    if m1.is_infinite() {
        return 0.0;
    }
    let (mut a, mut b) = (1.0f64, m1.sqrt());
    // Quadratic convergence: even from b = 1e-150 some 15 iterations suffice.
    for _ in 0..64 {
        if (a - b).abs() <= 4.0 * f64::EPSILON * a {
            break;
        }
        (a, b) = (0.5 * (a + b), (a * b).sqrt());
    }
    PI / (a + b)
}

/// Principal moments sorted ascending, with the rate components permuted
/// alike.
fn sorted_axes(inertia: [f64; 3], omega: [f64; 3]) -> ([f64; 3], [f64; 3]) {
    let mut idx = [0usize, 1, 2];
    idx.sort_by(|&i, &j| inertia[i].total_cmp(&inertia[j]));
    (idx.map(|k| inertia[k]), idx.map(|k| omega[k]))
}

/// The period of the body-frame angular velocity `ω(t)` of a torque-free
/// rigid body (the polhode period), from Euler's equations
///
/// ```text
/// I₁ ω̇₁ = (I₂ − I₃) ω₂ ω₃,   I₂ ω̇₂ = (I₃ − I₁) ω₃ ω₁,   I₃ ω̇₃ = (I₁ − I₂) ω₁ ω₂
/// ```
///
/// solved in Jacobi elliptic functions: Landau & Lifshitz, *Mechanics*
/// (Course of Theoretical Physics vol. 1, 3rd ed.), §37 "The asymmetrical
/// top" (the solution `Ω₁ ∝ cn τ, Ω₂ ∝ sn τ, Ω₃ ∝ dn τ` with its `τ`, `k²` and
/// period `T`).
///
/// `inertia` are the principal moments (any order: the axes are sorted so
/// that `I₁ ≤ I₂ ≤ I₃`, the period being independent of the labels) and
/// `omega_body` the body-frame components of `ω` at any instant. With
/// `2E = Σ Iᵢ ωᵢ²` and `L² = Σ Iᵢ² ωᵢ²`:
///
/// * `L² > 2E I₂` (`ω` circulates about the axis of largest moment `I₃`):
///
///   ```text
///   τ = λ t,  λ² = (I₃ − I₂)(L² − 2E I₁) / (I₁ I₂ I₃),
///   k² = (I₂ − I₁)(2E I₃ − L²) / ((I₃ − I₂)(L² − 2E I₁)),
///   ω₁ ∝ cn τ,  ω₂ ∝ sn τ,  ω₃ ∝ dn τ;
///   ```
///
/// * `L² < 2E I₂` (`ω` circulates about the axis of smallest moment `I₁`):
///   the same with the roles of `I₁` and `I₃` exchanged,
///
///   ```text
///   λ² = (I₂ − I₁)(2E I₃ − L²) / (I₁ I₂ I₃),
///   k² = (I₃ − I₂)(L² − 2E I₁) / ((I₂ − I₁)(2E I₃ − L²)),
///   ω₃ ∝ cn τ,  ω₂ ∝ sn τ,  ω₁ ∝ dn τ.
///   ```
///
/// `sn` and `cn` have period `4K(k²)` in `τ` (`dn` has `2K`), so `ω` has
///
/// ```text
/// T = 4 K(k²) / λ.
/// ```
///
/// **Dzhanibekov / tennis-racket flip.** In both cases `ω₂ ∝ sn τ` changes
/// sign every `2K/λ`: for a spin near the intermediate axis (`k² → 1`, long
/// quiet phases between quick reversals) the **flip interval = period / 2**,
/// the time between successive sign changes of the intermediate component
/// `ω₂`.
///
/// Numerics: the differences of the invariants are formed as sums of
/// non-negative terms, `L² − 2E I₁ = I₂(I₂−I₁)ω₂² + I₃(I₃−I₁)ω₃²`,
/// `2E I₃ − L² = I₁(I₃−I₁)ω₁² + I₂(I₃−I₂)ω₂²`, and the complementary
/// parameter directly as `1 − k² = (I₃ − I₁)(L² − 2E I₂) / ((I₃ − I₂)(L² −
/// 2E I₁))` (resp. with `2E I₂ − L²` and `(I₂ − I₁)(2E I₃ − L²)`), with
/// `L² − 2E I₂ = I₃(I₃−I₂)ω₃² − I₁(I₂−I₁)ω₁²`, so the result stays accurate
/// arbitrarily close to the separatrix.
///
/// Returns `+∞` on the separatrix `L² = 2E I₂` (including pure rotation
/// about the intermediate axis and `ω = 0`) and NaN if a moment is not
/// positive and finite. A pure spin about the largest or smallest axis gives
/// the period of the infinitesimal wobble about it, `2π/λ`.
#[must_use]
pub fn torque_free_period(inertia: [f64; 3], omega_body: [f64; 3]) -> f64 {
    let ([i1, i2, i3], [w1, w2, w3]) = sorted_axes(inertia, omega_body);
    if !(i1 > 0.0 && i3.is_finite()) {
        return f64::NAN;
    }
    let (w1s, w2s, w3s) = (w1 * w1, w2 * w2, w3 * w3);
    // L² − 2E I₁ ≥ 0, 2E I₃ − L² ≥ 0, and the case selector L² − 2E I₂.
    let l2_minus_e1 = i2 * (i2 - i1) * w2s + i3 * (i3 - i1) * w3s;
    let e3_minus_l2 = i1 * (i3 - i1) * w1s + i2 * (i3 - i2) * w2s;
    let l2_minus_e2 = i3 * (i3 - i2) * w3s - i1 * (i2 - i1) * w1s;
    let product = i1 * i2 * i3;
    let (lambda_sq, m1) = if l2_minus_e2 > 0.0 {
        (
            (i3 - i2) * l2_minus_e1 / product,
            (i3 - i1) * l2_minus_e2 / ((i3 - i2) * l2_minus_e1),
        )
    } else if l2_minus_e2 < 0.0 {
        (
            (i2 - i1) * e3_minus_l2 / product,
            (i3 - i1) * -l2_minus_e2 / ((i2 - i1) * e3_minus_l2),
        )
    } else if l2_minus_e2 == 0.0 {
        return f64::INFINITY;
    } else {
        return f64::NAN;
    };
    4.0 * elliptic_k_complementary(m1) / lambda_sq.sqrt()
}

/// Right-hand side of the torque-free Euler equations, `ω̇ = f(ω)`.
fn euler_rhs(inertia: [f64; 3], w: &[f64; 3]) -> [f64; 3] {
    let [i1, i2, i3] = inertia;
    [
        (i2 - i3) * w[1] * w[2] / i1,
        (i3 - i1) * w[2] * w[0] / i2,
        (i1 - i2) * w[0] * w[1] / i3,
    ]
}

/// One classical RK4 step of `ẏ = f(y)`.
fn rk4_step<const N: usize>(f: &impl Fn(&[f64; N]) -> [f64; N], y: &[f64; N], h: f64) -> [f64; N] {
    let shift = |k: &[f64; N], c: f64| -> [f64; N] { std::array::from_fn(|i| y[i] + c * k[i]) };
    let k1 = f(y);
    let k2 = f(&shift(&k1, 0.5 * h));
    let k3 = f(&shift(&k2, 0.5 * h));
    let k4 = f(&shift(&k3, h));
    std::array::from_fn(|i| y[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]))
}

/// The body-frame angular velocity at `t_end` of a torque-free body with
/// principal moments `inertia` started at `omega0`, by classical RK4 on
/// Euler's equations (see [`torque_free_period`]) with `⌈t_end/h⌉` equal
/// steps of at most `h`.
///
/// An integrator independent of the closed forms, for the tests that check
/// them (global error `O(h⁴)`).
///
/// # Panics
/// If `h` is not positive or `t_end` is negative or not finite.
#[must_use]
pub fn torque_free_omega_rk4(inertia: [f64; 3], omega0: [f64; 3], t_end: f64, h: f64) -> [f64; 3] {
    assert!(h > 0.0, "step must be positive (got {h})");
    assert!(
        t_end >= 0.0 && t_end.is_finite(),
        "t_end must be finite and non-negative (got {t_end})"
    );
    let steps = (t_end / h).ceil() as usize;
    if steps == 0 {
        return omega0;
    }
    let step = t_end / steps as f64;
    let f = |w: &[f64; 3]| euler_rhs(inertia, w);
    let mut w = omega0;
    for _ in 0..steps {
        w = rk4_step(&f, &w, step);
    }
    w
}

/// Steady-precession and nutation rates of a heavy symmetric top, rad/s
/// ([`top_slow_rates`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TopRates {
    /// Steady precession rate `φ̇₀` of the symmetry axis about the vertical.
    pub precession: f64,
    /// Angular frequency of small nutation (oscillation of the tilt `θ`)
    /// about that steady precession.
    pub nutation: f64,
}

/// The two steady-precession rates `(slow, fast)` of a heavy symmetric top
/// with a fixed tip at the tilt `theta0` (angle between the symmetry axis and
/// the upward vertical).
///
/// `m` mass, `g` gravity, `l` distance tip → centre of mass along the axis,
/// `a` transverse moment of inertia **about the tip** (`A = A_cm + m l²`),
/// `c` axial moment, `spin_total_omega3` the total angular-velocity
/// component along the symmetry axis `ω₃ = ψ̇ + φ̇ cos θ` (conserved:
/// `p_ψ = C ω₃`). With the Lagrangian
///
/// ```text
/// L = ½A(θ̇² + φ̇² sin²θ) + ½C(ψ̇ + φ̇ cos θ)² − m g l cos θ
/// ```
///
/// uniform precession without nutation (`θ̇ = θ̈ = 0`, `θ₀ ≠ 0, π`) requires
///
/// ```text
/// A cos θ₀ φ̇² − C ω₃ φ̇ + m g l = 0,
/// φ̇ = (C ω₃ ∓ √(C²ω₃² − 4 A m g l cos θ₀)) / (2 A cos θ₀)
/// ```
///
/// (Goldstein, Poole & Safko, *Classical Mechanics*, 3rd ed. (2002), §5.7
/// "The heavy symmetrical top with one point fixed", the condition for
/// uniform precession `β/2 = φ̇(a − φ̇ cos θ₀)` in Goldstein's notation
/// `a = I₃ω₃/I₁`, `β = 2Mgl/I₁`, here `I₁ = A`, `I₃ = C`, `M = m`).
///
/// `slow` is the root that tends to `m g l / (C ω₃)` for a fast top
/// (`C²ω₃² ≫ 4 A m g l |cos θ₀|`), `fast` the one that tends to
/// `C ω₃ / (A cos θ₀)`; they are computed without cancellation,
/// `q = ½(Cω₃ + sgn(Cω₃)√D)`, `slow = m g l / q`, `fast = q / (A cos θ₀)`,
/// so `slow` is finite also at `θ₀ = π/2` (where `fast` is infinite). Below
/// the horizontal (`cos θ₀ < 0`) the two roots have opposite signs.
///
/// Both are NaN where no steady precession exists (`D < 0`: the spin is too
/// slow for that tilt).
#[must_use]
pub fn top_steady_precession(
    m: f64,
    g: f64,
    l: f64,
    a: f64,
    c: f64,
    spin_total_omega3: f64,
    theta0: f64,
) -> (f64, f64) {
    let mgl = m * g * l;
    let p = c * spin_total_omega3;
    let a_cos = a * theta0.cos();
    let disc = p * p - 4.0 * a_cos * mgl;
    if disc.is_nan() || disc < 0.0 {
        return (f64::NAN, f64::NAN);
    }
    let q = 0.5 * (p + disc.sqrt().copysign(if p < 0.0 { -1.0 } else { 1.0 }));
    (mgl / q, q / a_cos)
}

/// The angular frequency of small nutation of a heavy symmetric top about
/// the steady precession `precession` (`φ̇₀`, a root from
/// [`top_steady_precession`]) at the tilt `theta0`:
///
/// ```text
/// Ω² = (C ω₃ / A − 2 φ̇₀ cos θ₀)² + φ̇₀² sin² θ₀.
/// ```
///
/// Parameters as for [`top_steady_precession`] (`a` about the tip, `omega3`
/// the total axial spin `ψ̇ + φ̇ cos θ`).
///
/// **Derivation.** In the Lagrangian `L = ½A(θ̇² + φ̇² sin²θ) + ½C(ψ̇ + φ̇ cos
/// θ)² − m g l cos θ` the angles `φ` and `ψ` are cyclic, with conserved
/// momenta `p_ψ = C ω₃` and `p_φ = A φ̇ sin²θ + p_ψ cos θ` (Goldstein,
/// Poole & Safko, *Classical Mechanics*, 3rd ed., §5.7), so along a motion
///
/// ```text
/// φ̇(θ) = (p_φ − p_ψ cos θ) / (A sin²θ),   sin θ dφ̇/dθ = p_ψ/A − 2 φ̇ cos θ.
/// ```
///
/// The `θ` Lagrange equation, with `φ̇ = φ̇(θ)` (the 1-D effective-potential
/// equation), is
///
/// ```text
/// A θ̈ = F(θ) := A φ̇² sin θ cos θ − p_ψ φ̇ sin θ + m g l sin θ,
/// ```
///
/// and `F(θ₀) = 0` is the steady-precession condition `A cos θ₀ φ̇₀² − p_ψ φ̇₀
/// + m g l = 0`. Linearizing with `p_φ`, `p_ψ` held at their values on the
/// steady motion (`θ = θ₀ + η`, `A η̈ = F'(θ₀) η`, `Ω² = −F'(θ₀)/A`) and
/// using `sin θ dφ̇/dθ` from above,
///
/// ```text
/// F'(θ₀) = 3 p_ψ φ̇₀ cos θ₀ − 3A φ̇₀² cos²θ₀ − A φ̇₀² sin²θ₀ − p_ψ²/A + m g l cos θ₀;
/// ```
///
/// eliminating `m g l cos θ₀ = p_ψ φ̇₀ cos θ₀ − A φ̇₀² cos²θ₀` (the steady
/// condition times `cos θ₀`) leaves
/// `−F'(θ₀)/A = (p_ψ/A − 2 φ̇₀ cos θ₀)² + φ̇₀² sin²θ₀`, the formula above. It is
/// the same as H. Lamb's `σ² = {(μ − ν cos α)² + 2(μ − ν cos α)(μ cos α −
/// ν) cos α + (μ cos α − ν)²} / (A² sin⁴α)` with `μ = p_φ`, `ν = p_ψ`,
/// `α = θ₀` (Encyclopaedia Britannica, 11th ed. (1911), article
/// "Mechanics", §20, eqs. (8)-(9)).
///
/// Limits: the fast top (`C ω₃` large, slow precession `φ̇₀ ≈ m g l/(C ω₃)`)
/// nutates at `Ω ≈ C ω₃ / A` (Goldstein §5.7, fast top); the spherical
/// pendulum (`C = 0`) at `Ω = |φ̇₀| √(1 + 3 cos²θ₀)`; the sleeping top
/// (`θ₀ → 0`, slow root) at `Ω → √(C²ω₃² − 4 A m g l) / A`.
///
/// `m`, `g`, `l` enter only through the steady condition: NaN is returned
/// unless `precession` satisfies it to a relative `1e-8` of its terms'
/// magnitudes (a rate that is not a steady precession has no nutation about
/// it).
#[must_use]
#[expect(
    clippy::too_many_arguments,
    reason = "the physical parameters of the top, in the order of top_steady_precession"
)]
pub fn top_nutation_frequency(
    m: f64,
    g: f64,
    l: f64,
    a: f64,
    c: f64,
    omega3: f64,
    theta0: f64,
    precession: f64,
) -> f64 {
    let mgl = m * g * l;
    let p = c * omega3;
    let (s, co) = theta0.sin_cos();
    let terms = [a * co * precession * precession, -p * precession, mgl];
    let residual: f64 = terms.iter().sum();
    let scale: f64 = terms.iter().map(|t| t.abs()).sum();
    if residual.is_nan() || residual.abs() > 1e-8 * scale {
        return f64::NAN;
    }
    let axial = p / a - 2.0 * precession * co;
    (axial * axial + (precession * s).powi(2)).sqrt()
}

/// The slow steady precession at `theta0` ([`top_steady_precession`]) and
/// the nutation frequency about it ([`top_nutation_frequency`]); NaN where no
/// steady precession exists.
#[must_use]
pub fn top_slow_rates(
    m: f64,
    g: f64,
    l: f64,
    a: f64,
    c: f64,
    omega3: f64,
    theta0: f64,
) -> TopRates {
    let (slow, _) = top_steady_precession(m, g, l, a, c, omega3, theta0);
    TopRates {
        precession: slow,
        nutation: top_nutation_frequency(m, g, l, a, c, omega3, theta0, slow),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `y(t₀ + s)` on `[0, h]` from the cubic Hermite interpolant of values
    /// and derivatives at the step's ends (error `O(h⁴)`, RK4's order).
    fn hermite(h: f64, y0: f64, d0: f64, y1: f64, d1: f64, s: f64) -> f64 {
        let x = s / h;
        let (x2, x3) = (x * x, x * x * x);
        (2.0 * x3 - 3.0 * x2 + 1.0) * y0
            + (x3 - 2.0 * x2 + x) * h * d0
            + (-2.0 * x3 + 3.0 * x2) * y1
            + (x3 - x2) * h * d1
    }

    /// The root in `[0, h]` of the Hermite cubic through a sign change
    /// (bisection to round-off).
    fn hermite_root(h: f64, y0: f64, d0: f64, y1: f64, d1: f64) -> f64 {
        let (mut lo, mut hi) = (0.0, h);
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            if (hermite(h, y0, d0, y1, d1, mid) > 0.0) == (y0 > 0.0) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    }

    /// RK4 of `ẏ = f(y)` from `y0` for `steps` steps of `h`, returning the
    /// times at which component `k` changes sign (the zero crossings of the
    /// Hermite interpolant built from `y_k` and `f(y)_k`).
    fn sign_changes<const N: usize>(
        f: impl Fn(&[f64; N]) -> [f64; N],
        y0: [f64; N],
        k: usize,
        h: f64,
        steps: usize,
    ) -> Vec<f64> {
        let mut y = y0;
        let mut d = f(&y);
        let mut out = Vec::new();
        for n in 0..steps {
            let y1 = rk4_step(&f, &y, h);
            let d1 = f(&y1);
            if (y[k] > 0.0) != (y1[k] > 0.0) {
                out.push(n as f64 * h + hermite_root(h, y[k], d[k], y1[k], d1[k]));
            }
            (y, d) = (y1, d1);
        }
        out
    }

    /// `L² − 2E I₂` for sorted moments, the case selector.
    fn l2_minus_2e_i2(i: [f64; 3], w: [f64; 3]) -> f64 {
        let two_e: f64 = (0..3).map(|k| i[k] * w[k] * w[k]).sum();
        let l2: f64 = (0..3).map(|k| (i[k] * w[k]).powi(2)).sum();
        l2 - two_e * i[1]
    }

    #[test]
    fn rigid_elliptic_k_matches_abramowitz_stegun_table_17_1() {
        // A&S Table 17.1 (K against the modular angle α, m = sin²α):
        // K(0) = π/2, K(0.5) (α = 45°), K(0.9). The AGM is accurate to a few
        // ulps; 4e-15 is ~9 ulps of K ≈ 2.6, while squaring the argument
        // (modulus/parameter confusion: K(0.25) = 1.6858 for m = 0.5) would
        // be off by 0.17.
        let table = [
            (0.0, std::f64::consts::FRAC_PI_2),
            (0.5, 1.854_074_677_301_372),
            (0.9, 2.578_092_113_348_173),
        ];
        for (m, k) in table {
            let got = elliptic_k(m);
            assert!((got - k).abs() <= 4e-15, "K({m}) = {got}, table {k}");
        }
        assert!(elliptic_k(1.0).is_infinite() && elliptic_k(1.0) > 0.0);
        assert!(elliptic_k(1.5).is_nan());
        assert!(elliptic_k(f64::NAN).is_nan());
    }

    #[test]
    fn rigid_elliptic_k_matches_quadrature() {
        // Independent of the AGM: K(m) = ½ ∫₀^π dθ/√(1 − m sin²θ) by the
        // trapezoid rule on a whole period of an analytic periodic integrand,
        // whose error is ~exp(−2 d N) with d the distance of the nearest
        // singularity from the real axis: acosh(1/√m) ≈ √(1 − m) ≥ 1e-3 for
        // 0 < m < 1, asinh(1/√−m) ≥ 0.48 for m < 0. With N = 2e5 points that
        // is below round-off; tolerance 1e-12 relative covers the summation
        // round-off of 2e5 terms, far below the effect of any formula slip.
        let n = 200_000;
        for m in [-4.0, -0.5, 0.1, 0.3, 0.7, 0.99, 0.999_999] {
            let sum: f64 = (0..n)
                .map(|j| {
                    let s = (PI * j as f64 / n as f64).sin();
                    1.0 / (1.0 - m * s * s).sqrt()
                })
                .sum();
            let quad = 0.5 * PI * sum / n as f64;
            let got = elliptic_k(m);
            assert!(
                (got - quad).abs() <= 1e-12 * quad,
                "K({m}) = {got}, quadrature {quad}"
            );
        }
    }

    /// The worst relative deviation from `T/2` of the intervals between
    /// successive sign changes of `ω₂` (flips) in an RK4 run of `periods`
    /// closed-form periods `T` with step `h`, and the number of flips.
    fn flip_interval_error(
        inertia: [f64; 3],
        omega0: [f64; 3],
        periods: f64,
        h: f64,
    ) -> (f64, usize) {
        let period = torque_free_period(inertia, omega0);
        assert!(period.is_finite() && period > 0.0, "period {period}");
        let steps = (periods * period / h).ceil() as usize;
        let flips = sign_changes(|w| euler_rhs(inertia, w), omega0, 1, h, steps);
        // One flip per half period; the last may fall just past the end.
        assert!(
            flips.len() as f64 >= 2.0 * periods - 1.0,
            "{} flips in {periods} periods",
            flips.len()
        );
        let half = 0.5 * period;
        // Written so that a NaN interval yields NaN (and fails the callers).
        let worst = flips
            .windows(2)
            .map(|p| ((p[1] - p[0]) - half).abs() / half)
            .fold(0.0f64, |acc, e| if e.is_nan() || e > acc { e } else { acc });
        eprintln!(
            "I = {inertia:?}, ω₀ = {omega0:?}, h = {h}: T = {period}, {} flips, \
             worst |Δt − T/2|/(T/2) = {worst:e}",
            flips.len()
        );
        (worst, flips.len())
    }

    /// Flip intervals at the step of the tests, `h = 1e-3` s, must equal the
    /// closed-form `T/2` to `1e-8` relative.
    ///
    /// Why `1e-8`: RK4's truncation error is `O(h⁴)`. Measured on these
    /// cases at coarse steps (see `..._away_from_the_separatrix`, which
    /// asserts the ratio 16 per halving) the relative error of a half period
    /// is ≈ `0.016 (h/1 s)⁴`, i.e. ~2e-14 at `h = 1e-3`; the crossings are
    /// located by a cubic Hermite interpolant, `O(h⁴)` as well. What remains
    /// is round-off: near the separatrix (`1 − k² ~ 1e-6`) the period depends
    /// on `L² − 2E I₂ ~ 1e-5`, a small difference of the invariants, whose
    /// round-off walk over ~1e5 steps gives the observed ~3e-10 to 5e-10.
    /// `1e-8` keeps a 20× margin over that floor, while a slip such as `2K`
    /// for `4K`, or the other case's formula, is off by tens of percent or
    /// NaN.
    fn check_flip_intervals(inertia: [f64; 3], omega0: [f64; 3], periods: f64) -> usize {
        let (worst, flips) = flip_interval_error(inertia, omega0, periods, 1e-3);
        assert!(worst <= 1e-8, "worst flip-interval error {worst:e}");
        flips
    }

    #[test]
    fn rigid_torque_free_period_near_intermediate_axis_l2_above_2e_i2() {
        // Dzhanibekov's nut: spin about the intermediate axis with a small
        // disturbance; here L² − 2E I₂ = (3ω₃² − ω₁²)·s² > 0.
        let inertia = [1.0, 2.0, 3.0];
        let s = 2.0;
        let omega0 = [1e-3 * s, s, 1e-3 * s];
        assert!(l2_minus_2e_i2(inertia, omega0) > 0.0);
        let flips = check_flip_intervals(inertia, omega0, 4.0);
        assert!(flips >= 7);
    }

    #[test]
    fn rigid_torque_free_period_near_intermediate_axis_l2_below_2e_i2() {
        // Other side of the separatrix: L² − 2E I₂ = (3ω₃² − ω₁²)·s² < 0.
        let inertia = [1.0, 2.0, 3.0];
        let s = 2.0;
        let omega0 = [2e-3 * s, s, 1e-3 * s];
        assert!(l2_minus_2e_i2(inertia, omega0) < 0.0);
        let flips = check_flip_intervals(inertia, omega0, 4.0);
        assert!(flips >= 7);
    }

    #[test]
    fn rigid_torque_free_period_away_from_the_separatrix() {
        // Generic tumbling on both sides of the separatrix; then the same
        // body with its axes given in another order (the period does not
        // depend on the labels).
        check_flip_intervals([1.0, 2.0, 3.0], [0.3, 0.4, 1.0], 6.0);
        check_flip_intervals([1.0, 2.0, 3.0], [1.0, 0.5, 0.2], 6.0);
        check_flip_intervals([0.4, 1.7, 2.1], [0.7, -0.9, 0.35], 6.0);
        // RK4's order shows at coarse steps: halving h divides the error by
        // 2⁴ = 16 (measured 16.0 and 16.1; accepted 12-20, i.e. order
        // 3.6-4.3; a first-order slip in the stepper would give ~2).
        for w0 in [[0.3, 0.4, 1.0], [0.002, 2.0, 0.002]] {
            let (coarse, _) = flip_interval_error([1.0, 2.0, 3.0], w0, 4.0, 4e-2);
            let (fine, _) = flip_interval_error([1.0, 2.0, 3.0], w0, 4.0, 2e-2);
            let ratio = coarse / fine;
            assert!(
                (12.0..=20.0).contains(&ratio),
                "error ratio {ratio} for ω₀ = {w0:?}"
            );
        }
        let a = torque_free_period([1.0, 2.0, 3.0], [0.3, 0.4, 1.0]);
        let b = torque_free_period([2.0, 3.0, 1.0], [0.4, 1.0, 0.3]);
        assert!((a - b).abs() <= 1e-14 * a, "{a} vs {b}");
    }

    #[test]
    fn rigid_torque_free_half_and_full_period_by_the_public_rk4() {
        // After T/2, sn and cn change sign and dn does not: for L² > 2E I₂
        // ω(T/2) = (−ω₁, −ω₂, ω₃), for L² < 2E I₂ ω(T/2) = (ω₁, −ω₂, −ω₃);
        // after T, ω(T) = ω₀. Step 1e-3 s with O(1) rates over t ≲ 11 s,
        // away from the separatrix: RK4's truncation error is ~(ωh)⁴ ω t ≈
        // 1e-11 at most and round-off ~1e-14 (observed ≤ 3e-14). Tolerance
        // 1e-10 rad/s; an error δ in T moves ω(T) by |ω̇| δ ≈ δ, so the
        // check resolves period errors down to ~1e-10 s.
        let h = 1e-3;
        let cases = [
            ([1.0, 2.0, 3.0], [0.3, 0.4, 1.0], [-1.0, -1.0, 1.0]),
            ([1.0, 2.0, 3.0], [1.0, 0.5, 0.2], [1.0, -1.0, -1.0]),
        ];
        for (inertia, w0, sign) in cases {
            let side = l2_minus_2e_i2(inertia, w0);
            assert!(
                (side > 0.0) == (sign[2] > 0.0),
                "case selector {side} for {w0:?}"
            );
            let period = torque_free_period(inertia, w0);
            let half = torque_free_omega_rk4(inertia, w0, 0.5 * period, h);
            let full = torque_free_omega_rk4(inertia, w0, period, h);
            eprintln!("ω₀ = {w0:?}: ω(T/2) = {half:?}, ω(T) = {full:?}");
            for k in 0..3 {
                assert!(
                    (half[k] - sign[k] * w0[k]).abs() <= 1e-10,
                    "ω(T/2) = {half:?} from {w0:?}"
                );
                assert!(
                    (full[k] - w0[k]).abs() <= 1e-10,
                    "ω(T) = {full:?} from {w0:?}"
                );
            }
        }
        // Degenerate inputs.
        assert!(torque_free_period([1.0, 2.0, 3.0], [0.0, 1.0, 0.0]).is_infinite());
        assert!(torque_free_period([0.0, 2.0, 3.0], [0.1, 1.0, 0.0]).is_nan());
        // Symmetric body: the body cone's rate (I₃ − I₁)ω₃/I₁.
        let sym = torque_free_period([1.0, 1.0, 3.0], [0.2, 0.1, 1.5]);
        let expect = 2.0 * PI / (2.0 * 1.5);
        assert!((sym - expect).abs() <= 1e-14 * expect, "{sym} vs {expect}");
    }

    /// A top: mass 1 kg, centre of mass 5 cm from the tip, A_cm = 2e-3,
    /// C = 3e-3 kg m² (A about the tip = A_cm + m l²).
    const M: f64 = 1.0;
    const G: f64 = 9.81;
    const L: f64 = 0.05;
    const C: f64 = 3e-3;
    const A: f64 = 2e-3 + M * L * L;

    #[test]
    fn rigid_top_steady_precession_roots_and_fast_top_limits() {
        let theta0 = 0.5;
        let w3 = 50.0;
        let (slow, fast) = top_steady_precession(M, G, L, A, C, w3, theta0);
        // Vieta: both roots of A cos θ₀ x² − C ω₃ x + m g l (relative 1e-14).
        let ac = A * theta0.cos();
        assert!((slow + fast - C * w3 / ac).abs() <= 1e-14 * fast);
        assert!((slow * fast - M * G * L / ac).abs() <= 1e-14 * slow * fast);
        assert!(slow > 0.0 && fast > slow);
        // Fast top: with ε = 4 A m g l cos θ₀ / (C ω₃)² the exact slow root is
        // (m g l / C ω₃)·2/(1 + √(1 − ε)) = (m g l / C ω₃)(1 + ε/4 + ε²/8 + …)
        // and the nutation Ω = (C ω₃/A)(1 − ε/2 + O(ε²)) (the O(ε²)
        // coefficient is 1/8 + tan²θ₀/32 + … < 1 at θ₀ = 0.5). The checks
        // with remainder ε² fail if either leading correction is wrong, and
        // ε shrinks ×100 over the spins used.
        for w3 in [60.0, 200.0, 1000.0] {
            let eps = 4.0 * A * M * G * L * theta0.cos() / (C * w3).powi(2);
            assert!(eps < 0.5, "ε = {eps}");
            let rates = top_slow_rates(M, G, L, A, C, w3, theta0);
            let prec_ratio = rates.precession / (M * G * L / (C * w3));
            let nut_ratio = rates.nutation / (C * w3 / A);
            assert!(
                (prec_ratio - (1.0 + 0.25 * eps)).abs() <= eps * eps,
                "ω₃ = {w3}: precession ratio {prec_ratio}, ε = {eps}"
            );
            assert!(
                (nut_ratio - (1.0 - 0.5 * eps)).abs() <= eps * eps,
                "ω₃ = {w3}: nutation ratio {nut_ratio}, ε = {eps}"
            );
        }
        // Too slow a spin: no steady precession.
        let (s, f) = top_steady_precession(M, G, L, A, C, 1.0, theta0);
        assert!(s.is_nan() && f.is_nan());
        // Horizontal axis: only the slow root is finite, m g l/(C ω₃).
        let (s, _) = top_steady_precession(M, G, L, A, C, w3, std::f64::consts::FRAC_PI_2);
        assert!((s - M * G * L / (C * w3)).abs() <= 1e-14 * s);
    }

    #[test]
    fn rigid_top_nutation_special_cases() {
        // Spherical pendulum (C = 0) hanging at θ₀ > π/2: conical rate
        // φ̇² = m g l/(A |cos θ₀|), small oscillation Ω = φ̇ √(1 + 3 cos²θ₀).
        let theta0 = 2.5;
        let (slow, fast) = top_steady_precession(M, G, L, A, 0.0, 0.0, theta0);
        let conical = (M * G * L / (A * theta0.cos().abs())).sqrt();
        assert!((slow - conical).abs() <= 1e-14 * conical);
        assert!((fast + conical).abs() <= 1e-14 * conical);
        let nut = top_nutation_frequency(M, G, L, A, 0.0, 0.0, theta0, slow);
        let expect = conical * (1.0 + 3.0 * theta0.cos().powi(2)).sqrt();
        assert!((nut - expect).abs() <= 1e-14 * expect, "{nut} vs {expect}");
        // Lamb's form with μ = p_φ, ν = p_ψ, at both roots of a spinning top.
        let (theta0, w3) = (0.7, 40.0);
        let (slow, fast) = top_steady_precession(M, G, L, A, C, w3, theta0);
        for prec in [slow, fast] {
            let (s, co) = theta0.sin_cos();
            let nu = C * w3;
            let mu = A * prec * s * s + nu * co;
            let (x, y) = (mu - nu * co, mu * co - nu);
            let lamb = ((x * x + 2.0 * x * y * co + y * y) / (A * A * s.powi(4))).sqrt();
            let ours = top_nutation_frequency(M, G, L, A, C, w3, theta0, prec);
            assert!((ours - lamb).abs() <= 1e-12 * lamb, "{ours} vs {lamb}");
        }
        // Sleeping-top limit θ₀ → 0 (slow root): √(C²ω₃² − 4 A m g l)/A, to
        // O(θ₀²) = 1e-8.
        let theta0 = 1e-4;
        let rates = top_slow_rates(M, G, L, A, C, w3, theta0);
        let sleeping = ((C * w3).powi(2) - 4.0 * A * M * G * L).sqrt() / A;
        assert!((rates.nutation - sleeping).abs() <= 1e-7 * sleeping);
        // Not a steady precession: NaN.
        assert!(top_nutation_frequency(M, G, L, A, C, w3, 0.7, 1.01 * slow).is_nan());
    }

    /// Euler-angle equations of the top with the conserved momenta, state
    /// `[θ, θ̇, φ, ψ]`: `A θ̈ = A φ̇² sin θ cos θ − p_ψ φ̇ sin θ + m g l sin θ`,
    /// `φ̇ = (p_φ − p_ψ cos θ)/(A sin²θ)`, `ψ̇ = ω₃ − φ̇ cos θ`.
    fn top_rhs(y: &[f64; 4], p_phi: f64, w3: f64) -> [f64; 4] {
        let p_psi = C * w3;
        let (s, co) = y[0].sin_cos();
        let phi_dot = (p_phi - p_psi * co) / (A * s * s);
        let theta_dd = (A * phi_dot * phi_dot * s * co - p_psi * phi_dot * s + M * G * L * s) / A;
        [y[1], theta_dd, phi_dot, w3 - phi_dot * co]
    }

    /// From θ₀ on the slow steady precession, kicked by `θ̇(0) = amp·Ω`
    /// (θ amplitude ≈ `amp`), returns the measured nutation period and the
    /// mean precession rate over the whole half periods observed.
    fn measured_nutation(theta0: f64, w3: f64, amp: f64, h: f64) -> (f64, f64) {
        let rates = top_slow_rates(M, G, L, A, C, w3, theta0);
        let p_phi = A * rates.precession * theta0.sin().powi(2) + C * w3 * theta0.cos();
        let f = |y: &[f64; 4]| top_rhs(y, p_phi, w3);
        let periods = 20.0;
        let steps = (periods * 2.0 * PI / rates.nutation / h).ceil() as usize;
        let mut y = [theta0, amp * rates.nutation, 0.0, 0.0];
        let mut d = f(&y);
        // Turning points of θ (θ̇ = 0) and φ there, both by Hermite.
        let mut turns: Vec<(f64, f64)> = Vec::new();
        for n in 0..steps {
            let y1 = rk4_step(&f, &y, h);
            let d1 = f(&y1);
            if (y[1] > 0.0) != (y1[1] > 0.0) {
                let s = hermite_root(h, y[1], d[1], y1[1], d1[1]);
                let phi = hermite(h, y[2], d[2], y1[2], d1[2], s);
                turns.push((n as f64 * h + s, phi));
            }
            (y, d) = (y1, d1);
        }
        assert!(turns.len() >= 38, "{} turning points", turns.len());
        let (first, last) = (turns[0], turns[turns.len() - 1]);
        let halves = (turns.len() - 1) as f64;
        (
            2.0 * (last.0 - first.0) / halves,
            (last.1 - first.1) / (last.0 - first.0),
        )
    }

    #[test]
    fn rigid_top_nutation_period_matches_rk4_of_the_euler_angle_equations() {
        // Start at θ₀ with φ̇ = the slow steady precession (so p_φ, p_ψ are
        // those of the steady motion) and a small θ̇: θ oscillates about θ₀
        // with amplitude `amp` in the effective potential. The measured
        // period differs from 2π/Ω by the anharmonic shift, second order in
        // the amplitude, κ·amp² with κ = O(1/sin²θ₀); RK4 at h = 1e-5 s
        // (Ω h ≈ 3e-4) adds ~(Ωh)⁴ ≈ 1e-14 relative per radian, and the
        // Hermite location of the turning points O(h⁴). So:
        // * amp = 1e-3: |T − 2π/Ω| ≤ 1e-5·T (κ ≤ 10);
        // * doubling the amplitude multiplies the deviation by 4 (±5%),
        //   which a wrong Ω (deviation independent of amp) cannot mimic;
        // * the Richardson value (4 T(amp) − T(2amp))/3 removes the amp²
        //   term and agrees with 2π/Ω to 1e-9 relative (amp⁴ and RK4 terms).
        // The same holds for the mean precession rate vs the slow root.
        for (theta0, w3) in [(0.5, 50.0), (1.2, 30.0), (2.2, 60.0)] {
            let rates = top_slow_rates(M, G, L, A, C, w3, theta0);
            assert!(rates.nutation.is_finite() && rates.precession.is_finite());
            let exact = 2.0 * PI / rates.nutation;
            let h = 1e-5;
            let amp = 1e-3;
            let (t1, p1) = measured_nutation(theta0, w3, amp, h);
            let (t2, p2) = measured_nutation(theta0, w3, 2.0 * amp, h);
            let (d1, d2) = (t1 - exact, t2 - exact);
            let rich = (4.0 * t1 - t2) / 3.0;
            let prich = (4.0 * p1 - p2) / 3.0;
            eprintln!(
                "θ₀ = {theta0}, ω₃ = {w3}: 2π/Ω = {exact}, T(a) − 2π/Ω = {d1:e}, \
                 ratio {}, Richardson error {:e}; precession {} vs {}, Richardson error {:e}",
                d2 / d1,
                (rich - exact) / exact,
                p1,
                rates.precession,
                (prich - rates.precession) / rates.precession
            );
            assert!(d1.abs() <= 1e-5 * exact, "deviation {d1}");
            assert!((d2 / d1 - 4.0).abs() <= 0.2, "ratio {}", d2 / d1);
            assert!(
                (rich - exact).abs() <= 1e-9 * exact,
                "Richardson {rich} vs {exact}"
            );
            let prec = rates.precession;
            assert!(
                (p1 - prec).abs() <= 1e-5 * prec.abs(),
                "precession {p1} vs {prec}"
            );
            assert!(
                (prich - prec).abs() <= 1e-9 * prec.abs(),
                "precession Richardson {prich} vs {prec}"
            );
        }
    }
}
