//! Rigid-body kinematics in Euler parameters `p = (e₀, e)`, written out here
//! from Haug, *Computer-Aided Kinematics and Dynamics of Mechanical Systems*
//! (1989), §6.3 — independently of `mstar::model::spatial`, so that the
//! spatial references share no code with the path they check.

/// `A(p) = (2e₀² − 1) I + 2(e eᵀ + e₀ ẽ)`, body to global, for a unit `p`.
pub(super) fn rotation(p: &[f64]) -> [[f64; 3]; 3] {
    let [e0, e1, e2, e3] = [p[0], p[1], p[2], p[3]];
    [
        [
            2.0 * (e0 * e0 + e1 * e1) - 1.0,
            2.0 * (e1 * e2 - e0 * e3),
            2.0 * (e1 * e3 + e0 * e2),
        ],
        [
            2.0 * (e1 * e2 + e0 * e3),
            2.0 * (e0 * e0 + e2 * e2) - 1.0,
            2.0 * (e2 * e3 - e0 * e1),
        ],
        [
            2.0 * (e1 * e3 - e0 * e2),
            2.0 * (e2 * e3 + e0 * e1),
            2.0 * (e0 * e0 + e3 * e3) - 1.0,
        ],
    ]
}

/// `A x`.
pub(super) fn apply(a: &[[f64; 3]; 3], x: [f64; 3]) -> [f64; 3] {
    a.map(|row| row[0] * x[0] + row[1] * x[1] + row[2] * x[2])
}

/// `x × y`.
pub(super) fn cross(x: [f64; 3], y: [f64; 3]) -> [f64; 3] {
    [
        x[1] * y[2] - x[2] * y[1],
        x[2] * y[0] - x[0] * y[2],
        x[0] * y[1] - x[1] * y[0],
    ]
}

/// `x · y`.
pub(super) fn dot(x: [f64; 3], y: [f64; 3]) -> f64 {
    x[0] * y[0] + x[1] * y[1] + x[2] * y[2]
}

/// The angular velocity in body axes, `ω′ = 2 G(p) ṗ`,
/// `G = [−e, −ẽ + e₀ I]` (Haug eq. 6.3.18).
pub(super) fn omega_body(p: &[f64], pd: &[f64]) -> [f64; 3] {
    let (e, ed) = ([p[1], p[2], p[3]], [pd[1], pd[2], pd[3]]);
    let exd = cross(e, ed);
    std::array::from_fn(|i| 2.0 * (-e[i] * pd[0] + p[0] * ed[i] - exd[i]))
}

/// The angular velocity in global axes, `ω = 2 E(p) ṗ`,
/// `E = [−e, ẽ + e₀ I]` (Haug eq. 6.3.17).
#[cfg(test)]
pub(super) fn omega_global(p: &[f64], pd: &[f64]) -> [f64; 3] {
    let (e, ed) = ([p[1], p[2], p[3]], [pd[1], pd[2], pd[3]]);
    let exd = cross(e, ed);
    std::array::from_fn(|i| 2.0 * (-e[i] * pd[0] + p[0] * ed[i] + exd[i]))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A quarter turn about z takes x to y; the rates of a spin `w` about
    /// the body's z axis give `ω′ = ω = (0, 0, w)`.
    #[test]
    fn a_quarter_turn_and_a_spin_about_z() {
        let h = std::f64::consts::FRAC_PI_4;
        let p = [h.cos(), 0.0, 0.0, h.sin()];
        let x = apply(&rotation(&p), [1.0, 0.0, 0.0]);
        assert!((x[0]).abs() < 1e-15 && (x[1] - 1.0).abs() < 1e-15 && x[2].abs() < 1e-15);
        // ṗ = ½ w (−e₃, 0, 0, e₀) for a spin w about z.
        let w = 3.0;
        let pd = [-0.5 * w * p[3], 0.0, 0.0, 0.5 * w * p[0]];
        for omega in [omega_body(&p, &pd), omega_global(&p, &pd)] {
            assert!(omega[0].abs() < 1e-15 && omega[1].abs() < 1e-15);
            assert!((omega[2] - w).abs() < 1e-14, "{omega:?}");
        }
    }

    /// A tilt about x then a spin about the body's z: `ω = A ω′`.
    #[test]
    fn global_and_body_angular_velocities_differ_by_the_rotation() {
        let (c, s) = (0.3f64.cos(), 0.3f64.sin());
        let p = [c, s, 0.0, 0.0];
        let pd = [0.1, -0.2, 0.7, 0.4];
        let (body, global) = (omega_body(&p, &pd), omega_global(&p, &pd));
        let rotated = apply(&rotation(&p), body);
        for i in 0..3 {
            assert!(
                (rotated[i] - global[i]).abs() < 1e-14,
                "{rotated:?} {global:?}"
            );
        }
    }
}
