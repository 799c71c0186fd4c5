//! Redundant constraints: finding the rows of `B` that depend on the ones
//! before them, and running a model that has some with minimum-norm
//! multipliers (`[simulation] redundant = "minimum-norm"`,
//! docs/model-format.md).
//!
//! With dependent rows the KKT matrix of eq. (15) is singular, whatever the
//! mass matrix: the multipliers are not unique. The dependent rows are left
//! out of the solve ([`RowSubset`]), which gives the motion (the kept rows
//! impose the left-out ones near the start) and one set of multipliers;
//! [`MinimumNorm`] turns it into the multipliers of all rows with the least
//! Euclidean norm that give the same constraint forces `Bᵀλ`:
//! `λ = (Bᵀ)⁺ B_keptᵀ λ_kept`, the pseudo-inverse by a singular value
//! decomposition (rank-revealing; dense, for models of up to a few hundred
//! rows).

use mstar_model::{Pattern, RowSubset, SampleRef, System};
use mstar_newmark::Observer;
use nalgebra::{DMatrix, DVector};

mod sparse;

/// Largest `m × n` that takes the dense computations: minimum-norm
/// multipliers (a pseudo-inverse of `Bᵀ`), and the least fill budget of the
/// sparse elimination ([`fill_budget`], the memory of the dense `B`).
pub const DENSE_LIMIT: usize = 4_000_000;

/// Largest `m × n` whose rows are sorted out densely (modified Gram–Schmidt,
/// [`dense_rows`], `O(m n rank)`); above it, by the sparse elimination
/// ([`sparse_rows`]), which finds the same rows. Dense up to 4·10⁶ took
/// 0.16 s of a 0.26 s run of a 100-bar spatial chain (700 × 400, 300 steps;
/// docs/performance.md, "Set-up of a model file"); a chain's sparse
/// elimination costs `O(nnz)`.
pub const SPARSE_FROM: usize = 40_000;

/// The rows of `B` at a state: which are independent, which depend on the
/// rows before them.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Rows {
    /// `rank B`.
    pub rank: usize,
    /// The rows kept: each independent of the kept rows before it.
    pub kept: Vec<usize>,
    /// The rows that depend on the rows before them.
    pub dependent: Vec<usize>,
}

impl Rows {
    fn of((kept, dependent): (Vec<usize>, Vec<usize>)) -> Self {
        Self {
            rank: kept.len(),
            kept,
            dependent,
        }
    }
}

/// Why the rows of `B` were not sorted out: the sparse elimination filled
/// in beyond its budget (a model whose joints couple many bodies at once).
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "the elimination of the rows of B fills in beyond {budget} entries (the model couples many bodies through its joints)"
)]
pub struct NotComputed {
    /// The budget, entries of the eliminated rows.
    pub budget: usize,
}

/// The rows of `B(t, u)`: densely up to `n · m` = [`SPARSE_FROM`], sparsely
/// above.
///
/// # Errors
/// [`NotComputed`] when the sparse elimination exceeds its budget of
/// [`fill_budget`] entries.
pub fn rows<S: System + ?Sized>(sys: &S, t: f64, u: &[f64]) -> Result<Rows, NotComputed> {
    if sys.n_coords() * sys.n_constraints() > SPARSE_FROM {
        // The pattern read once (a copy each time: 10⁶ entries at 10⁵
        // bodies), for the budget and the elimination.
        let p = sys.b_pattern();
        let budget = fill_budget(p.len());
        sparse_rows_of(sys, &p, t, u, budget)
    } else {
        Ok(dense_rows(sys, t, u))
    }
}

/// The entries the sparse elimination may keep for `B` with `nnz` entries:
/// 20 times its own, at least [`DENSE_LIMIT`] (the memory of the dense
/// computation it replaces).
#[must_use]
pub fn fill_budget(nnz: usize) -> usize {
    DENSE_LIMIT.max(20 * nnz)
}

/// The rows of `B(t, u)` by modified Gram–Schmidt on the dense rows (for
/// small models: `O(m n rank)`).
#[must_use]
pub fn dense_rows<S: System + ?Sized>(sys: &S, t: f64, u: &[f64]) -> Rows {
    Rows::of(dependent_rows(&dense_b(sys, t, u)))
}

