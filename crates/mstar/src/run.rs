//! Running and checking model files (`docs/model-format.md`): the integrator
//! configuration of a file's `[simulation]`, and what `mstar check` reports
//! before a run (degrees of freedom, redundant constraints by name, how far
//! the initial state is from the constraints).

use mstar_kkt::{Backend, MaxAbs};
use mstar_model::System;
use mstar_model::file::{IntegratorChoice, NewtonChoice, Simulation};
use mstar_model::planar::PlanarSystem;
use mstar_newmark::{Config, Integrator, Newton, Scheme};

/// The defaults of `[simulation]` (`docs/model-format.md`).
pub mod defaults {
    /// `t_end`, s.
    pub const T_END: f64 = 1.0;
    /// `h`, s.
    pub const H: f64 = 1e-3;
    /// `rho` (generalized-α).
    pub const RHO: f64 = 0.9;
    /// `alpha` (HHT).
    pub const ALPHA: f64 = -0.1;
    /// `beta`, `gamma` (Newmark: the paper's trapezoidal rule).
    pub const BETA: f64 = 0.25;
    /// See [`BETA`].
    pub const GAMMA: f64 = 0.5;
}

/// The integrator configuration and end time of a model file's
/// `[simulation]`, its defaults applied.
///
/// # Errors
/// A message for a KKT solver name that no backend has.
pub fn config(sim: &Simulation) -> Result<(Config, f64), String> {
    let mut c = Config {
        h: sim.h.unwrap_or(defaults::H),
        h_min: sim.h_min,
        ..Config::default()
    };
    c.scheme = match sim.integrator.unwrap_or(IntegratorChoice::GeneralizedAlpha) {
        IntegratorChoice::GeneralizedAlpha => Scheme::GeneralizedAlpha {
            rho_inf: sim.rho.unwrap_or(defaults::RHO),
        },
        IntegratorChoice::Hht => Scheme::Hht {
            alpha: sim.alpha.unwrap_or(defaults::ALPHA),
        },
        IntegratorChoice::Newmark => Scheme::Newmark {
            beta: sim.beta.unwrap_or(defaults::BETA),
            gamma: sim.gamma.unwrap_or(defaults::GAMMA),
        },
    };
    if let Some(tol) = sim.tol {
        c.tol = tol;
    }
    if let Some(k) = sim.max_iterations {
        c.max_iterations = k;
    }
    c.newton = match sim.newton {
        Some(NewtonChoice::Full) => Newton::Full,
        Some(NewtonChoice::Modified) | None => Newton::MODIFIED,
    };
    if let Some(name) = &sim.kkt {
        c.kkt.backend = Backend::named(name).ok_or_else(|| {
            let names: Vec<_> = mstar_kkt::backends()
                .iter()
                .map(|r| r.backend.name())
                .collect();
            format!(
                "[simulation] kkt: no KKT solver is called '{name}'; the solvers are: auto, {}",
                names.join(", ")
            )
        })?;
    }
    c.validate().map_err(|e| e.to_string())?;
    Ok((c, sim.t_end.unwrap_or(defaults::T_END)))
}

/// What `mstar check` finds out about a model before running it.
#[derive(Clone, Debug, PartialEq)]
pub struct CheckReport {
    /// Coordinates `n`.
    pub coordinates: usize,
    /// Constraint equations `m`.
    pub constraints: usize,
    /// `rank B` at the initial pose (`None` when the model is too large for
    /// the dense rank computation).
    pub rank: Option<usize>,
    /// The joints and drivers with a constraint row that depends on the rows
    /// before it, by name, in file order.
    pub redundant: Vec<String>,
    /// The most violated constraint row at the initial pose, by owner and
    /// row name, with `|Φ|`.
    pub position_violation: Option<(String, String, f64)>,
    /// The same for the velocity constraint `B u̇ + Φ_t`.
    pub velocity_violation: Option<(String, String, f64)>,
    /// What the initial projection moves most: coordinate and amount, for
    /// positions and velocities (`None` when the start fails).
    pub projection: Option<[(String, f64); 2]>,
    /// Why the model cannot start, if it cannot.
    pub start_error: Option<String>,
}

/// Largest dense `m × n` the rank computation takes.
const DENSE_LIMIT: usize = 4_000_000;

