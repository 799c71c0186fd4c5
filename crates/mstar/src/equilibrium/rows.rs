//! Redundant constraints in statics: the equilibrium is solved on the
//! independent rows of `B` (a [`RowSubset`]), and the multipliers of all
//! rows are recovered from those of the kept rows (`crate::redundant`).
//!
//! The pose and the constraint forces `Bᵀλ` do not depend on which of a
//! dependent set of rows carries them; the multipliers do, and are the
//! minimum-norm ones, as in a run with `redundant = "minimum-norm"`
//! (docs/analysis.md, "Redundant constraints").

use mstar_model::{RowSubset, System};

use super::{Equilibrium, EquilibriumError, EquilibriumOptions};
use crate::redundant::all_multipliers;

/// [`super::solve_on`] for `sys` with only the rows `kept`, its result
/// (also a neutral one) carried back to all rows of `sys`.
pub(super) fn solve_on_rows<S: System + ?Sized>(
    sys: &S,
    kept: Vec<usize>,
    u0: &[f64],
    options: &EquilibriumOptions,
    descend: bool,
) -> Result<Equilibrium, EquilibriumError> {
    let subset = RowSubset::new(sys, kept.clone());
    match super::solve_on(&subset, u0, options, descend) {
        Ok(eq) => expand(sys, &kept, eq, options),
        Err(EquilibriumError::Neutral {
            equilibrium,
            direction,
        }) => Err(EquilibriumError::Neutral {
            equilibrium: Box::new(expand(sys, &kept, *equilibrium, options)?),
            direction,
        }),
        Err(e) => Err(e),
    }
}

/// `eq` (of the rows `kept`) with the multipliers of all rows of `sys`, and
/// the left-out rows checked to hold at its pose.
fn expand<S: System + ?Sized>(
    sys: &S,
    kept: &[usize],
    mut eq: Equilibrium,
    options: &EquilibriumOptions,
) -> Result<Equilibrium, EquilibriumError> {
    let (n, m) = (sys.n_coords(), sys.n_constraints());
    let mut phi = vec![0.0; m];
    sys.phi_into(options.t0, &eq.u, &mut phi);
    let constraint = phi.iter().fold(0.0_f64, |a, p| a.max(p.abs()));
    let limit = options.tol * eq.u.iter().fold(1.0_f64, |l, x| l.max(x.abs()));
    // (A NaN does not hold.)
    let holds = |p: f64| p.abs() <= limit;
    let left_out: Vec<usize> = (0..m).filter(|k| kept.binary_search(k).is_err()).collect();
    let violated: Vec<usize> = left_out
        .iter()
        .copied()
        .filter(|&k| !holds(phi[k]))
        .collect();
    if !violated.is_empty() {
        return Err(EquilibriumError::Contradicting {
            rows: violated.iter().map(|&k| sys.constraint_name(k)).collect(),
            violation: constraint,
        });
    }
    eq.lambda = all_multipliers(sys, kept, options.t0, &eq.u, &eq.lambda);
    eq.constraint = constraint;
    eq.left_out = left_out;
    debug_assert_eq!(eq.u.len(), n);
    Ok(eq)
}