/// The rows of `B(t, u)` by sparse Gaussian elimination of its rows in order,
/// the same rows as [`dense_rows`] (up to rounding: both call a row
/// dependent when what the rows before it leave of it is at most `1e-10` of
/// its norm), with at most `budget` entries in the eliminated rows.
///
/// # Errors
/// [`NotComputed`] past the budget.
pub fn sparse_rows<S: System + ?Sized>(
    sys: &S,
    t: f64,
    u: &[f64],
    budget: usize,
) -> Result<Rows, NotComputed> {
    sparse_rows_of(sys, &sys.b_pattern(), t, u, budget)
}

/// [`sparse_rows`] with `sys`'s `B` pattern `p` given.
fn sparse_rows_of<S: System + ?Sized>(
    sys: &S,
    p: &Pattern,
    t: f64,
    u: &[f64],
    budget: usize,
) -> Result<Rows, NotComputed> {
    let mut values = vec![0.0; p.len()];
    sys.b_into(t, u, &mut values);
    sparse::dependent_rows(p, &values, budget)
        .map(Rows::of)
        .map_err(|e| NotComputed { budget: e.budget })
}

/// `B(t, u)`, dense, row by row.
#[must_use]
pub fn dense_b<S: System + ?Sized>(sys: &S, t: f64, u: &[f64]) -> Vec<Vec<f64>> {
    let p = sys.b_pattern();
    let mut values = vec![0.0; p.len()];
    sys.b_into(t, u, &mut values);
    p.to_dense(&values)
}

/// The independent rows and the rows that depend on the ones before them:
/// modified Gram–Schmidt with one reorthogonalization, a row whose remainder
/// is at most `1e-10` of its norm counting as dependent (as a zero or NaN
/// row does).
fn dependent_rows(rows: &[Vec<f64>]) -> (Vec<usize>, Vec<usize>) {
    let mut basis: Vec<Vec<f64>> = Vec::new();
    let (mut kept, mut dependent) = (Vec::new(), Vec::new());
    for (i, row) in rows.iter().enumerate() {
        let norm = row.iter().map(|x| x * x).sum::<f64>().sqrt();
        let mut r = row.clone();
        for _ in 0..2 {
            for q in &basis {
                let d: f64 = r.iter().zip(q).map(|(a, b)| a * b).sum();
                r.iter_mut().zip(q).for_each(|(a, b)| *a -= d * b);
            }
        }
        let rest = r.iter().map(|x| x * x).sum::<f64>().sqrt();
        if rest.is_nan() || rest <= 1e-10 * norm || norm == 0.0 {
            dependent.push(i);
        } else {
            r.iter_mut().for_each(|a| *a /= rest);
            basis.push(r);
            kept.push(i);
        }
    }
    (kept, dependent)
}

/// The rows of `sys` to solve on at `(t, u0)`: `Some(kept)` when some rows
/// depend on others, `None` when all are independent or the rows were not
/// sorted out (past the sparse elimination's budget: all rows, and the
/// factorization finds out).
pub fn kept_if_dependent<S: System + ?Sized>(sys: &S, t: f64, u0: &[f64]) -> Option<Vec<usize>> {
    let rows = rows(sys, t, u0).ok()?;
    (!rows.dependent.is_empty()).then_some(rows.kept)
}

/// The multipliers of all rows of `sys` at `(t, u)` from `lambda_kept`, those
/// of the rows `kept`: the minimum-norm ones with the same `Bᵀλ` up to
/// `n · m` = [`DENSE_LIMIT`] ([`MinimumNorm`]), above it `λ_kept` with zeros
/// on the left-out rows (the same `Bᵀλ`, not the least norm).
pub fn all_multipliers<S: System + ?Sized>(
    sys: &S,
    kept: &[usize],
    t: f64,
    u: &[f64],
    lambda_kept: &[f64],
) -> Vec<f64> {
    if sys.n_coords() * sys.n_constraints() <= DENSE_LIMIT {
        return MinimumNorm::new(sys, kept.to_vec())
            .lambda(t, u, lambda_kept)
            .to_vec();
    }
    let mut lambda = vec![0.0; sys.n_constraints()];
    for (&k, &l) in kept.iter().zip(lambda_kept) {
        lambda[k] = l;
    }
    lambda
}

/// The minimum-norm multipliers of all rows from those of the kept rows.
#[derive(Debug)]
pub struct MinimumNorm<'a, S: System + ?Sized> {
    sys: &'a S,
    kept: Vec<usize>,
    lambda: Vec<f64>,
}

