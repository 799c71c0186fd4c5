//! Unit tests of [`super::modes`] against closed forms, on hand-written
//! systems: point masses in the plane kept on the x axis by one constraint
//! each (`Φᵢ = yᵢ`, so `B` is not trivial), joined by springs and dampers
//! along x.

use super::{Method, ModeKind, ModesError, ModesOptions, modes};
use mstar_model::{Pattern, System};

/// `n` masses `m` on the x axis, springs `k` (dampers `c`) between
/// neighbours and to walls at both ends (fixed–fixed); `u = [x₀, y₀, x₁,
/// y₁, …]` measured from the rest positions.
struct Line {
    n: usize,
    m: f64,
    k: f64,
    c: f64,
}

impl Line {
    /// `(i, j, value)` of the `n × n` tridiagonal matrix of the x
    /// coordinates for a spring (or damper) constant `a`.
    fn tridiagonal(&self, a: f64) -> Vec<(usize, usize, f64)> {
        let mut out = Vec::new();
        for i in 0..self.n {
            out.push((2 * i, 2 * i, 2.0 * a));
            if i + 1 < self.n {
                out.push((2 * i, 2 * i + 2, -a));
                out.push((2 * i + 2, 2 * i, -a));
            }
        }
        out
    }
}

impl System for Line {
    fn n_coords(&self) -> usize {
        2 * self.n
    }
    fn n_constraints(&self) -> usize {
        self.n
    }
    fn mass_pattern(&self) -> Pattern {
        Pattern::diagonal(2 * self.n)
    }
    fn mass_into(&self, _t: f64, _u: &[f64], mass: &mut [f64]) {
        mass.fill(self.m);
    }
    fn forces_into(&self, _t: f64, u: &[f64], v: &[f64], g: &mut [f64]) {
        g.fill(0.0);
        for (i, j, a) in self.tridiagonal(1.0) {
            g[i] -= a * (self.k * u[j] + self.c * v[j]);
        }
    }
    fn phi_into(&self, _t: f64, u: &[f64], phi: &mut [f64]) {
        for (i, p) in phi.iter_mut().enumerate() {
            *p = u[2 * i + 1];
        }
    }
    fn b_pattern(&self) -> Pattern {
        Pattern::from_entries(
            self.n,
            2 * self.n,
            (0..self.n).map(|i| (i, 2 * i + 1)).collect(),
        )
    }
    fn b_into(&self, _t: f64, _u: &[f64], b: &mut [f64]) {
        b.fill(1.0);
    }
    fn forces_du_pattern(&self) -> Pattern {
        let entries = self
            .tridiagonal(1.0)
            .iter()
            .map(|&(i, j, _)| (i, j))
            .collect();
        Pattern::from_entries(2 * self.n, 2 * self.n, entries)
    }
    fn forces_du_into(&self, _t: f64, _u: &[f64], _v: &[f64], g_u: &mut [f64]) {
        for (out, (_, _, a)) in g_u.iter_mut().zip(self.tridiagonal(-self.k)) {
            *out = a;
        }
    }
    fn forces_dv_pattern(&self) -> Pattern {
        self.forces_du_pattern()
    }
    fn forces_dv_into(&self, _t: f64, _u: &[f64], _v: &[f64], g_v: &mut [f64]) {
        for (out, (_, _, a)) in g_v.iter_mut().zip(self.tridiagonal(-self.c)) {
            *out = a;
        }
    }
}

/// `ω_j = 2 √(k/m) sin(jπ / (2(n + 1)))`, the fixed–fixed chain's modes
/// (`k/m` times the eigenvalues `2 − 2 cos(jπ/(n+1))` of the tridiagonal
/// matrix `(−1, 2, −1)`), rad/s.
fn chain_omega(j: usize, n: usize, k: f64, m: f64) -> f64 {
    2.0 * (k / m).sqrt() * (j as f64 * std::f64::consts::PI / (2.0 * (n as f64 + 1.0))).sin()
}

