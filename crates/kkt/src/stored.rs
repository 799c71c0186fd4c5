//! A copy of the factored matrix, for the backends that factor the whole KKT
//! matrix: their residual checks and refinement multiply with it.

use crate::{Csc, KktError, MaxAbs};

/// The structure analysed, the values of the last factorization, and scratch
/// for the absolute row sums.
#[derive(Clone, Debug)]
pub(crate) struct Stored {
    a: Csc,
    row_sums: Vec<f64>,
}

impl Stored {
    /// The structure of `a` (its values are ignored).
    pub(crate) fn new(a: &Csc) -> Self {
        Self {
            a: Csc {
                values: vec![0.0; a.nnz()],
                ..a.clone()
            },
            row_sums: vec![0.0; a.n],
        }
    }

    /// Copies `values` and returns `‖A‖∞`, the largest absolute row sum, in
    /// one pass.
    ///
    /// # Errors
    /// [`KktError::NonFinite`] for a NaN or infinite value.
    ///
    /// # Panics
    /// If `values` does not have one value per structural entry.
    pub(crate) fn load(&mut self, values: &[f64]) -> Result<f64, KktError> {
        assert_eq!(values.len(), self.a.values.len(), "one value per entry");
        self.row_sums.fill(0.0);
        for ((&i, v), &x) in self.a.row_idx.iter().zip(&mut self.a.values).zip(values) {
            *v = x;
            self.row_sums[i] += x.abs();
        }
        let mut norm = MaxAbs::new();
        for &s in &self.row_sums {
            norm.push(s);
        }
        if norm.is_finite() {
            Ok(norm.value())
        } else {
            Err(KktError::NonFinite)
        }
    }

    /// The matrix of the last [`load`](Self::load).
    pub(crate) fn matrix(&self) -> &Csc {
        &self.a
    }

    /// `y = A x`.
    pub(crate) fn mul(&self, x: &[f64], y: &mut [f64]) {
        self.a.mul(x, y);
    }
}