impl<'a, S: System + ?Sized> MinimumNorm<'a, S> {
    /// For `sys` solved on the rows `kept`.
    #[must_use]
    pub fn new(sys: &'a S, kept: Vec<usize>) -> Self {
        Self {
            sys,
            kept,
            lambda: vec![0.0; sys.n_constraints()],
        }
    }

    /// `λ = (Bᵀ)⁺ B_keptᵀ λ_kept` at `(t, u)`: the multipliers of all rows
    /// with the least norm among those with the same `f = Bᵀλ`.
    ///
    /// The least-norm solution of `Bᵀλ = f` is `λ = B y` with `BᵀB y = f`,
    /// and `y` may be taken in the span of the kept rows, of which the QR
    /// factorization `B_kᵀ = Q₁R₁` gives an orthonormal basis: `y = Q₁ z`.
    /// With `D = B Q₁` (`m × r`) this is `DᵀD z = Q₁ᵀ f`, and with `D =
    /// Q₂R₂`, `λ = D z = Q₂ R₂⁻ᵀ Q₁ᵀ f` — as accurate as the SVD of `Bᵀ`
    /// (errors `ε κ(B)`) at a fraction of its cost: `O(m n r)` against a
    /// full SVD (`minimum_norm_multipliers_solve_in_the_range_of_b`).
    /// Neither `Q` is formed: `Dᵀ` is the first `r` rows of `Q₁ᵀ Bᵀ` (the
    /// reflections applied to `Bᵀ`), and `λ = Q₂ w = D v` with `R₂ v = w`
    /// (docs/performance.md, "Other measured costs").
    pub fn lambda(&mut self, t: f64, u: &[f64], lambda_kept: &[f64]) -> &[f64] {
        let b = dense_b(self.sys, t, u);
        let (m, n, r) = (b.len(), self.sys.n_coords(), self.kept.len());
        if r == 0 {
            // `f = 0`: the least-norm solution is zero.
            self.lambda.fill(0.0);
            return &self.lambda;
        }
        let bk_t = DMatrix::from_fn(n, r, |i, j| b[self.kept[j]][i]);
        let mut f = &bk_t * DVector::from_column_slice(lambda_kept);
        let qr1 = bk_t.qr();
        let mut bt = DMatrix::from_fn(n, m, |i, j| b[j][i]);
        qr1.q_tr_mul(&mut bt);
        qr1.q_tr_mul(&mut f);
        let d = bt.rows(0, r).transpose();
        let r2 = d.clone().qr().r();
        let v = r2
            .transpose()
            .solve_lower_triangular(&f.rows(0, r))
            .and_then(|w| r2.solve_upper_triangular(&w));
        match v {
            Some(v) if v.iter().all(|x| x.is_finite()) => {
                self.lambda.copy_from_slice((d * v).as_slice());
            }
            _ => self.lambda.fill(f64::NAN),
        }
        &self.lambda
    }
}

/// An observer of a run on [`RowSubset`] that passes on every sample with
/// the minimum-norm multipliers of all rows.
///
/// It also watches the left-out rows: they hold while the redundancy is the
/// one found at the start; [`drifted`](Self::drifted) reports the first
/// sample where one does not (the redundancy changed along the motion, and
/// the motion from there on is not the mechanism's).
pub struct Expanded<'a, 'o, S: System + ?Sized> {
    minimum_norm: MinimumNorm<'a, S>,
    inner: &'o mut dyn Observer,
    left_out: Vec<usize>,
    phi: Vec<f64>,
    drift: Option<Drift>,
    /// The largest `|Φ|` of a left-out row over the samples watched.
    largest: f64,
}

/// The first sample where a left-out row is violated.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Drift {
    /// Time, s.
    pub t: f64,
    /// The row.
    pub row: usize,
    /// `|Φ_row|`, m or rad.
    pub violation: f64,
}

impl<'a, 'o, S: System + ?Sized> Expanded<'a, 'o, S> {
    /// Passes the samples of `subset`'s run on to `inner`.
    pub fn new(subset: &RowSubset<'a, S>, inner: &'o mut dyn Observer) -> Self {
        let sys = subset.inner();
        let m = sys.n_constraints();
        let mut kept = vec![false; m];
        subset.rows().iter().for_each(|&r| kept[r] = true);
        let left_out = (0..m).filter(|&r| !kept[r]).collect();
        Self {
            minimum_norm: MinimumNorm::new(sys, subset.rows().to_vec()),
            inner,
            left_out,
            phi: vec![0.0; m],
            drift: None,
            largest: 0.0,
        }
    }