/// Checks the chain's lowest `count` modes by `method`: frequencies to
/// `10⁻⁹` relative (round-off of eigensolvers on matrices of condition
/// `≈ 4(n+1)²/π²`, far below), unit modal mass, and shapes
/// `sin(i j π/(n+1))` up to sign.
fn check_chain(method: Method, n: usize, count: usize) {
    let (m, k) = (2.0, 50.0);
    let sys = Line { n, m, k, c: 0.0 };
    let u = vec![0.0; 2 * n];
    let lambda = vec![0.0; n];
    let options = ModesOptions {
        count,
        method,
        ..ModesOptions::default()
    };
    let found = modes(&sys, &u, &lambda, &options).expect("modes");
    assert_eq!(found.dof, n);
    assert!(!found.damped);
    assert_eq!(found.modes.len(), count);
    for (j, mode) in found.modes.iter().enumerate() {
        let omega = chain_omega(j + 1, n, k, m);
        let f = omega / std::f64::consts::TAU;
        assert!(
            (mode.frequency_hz - f).abs() <= 1e-9 * f,
            "mode {}: {} vs {f}",
            j + 1,
            mode.frequency_hz
        );
        assert_eq!(mode.kind, ModeKind::Oscillating);
        assert!(mode.damping_ratio.abs() <= 1e-12);
        let modal_mass: f64 = mode.shape.iter().map(|x| m * x * x).sum();
        assert!((modal_mass - 1.0).abs() <= 1e-12, "modal mass {modal_mass}");
        // Closed-form shape, scaled to unit modal mass: Σ m sin² = m (n+1)/2.
        let norm = (m * (n as f64 + 1.0) / 2.0).sqrt();
        let reference: Vec<f64> = (0..n)
            .map(|i| {
                ((i + 1) as f64 * (j + 1) as f64 * std::f64::consts::PI / (n as f64 + 1.0)).sin()
                    / norm
            })
            .collect();
        let sign = if mode.shape[0] * reference[0] < 0.0 {
            -1.0
        } else {
            1.0
        };
        for i in 0..n {
            assert!(
                (sign * mode.shape[2 * i] - reference[i]).abs() <= 1e-8,
                "shape {i} of mode {}",
                j + 1
            );
            assert!(mode.shape[2 * i + 1].abs() <= 1e-12, "y moves");
        }
    }
}

#[test]
fn fixed_fixed_chain_dense() {
    check_chain(Method::Dense, 6, 6);
}

#[test]
fn fixed_fixed_chain_sparse() {
    check_chain(Method::Sparse, 30, 5);
}

/// One mass on a spring and a damper: `s = −c/(2m) ± i √(k/m − (c/2m)²)`,
/// so `|s| = √(k/m)` and `ζ = c / (2 √(k m))`.
#[test]
fn damped_single_mode() {
    let (m, k, c) = (2.0, 50.0, 3.0);
    // One mass between two walls: stiffness 2k, damping 2c.
    let sys = Line { n: 1, m, k, c };
    let found = modes(
        &sys,
        &[0.0, 0.0],
        &[0.0],
        &ModesOptions {
            count: 1,
            ..ModesOptions::default()
        },
    )
    .expect("modes");
    assert!(found.damped);
    let mode = &found.modes[0];
    let (k2, c2) = (2.0 * k, 2.0 * c);
    let re = -c2 / (2.0 * m);
    let im = (k2 / m - re * re).sqrt();
    assert!(
        (mode.s.0 - re).abs() <= 1e-9 * im && (mode.s.1 - im).abs() <= 1e-9 * im,
        "{:?}",
        mode.s
    );
    let f = (k2 / m).sqrt() / std::f64::consts::TAU;
    assert!((mode.frequency_hz - f).abs() <= 1e-9 * f);
    let zeta = c2 / (2.0 * (k2 * m).sqrt());
    assert!((mode.damping_ratio - zeta).abs() <= 1e-9);
    // Unit modal mass, rotated real: φ = [1/√m, 0].
    assert!((mode.shape[0] - m.sqrt().recip()).abs() <= 1e-12);
    assert!(mode.shape_imag[0].abs() <= 1e-12);
}

