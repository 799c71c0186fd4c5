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

    fn solve_dense(&mut self, rhs: &mut [f64]) {
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
