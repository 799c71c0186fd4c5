//! Structural sparsity patterns and the value buffers that go with them.

/// The structural sparsity of a matrix, declared once by a [`crate::System`].
///
/// A pattern is a list of `(row, col)` entries. The matching *value buffer* is a
/// `&[f64]` of the same length whose `k`-th value belongs to the `k`-th entry.
/// Entries may repeat: repeated entries are summed, which lets elements of a
/// model contribute to the same matrix position independently.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Pattern {
    /// Number of rows of the matrix.
    pub nrows: usize,
    /// Number of columns of the matrix.
    pub ncols: usize,
    /// The `(row, col)` of each value, in the order the values are written.
    pub entries: Vec<(usize, usize)>,
}

impl Pattern {
    /// An empty pattern of an `nrows × ncols` matrix.
    #[must_use]
    pub fn new(nrows: usize, ncols: usize) -> Self {
        Self {
            nrows,
            ncols,
            entries: Vec::new(),
        }
    }

    /// A pattern from a list of entries.
    #[must_use]
    pub fn from_entries(nrows: usize, ncols: usize, entries: Vec<(usize, usize)>) -> Self {
        Self {
            nrows,
            ncols,
            entries,
        }
    }

    /// The full diagonal of an `n × n` matrix.
    #[must_use]
    pub fn diagonal(n: usize) -> Self {
        Self::from_entries(n, n, (0..n).map(|i| (i, i)).collect())
    }

    /// Appends the entry `(row, col)` and returns its index in the value buffer.
    pub fn push(&mut self, row: usize, col: usize) -> usize {
        self.entries.push((row, col));
        self.entries.len() - 1
    }

    /// Number of entries (the length of the value buffer).
    #[must_use]
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// `true` when the pattern has no entries.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// The first entry outside the `nrows × ncols` bounds, if any.
    #[must_use]
    pub fn out_of_bounds(&self) -> Option<(usize, usize)> {
        self.entries
            .iter()
            .copied()
            .find(|&(i, j)| i >= self.nrows || j >= self.ncols)
    }

    /// `y += A x` for the matrix `A` with these values.
    ///
    /// # Panics
    /// If `values`, `x` or `y` do not match the pattern's dimensions.
    pub fn mul_add(&self, values: &[f64], x: &[f64], y: &mut [f64]) {
        self.product::<false, false>(values, x, y);
    }

    /// `y −= A x`, for a residual `r − A x` formed in place (no buffer for
    /// `A x`).
    ///
    /// # Panics
    /// As [`mul_add`](Self::mul_add).
    pub fn mul_sub(&self, values: &[f64], x: &[f64], y: &mut [f64]) {
        self.product::<false, true>(values, x, y);
    }

    /// `y += Aᵀ x` for the matrix `A` with these values.
    ///
    /// # Panics
    /// If `values`, `x` or `y` do not match the pattern's dimensions.
    pub fn mul_transpose_add(&self, values: &[f64], x: &[f64], y: &mut [f64]) {
        self.product::<true, false>(values, x, y);
    }

    /// `y −= Aᵀ x`, as [`mul_sub`](Self::mul_sub).
    ///
    /// # Panics
    /// As [`mul_transpose_add`](Self::mul_transpose_add).
    pub fn mul_transpose_sub(&self, values: &[f64], x: &[f64], y: &mut [f64]) {
        self.product::<true, true>(values, x, y);
    }

    /// `y ± A x` (`A` or, with `TRANSPOSE`, `Aᵀ`; subtracting with `SUB`):
    /// one loop for the four products, the choices resolved at compile time.
    fn product<const TRANSPOSE: bool, const SUB: bool>(
        &self,
        values: &[f64],
        x: &[f64],
        y: &mut [f64],
    ) {
        let (rows, cols) = if TRANSPOSE {
            (self.ncols, self.nrows)
        } else {
            (self.nrows, self.ncols)
        };
        assert_eq!(values.len(), self.entries.len());
        assert_eq!(x.len(), cols);
        assert_eq!(y.len(), rows);
        for (&(i, j), &a) in self.entries.iter().zip(values) {
            let (to, from) = if TRANSPOSE { (j, i) } else { (i, j) };
            if SUB {
                y[to] -= a * x[from];
            } else {
                y[to] += a * x[from];
            }
        }
    }

    /// The dense row-major matrix (duplicates summed); for tests and small systems.
    #[must_use]
    pub fn to_dense(&self, values: &[f64]) -> Vec<Vec<f64>> {
        let mut a = vec![vec![0.0; self.ncols]; self.nrows];
        for (&(i, j), &v) in self.entries.iter().zip(values) {
            a[i][j] += v;
        }
        a
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn products_sum_duplicates() {
        let p = Pattern::from_entries(2, 3, vec![(0, 0), (1, 2), (0, 0)]);
        let vals = [1.0, 2.0, 3.0];
        let mut y = [0.0; 2];
        p.mul_add(&vals, &[1.0, 10.0, 100.0], &mut y);
        assert_eq!(y, [4.0, 200.0]);
        let mut z = [0.0; 3];
        p.mul_transpose_add(&vals, &[1.0, 1.0], &mut z);
        assert_eq!(z, [4.0, 0.0, 2.0]);
        // The subtracting forms undo the adding ones.
        p.mul_sub(&vals, &[1.0, 10.0, 100.0], &mut y);
        assert_eq!(y, [0.0, 0.0]);
        p.mul_transpose_sub(&vals, &[1.0, 2.0], &mut z);
        assert_eq!(z, [0.0, 0.0, -2.0]);
        assert_eq!(p.to_dense(&vals)[0][0], 4.0);
        assert_eq!(p.out_of_bounds(), None);
        assert_eq!(
            Pattern::from_entries(1, 1, vec![(0, 1)]).out_of_bounds(),
            Some((0, 1))
        );
    }
}