    /// The largest violation of a left-out row over the samples (until the
    /// first [`drifted`](Self::drifted) one, included), m or rad: the run's
    /// own `max ‖Φ‖∞` is of the rows it solves.
    #[must_use]
    pub fn largest_violation(&self) -> f64 {
        self.largest
    }

    /// The first sample where a left-out row was violated by more than
    /// `1e-8 max(1, ‖u‖∞)`, if any.
    #[must_use]
    pub fn drifted(&self) -> Option<Drift> {
        self.drift
    }

    fn watch(&mut self, s: &SampleRef<'_>) {
        if self.drift.is_some() {
            return;
        }
        self.minimum_norm.sys.phi_into(s.t, s.u, &mut self.phi);
        let scale = s.u.iter().fold(1.0f64, |m, x| m.max(x.abs()));
        let (k, violation) = mstar_kkt::argmax_abs(
            &self
                .left_out
                .iter()
                .map(|&r| self.phi[r])
                .collect::<Vec<_>>(),
        );
        self.largest = self.largest.max(violation);
        if violation > 1e-8 * scale || violation.is_nan() {
            self.drift = Some(Drift {
                t: s.t,
                row: self.left_out[k],
                violation,
            });
        }
    }
}

impl<S: System + ?Sized> Observer for Expanded<'_, '_, S> {
    fn observe(&mut self, s: &SampleRef<'_>) {
        self.watch(s);
        let lambda = self.minimum_norm.lambda(s.t, s.u, s.lambda);
        self.inner.observe(&SampleRef { lambda, ..*s });
    }

