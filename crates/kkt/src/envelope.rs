//! LDLᵀ without pivoting of a symmetric matrix stored by its lower envelope
//! (profile, or skyline): row `i` holds columns `first[i] ..= i` contiguously.
//! The factor has the same envelope (no fill outside it), every pass is
//! sequential in memory, and the work is `Σ_i (i − first[i])²`: for a
//! band of width `w`, `O(n w²)`. The Schur backend uses it for
//! `C = B S⁻¹ Bᵀ` when the constraints' own order gives a narrow envelope (a
//! chain's joints in order: width 3), which is then faster than a general
//! sparse factorization.
//!
//! The pivot check is that of `sparse_ldlt`: a pivot at most
//! `PIVOT_TOLERANCE` times the terms it is computed from,
//! `|c_ii| + Σ_j l_ij² |d_j|`, is taken for zero.

use crate::MaxAbs;
use crate::sparse_ldlt::PIVOT_TOLERANCE;

/// The start of each row of the lower envelope whose rows `i` hold columns
/// `first[i] ..= i` (`n + 1` entries), and its length; `None` beyond
/// `u32::MAX` values (32-bit pointers: the solves stream them for a long
/// chain). Shared by [`EnvelopeLdlt`] and the envelope LU.
pub(crate) fn row_pointers(first: &[usize]) -> Option<(Vec<u32>, usize)> {
    let mut row_ptr = Vec::with_capacity(first.len() + 1);
    let mut len = 0usize;
    row_ptr.push(0);
    for (i, &f) in first.iter().enumerate() {
        len += i + 1 - f.min(i);
        row_ptr.push(u32::try_from(len).ok()?);
    }
    Some((row_ptr, len))
}

/// The envelope structure, the matrix values, then the factor in place.
#[derive(Clone, Debug)]
pub(crate) struct EnvelopeLdlt {
    /// Start of each row in `values` (`n + 1` entries). Row `i` holds columns
    /// `first(i) ..= i`, the diagonal last. 32 bits: the solve streams these
    /// from memory for a long chain.
    row_ptr: Vec<u32>,
    /// The lower envelope of the matrix (after [`values_mut`] filling), then
    /// `L` below the diagonal and `D` on it.
    values: Vec<f64>,
    /// `D` again, contiguous (one read per row in the solve, not a cache line).
    d: Vec<f64>,
    /// The factorization's updates `t_ij −= Σ_k t_ik l_jk` with at least
    /// one term, row by row (`update_ptr`): see [`Update`].
    updates: Vec<Update>,
    /// Start of each row's updates in `updates` (`n + 1` entries).
    update_ptr: Vec<u32>,
}

/// One entry `(i, j)` of the factor whose sum has terms: its position in
/// row `i` (`j − first[i]`), the end of row `j`'s terms in the values (the
/// position of its diagonal: the terms are its last `m` entries before it)
/// and their number `m =
/// min(j − first[i], j − first[j])`. Computed once from the envelope: an
/// entry without terms (a row's first, or a column whose row starts at its
/// diagonal) costs the factorization nothing, and the others no index
/// arithmetic (the factorization of a small closed loop's `C` spent more
/// on that than on its terms, docs/performance.md).
#[derive(Clone, Copy, Debug)]
struct Update {
    at: u32,
    end: u32,
    m: u32,
}

/// [`Update`]s of the envelope with row pointers `row_ptr`, and where each
/// row's start; `None` beyond 32-bit counts.
fn updates_of(row_ptr: &[u32]) -> Option<(Vec<Update>, Vec<u32>)> {
    let n = row_ptr.len() - 1;
    let (mut updates, mut update_ptr) = (Vec::new(), Vec::with_capacity(n + 1));
    update_ptr.push(0);
    for i in 0..n {
        let (_, fi) = row_of(row_ptr, i);
        for j in fi..i {
            let (rj, fj) = row_of(row_ptr, j);
            let m = j - fi.max(fj);
            if m > 0 {
                updates.push(Update {
                    at: u32::try_from(j - fi).ok()?,
                    end: u32::try_from(rj.end - 1).ok()?,
                    m: u32::try_from(m).ok()?,
                });
            }
        }
        update_ptr.push(u32::try_from(updates.len()).ok()?);
    }
    Some((updates, update_ptr))
}