/// Checks `sys` at its initial state with the integrator configuration
/// `config`.
#[must_use]
pub fn check(sys: &PlanarSystem, config: &Config) -> CheckReport {
    let (n, m) = (sys.n_coords(), sys.n_constraints());
    let (u0, v0) = (sys.initial_position(), sys.initial_velocity());
    let (rank, dependent) = if n * m <= DENSE_LIMIT {
        let (rank, rows) = dependent_rows(&dense_b(sys, &u0));
        (Some(rank), rows)
    } else {
        (None, Vec::new())
    };
    let mut redundant: Vec<String> = Vec::new();
    for row in dependent {
        let owner = sys.constraint_owner(row).unwrap_or("?").to_string();
        if !redundant.contains(&owner) {
            redundant.push(owner);
        }
    }
    let mut phi = vec![0.0; m];
    sys.phi_into(0.0, &u0, &mut phi);
    let mut w = vec![0.0; m];
    sys.phi_t_into(0.0, &u0, &mut w);
    let b = dense_b(sys, &u0);
    for (wi, row) in w.iter_mut().zip(&b) {
        *wi += row.iter().zip(&v0).map(|(x, y)| x * y).sum::<f64>();
    }
    let (projection, start_error) = match Integrator::new(sys, config.clone(), 0.0, &u0, &v0) {
        Ok(integ) => {
            let report = integ.start_report();
            let largest = |d: &[f64]| {
                let (i, x) = argmax(d);
                (sys.coord_name(i), x)
            };
            (
                Some([
                    largest(&report.position_correction),
                    largest(&report.velocity_correction),
                ]),
                None,
            )
        }
        Err(e) => (None, Some(e.to_string())),
    };
    CheckReport {
        coordinates: n,
        constraints: m,
        rank,
        redundant,
        position_violation: violation(sys, &phi),
        velocity_violation: violation(sys, &w),
        projection,
        start_error,
    }
}

impl CheckReport {
    /// Whether the model can run as written: no redundant constraint, and a
    /// start.
    #[must_use]
    pub fn can_run(&self) -> bool {
        self.redundant.is_empty() && self.start_error.is_none()
    }

    /// The degrees of freedom `n − rank B`, when the rank is known.
    #[must_use]
    pub fn degrees_of_freedom(&self) -> Option<usize> {
        self.rank.map(|r| self.coordinates - r)
    }
}

impl std::fmt::Display for CheckReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "coordinates: {}", self.coordinates)?;
        writeln!(f, "constraints: {}", self.constraints)?;
        match self.degrees_of_freedom() {
            Some(dof) => writeln!(f, "degrees of freedom: {dof}")?,
            None => writeln!(
                f,
                "degrees of freedom: not computed (n·m above {DENSE_LIMIT})"
            )?,
        }
        let redundant = if self.redundant.is_empty() {
            "none".to_string()
        } else {
            self.redundant.join(", ")
        };
        writeln!(f, "redundant constraints: {redundant}")?;
        for (level, v) in [
            ("position", &self.position_violation),
            ("velocity", &self.velocity_violation),
        ] {
            match v {
                Some((owner, row, value)) => writeln!(
                    f,
                    "initial {level} violation: {value:.3e} at '{owner}' (row {row})"
                )?,
                None => writeln!(f, "initial {level} violation: none")?,
            }
        }
        match (&self.projection, &self.start_error) {
            (Some(moved), _) => {
                for (level, (name, by)) in ["position", "velocity"].iter().zip(moved) {
                    if *by == 0.0 {
                        writeln!(f, "initial projection: no {level} moves")?;
                    } else {
                        writeln!(
                            f,
                            "initial projection: moves {level} '{name}' by {by:.3e} (the most)"
                        )?;
                    }
                }
                Ok(())
            }
            (None, Some(e)) => writeln!(f, "start: fails: {e}"),
            (None, None) => Ok(()),
        }
    }
}

/// `B` at `u`, dense, row by row.
fn dense_b(sys: &PlanarSystem, u: &[f64]) -> Vec<Vec<f64>> {
    let p = sys.b_pattern();
    let mut values = vec![0.0; p.len()];
    sys.b_into(0.0, u, &mut values);
    p.to_dense(&values)
}

