//! LU without pivoting of a matrix with a symmetric pattern, stored by its
//! envelope: the lower envelope by rows (row `i` holds columns
//! `first[i] ..= i`, the diagonal last, as in [`EnvelopeLdlt`]) and the upper
//! envelope by columns (column `j` holds rows `first[j] .. j`). `L` (unit
//! lower) and `U` have the same envelope (no fill outside it), and the work
//! is twice that of the LDLᵀ, `O(n w²)` for a band of width `w`.
//!
//! The Schur backend uses it for `C = B S⁻¹ Bᵀ` when `S` is not symmetric
//! (the exact iteration matrix of bodies with gyroscopic terms, theory.md
//! "Spatial bodies"): `C` then has the symmetric pattern of `B Bᵀ` but
//! unsymmetric values. Its symmetric part is positive definite when that of
//! `S⁻¹` is and `B` has full row rank, and then every leading minor is
//! nonzero: no pivoting is needed. A pivot at the rounding level (a
//! redundant constraint) is reported as the LDLᵀ reports it: at most
//! `PIVOT_TOLERANCE` times the terms it is computed from,
//! `|c_ii| + Σ_j |l_ij u_ji|`.
//!
//! [`EnvelopeLdlt`]: crate::envelope::EnvelopeLdlt

use crate::MaxAbs;
use crate::sparse_ldlt::PIVOT_TOLERANCE;

/// The envelope structure, the matrix values, then `L` and `U` in place.
#[derive(Clone, Debug)]
pub(crate) struct EnvelopeLu {
    /// Start of each row of the lower envelope in `values` (`n + 1`
    /// entries; row `i` holds columns `first(i) ..= i`, the diagonal last).
    /// Column `j` of the upper envelope starts at `lower_len + row_ptr[j] −
    /// j` and holds rows `first(j) .. j`: one value fewer than row `j`.
    row_ptr: Vec<u32>,
    /// The lower envelope (by rows, `lower_len` values), then the strict
    /// upper envelope (by columns); after [`factor`](Self::factor) `L` below
    /// the diagonal, `U`'s diagonal on it, and `U` above.
    values: Vec<f64>,
    lower_len: usize,
    /// `1 / u_jj`, contiguous (one read per row in the solve): `L`'s
    /// entries and the solve's divisions by the pivots are products with
    /// it, a multiplication's latency instead of a division's on the chain
    /// from column to column (the values differ from the quotients' by the
    /// rounding of the reciprocal, an ulp).
    d_inv: Vec<f64>,
}

impl EnvelopeLu {
    /// The envelope of `n` rows and columns whose first stored columns (and
    /// rows) are `first` (`first[i] ≤ i`); `None` if the lower envelope has
    /// more than `u32::MAX` values.
    pub(crate) fn new(first: &[usize]) -> Option<Self> {
        let (row_ptr, len) = crate::envelope::row_pointers(first)?;
        let n = first.len();
        Some(Self {
            row_ptr,
            values: vec![0.0; 2 * len - n],
            lower_len: len,
            d_inv: vec![0.0; n],
        })
    }

    /// Row `i`'s positions in the lower values, its first stored column, and
    /// the start of column `i` of the strict upper envelope.
    #[inline]
    fn row(&self, i: usize) -> (std::ops::Range<usize>, usize, usize) {
        row_of(&self.row_ptr, self.lower_len, i)
    }

    /// Position of entry `(r, s)` in the values, `None` outside the envelope.
    pub(crate) fn checked_slot(&self, r: usize, s: usize) -> Option<usize> {
        let n = self.d_inv.len();
        if r >= n || s >= n {
            return None;
        }
        if r >= s {
            let (range, first, _) = self.row(r);
            (first <= s).then(|| range.start + s - first)
        } else {
            let (_, first, upper) = self.row(s);
            (first <= r).then(|| upper + r - first)
        }
    }

    /// The values to fill with the matrix's envelope before
    /// [`factor`](Self::factor) (positions by [`checked_slot`](Self::checked_slot)).
    pub(crate) fn values_mut(&mut self) -> &mut [f64] {
        &mut self.values
    }

    /// Factors in place: `L U`, row `i` of `L` and column `i` of `U` at step
    /// `i` (Crout's order, as a skyline solver does). `Err(i)` when the pivot
    /// `u_ii` is zero at the rounding level (row `i` depends on the rows
    /// before it).
    pub(crate) fn factor(&mut self) -> Result<(), usize> {
        let (lower, upper) = self.values.split_at_mut(self.lower_len);
        for i in 0..self.d_inv.len() {
            let (range, fi, ui) = row_of(&self.row_ptr, self.lower_len, i);
            let (l_done, l_rest) = lower.split_at_mut(range.start);
            let (u_done, u_rest) = upper.split_at_mut(ui - self.lower_len);
            let width = i - fi;
            let (l_row, c_ii) = l_rest[..=width].split_at_mut(width);
            let u_col = &mut u_rest[..width];
            for j in fi..i {
                let (rj, fj, uj) = row_of(&self.row_ptr, self.lower_len, j);
                let k0 = fi.max(fj);
                let (l_j, u_j) = (&l_done[rj.start..], &u_done[uj - self.lower_len..]);
                // u_ji = c_ji − Σ_k l_jk u_ki,  t_ij = c_ij − Σ_k l_ik u_kj.
                let (mut u, mut t) = (u_col[j - fi], l_row[j - fi]);
                for k in k0..j {
                    u -= l_j[k - fj] * u_col[k - fi];
                    t -= l_row[k - fi] * u_j[k - fj];
                }
                u_col[j - fi] = u;
                l_row[j - fi] = t * self.d_inv[j];
            }
            // u_ii = c_ii − Σ_j l_ij u_ji.
            let (mut d, mut scale) = (c_ii[0], c_ii[0].abs());
            for (&l, &u) in l_row.iter().zip(u_col.iter()) {
                d -= l * u;
                scale += (l * u).abs();
            }
            if d.is_nan() || d.abs() <= PIVOT_TOLERANCE * scale {
                return Err(i);
            }
            c_ii[0] = d;
            self.d_inv[i] = 1.0 / d;
        }
        Ok(())
    }