impl EnvelopeLdlt {
    /// The envelope of `n` rows whose first stored columns are `first`
    /// (`first[i] ≤ i`); `None` if it has more than `u32::MAX` values.
    pub(crate) fn new(first: &[usize]) -> Option<Self> {
        let (row_ptr, len) = row_pointers(first)?;
        let (updates, update_ptr) = updates_of(&row_ptr)?;
        Some(Self {
            row_ptr,
            values: vec![0.0; len],
            d: vec![0.0; first.len()],
            updates,
            update_ptr,
        })
    }

    /// The positions of row `i` in `values` and its first stored column.
    #[inline]
    fn row(&self, i: usize) -> (std::ops::Range<usize>, usize) {
        row_of(&self.row_ptr, i)
    }

    /// Position of entry `(r, s)`, `first(r) ≤ s ≤ r`, in the values.
    pub(crate) fn slot(&self, r: usize, s: usize) -> usize {
        let (range, first) = self.row(r);
        debug_assert!(first <= s && s <= r);
        range.start + s - first
    }

    /// Position of entry `(r, s)` in the values, `None` outside the envelope.
    pub(crate) fn checked_slot(&self, r: usize, s: usize) -> Option<usize> {
        if r >= self.d.len() {
            return None;
        }
        let (range, first) = self.row(r);
        (first <= s && s <= r).then(|| range.start + s - first)
    }

    /// Adds `v` to entry `(r, s)`, `first(r) ≤ s ≤ r`, before
    /// [`factor`](Self::factor).
    #[inline]
    pub(crate) fn add(&mut self, r: usize, s: usize, v: f64) {
        let k = self.slot(r, s);
        self.values[k] += v;
    }

    /// The values to fill with the matrix's lower envelope before
    /// [`factor`](Self::factor).
    pub(crate) fn values_mut(&mut self) -> &mut [f64] {
        &mut self.values
    }

    /// Factors in place: `L D Lᵀ`. `Err(i)` when the pivot of row `i` is zero
    /// at the rounding level (row `i` depends on the rows before it).
    pub(crate) fn factor(&mut self) -> Result<(), usize> {
        let n = self.d.len();
        for i in 0..n {
            let (range, fi) = self.row(i);
            let (done, rest) = self.values.split_at_mut(range.start);
            let row = &mut rest[..range.len()];
            let updates =
                &self.updates[self.update_ptr[i] as usize..self.update_ptr[i + 1] as usize];
            eliminate_row(done, row, updates);
            // l_ij = t_ij / d_j; d_i = c_ii − Σ_j t_ij l_ij.
            let (below, diagonal) = row.split_at_mut(i - fi);
            let c_ii = diagonal[0];
            let (mut d, mut scale) = (c_ii, c_ii.abs());
            let d_before = &self.d[fi..i];
            for k in 0..below.len() {
                let t = below[k];
                let l = t / d_before[k];
                below[k] = l;
                d -= t * l;
                scale += (t * l).abs();
            }
            if d.is_nan() || d.abs() <= PIVOT_TOLERANCE * scale {
                return Err(i);
            }
            diagonal[0] = d;
            self.d[i] = d;
        }
        Ok(())
    }

    /// Solves `L D Lᵀ x = b` in place with the last factorization.
    pub(crate) fn solve_in_place(&self, x: &mut [f64]) {
        self.solve(x, false);
    }