/// The rank of the rows and the rows that depend on the ones before them:
/// modified Gram–Schmidt with one reorthogonalization, a row whose remainder
/// is at most `1e-10` of its norm counting as dependent.
fn dependent_rows(rows: &[Vec<f64>]) -> (usize, Vec<usize>) {
    let mut basis: Vec<Vec<f64>> = Vec::new();
    let mut dependent = Vec::new();
    for (i, row) in rows.iter().enumerate() {
        let norm = row.iter().map(|x| x * x).sum::<f64>().sqrt();
        let mut r = row.clone();
        for _ in 0..2 {
            for q in &basis {
                let d: f64 = r.iter().zip(q).map(|(a, b)| a * b).sum();
                r.iter_mut().zip(q).for_each(|(a, b)| *a -= d * b);
            }
        }
        let rest = r.iter().map(|x| x * x).sum::<f64>().sqrt();
        if rest.is_nan() || rest <= 1e-10 * norm {
            dependent.push(i);
        } else {
            r.iter_mut().for_each(|a| *a /= rest);
            basis.push(r);
        }
    }
    (basis.len(), dependent)
}

/// The largest `|xᵢ|` by owner and row name, `None` when all are zero.
fn violation(sys: &PlanarSystem, x: &[f64]) -> Option<(String, String, f64)> {
    let mut m = MaxAbs::new();
    x.iter().for_each(|&v| m.push(v));
    if m.value() == 0.0 {
        return None;
    }
    let (i, value) = argmax(x);
    Some((
        sys.constraint_owner(i).unwrap_or("?").to_string(),
        sys.constraint_name(i),
        value,
    ))
}

/// Index and magnitude of the largest `|xᵢ|` (NaN wins).
fn argmax(x: &[f64]) -> (usize, f64) {
    x.iter()
        .enumerate()
        .fold((0, 0.0f64), |(k, best), (i, &v)| {
            if v.abs() > best || v.is_nan() {
                (i, v.abs())
            } else {
                (k, best)
            }
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dependent_rows_are_found_in_order() {
        let rows = vec![
            vec![1.0, 0.0, 0.0],
            vec![0.0, 1.0, 0.0],
            vec![1.0, 1.0, 0.0],
            vec![0.0, 0.0, 2.0],
            vec![0.0, 0.0, 0.0],
        ];
        assert_eq!(dependent_rows(&rows), (3, vec![2, 4]));
    }
}

/// The reaction and effort columns of a planar model's CSV
/// (`docs/model-format.md`, "Output"): per joint and driver, in the order of
/// the file, `reaction:<name>.fx`, `.fy`, `.tau` — the constraint force
/// `−Bᵀλ` its rows put on its body ([`PlanarSystem::reaction`]) — then per
/// driver `effort:<name>` = `−λ`, the force (N) or torque (N m) the driver
/// applies along the coordinate it drives, positive in that coordinate's
/// direction.
#[derive(Debug)]
pub struct ReactionColumns<'a> {
    sys: &'a PlanarSystem,
    /// `(joint index, first row)` of each driver.
    drivers: Vec<(usize, usize)>,
}

impl<'a> ReactionColumns<'a> {
    /// The columns of `sys`.
    #[must_use]
    pub fn new(sys: &'a PlanarSystem) -> Self {
        let drivers = sys
            .joint_names()
            .enumerate()
            .filter(|(_, name)| sys.is_driver(name) == Some(true))
            .filter_map(|(i, name)| Some((i, sys.joint_rows(name)?.start)))
            .collect();
        Self { sys, drivers }
    }
}

impl crate::csv::Columns for ReactionColumns<'_> {
    fn names(&self) -> Vec<String> {
        let mut names: Vec<String> = self
            .sys
            .joint_names()
            .flat_map(|j| ["fx", "fy", "tau"].map(|c| format!("reaction:{j}.{c}")))
            .collect();
        let joints: Vec<&str> = self.sys.joint_names().collect();
        names.extend(
            self.drivers
                .iter()
                .map(|&(i, _)| format!("effort:{}", joints[i])),
        );
        names
    }

    fn values(&self, s: &mstar_model::SampleRef<'_>, out: &mut Vec<f64>) {
        for i in 0..self.sys.joint_names().count() {
            match self.sys.reaction_at(i, s.t, s.u, s.lambda) {
                Some(r) => out.extend([r.force[0], r.force[1], r.moment]),
                None => out.extend([f64::NAN; 3]),
            }
        }
        out.extend(
            self.drivers
                .iter()
                .map(|&(_, row)| s.lambda.get(row).map_or(f64::NAN, |l| -l)),
        );
    }
}