/// Overdamped: two real roots `s = −c/m ± √((c/m)² − k/m)`
/// (with the doubled constants of one mass between two walls).
#[test]
fn overdamped_single_mass() {
    let (m, k, c) = (1.0, 1.0, 5.0);
    let sys = Line { n: 1, m, k, c };
    let found = modes(
        &sys,
        &[0.0, 0.0],
        &[0.0],
        &ModesOptions {
            count: 1,
            ..ModesOptions::default()
        },
    )
    .expect("modes");
    let (k2, c2) = (2.0 * k, 2.0 * c);
    let slow = -c2 / (2.0 * m) + ((c2 / (2.0 * m)).powi(2) - k2 / m).sqrt();
    let mode = &found.modes[0];
    assert_eq!(mode.kind, ModeKind::Overdamped);
    assert!(
        (mode.s.0 - slow).abs() <= 1e-9 * slow.abs(),
        "{:?} vs {slow}",
        mode.s
    );
    assert!((mode.damping_ratio - 1.0).abs() <= 1e-15);
}

#[test]
fn too_many_modes_is_an_error() {
    let sys = Line {
        n: 3,
        m: 1.0,
        k: 1.0,
        c: 0.0,
    };
    let options = ModesOptions {
        count: 4,
        ..ModesOptions::default()
    };
    let e = modes(&sys, &[0.0; 6], &[0.0; 3], &options).expect_err("3 degrees of freedom");
    assert!(
        matches!(
            e,
            ModesError::TooMany {
                count: 4,
                dof: 3,
                ..
            }
        ),
        "{e}"
    );
    assert!(e.to_string().contains("ask for at most 3"), "{e}");
}

#[test]
fn sparse_refuses_dampers() {
    let sys = Line {
        n: 3,
        m: 1.0,
        k: 1.0,
        c: 0.1,
    };
    let options = ModesOptions {
        count: 2,
        method: Method::Sparse,
        ..ModesOptions::default()
    };
    let e = modes(&sys, &[0.0; 6], &[0.0; 3], &options).expect_err("damped");
    assert!(e.to_string().contains("has dampers"), "{e}");
}

/// A free mass (no springs): one rigid mode per free direction.
#[test]
fn free_mass_is_rigid() {
    let sys = Line {
        n: 1,
        m: 1.0,
        k: 0.0,
        c: 0.0,
    };
    let found = modes(
        &sys,
        &[0.0, 0.0],
        &[0.0],
        &ModesOptions {
            count: 1,
            ..ModesOptions::default()
        },
    )
    .expect("modes");
    assert_eq!(found.modes[0].kind, ModeKind::Rigid);
    assert_eq!(found.modes[0].frequency_hz, 0.0);
}

/// Springs of negative stiffness (an inverted, unstable state): `ω² =
/// −ω_j²` of the chain with `|k|`, so each mode is a real `s = ω_j > 0`,
/// reported unstable with `ζ = −1` and `f = ω_j/2π`, by both methods.
#[test]
fn negative_stiffness_is_unstable() {
    let (n, m, k) = (4, 1.5, -30.0);
    let sys = Line { n, m, k, c: 0.0 };
    for method in [Method::Dense, Method::Sparse] {
        let options = ModesOptions {
            count: n,
            method,
            ..ModesOptions::default()
        };
        let found = modes(&sys, &[0.0; 8], &[0.0; 4], &options).expect("modes");
        for (j, mode) in found.modes.iter().enumerate() {
            let omega = chain_omega(j + 1, n, -k, m);
            assert_eq!(mode.kind, ModeKind::Unstable, "{method:?}");
            assert!(
                (mode.s.0 - omega).abs() <= 1e-9 * omega,
                "{method:?}: {:?}",
                mode.s
            );
            assert_eq!(mode.damping_ratio, -1.0);
            let f = omega / std::f64::consts::TAU;
            assert!((mode.frequency_hz - f).abs() <= 1e-9 * f);
        }
    }
}
