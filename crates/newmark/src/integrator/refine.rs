//! A sensitivity's solve with the step's own factorization
//! (`docs/analysis.md`, "Parameter sensitivities"; `algorithm.md` §4).
//!
//! The sensitivity system `J x = c` has `J` at the converged state; full
//! Newton leaves a factorization `J̃` of an iterate of the same step, which
//! differs from the converged one by the corrections `Δu` made after it (the
//! "drift"; when that factorization took the Jacobians of the state before
//! the step, `System::jacobians_are_costly`, the predictor's move from that
//! state as well). Refinement `x ← x + J̃⁻¹ (c − J x)` contracts the error by
//! `ρ = ‖I − J̃⁻¹ J‖`, which is proportional to the drift (`J` is smooth in
//! `u`): about `5e-11` on the N-four-bar.
//!
//! Started from zero, two passes are needed (`ρ ≈ 5e-11` relative after one).
//! Started from the extrapolation `3 x_n − 3 x_{n−1} + x_{n−2}` of the
//! parameter's last three solutions, the first pass's change `‖y‖ / ‖x‖` is already small, and
//! its error is about `ρ ‖y‖`: one pass suffices when
//! `SAFETY · (ρ / drift)_measured · drift · ‖y‖ / ‖x‖ ≤ REFINED`. The ratio
//! `ρ / drift` is measured by a refinement from zero (its second pass's
//! change is `ρ`) at the first step and every [`MEASURE_EVERY`] steps.

use mstar_model::System;

use super::{Integrator, State};
use crate::IntegrationError;

/// A refined sensitivity is accepted when the next pass would change it by
/// at most this, relative.
const REFINED: f64 = 1e-12;

/// The most refinement passes of a sensitivity's solve before the matrix is
/// factored at the converged state (two suffice with a factorization of
/// the same step: its matrix differs from the converged one by the step's
/// Newton corrections).
const MAX_REFINEMENTS: usize = 3;

/// Steps between two measurements of the contraction per drift.
const MEASURE_EVERY: usize = 32;

/// The factor between the measured contraction per drift and the one a
/// single pass is accepted with. The contraction grows with the
/// conditioning of `J`: on the N-four-bar it rose 10⁵-fold over the 20
/// steps before a singular position (replayed with every step measured,
/// with 100 and a measurement every 32 steps no step accepted an error above
/// 1.3e-13; the first pass's change grows with it and turns the rest away).
const SAFETY: f64 = 100.0;

/// The contraction of a refinement pass per unit drift, as last measured,
/// the steps since, and what a single pass is expected to change.
#[derive(Debug)]
pub(super) struct Contraction {
    /// `ρ / drift`; infinite until measured.
    per_drift: f64,
    since: usize,
    /// The first pass's change from the extrapolation at the last step that
    /// made one, halved at each step that did not (so that it is tried
    /// again).
    first_change: f64,
}

impl Default for Contraction {
    fn default() -> Self {
        Self {
            per_drift: f64::INFINITY,
            since: 0,
            first_change: 0.0,
        }
    }
}

impl Contraction {
    /// Whether this step measures the contraction (a refinement from zero).
    fn due(&self) -> bool {
        !self.per_drift.is_finite() || self.since >= MEASURE_EVERY
    }

    /// The contraction assumed at `drift`, with the safety factor (NaN or
    /// infinite, so that nothing is accepted by it, until measured).
    fn bound(&self, drift: f64) -> f64 {
        SAFETY * self.per_drift * drift
    }

    /// `rho` measured at `drift`. At a zero drift nothing is learnt of how
    /// the contraction grows with it: the estimate stays unknown.
    fn measured(&mut self, rho: f64, drift: f64) {
        self.per_drift = if drift > 0.0 {
            rho / drift
        } else {
            f64::INFINITY
        };
        self.since = 0;
    }

    /// Whether a single pass from the extrapolation is expected to be
    /// accepted at `drift` (else the refinement starts from zero, which
    /// spares the product `J x` of the start: two passes either way).
    fn expects_one_pass(&mut self, drift: f64) -> bool {
        let expected = self.bound(drift) * self.first_change <= REFINED;
        if !expected {
            self.first_change *= 0.5;
        }
        expected
    }

    /// One more step refined.
    pub(super) fn tick(&mut self) {
        self.since += 1;
    }
}

