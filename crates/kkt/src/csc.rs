//! The compressed sparse column matrix every backend reads.

use crate::KktError;

/// A square sparse matrix in compressed sparse column form with sorted row
/// indices and no duplicates.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Csc {
    /// Dimension.
    pub n: usize,
    /// Column pointers, length `n + 1`.
    pub col_ptr: Vec<usize>,
    /// Row indices, length `nnz`.
    pub row_idx: Vec<usize>,
    /// Values, length `nnz`.
    pub values: Vec<f64>,
}

impl Csc {
    /// The `n × n` pattern of the `(column, row)` pairs, given in any order
    /// and with repeats, values zero: the columns bucketed by a counting
    /// sort, then each sorted and deduplicated on its own (linear in the
    /// pairs but for the short per-column sorts, where sorting all the
    /// pairs at once took 8 % of reading a 10⁵-body model file).
    ///
    /// # Panics
    /// If a column is not below `n`.
    #[must_use]
    pub fn from_pairs(n: usize, pairs: &[(usize, usize)]) -> Self {
        Self::from_pairs_of(n, || pairs.iter().copied())
    }

    /// As [`from_pairs`](Self::from_pairs), the pairs given by `pairs()`
    /// (called twice, the same pairs each time): no list of them is made
    /// when they come from several lists or are computed.
    ///
    /// # Panics
    /// If a column is not below `n`.
    #[must_use]
    pub fn from_pairs_of<I: Iterator<Item = (usize, usize)>>(
        n: usize,
        pairs: impl Fn() -> I,
    ) -> Self {
        let mut start = vec![0usize; n + 1];
        for (j, _) in pairs() {
            start[j + 1] += 1;
        }
        for j in 0..n {
            start[j + 1] += start[j];
        }
        let mut rows = vec![0usize; start[n]];
        let mut next = start.clone();
        for (j, i) in pairs() {
            rows[next[j]] = i;
            next[j] += 1;
        }
        let mut col_ptr = next;
        col_ptr[0] = 0;
        let mut len = 0;
        for j in 0..n {
            let column = &mut rows[start[j]..start[j + 1]];
            column.sort_unstable();
            for k in start[j]..start[j + 1] {
                // Compacted in place: `len <= k`, and the rows before it
                // are this column's distinct rows so far.
                if len == col_ptr[j] || rows[len - 1] != rows[k] {
                    rows[len] = rows[k];
                    len += 1;
                }
            }
            col_ptr[j + 1] = len;
        }
        rows.truncate(len);
        rows.shrink_to_fit();
        Self {
            n,
            col_ptr,
            row_idx: rows,
            values: vec![0.0; len],
        }
    }

    /// Number of stored values.
    #[must_use]
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    /// The row indices of column `j`.
    #[must_use]
    pub fn column(&self, j: usize) -> &[usize] {
        &self.row_idx[self.col_ptr[j]..self.col_ptr[j + 1]]
    }

    /// `y = A x`.
    ///
    /// # Panics
    /// If `x` or `y` is not of length `n`.
    pub fn mul(&self, x: &[f64], y: &mut [f64]) {
        assert_eq!(x.len(), self.n);
        assert_eq!(y.len(), self.n);
        y.fill(0.0);
        for (j, &xj) in x.iter().enumerate() {
            for k in self.col_ptr[j]..self.col_ptr[j + 1] {
                y[self.row_idx[k]] += self.values[k] * xj;
            }
        }
    }

    /// The dense row-major matrix (for tests, diagnostics and small systems).
    #[must_use]
    pub fn to_dense(&self) -> Vec<Vec<f64>> {
        let mut a = vec![vec![0.0; self.n]; self.n];
        for j in 0..self.n {
            for k in self.col_ptr[j]..self.col_ptr[j + 1] {
                a[self.row_idx[k]][j] += self.values[k];
            }
        }
        a
    }

    /// Checks the structure: lengths, bounds, sorted unique row indices.
    ///
    /// # Errors
    /// [`KktError::Structure`] saying what is malformed.
    pub fn validate(&self) -> Result<(), KktError> {
        let bad = |why: &str| Err(KktError::Structure(why.to_string()));
        if self.col_ptr.len() != self.n + 1 || self.col_ptr[0] != 0 {
            return bad("col_ptr must have n + 1 entries starting at 0");
        }
        if self.col_ptr.windows(2).any(|w| w[0] > w[1]) {
            return bad("col_ptr must be non-decreasing");
        }
        if self.col_ptr[self.n] != self.row_idx.len() || self.values.len() != self.row_idx.len() {
            return bad("row_idx and values must have col_ptr[n] entries");
        }
        for j in 0..self.n {
            let col = self.column(j);
            if col.windows(2).any(|w| w[0] >= w[1]) || col.iter().any(|&i| i >= self.n) {
                return bad("row indices must be sorted, unique and below n");
            }
        }
        Ok(())
    }

    /// Position of entry `(i, j)` in the values, if it is stored.
    #[must_use]
    pub fn position(&self, i: usize, j: usize) -> Option<usize> {
        self.column(j)
            .binary_search(&i)
            .ok()
            .map(|k| self.col_ptr[j] + k)
    }
}

/// The 2-norm condition number `σ_max / σ_min` of a (small) sparse matrix,
/// computed from the singular values of its dense form; `inf` when singular.
/// For diagnostics and conditioning studies, not for large systems.
#[must_use]
pub fn condition_number(a: &Csc) -> f64 {
    let mut d = nalgebra::DMatrix::<f64>::zeros(a.n, a.n);
    for j in 0..a.n {
        for k in a.col_ptr[j]..a.col_ptr[j + 1] {
            d[(a.row_idx[k], j)] += a.values[k];
        }
    }
    let s = d.singular_values();
    let max = crate::max_abs(s.as_slice());
    let min = s.iter().fold(f64::INFINITY, |m, &x| m.min(x));
    if max.is_nan() {
        f64::NAN
    } else if min == 0.0 {
        f64::INFINITY
    } else {
        max / min
    }
}

#[cfg(test)]
mod tests {
    use super::Csc;
    use proptest::prelude::*;

    proptest! {
        /// The pattern is that of all the pairs sorted and deduplicated.
        #[test]
        fn from_pairs_is_the_sorted_unique_pairs(
            n in 1usize..12,
            raw in proptest::collection::vec((0usize..100, 0usize..100), 0..80),
        ) {
            let pairs: Vec<(usize, usize)> = raw.iter().map(|&(j, i)| (j % n, i % n)).collect();
            let c = Csc::from_pairs(n, &pairs);
            c.validate().map_err(|e| TestCaseError::fail(e.to_string()))?;
            let mut want = pairs.clone();
            want.sort_unstable();
            want.dedup();
            let got: Vec<(usize, usize)> = (0..n)
                .flat_map(|j| c.column(j).iter().map(move |&i| (j, i)))
                .collect();
            prop_assert_eq!(got, want);
            prop_assert_eq!(c.values.len(), c.row_idx.len());
        }
    }
}