    fn reads_energy(&self) -> bool {
        self.inner.reads_energy()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mstar_model::planar::{At, PlanarBuilder, RigidBody};
    use proptest::prelude::*;

    /// A mechanism of `poses.len()` bars joined by revolute joints
    /// `(a, b, sa, sb)` (side 0 is the ground, points along the bars), the
    /// joints of `twice` added a second time.
    fn mechanism(
        poses: &[[f64; 3]],
        joints: &[(usize, usize, f64, f64)],
        twice: &[usize],
    ) -> mstar_model::planar::PlanarSystem {
        let mut b = PlanarBuilder::new();
        let ids: Vec<_> = poses
            .iter()
            .enumerate()
            .map(|(i, &pose)| {
                let body = RigidBody {
                    mass: 1.0,
                    inertia: 0.1,
                    pose,
                    velocity: [0.0; 3],
                };
                b.rigid_body(&format!("b{i}"), body)
            })
            .collect();
        let at = |side: usize, s: f64| match side {
            0 => At::Ground([s, -s]),
            k => At::Body(ids[k - 1], [s, 0.0]),
        };
        let all = joints
            .iter()
            .chain(twice.iter().filter_map(|&k| joints.get(k)));
        for (k, &(a, c, sa, sc)) in all.enumerate() {
            let c = if a == c {
                (c + 1) % (poses.len() + 1)
            } else {
                c
            };
            if a == 0 && c == 0 {
                continue;
            }
            b.revolute(&format!("j{k}"), at(a, sa), at(c, sc));
        }
        b.build().expect("a valid mechanism")
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        #[test]
        fn sparse_rows_are_the_dense_rows(
            poses in prop::collection::vec(prop::array::uniform3(-2.0..2.0f64), 1..6),
            joints in prop::collection::vec((0usize..6, 0usize..6, -1.0..1.0f64, -1.0..1.0f64), 1..9),
            twice in prop::collection::vec(0usize..9, 0..3),
        ) {
            let n = poses.len();
            let joints: Vec<_> = joints.into_iter().map(|(a, c, sa, sc)| (a % (n + 1), c % (n + 1), sa, sc)).collect();
            let sys = mechanism(&poses, &joints, &twice);
            let u = sys.initial_position();
            let dense = dense_rows(&sys, 0.0, &u);
            let sparse = sparse_rows(&sys, 0.0, &u, 1000).expect("within the budget");
            prop_assert_eq!(sparse, dense);
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        /// The least-norm solution of `Bᵀλ = f` is the one in the range of
        /// `B`: checked with the SVD of `B` (nalgebra) on random mechanisms
        /// with repeated joints and random kept multipliers. (The SVD's own
        /// solve is no reference: near degenerate poses its truncation at
        /// `1e-10 σ_max` leaves `Bᵀλ = f` unsolved by up to 7e-4.)
        #[test]
        fn minimum_norm_multipliers_solve_in_the_range_of_b(
            poses in prop::collection::vec(prop::array::uniform3(-2.0..2.0f64), 1..6),
            joints in prop::collection::vec((0usize..6, 0usize..6, -1.0..1.0f64, -1.0..1.0f64), 1..9),
            twice in prop::collection::vec(0usize..9, 0..3),
            seed in prop::collection::vec(-10.0..10.0f64, 40),
        ) {
            let n = poses.len();
            let joints: Vec<_> = joints.into_iter().map(|(a, c, sa, sc)| (a % (n + 1), c % (n + 1), sa, sc)).collect();
            let sys = mechanism(&poses, &joints, &twice);
            let u = sys.initial_position();
            let rows = dense_rows(&sys, 0.0, &u);
            let kept: Vec<usize> = (0..sys.n_constraints()).filter(|r| !rows.dependent.contains(r)).collect();
            let lambda_kept = &seed[..kept.len()];
            let b = dense_b(&sys, 0.0, &u);
            let bt = DMatrix::from_fn(sys.n_coords(), b.len(), |i, j| b[j][i]);
            let mut f = DVector::zeros(sys.n_coords());
            for (&k, &l) in kept.iter().zip(lambda_kept) {
                f += DVector::from_column_slice(&b[k]) * l;
            }
            let mut minimum_norm = MinimumNorm::new(&sys, kept.clone());
            let got = DVector::from_column_slice(minimum_norm.lambda(0.0, &u, lambda_kept));
            // It solves Bᵀλ = f (a NaN fails the comparisons) …
            let tol = 1e-10 * bt.amax() * got.amax().max(1.0) * sys.n_coords() as f64;
            let residual = (&bt * &got - &f).amax();
            prop_assert!(residual <= tol, "residual {residual:e}: {got}");
            // … in the range of B, where the least-norm solution is: the
            // leading columns of Q of B's QR factorization with column
            // pivoting (nalgebra), as many as the kept rows. (Only where its
            // rank, |R_ii| above 1e-10 |R_00|, is theirs: near degenerate
            // poses the two rank tests may count differently.)
            prop_assume!(!kept.is_empty());
            let b_matrix = DMatrix::from_fn(b.len(), sys.n_coords(), |i, j| b[i][j]);
            let qr = b_matrix.col_piv_qr();
            let r = qr.r();
            let rank = (0..r.nrows().min(r.ncols())).filter(|&i| r[(i, i)].abs() > 1e-10 * r[(0, 0)].abs()).count();
            prop_assume!(rank == kept.len());
            let q_r = qr.q().columns(0, rank).into_owned();
            let outside = (&got - &q_r * q_r.tr_mul(&got)).amax();
            // λ carries errors of ε κ(B) of its size (perturbation of a
            // least-squares problem), κ from R's diagonal (a lower bound).
            let kappa = r[(0, 0)].abs() / r[(rank - 1, rank - 1)].abs();
            let bound = 100.0 * f64::EPSILON * kappa * got.amax().max(1.0) * (b.len() as f64).sqrt();
            prop_assert!(outside <= bound, "{outside:e} outside the range of B (κ = {kappa:e}): {got}");
        }
    }

    #[test]
    fn a_repeated_joint_is_dependent_and_the_fill_budget_is_kept() {
        let poses = [[0.5, 0.0, 0.0], [1.5, 0.0, 0.0], [2.5, 0.0, 0.0]];
        let joints = [(0, 1, 0.0, -0.5), (1, 2, 0.5, -0.5), (2, 3, 0.5, -0.5)];
        let sys = mechanism(&poses, &joints, &[1]);
        let u = sys.initial_position();
        let rows = sparse_rows(&sys, 0.0, &u, 1000).expect("within the budget");
        // Rows 6, 7: the second copy of joint 1.
        assert_eq!((rows.rank, rows.dependent), (6, vec![6, 7]));
        assert_eq!(
            sparse_rows(&sys, 0.0, &u, 3),
            Err(NotComputed { budget: 3 })
        );
    }

    #[test]
    fn dependent_rows_are_found_in_order() {
        let rows = vec![
            vec![1.0, 0.0, 0.0],
            vec![0.0, 1.0, 0.0],
            vec![1.0, 1.0, 0.0],
            vec![0.0, 0.0, 2.0],
            vec![0.0, 0.0, 0.0],
        ];
        assert_eq!(dependent_rows(&rows), (vec![0, 1, 3], vec![2, 4]));
    }
}