/// One parameter's last three solutions `x = [δΔ; δλ]` and the step sizes
/// they were made with.
#[derive(Debug)]
pub(super) struct PastSolutions {
    x: [Vec<f64>; 3],
    /// NaN where there is none.
    h: [f64; 3],
}

impl Default for PastSolutions {
    fn default() -> Self {
        Self {
            x: [Vec::new(), Vec::new(), Vec::new()],
            h: [f64::NAN; 3],
        }
    }
}

impl PastSolutions {
    /// `x = 3 x_n − 3 x_{n−1} + x_{n−2}` (the parabola through them) when
    /// all three were made with the step `h` (the corrections'
    /// sensitivities scale with `h²`); `false`, and `x` left as it was,
    /// otherwise.
    fn extrapolate_into(&self, h: f64, x: &mut [f64]) -> bool {
        if self.h != [h, h, h] || self.x[0].len() != x.len() {
            return false;
        }
        let [a, b, c] = &self.x;
        for (i, x) in x.iter_mut().enumerate() {
            *x = 3.0 * (a[i] - b[i]) + c[i];
        }
        true
    }

    /// Records the solution `x` made with the step `h`, by taking its
    /// buffer (and leaving the oldest solution's in `x`).
    pub(super) fn push(&mut self, x: &mut Vec<f64>, h: f64) {
        self.x.rotate_right(1);
        self.h.rotate_right(1);
        std::mem::swap(&mut self.x[0], x);
        self.h[0] = h;
    }
}

impl<S: System + ?Sized> Integrator<'_, S> {
    /// The sensitivity system `J x = b` (`b` from `scratch.partials` and the
    /// predicted sensitivities, [`kkt_residual`](Self::kkt_residual)) into
    /// `scratch.x` by refinement with the step's factorization (module
    /// documentation), started from `past`
    /// unless the contraction is due to be measured. `Ok(true)` when
    /// accepted; `Ok(false)` when it did not converge within
    /// [`MAX_REFINEMENTS`] passes or stopped contracting (then `J` is to be
    /// factored at the converged state). `solves`: counts the solves made.
    pub(super) fn refined(
        &mut self,
        scratch: &mut Scratch,
        (past, contraction): (&PastSolutions, &mut Contraction),
        h: f64,
        solves: &mut usize,
    ) -> Result<bool, IntegrationError> {
        let n = self.sys.n_coords();
        let drift = self.drift;
        let scale = self.p.coefficients(h, self.config.scaling).scale;
        let measure = contraction.due();
        let from_past = !measure
            && contraction.expects_one_pass(drift)
            && past.extrapolate_into(h, &mut scratch.x);
        // The last pass's change of `x`, relative.
        let mut previous: Option<f64> = None;
        if !from_past {
            // From zero: the first pass solves the right-hand side into `x`
            // (a change of 1).
            self.kkt_residual(scratch, h, true);
            *solves += 1;
            self.solve_scaled(&scratch.residual, h, &mut scratch.x, true)?;
            previous = Some(1.0);
        }
        self.kkt_residual(scratch, h, false);
        for pass in usize::from(!from_past)..MAX_REFINEMENTS {
            // Without the backend's own refinement step (`schur-lu`'s,
            // against the factored matrix): this loop refines against `J`
            // at the converged state, and corrects that solve's error too.
            *solves += 1;
            self.solve_scaled(&scratch.residual, h, &mut scratch.y, true)?;
            let change = add_change(&mut scratch.x, &scratch.y, n, scale);
            match previous {
                // The first pass from the extrapolation (from zero, the
                // first pass was made above).
                None => {
                    contraction.first_change = change;
                    if contraction.bound(drift) * change <= REFINED {
                        return Ok(true);
                    }
                }
                Some(previous) => {
                    if measure && pass == 1 && previous > 0.0 {
                        contraction.measured(change / previous, drift);
                    }
                    // Contracting by `change / previous` a pass, the next
                    // pass would change `x` by `change² / previous`.
                    if change * change <= REFINED * previous || change <= REFINED {
                        return Ok(true);
                    }
                    if change > 0.5 * previous {
                        return Ok(false);
                    }
                }
            }
            previous = Some(change);
            self.kkt_residual(scratch, h, false);
        }
        Ok(false)
    }

    /// `scratch.residual = [c_u − K_T (δu^p + x_u) − C_T (δu̇^p + γ' x_u) −
    /// β' M x_u − Bᵀ x_λ; c_λ − B (δu^p + x_u)]`, with `c` the partials and
    /// `δu^p, δu̇^p` the predicted sensitivities: the right-hand side of the
    /// sensitivity system minus `J x`, both with the Jacobians at the
    /// converged state, in one product each. `zero`: `x = 0` (not read).
    pub(super) fn kkt_residual(&self, scratch: &mut Scratch, h: f64, zero: bool) {
        let n = self.sys.n_coords();
        let c = self.p.coefficients(h, self.config.scaling);
        let Scratch {
            predicted,
            partials,
            x,
            residual,
            w_u,
            w_v,
            x_a,
            ..
        } = scratch;
        residual.copy_from_slice(partials);
        let (top, bottom) = residual.split_at_mut(n);
        if zero {
            self.lin.tangent_mul_sub(&predicted.u, &predicted.v, top);
            self.lin.b_mul_sub(&predicted.u, bottom);
            return;
        }
        let (x_u, x_l) = x.split_at(n);
        for i in 0..n {
            w_u[i] = predicted.u[i] + x_u[i];
            w_v[i] = predicted.v[i] + c.c_v * x_u[i];
            x_a[i] = c.c_a * x_u[i];
        }
        self.lin.tangent_mul_sub(w_u, w_v, top);
        self.lin.mass_mul_sub(x_a, top);
        self.lin.b_mul_transpose_sub(x_l, top);
        self.lin.b_mul_sub(w_u, bottom);
    }
}