    /// Solves `L D Lᵀ x = b` in place and stores `−x` (when `negate`; the
    /// caller then saves a pass negating `b`: the solve is linear and its
    /// rounding symmetric, so `−x` is bit for bit the solution for `−b`).
    /// Returns `‖x‖∞`, NaN if `x` has a NaN or an infinity.
    pub(crate) fn solve(&self, x: &mut [f64], negate: bool) -> f64 {
        let n = self.d.len();
        let x = &mut x[..n];
        self.forward(x);
        let max = self.backward(x, if negate { -1.0 } else { 1.0 });
        if max.is_finite() {
            max.value()
        } else {
            f64::NAN
        }
    }

    /// `L z = b` in place, row by row. The term of column `i − 1` (a row's
    /// last below the diagonal) is added last, from `z_{i−1}` kept in a
    /// register: the chain of dependent operations from row to row is one
    /// product and two sums, without a store and a load of `z_{i−1}`. The
    /// sums are those of `Iterator::sum` over the row in order (from
    /// `−0.0`): the same values to the bit.
    fn forward(&self, x: &mut [f64]) {
        let mut previous = 0.0;
        for (i, w) in self.row_ptr.windows(2).enumerate() {
            let l = &self.values[w[0] as usize..w[1] as usize - 1];
            let (done, rest) = x.split_at_mut(i);
            let s = match l.split_last() {
                Some((&l_last, l_rest)) => {
                    let z = &done[i - l.len()..];
                    let head: f64 = l_rest.iter().zip(z).map(|(l, z)| l * z).sum();
                    head + l_last * previous
                }
                None => -0.0,
            };
            let zi = rest[0] - s;
            rest[0] = zi;
            previous = zi;
        }
    }

    /// `D w = z`, then `Lᵀ x = w`, in place from the last row up: each
    /// row's `x_i` (final once the rows below it have been subtracted) is
    /// subtracted from the entries above it; `x_{i−1}`'s update stays in a
    /// register (it is the next row's `x_i`). Each `w_k = z_k / d_k` is
    /// formed just before the first row that subtracts from it: the same
    /// operations in the same order as a pass of divisions first, whose
    /// throughput now overlaps the sweep's chain of dependent operations.
    /// Stores `sign x`; returns `‖x‖∞`.
    fn backward(&self, x: &mut [f64], sign: f64) -> MaxAbs {
        let mut max = MaxAbs::new();
        let n = x.len();
        if n == 0 {
            return max;
        }
        let d = &self.d[..n];
        // x[k] for k ≥ divided holds w_k.
        let mut divided = n - 1;
        x[n - 1] /= d[n - 1];
        let mut xi = x[n - 1];
        for (i, w) in self.row_ptr.windows(2).enumerate().rev() {
            let l = &self.values[w[0] as usize..w[1] as usize - 1];
            // The entries this row subtracts from, and x_{i−1}.
            let lowest = if l.is_empty() {
                i.saturating_sub(1)
            } else {
                i - l.len()
            };
            while divided > lowest {
                divided -= 1;
                x[divided] /= d[divided];
            }
            let (above, rest) = x.split_at_mut(i);
            rest[0] = sign * xi;
            max.push(xi);
            let next = match l.split_last() {
                Some((&l_last, l_rest)) => {
                    let fi = i - l.len();
                    for (xk, l) in above[fi..].iter_mut().zip(l_rest) {
                        *xk -= l * xi;
                    }
                    above[i - 1] - l_last * xi
                }
                None => above.last().copied().unwrap_or(0.0),
            };
            xi = next;
        }
        max
    }
}

/// `t_ij = c_ij − Σ_{k<j} t_ik l_jk` (`t_ik = l_ik d_k`) for the columns
/// `j` of one row below its diagonal that have terms (`updates`), in
/// place: `done` holds the rows before it, factored. Row `j`'s entries
/// that meet the row's own are its last `m` before its diagonal.
#[inline]
fn eliminate_row(done: &[f64], row: &mut [f64], updates: &[Update]) {
    for u in updates {
        let (at, end, m) = (u.at as usize, u.end as usize, u.m as usize);
        let (lj, (ti, t)) = (&done[end - m..end], row[at - m..].split_at_mut(m));
        let mut sum = t[0];
        for k in 0..m {
            sum -= ti[k] * lj[k];
        }
        t[0] = sum;
    }
}

