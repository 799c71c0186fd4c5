//! Dense LU with partial pivoting for tiny KKT systems, in place, no allocation
//! after construction.

use crate::KktError;

/// Dense LU factors of a small square matrix given in CSC form.
#[derive(Clone, Debug)]
pub(crate) struct DenseLu {
    n: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    /// Row-major `n × n`: the matrix, then its LU factors.
    a: Vec<f64>,
    /// `perm[k]` = original row in position `k`.
    perm: Vec<usize>,
    work: Vec<f64>,
}

impl DenseLu {
    pub(crate) fn new(n: usize, col_ptr: &[usize], row_idx: &[usize]) -> Self {
        Self {
            n,
            col_ptr: col_ptr.to_vec(),
            row_idx: row_idx.to_vec(),
            a: vec![0.0; n * n],
            perm: (0..n).collect(),
            work: vec![0.0; n],
        }
    }

    /// Factors `P A = L U`. A pivot smaller than `n · ε` times the largest entry
    /// of its column of `A` means that column (unknown) `k` is numerically
    /// dependent on the previous ones.
    pub(crate) fn factor(&mut self, values: &[f64]) -> Result<(), KktError> {
        let n = self.n;
        let a = &mut self.a;
        a.fill(0.0);
        for j in 0..n {
            for k in self.col_ptr[j]..self.col_ptr[j + 1] {
                a[self.row_idx[k] * n + j] += values[k];
            }
        }
        if a.iter().any(|x| !x.is_finite()) {
            return Err(KktError::NonFinite);
        }
        // Column norms of A: a pivot is judged against its own column, so that a
        // badly scaled but regular KKT matrix (unscaled, small h) is not taken
        // for a singular one.
        for (j, w) in self.work.iter_mut().enumerate() {
            *w = (0..n).fold(0.0f64, |m, i| m.max(a[i * n + j].abs()));
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
                for j in 0..n {
                    a.swap(k * n + j, p * n + j);
                }
                self.perm.swap(k, p);
            }
            let pivot = a[k * n + k];
            for i in k + 1..n {
                let l = a[i * n + k] / pivot;
                a[i * n + k] = l;
                if l != 0.0 {
                    for j in k + 1..n {
                        a[i * n + j] -= l * a[k * n + j];
                    }
                }
            }
        }
        Ok(())
    }

    pub(crate) fn solve_in_place(&mut self, rhs: &mut [f64]) {
        let n = self.n;
        let a = &self.a;
        for (k, &p) in self.perm.iter().enumerate() {
            self.work[k] = rhs[p];
        }
        let x = &mut self.work;
        for i in 0..n {
            let mut s = x[i];
            for j in 0..i {
                s -= a[i * n + j] * x[j];
            }
            x[i] = s;
        }
        for i in (0..n).rev() {
            let mut s = x[i];
            for j in i + 1..n {
                s -= a[i * n + j] * x[j];
            }
            x[i] = s / a[i * n + i];
        }
        rhs.copy_from_slice(x);
    }
}