/// The buffers of one step's sensitivity solves (`n + m` values, the
/// predictor's and the products' `n`), sized at the first step.
pub(super) struct Scratch {
    /// The predictor applied to a parameter's sensitivities (`u`, `v`,
    /// `a_alpha`).
    pub(super) predicted: State,
    /// The partials `c = [r_p; −Φ_p]`.
    pub(super) partials: Vec<f64>,
    pub(super) x: Vec<f64>,
    pub(super) residual: Vec<f64>,
    pub(super) y: Vec<f64>,
    /// `δu^p + x_u`, `δu̇^p + γ' x_u` and `β' x_u` (`kkt_residual`).
    w_u: Vec<f64>,
    w_v: Vec<f64>,
    x_a: Vec<f64>,
}

impl Default for Scratch {
    fn default() -> Self {
        Self {
            predicted: State::zeros(0, 0),
            partials: Vec::new(),
            x: Vec::new(),
            residual: Vec::new(),
            y: Vec::new(),
            w_u: Vec::new(),
            w_v: Vec::new(),
            x_a: Vec::new(),
        }
    }
}

impl Scratch {
    /// Sizes the buffers for `n` coordinates and `m` constraints.
    pub(super) fn size(&mut self, n: usize, m: usize) {
        if self.predicted.u.len() != n {
            self.predicted = State::zeros(n, 0);
        }
        for v in [
            &mut self.partials,
            &mut self.x,
            &mut self.residual,
            &mut self.y,
        ] {
            v.resize(n + m, 0.0);
        }
        for v in [&mut self.w_u, &mut self.w_v, &mut self.x_a] {
            v.resize(n, 0.0);
        }
    }
}

/// Below this fraction of the solver's whole solution `[x_u; scale · x_λ]`,
/// a part's entries are at the solve's round-off (`ε κ` of the whole, `κ`
/// the scaled matrix's condition): a part's change is judged against the
/// part or against this fraction of the whole, whichever is larger. Without
/// it a part that is zero in exact arithmetic (the coordinates of a
/// mechanism the drivers fix, whose multipliers alone depend on a mass)
/// changes by O(1) of itself at every pass and is never accepted.
const PART_FLOOR: f64 = 1e-4;

