//! [`RowSubset`]: a system with some of its constraint rows left out — the
//! independent rows of a model with redundant constraints, which the KKT
//! system of eq. (15) cannot take as they are (its matrix is singular when
//! `B` has dependent rows; `algorithm.md` §3).

use crate::{Pattern, System};

/// The system `inner` with only the constraint rows `rows` (ascending);
/// everything else is `inner`'s.
#[derive(Debug)]
pub struct RowSubset<'a, S: System + ?Sized> {
    inner: &'a S,
    rows: Vec<usize>,
    /// For each entry of the subset's `B` pattern, its index in `inner`'s.
    b_entries: Vec<usize>,
    b_pattern: Pattern,
}

impl<'a, S: System + ?Sized> RowSubset<'a, S> {
    /// Keeps the rows `rows` of `inner`'s constraints (sorted, duplicates and
    /// rows past the last dropped).
    #[must_use]
    pub fn new(inner: &'a S, mut rows: Vec<usize>) -> Self {
        let m = inner.n_constraints();
        rows.sort_unstable();
        rows.dedup();
        rows.retain(|&r| r < m);
        let mut new_row = vec![usize::MAX; m];
        for (k, &r) in rows.iter().enumerate() {
            new_row[r] = k;
        }
        let full = inner.b_pattern();
        let mut b_pattern = Pattern::new(rows.len(), full.ncols);
        let mut b_entries = Vec::new();
        for (e, &(r, c)) in full.entries.iter().enumerate() {
            if new_row[r] != usize::MAX {
                b_pattern.push(new_row[r], c);
                b_entries.push(e);
            }
        }
        Self {
            inner,
            rows,
            b_entries,
            b_pattern,
        }
    }

    /// The whole system.
    #[must_use]
    pub fn inner(&self) -> &'a S {
        self.inner
    }

    /// The kept rows of `inner`, ascending.
    #[must_use]
    pub fn rows(&self) -> &[usize] {
        &self.rows
    }

    /// `x` of `inner`'s rows restricted to the kept ones.
    fn select(&self, full: &[f64], out: &mut [f64]) {
        for (o, &r) in out.iter_mut().zip(&self.rows) {
            *o = full[r];
        }
    }

    /// A per-row function of `inner`, restricted to the kept rows.
    fn rows_of(&self, out: &mut [f64], f: impl FnOnce(&mut [f64])) {
        let mut full = vec![0.0; self.inner.n_constraints()];
        f(&mut full);
        self.select(&full, out);
    }
}

