//! Whether an equilibrium is stable: the modes about it
//! (`crate::modes`, dense) have no real `s > 0`. Newton's method converges
//! to the stationary pose nearest its path, which may be a maximum or a
//! saddle of the potential (a bar started near upright stays upright).

use mstar_model::System;

use super::{Equilibrium, EquilibriumError, EquilibriumOptions};
use crate::modes::{DENSE_LIMIT, Method, ModeKind, ModesOptions};

/// The stability of an equilibrium, as far as it was checked.
#[derive(Clone, Debug, PartialEq)]
pub enum Stability {
    /// No mode about it grows.
    Stable,
    /// A mode grows: the coordinates of its shape (components of at least a
    /// tenth of the largest, largest first, the largest `1`) and its growth
    /// rate `s`, 1/s.
    Unstable {
        /// The direction along which the motion runs away.
        direction: Vec<(String, f64)>,
        /// The growth rate `s > 0`, 1/s.
        rate: f64,
        /// The mode's shape in all coordinates, its largest component `1`.
        shape: Vec<f64>,
    },
    /// Not checked: more than [`DENSE_LIMIT`] coordinates (the check takes
    /// every mode, by the dense method), or the modes could not be computed.
    Unchecked,
}

/// The stability of `eq`, an equilibrium of `sys` with drivers held at
/// `t0`: every mode about it by the dense method (models of up to
/// [`DENSE_LIMIT`] coordinates), unstable when one has a real `s > 0`.
#[must_use]
pub fn stability<S: System + ?Sized>(sys: &S, eq: &Equilibrium, t0: f64) -> Stability {
    let n = sys.n_coords();
    if n > DENSE_LIMIT {
        return Stability::Unchecked;
    }
    let rank = crate::redundant::dense_rows(sys, t0, &eq.u).rank;
    if rank >= n {
        return Stability::Stable;
    }
    let options = ModesOptions {
        count: n - rank,
        t0,
        method: Method::Dense,
    };
    let Ok(modes) = crate::modes::modes(sys, &eq.u, &eq.lambda, &options) else {
        return Stability::Unchecked;
    };
    let Some(mode) = modes.modes.iter().find(|m| m.kind == ModeKind::Unstable) else {
        return Stability::Stable;
    };
    let big = mode.shape.iter().fold(0.0_f64, |a, x| a.max(x.abs()));
    let mut idx: Vec<usize> = (0..n)
        .filter(|&i| big > 0.0 && mode.shape[i].abs() >= 0.1 * big)
        .collect();
    idx.sort_by(|&a, &b| mode.shape[b].abs().total_cmp(&mode.shape[a].abs()));
    idx.truncate(8);
    Stability::Unstable {
        direction: idx
            .into_iter()
            .map(|i| (sys.coord_name(i), mode.shape[i] / big))
            .collect(),
        rate: mode.s.0,
        shape: mode.shape.iter().map(|x| x / big).collect(),
    }
}

/// The search's result `found` (an equilibrium, or a neutral one), or when
/// it is unstable the one found by a search that starts from it displaced
/// along its growing mode (by `0.05 L` either way, `L = max(1, ‖u‖∞)`) and
/// lowers the potential energy at every step ([`super::solve_from`] with
/// `descend`; Newton's steps would lead back up to it): the first of lower
/// potential energy that is not unstable (a neutral one stays an error
/// that carries it). `found` itself when neither side gives one (the
/// potential energy does not hold every force, or there is none), or when
/// its stability is not checked.
pub(super) fn stable_or_as_found<S: System + ?Sized>(
    sys: &S,
    mut found: Result<Equilibrium, EquilibriumError>,
    options: &EquilibriumOptions,
) -> Result<Equilibrium, EquilibriumError> {
    let Some(eq) = pose_of(&mut found) else {
        return found;
    };
    eq.stability = stability(sys, eq, options.t0);
    let Stability::Unstable { shape, .. } = &eq.stability else {
        return found;
    };
    let length = eq.u.iter().fold(1.0_f64, |l, x| l.max(x.abs()));
    let energy = sys.potential_energy(options.t0, &eq.u);
    let starts: Vec<Vec<f64>> = [1.0, -1.0]
        .iter()
        .map(|sign| {
            eq.u.iter()
                .zip(shape)
                .map(|(u, p)| u + sign * 0.05 * length * p)
                .collect()
        })
        .collect();
    let (iterations, damped) = (eq.iterations, eq.damped);
    for start in starts {
        let mut candidate = super::solve_from(sys, &start, options, true);
        let Some(c) = pose_of(&mut candidate) else {
            continue;
        };
        c.stability = stability(sys, c, options.t0);
        let better = sys.potential_energy(options.t0, &c.u) < energy
            && !matches!(c.stability, Stability::Unstable { .. });
        if better {
            c.iterations += iterations;
            c.damped += damped;
            return candidate;
        }
    }
    found
}

