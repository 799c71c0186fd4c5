//! A KKT backend defined outside mstar-kkt: registered at run time, found by
//! name and by the automatic choice, and solving as the built-in ones do.

use mstar_kkt::{
    Backend, Csc, KktBackend, KktError, KktOptions, KktSolver, Registration, Structure, backends,
    max_abs, register,
};

/// Dense Gaussian elimination with partial pivoting, written here: the
/// matrix copied from the CSC values, factored in place.
struct Gauss {
    a: Csc,
    lu: Vec<f64>,
    perm: Vec<usize>,
}

impl Gauss {
    fn analyse(a: &Csc, _: &KktOptions) -> Result<Box<dyn KktBackend>, KktError> {
        Ok(Box::new(Self {
            a: a.clone(),
            lu: vec![0.0; a.n * a.n],
            perm: (0..a.n).collect(),
        }))
    }
}

impl KktBackend for Gauss {
    fn factor(&mut self, values: &[f64]) -> Result<f64, KktError> {
        let n = self.a.n;
        self.a.values.copy_from_slice(values);
        self.lu.fill(0.0);
        for j in 0..n {
            for (&i, &v) in self.a.column(j).iter().zip(&values[self.a.col_ptr[j]..]) {
                self.lu[i * n + j] = v;
            }
        }
        self.perm = (0..n).collect();
        for k in 0..n {
            let p = (k..n)
                .max_by(|&x, &y| {
                    self.lu[x * n + k]
                        .abs()
                        .total_cmp(&self.lu[y * n + k].abs())
                })
                .unwrap_or(k);
            if self.lu[p * n + k] == 0.0 {
                return Err(KktError::Singular { unknown: Some(k) });
            }
            for j in 0..n {
                self.lu.swap(k * n + j, p * n + j);
            }
            self.perm.swap(k, p);
            for i in k + 1..n {
                let f = self.lu[i * n + k] / self.lu[k * n + k];
                self.lu[i * n + k] = f;
                for j in k + 1..n {
                    self.lu[i * n + j] -= f * self.lu[k * n + j];
                }
            }
        }
        let rows = (0..n).map(|i| {
            (0..n)
                .map(|j| self.a.position(i, j).map_or(0.0, |p| values[p].abs()))
                .sum::<f64>()
        });
        Ok(rows.fold(0.0, f64::max))
    }

    fn solve_in_place(&mut self, rhs: &mut [f64]) -> f64 {
        let n = self.a.n;
        let mut x: Vec<f64> = self.perm.iter().map(|&p| rhs[p]).collect();
        for i in 0..n {
            for j in 0..i {
                x[i] -= self.lu[i * n + j] * x[j];
            }
        }
        for i in (0..n).rev() {
            for j in i + 1..n {
                x[i] -= self.lu[i * n + j] * x[j];
            }
            x[i] /= self.lu[i * n + i];
        }
        rhs.copy_from_slice(&x);
        max_abs(rhs)
    }

    fn mul(&self, x: &[f64], y: &mut [f64]) {
        self.a.mul(x, y);
    }
}

const GAUSS: Registration = Registration {
    backend: Backend::new("gauss"),
    summary: "dense Gaussian elimination written in a test",
    structure: Structure::AUGMENTED,
    symmetric: false,
    analyse: Gauss::analyse,
    automatic: Some(0),
    needs_n_primal: false,
};

/// `[[S, Bᵀ], [B, 0]]`: `S` = diag(2, 3, 4, …) on 30 unknowns, `B` joining
/// neighbours (`x_i − x_{i+1}`, 29 rows): dimension 59, above the dense threshold.
fn kkt() -> Csc {
    let (np, m) = (30, 29);
    let n = np + m;
    let mut pairs = Vec::new();
    for i in 0..np {
        pairs.push((i, i));
    }
    for r in 0..m {
        for c in [r, r + 1] {
            pairs.push((np + r, c));
            pairs.push((c, np + r));
        }
    }
    let mut a = Csc::from_pairs(n, &pairs);
    for j in 0..n {
        for (k, i) in a.column(j).to_vec().into_iter().enumerate() {
            let v = if i == j && i < np {
                2.0 + i as f64
            } else if i.max(j) >= np && i.min(j) < np {
                let (r, c) = if i >= np { (i - np, j) } else { (j - np, i) };
                if c == r { 1.0 } else { -1.0 }
            } else {
                0.0
            };
            a.values[a.col_ptr[j] + k] = v;
        }
    }
    a
}

fn solve(a: &Csc, options: &KktOptions) -> (Backend, Vec<f64>) {
    let mut solver = KktSolver::new(a, options).expect("analysis");
    solver.factor(&a.values).expect("factorization");
    let mut x: Vec<f64> = (0..a.n).map(|i| (i % 7) as f64 - 3.0).collect();
    solver.solve_in_place(&mut x).expect("solve");
    (solver.backend(), x)
}

#[test]
fn a_registered_backend_is_found_by_name_and_by_the_automatic_choice() {
    assert_eq!(Backend::named("gauss"), None, "not before it is registered");
    assert_eq!(register(GAUSS), Ok(Backend::new("gauss")));
    assert_eq!(Backend::named("gauss"), Some(Backend::new("gauss")));
    assert!(backends().iter().any(|r| r.backend.name() == "gauss"));

    // Names that are taken or reserved are refused.
    for name in ["gauss", "lu", "auto", ""] {
        let again = Registration {
            backend: Backend::new(name),
            ..GAUSS
        };
        assert_eq!(register(again), Err(KktError::NameTaken { name }), "{name}");
    }

    // The automatic choice tries it first (rank 0), above the dense threshold.
    let a = kkt();
    let auto = KktOptions::default();
    assert_eq!(auto.candidates(a.n)[0], Backend::new("gauss"));
    assert_eq!(auto.candidates(10), [Backend::DENSE]);
    let (chosen, x) = solve(&a, &auto);
    assert_eq!(chosen, Backend::new("gauss"));

    // It solves as the built-in sparse LU does.
    let lu = KktOptions {
        backend: Backend::SPARSE_LU,
        ..auto
    };
    let (_, reference) = solve(&a, &lu);
    assert!(x.iter().all(|v| v.is_finite()));
    let scale = max_abs(&reference);
    for (i, (xi, ri)) in x.iter().zip(&reference).enumerate() {
        assert!(
            (xi - ri).abs() <= 1e-12 * scale,
            "unknown {i}: {xi} against {ri}"
        );
    }
}