/// Row `i`'s positions in the values and its first stored column.
#[inline]
fn row_of(row_ptr: &[u32], i: usize) -> (std::ops::Range<usize>, usize) {
    let (start, end) = (row_ptr[i] as usize, row_ptr[i + 1] as usize);
    (start..end, i + 1 - (end - start))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The symmetric matrix of the envelope `first` with entries `off(i, j)`
    /// below the diagonal (mirrored above) and `diagonal(i)` on it.
    fn symmetric(
        first: &[usize],
        off: impl Fn(usize, usize) -> f64,
        diagonal: impl Fn(usize) -> f64,
    ) -> Vec<Vec<f64>> {
        let n = first.len();
        let mut a = vec![vec![0.0; n]; n];
        for i in 0..n {
            for j in first[i]..i {
                a[i][j] = off(i, j);
                a[j][i] = a[i][j];
            }
            a[i][i] = diagonal(i);
        }
        a
    }

    /// A symmetric positive definite band matrix with a varying envelope.
    fn example(n: usize) -> (Vec<usize>, Vec<Vec<f64>>) {
        let first: Vec<usize> = (0..n).map(|i| i.saturating_sub(1 + i % 3)).collect();
        let a = symmetric(
            &first,
            |i, j| ((i * 7 + j * 3) % 5) as f64 * 0.1 - 0.2,
            |i| 2.0 + (i % 4) as f64,
        );
        (first, a)
    }

    /// Fills an envelope with `a` (its entries within the envelope), factors
    /// it and checks a solve against a known solution.
    fn check_solve(first: &[usize], a: &[Vec<f64>]) {
        let n = first.len();
        let mut env = EnvelopeLdlt::new(first).expect("small");
        for i in 0..n {
            for j in first[i]..=i {
                let k = env.slot(i, j);
                env.values_mut()[k] = a[i][j];
            }
        }
        env.factor().expect("positive definite");
        let x_true: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
        let mut x: Vec<f64> = (0..n)
            .map(|i| (0..n).map(|j| a[i][j] * x_true[j]).sum())
            .collect();
        env.solve_in_place(&mut x);
        for (xi, ti) in x.iter().zip(&x_true) {
            assert!((xi - ti).abs() < 1e-13, "{xi} vs {ti}");
        }
    }

    #[test]
    fn solves_a_system_whose_rows_start_anywhere() {
        // The envelope of a closed loop's `C` (Andrews' squeezer, 18
        // rows): rows that start at their diagonal, rows that start after
        // the rows before them, and entries without terms.
        let first = [0, 0, 0, 0, 2, 2, 2, 2, 2, 2, 10, 10, 6, 6, 14, 14, 8, 8];
        // Diagonally dominant (at most 17 entries of at most 0.15 a row).
        let a = symmetric(
            &first,
            |i, j| ((i * 5 + j * 11) % 7) as f64 * 0.05 - 0.15,
            |i| 3.0 + (i % 3) as f64,
        );
        check_solve(&first, &a);
    }

    #[test]
    fn solves_a_band_system() {
        let n = 40;
        let (first, a) = example(n);
        check_solve(&first, &a);
    }

    #[test]
    fn a_dependent_row_is_named() {
        // Row 2 = row 1 in a semidefinite matrix: [[1,1,1],[1,1,1],[1,1,1]]
        // has its second pivot zero.
        let mut env = EnvelopeLdlt::new(&[0, 0, 0]).expect("small");
        for i in 0..3 {
            for j in 0..=i {
                let k = env.slot(i, j);
                env.values_mut()[k] = 1.0;
            }
        }
        assert_eq!(env.factor(), Err(1));
    }
}