/// `x += y`, and the larger of `‖y_u‖∞ / ‖x_u‖∞` and `‖y_λ‖∞ / ‖x_λ‖∞`
/// after it (each 0 when `y`'s part is 0): coordinates and multipliers have
/// units of their own. Each part's norm is floored at [`PART_FLOOR`] of the
/// whole in its units, the multipliers entering the solved system as
/// `scale · λ` ([`solve_scaled`](Integrator::solve_scaled)). The norms are
/// taken in the same pass.
fn add_change(x: &mut [f64], y: &[f64], n: usize, scale: f64) -> f64 {
    let part = |x: &mut [f64], y: &[f64]| {
        let (mut dy, mut sx) = (
            mstar_linearize::MaxAbs::new(),
            mstar_linearize::MaxAbs::new(),
        );
        for (x, &y) in x.iter_mut().zip(y) {
            *x += y;
            dy.push(y);
            sx.push(*x);
        }
        (dy.value(), sx.value())
    };
    let (x_u, x_l) = x.split_at_mut(n);
    let (y_u, y_l) = y.split_at(n);
    let (dy_u, sx_u) = part(x_u, y_u);
    let (dy_l, sx_l) = part(x_l, y_l);
    let whole = sx_u.max(scale * sx_l);
    let relative = |dy: f64, sx: f64| if dy == 0.0 { 0.0 } else { dy / sx };
    relative(dy_u, sx_u.max(PART_FLOOR * whole))
        .max(relative(dy_l, sx_l.max(PART_FLOOR * whole / scale)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn extrapolation_needs_three_solutions_of_the_same_step() {
        let mut past = PastSolutions::default();
        let mut x = vec![0.0; 2];
        assert!(!past.extrapolate_into(0.1, &mut x));
        for (k, solution) in [[1.0, 2.0], [2.0, 5.0]].into_iter().enumerate() {
            past.push(&mut solution.to_vec(), 0.1);
            assert!(!past.extrapolate_into(0.1, &mut x), "{} solutions", k + 1);
        }
        past.push(&mut vec![4.0, 10.0], 0.1);
        // The parabola through (−2, 1), (−1, 2), (0, 4) at 1: 7; through
        // (−2, 2), (−1, 5), (0, 10) at 1: 17.
        assert!(past.extrapolate_into(0.1, &mut x));
        assert_eq!(x, [7.0, 17.0]);
        assert!(!past.extrapolate_into(0.05, &mut x));
        past.push(&mut vec![4.0, 0.0], 0.05);
        assert!(!past.extrapolate_into(0.05, &mut x));
    }

    /// A part at round-off of the whole is judged against the floor; a
    /// small part above it, against itself.
    #[test]
    fn a_part_s_change_is_relative_to_it_or_to_the_floor() {
        let scale = 1e-6;
        // Coordinates of 5e-19 against multipliers of 5 (`scale · λ` = 5e-6):
        // a change of 3e-20 is 6e-3 of them but 6e-11 of the floor 5e-10;
        // the multipliers change by 2e-12 / 5 = 4e-13.
        let mut x = vec![5e-19, 5.0];
        let change = add_change(&mut x, &[3e-20, 2e-12], 1, scale);
        let expected = 3e-20 / (PART_FLOOR * 5.0 * scale);
        assert!((change - expected).abs() <= 1e-6 * expected, "{change:e}");
        // Coordinates of 1e-8, above the floor: relative to themselves.
        let mut x = vec![1e-8, 5.0];
        let change = add_change(&mut x, &[1e-15, 0.0], 1, scale);
        let expected = 1e-15 / (1e-8 + 1e-15);
        assert!((change - expected).abs() <= 1e-6 * expected, "{change:e}");
        // Multipliers at round-off of large coordinates: against the floor.
        let mut x = vec![1.0, 1e-20];
        let change = add_change(&mut x, &[0.0, 1e-20], 1, scale);
        let expected = 1e-20 / (PART_FLOOR * 1.0 / scale);
        assert!((change - expected).abs() <= 1e-6 * expected, "{change:e}");
    }

    #[test]
    fn the_contraction_is_unknown_until_measured_and_remeasured_on_schedule() {
        let mut c = Contraction::default();
        assert!(c.due());
        // Unknown: NaN or infinite, which no acceptance test passes.
        assert!(!c.bound(1e-3).is_finite());
        c.measured(5e-11, 1e-4);
        assert!(!c.due());
        assert!((c.bound(1e-4) - SAFETY * 5e-11).abs() <= 1e-25);
        for _ in 0..MEASURE_EVERY {
            c.tick();
        }
        assert!(c.due());
        c.measured(0.0, 0.0);
        assert!(c.per_drift.is_infinite() && c.due());
    }
}
