//! Dense LU with partial pivoting for tiny KKT systems, in place, no allocation
//! after construction.

use crate::backend::{Backend, KktBackend, Registration, Structure};
use crate::stored::Stored;
use crate::{Csc, KktError, KktOptions, max_abs};

/// The `dense` backend.
pub(crate) const REGISTRATION: Registration = Registration {
    backend: Backend::DENSE,
    summary: "dense LU with partial pivoting (tiny systems)",
    structure: Structure::AUGMENTED,
    symmetric: false,
    analyse: |a, _: &KktOptions| Ok(Box::new(DenseLu::new(a))),
    automatic: None,
    needs_n_primal: false,
};

/// Dense LU factors of a small square matrix given in CSC form.
#[derive(Clone, Debug)]
pub(crate) struct DenseLu {
    n: usize,
    stored: Stored,
    /// Row-major `n × n`: the matrix, then its LU factors.
    a: Vec<f64>,
    /// `perm[k]` = original row in position `k`.
    perm: Vec<usize>,
    work: Vec<f64>,
}

impl DenseLu {
    fn new(a: &Csc) -> Self {
        let n = a.n;
        Self {
            n,
            stored: Stored::new(a),
            a: vec![0.0; n * n],
            perm: (0..n).collect(),
            work: vec![0.0; n],
        }
    }

    /// Factors `P A = L U`. A pivot smaller than `n · ε` times the largest entry
    /// of its column of `A` means that column (unknown) `k` is numerically
    /// dependent on the previous ones.
    fn factor_dense(&mut self) -> Result<(), KktError> {
        let n = self.n;
        if n == 0 {
            // (Rows of no entries cannot be walked as chunks.)
            return Ok(());
        }
        let a = &mut self.a;
        a.fill(0.0);
        let m = self.stored.matrix();
        for j in 0..n {
            for k in m.col_ptr[j]..m.col_ptr[j + 1] {
                a[m.row_idx[k] * n + j] += m.values[k];
            }
        }
        // Column norms of A: a pivot is judged against its own column, so that a
        // badly scaled but regular KKT matrix (unscaled, small h) is not taken
        // for a singular one.
        self.work.fill(0.0);
        for row in a.chunks_exact(n) {
            for (w, x) in self.work.iter_mut().zip(row) {
                *w = w.max(x.abs());
            }
        }
        let eps = (n as f64) * f64::EPSILON;
        for (k, p) in self.perm.iter_mut().enumerate() {
            *p = k;
        }
        for k in 0..n {
            let (mut p, mut best) = (k, a[k * n + k].abs());
            for i in k + 1..n {
                let v = a[i * n + k].abs();
                if v > best {
                    (p, best) = (i, v);
                }
            }
            if best <= eps * self.work[k] || best == 0.0 {
                return Err(KktError::Singular { unknown: Some(k) });
            }
            if p != k {
                let (upper, lower) = a.split_at_mut(p * n);
                upper[k * n..(k + 1) * n].swap_with_slice(&mut lower[..n]);
                self.perm.swap(k, p);
            }
            // The rows below `k` take `l` times row `k` (its part right of
            // the diagonal), row by row through slices: the same operations
            // in the same order as by index, without the bounds checks that
            // kept the inner loop from being vectorized.
            let (done, below) = a.split_at_mut((k + 1) * n);
            let pivot_row = &done[k * n + k + 1..(k + 1) * n];
            let pivot = done[k * n + k];
            for row in below.chunks_exact_mut(n) {
                let l = row[k] / pivot;
                row[k] = l;
                if l != 0.0 {
                    for (x, &u) in row[k + 1..].iter_mut().zip(pivot_row) {
                        *x -= l * u;
                    }
                }
            }
        }
        Ok(())
    }

    fn solve_dense(&mut self, rhs: &mut [f64]) {
        let n = self.n;
        if n == 0 {
            return;
        }
        let a = &self.a;
        for (k, &p) in self.perm.iter().enumerate() {
            self.work[k] = rhs[p];
        }
        let x = &mut self.work;
        // Rows through slices (the same operations in the same order).
        for (i, row) in a.chunks_exact(n).enumerate() {
            let s = row[..i]
                .iter()
                .zip(&x[..i])
                .fold(x[i], |s, (l, x)| s - l * x);
            x[i] = s;
        }
        for (i, row) in a.chunks_exact(n).enumerate().rev() {
            let s = row[i + 1..]
                .iter()
                .zip(&x[i + 1..])
                .fold(x[i], |s, (u, x)| s - u * x);
            x[i] = s / row[i];
        }
        rhs.copy_from_slice(x);
    }
}

impl KktBackend for DenseLu {
    fn factor(&mut self, values: &[f64]) -> Result<f64, KktError> {
        let norm = self.stored.load(values)?;
        self.factor_dense()?;
        Ok(norm)
    }

    fn solve_in_place(&mut self, rhs: &mut [f64]) -> f64 {
        self.solve_dense(rhs);
        max_abs(rhs)
    }

    fn mul(&self, x: &[f64], y: &mut [f64]) {
        self.stored.mul(x, y);
    }
}