/// The pose a search ended at: an equilibrium, or a neutral one.
fn pose_of(found: &mut Result<Equilibrium, EquilibriumError>) -> Option<&mut Equilibrium> {
    match found {
        Ok(eq) => Some(eq),
        Err(EquilibriumError::Neutral { equilibrium, .. }) => Some(&mut **equilibrium),
        Err(_) => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mstar_model::{Link, PendulumChain};

    /// A point mass on a rod (m = 1 kg, l = 1 m, g = 9.81): hanging it is
    /// stable, upright it runs away as `e^{st}` with `s = √(g/l)` (the
    /// linearized inverted pendulum `θ̈ = (g/l) θ`), along its angle. The
    /// rate comes from a dense eigensolver: round-off, `10⁻¹⁰` relative.
    #[test]
    fn an_upright_pendulum_is_unstable_at_the_closed_form_rate() {
        let sys = PendulumChain::new(vec![Link { m: 1.0, l: 1.0 }], 9.81);
        let at = |theta: f64| {
            let u = sys.position(&[theta]);
            let lambda = crate::modes::rest_multipliers(&sys, &u, 0.0).expect("multipliers");
            Equilibrium {
                u,
                lambda,
                iterations: 0,
                damped: 0,
                residual: 0.0,
                constraint: 0.0,
                left_out: Vec::new(),
                stability: Stability::Unchecked,
            }
        };
        assert_eq!(stability(&sys, &at(0.0), 0.0), Stability::Stable);
        match stability(&sys, &at(std::f64::consts::PI), 0.0) {
            Stability::Unstable {
                direction, rate, ..
            } => {
                let want = 9.81_f64.sqrt();
                assert!(
                    (rate - want).abs() <= 1e-10 * want,
                    "s = {rate}, want {want}"
                );
                assert!(
                    direction.iter().any(|(name, _)| name.ends_with("theta")),
                    "{direction:?}"
                );
            }
            other => panic!("{other:?}"),
        }
    }

    /// Started 0.3 rad from upright, the search's Newton steps converge to
    /// the upright equilibrium; it is unstable, so the search goes on from
    /// beside it, lowering the potential energy, to the hanging one: the mass
    /// straight below the pivot at `(0, −l)`.
    #[test]
    fn a_start_near_upright_ends_hanging() {
        let sys = PendulumChain::new(vec![Link { m: 1.0, l: 1.0 }], 9.81);
        let u0 = sys.position(&[std::f64::consts::PI - 0.3]);
        let options = EquilibriumOptions::default();
        let upright = super::super::solve_from(&sys, &u0, &options, false).expect("upright");
        assert!((upright.u[1] - 1.0).abs() < 1e-10, "y = {}", upright.u[1]);
        let eq = super::super::solve(&sys, &u0, &EquilibriumOptions::default()).expect("found");
        assert!(eq.u[0].abs() < 1e-10, "x = {}", eq.u[0]);
        assert!((eq.u[1] + 1.0).abs() < 1e-10, "y = {}", eq.u[1]);
        assert_eq!(stability(&sys, &eq, 0.0), Stability::Stable);
        assert_eq!(eq.stability, Stability::Stable, "as solve found it");
    }
}