    /// Solves `L U x = b` in place with the last factorization.
    pub(crate) fn solve_in_place(&self, x: &mut [f64]) {
        let n = self.d_inv.len();
        // L z = b (unit diagonal), by rows.
        for i in 0..n {
            let (range, fi, _) = self.row(i);
            let row = &self.values[range.start..range.end - 1];
            let s: f64 = row.iter().zip(&x[fi..i]).map(|(l, z)| l * z).sum();
            x[i] -= s;
        }
        // U x = z by columns from the last: x_i is final once the columns
        // after it have been subtracted.
        for i in (0..n).rev() {
            let (_, fi, ui) = self.row(i);
            let xi = x[i] * self.d_inv[i];
            x[i] = xi;
            let column = &self.values[ui..ui + i - fi];
            for (xk, u) in x[fi..i].iter_mut().zip(column) {
                *xk -= u * xi;
            }
        }
    }

    /// [`solve_in_place`](Self::solve_in_place) returning `‖x‖∞` (NaN if
    /// `x` has a NaN or an infinity).
    pub(crate) fn solve(&self, x: &mut [f64]) -> f64 {
        self.solve_in_place(x);
        let mut max = MaxAbs::new();
        for &xi in x.iter() {
            max.push(xi);
        }
        if max.is_finite() {
            max.value()
        } else {
            f64::NAN
        }
    }
}

/// Row `i`'s positions in the lower values, its first stored column, and the
/// start of column `i` of the strict upper envelope (after `lower_len`).
#[inline]
fn row_of(row_ptr: &[u32], lower_len: usize, i: usize) -> (std::ops::Range<usize>, usize, usize) {
    let (start, end) = (row_ptr[i] as usize, row_ptr[i + 1] as usize);
    (start..end, i + 1 - (end - start), lower_len + start - i)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::Lcg;

    /// An unsymmetric matrix with a symmetric envelope pattern and a
    /// positive definite symmetric part (diagonally dominant), as dense rows.
    fn example(n: usize, seed: u64) -> (Vec<usize>, Vec<Vec<f64>>) {
        let mut rng = Lcg::new(seed);
        let first: Vec<usize> = (0..n).map(|i| i.saturating_sub(1 + i % 4)).collect();
        let mut a = vec![vec![0.0; n]; n];
        for i in 0..n {
            for j in first[i]..i {
                a[i][j] = rng.range(-1.0, 1.0);
                a[j][i] = rng.range(-1.0, 1.0);
            }
        }
        for i in 0..n {
            a[i][i] = 1.0 + (0..n).map(|j| a[i][j].abs() + a[j][i].abs()).sum::<f64>();
        }
        (first, a)
    }

    fn load(first: &[usize], a: &[Vec<f64>]) -> EnvelopeLu {
        let mut lu = EnvelopeLu::new(first).expect("small");
        for i in 0..a.len() {
            for j in first[i]..=i {
                let (p, q) = (
                    lu.checked_slot(i, j).expect("lower"),
                    lu.checked_slot(j, i).expect("upper"),
                );
                lu.values_mut()[p] = a[i][j];
                lu.values_mut()[q] = a[j][i];
            }
        }
        lu
    }

    #[test]
    fn solves_an_unsymmetric_band_system() {
        let n = 40;
        let (first, a) = example(n, 3);
        let mut lu = load(&first, &a);
        lu.factor().expect("regular");
        let x_true: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
        let mut x: Vec<f64> = (0..n)
            .map(|i| (0..n).map(|j| a[i][j] * x_true[j]).sum())
            .collect();
        let norm = lu.solve(&mut x);
        for (xi, ti) in x.iter().zip(&x_true) {
            assert!((xi - ti).abs() < 1e-13, "{xi} vs {ti}");
        }
        assert_eq!(norm, x.iter().fold(0.0f64, |m, v| m.max(v.abs())));
    }

    #[test]
    fn slots_outside_the_envelope_are_none() {
        let lu = EnvelopeLu::new(&[0, 0, 1]).expect("small");
        // Lower: rows of 1, 2, 2 values (0..5); upper columns 1, 2 at 5, 6.
        assert_eq!(lu.checked_slot(2, 1), Some(3));
        assert_eq!(lu.checked_slot(0, 1), Some(5));
        assert_eq!(lu.checked_slot(1, 2), Some(6));
        assert_eq!(lu.checked_slot(2, 0), None);
        assert_eq!(lu.checked_slot(0, 2), None);
        assert_eq!(lu.checked_slot(3, 3), None);
    }

    #[test]
    fn a_dependent_row_is_named() {
        // Row 2 = row 1 + row 0 in an unsymmetric matrix.
        let a = vec![
            vec![2.0, 1.0, 3.0],
            vec![-1.0, 3.0, 2.0],
            vec![1.0, 4.0, 5.0],
        ];
        let mut lu = load(&[0, 0, 0], &a);
        assert_eq!(lu.factor(), Err(2));
    }
}