impl<S: System + ?Sized> System for RowSubset<'_, S> {
    fn n_coords(&self) -> usize {
        self.inner.n_coords()
    }
    fn n_constraints(&self) -> usize {
        self.rows.len()
    }
    fn mass_pattern(&self) -> Pattern {
        self.inner.mass_pattern()
    }
    fn mass_into(&self, t: f64, u: &[f64], mass: &mut [f64]) {
        self.inner.mass_into(t, u, mass);
    }
    fn forces_into(&self, t: f64, u: &[f64], v: &[f64], g: &mut [f64]) {
        self.inner.forces_into(t, u, v, g);
    }
    fn phi_into(&self, t: f64, u: &[f64], phi: &mut [f64]) {
        self.rows_of(phi, |full| self.inner.phi_into(t, u, full));
    }
    fn b_pattern(&self) -> Pattern {
        self.b_pattern.clone()
    }
    fn b_into(&self, t: f64, u: &[f64], b: &mut [f64]) {
        let mut full = vec![0.0; self.inner.b_pattern().len()];
        self.inner.b_into(t, u, &mut full);
        for (o, &e) in b.iter_mut().zip(&self.b_entries) {
            *o = full[e];
        }
    }
    fn coord_name(&self, i: usize) -> String {
        self.inner.coord_name(i)
    }
    fn constraint_name(&self, i: usize) -> String {
        self.inner.constraint_name(self.rows[i])
    }
    fn mass_is_constant(&self) -> bool {
        self.inner.mass_is_constant()
    }
    fn forces_are_constant(&self) -> bool {
        self.inner.forces_are_constant()
    }
    fn tangent_is_symmetric(&self) -> bool {
        self.inner.tangent_is_symmetric()
    }
    fn potential_energy(&self, t: f64, u: &[f64]) -> f64 {
        self.inner.potential_energy(t, u)
    }
    fn conserves_energy(&self) -> bool {
        self.inner.conserves_energy()
    }
    fn jacobians_are_costly(&self) -> bool {
        self.inner.jacobians_are_costly()
    }
    fn fresh_jacobians_pay(&self) -> bool {
        self.inner.fresh_jacobians_pay()
    }
    fn phi_t_into(&self, t: f64, u: &[f64], phi_t: &mut [f64]) {
        self.rows_of(phi_t, |full| self.inner.phi_t_into(t, u, full));
    }
    fn hessian_pattern(&self) -> Pattern {
        self.inner.hessian_pattern()
    }
    fn hessian_into(&self, t: f64, u: &[f64], mu: &[f64], out: &mut [f64]) {
        // The left-out rows weigh nothing in Σ μᵢ ∂²Φᵢ/∂u².
        let mut full = vec![0.0; self.inner.n_constraints()];
        for (&r, &x) in self.rows.iter().zip(mu) {
            full[r] = x;
        }
        self.inner.hessian_into(t, u, &full, out);
    }
    fn accel_rhs_into(&self, t: f64, u: &[f64], v: &[f64], c: &mut [f64]) {
        self.rows_of(c, |full| self.inner.accel_rhs_into(t, u, v, full));
    }
    fn forces_du_pattern(&self) -> Pattern {
        self.inner.forces_du_pattern()
    }
    fn forces_du_into(&self, t: f64, u: &[f64], v: &[f64], g_u: &mut [f64]) {
        self.inner.forces_du_into(t, u, v, g_u);
    }
    fn forces_dv_pattern(&self) -> Pattern {
        self.inner.forces_dv_pattern()
    }
    fn forces_dv_into(&self, t: f64, u: &[f64], v: &[f64], g_v: &mut [f64]) {
        self.inner.forces_dv_into(t, u, v, g_v);
    }
    fn mass_du_pattern(&self) -> Pattern {
        self.inner.mass_du_pattern()
    }
    fn mass_du_into(&self, t: f64, u: &[f64], w: &[f64], out: &mut [f64]) {
        self.inner.mass_du_into(t, u, w, out);
    }
}

#[cfg(test)]
mod tests {
    use super::RowSubset;
    use crate::{PendulumChain, System};

    #[test]
    fn a_subset_keeps_the_rows_it_names_and_their_derivatives() {
        let sys = PendulumChain::paper(1.0, 1.0, 9.81);
        let u = [0.3, -0.9, 0.7];
        let sub = RowSubset::new(&sys, vec![1, 5, 1]);
        assert_eq!(sub.rows(), [1]);
        assert_eq!(sub.n_constraints(), 1);
        assert_eq!(sub.constraint_name(0), sys.constraint_name(1));
        let (mut full, mut one) = (vec![0.0; 2], vec![0.0; 1]);
        sys.phi_into(0.0, &u, &mut full);
        sub.phi_into(0.0, &u, &mut one);
        assert_eq!(one[0], full[1]);
        // B: the row-1 entries of the full pattern, in order.
        let (p, q) = (sys.b_pattern(), sub.b_pattern());
        let mut bf = vec![0.0; p.len()];
        let mut bs = vec![0.0; q.len()];
        sys.b_into(0.0, &u, &mut bf);
        sub.b_into(0.0, &u, &mut bs);
        let expected: Vec<(usize, f64)> = p
            .entries
            .iter()
            .zip(&bf)
            .filter(|((r, _), _)| *r == 1)
            .map(|((_, c), v)| (*c, *v))
            .collect();
        let got: Vec<(usize, f64)> = q
            .entries
            .iter()
            .zip(&bs)
            .map(|((r, c), v)| {
                assert_eq!(*r, 0);
                (*c, *v)
            })
            .collect();
        assert_eq!(got, expected);
        // The Hessian weighs the kept row only.
        let h = sys.hessian_pattern();
        let (mut hf, mut hs) = (vec![0.0; h.len()], vec![0.0; h.len()]);
        sys.hessian_into(0.0, &u, &[0.0, 2.5], &mut hf);
        sub.hessian_into(0.0, &u, &[2.5], &mut hs);
        assert_eq!(hf, hs);
    }
}
