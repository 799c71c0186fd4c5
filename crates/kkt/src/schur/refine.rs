//! One step of iterative refinement for the `schur-lu` backend (Björck's
//! corrected semi-normal equations).
//!
//! Eliminating `x` squares the conditioning that the multipliers see:
//! `C = B S⁻¹ Bᵀ` has roughly the square of the condition number of the KKT
//! matrix for `y` (a chain of `N` bodies: `N²` against `N`, times that of
//! `S`'s blocks; a slender bar's 4 × 4 rotational block has about 400). The
//! solution is still backward stable (its residual is at the rounding level),
//! but its multipliers carry a forward error of order `cond(C) ε`. On a long
//! spatial chain that error comes back as noise in `λ` from step to step,
//! which the bilinear term `(∂B/∂u Δu)ᵀ Δλ` of the next Newton residual
//! turns into a second iteration on a good share of the steps (measured with
//! the exact tangent at the default tolerance: 1.11 iterations a step at
//! N = 1000, 1.73 at 10⁴, against 1.00 and 1.05 for sparse LU on the whole
//! matrix). One correction `x += A⁻¹ (b − A x)` with the residual formed on
//! the whole KKT matrix `A` brings the forward error down to that of `A`
//! (`cond(A) ε`): the semi-normal equations' classic remedy.
//!
//! Those counts were measured on 2026-11-23. With the normalization rows
//! eliminated with their blocks and the predictor over five steps the
//! unrefined solve takes the same iterations (2026-11-28: 1.00 at
//! N = 1000, 1.05 at 10⁴), so Newton's solves skip this step
//! (`KktSolver::solve_correction`); the solves whose result is used as it
//! comes (the start, sensitivities, the adjoint) keep it
//! (docs/performance.md, "Newton's solves without `schur-lu`'s refinement").

use super::Schur;
use crate::{MaxAbs, max_abs};

impl Schur {
    /// Solves `A x = b` in place (`rhs` is `b` on entry) by the Schur
    /// complement and one step of refinement against the whole matrix.
    /// Returns `(‖x‖∞, ‖A x₀ − b‖∞)` with `x₀` the unrefined solution: its
    /// residual is the check of the factorization (backward stability), and
    /// the correction only lowers it.
    pub(super) fn solve_refined(&mut self, rhs: &mut [f64]) -> (f64, f64) {
        // Taken out for the product (which borrows `self`), put back below.
        let (mut b, mut r) = (
            std::mem::take(&mut self.refine_b),
            std::mem::take(&mut self.refine_r),
        );
        b.copy_from_slice(rhs);
        self.solve_general(rhs);
        self.product(rhs, &mut r);
        // r = b − A x₀ and its norm.
        let mut residual = MaxAbs::new();
        for (ri, &bi) in r.iter_mut().zip(&b) {
            *ri = bi - *ri;
            residual.push(*ri);
        }
        self.solve_general(&mut r);
        for (xi, &d) in rhs.iter_mut().zip(&r) {
            *xi += d;
        }
        (self.refine_b, self.refine_r) = (b, r);
        (max_abs(rhs), residual.value())
    }
}
