//! Test matrices: KKT systems of planar chains of rigid bodies.

use crate::Csc;

/// A tiny deterministic generator (64-bit LCG, Knuth's constants).
pub(crate) struct Lcg(u64);

impl Lcg {
    pub(crate) fn new(seed: u64) -> Self {
        Self(seed ^ 0x9e37_79b9_7f4a_7c15)
    }

    /// Uniform in `[0, 1)`.
    pub(crate) fn next_f64(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in `[lo, hi)`.
    pub(crate) fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next_f64()
    }
}

/// The KKT matrix `[[S, Bᵀ], [B, 0]]` of a planar chain of `n_bodies` rigid
/// bodies `(x, y, θ)` joined by revolute joints (joint 0 pins body 0 to the
/// ground, joint `k` joins bodies `k − 1` and `k`), with `S = c M + BᵀB`
/// (symmetric positive definite). Unknowns: `3 n_bodies` coordinates, then `2
/// n_bodies` multipliers (x and y row of each joint), plus one more if
/// `duplicate = Some((r, f))`: constraint row `r` times `f` (a redundant
/// constraint). The structure depends only on `n_bodies` and `duplicate`.
pub(crate) fn chain(n_bodies: usize, seed: u64, duplicate: Option<(usize, f64)>) -> Csc {
    chain_with(n_bodies, seed, duplicate, true)
}

/// [`chain`] with `S = c M + BᵀB` (`augmented`) or `S = c M` (block-diagonal,
/// for the Schur backend).
pub(crate) fn chain_with(
    n_bodies: usize,
    seed: u64,
    duplicate: Option<(usize, f64)>,
    augmented: bool,
) -> Csc {
    let mut rng = Lcg::new(seed);
    let np = 3 * n_bodies;
    // Constraint rows as (coordinate, value) lists.
    let mut rows: Vec<Vec<(usize, f64)>> = Vec::with_capacity(2 * n_bodies + 1);
    for k in 0..n_bodies {
        let (th, l1) = (rng.range(-3.0, 3.0), rng.range(0.5, 1.5));
        let (mut rx, mut ry) = (
            vec![(3 * k, 1.0), (3 * k + 2, -l1 * th.sin())],
            vec![(3 * k + 1, 1.0), (3 * k + 2, l1 * th.cos())],
        );
        if k > 0 {
            let (thp, l2) = (rng.range(-3.0, 3.0), rng.range(0.5, 1.5));
            rx.extend([(3 * k - 3, -1.0), (3 * k - 1, -l2 * thp.sin())]);
            ry.extend([(3 * k - 2, -1.0), (3 * k - 1, l2 * thp.cos())]);
        }
        rows.push(rx);
        rows.push(ry);
    }
    if let Some((r, f)) = duplicate {
        let row = rows[r].iter().map(|&(p, v)| (p, f * v)).collect();
        rows.push(row);
    }
    let n = np + rows.len();
    let mut cols: Vec<Vec<(usize, f64)>> = vec![Vec::new(); n];
    let c = rng.range(0.1, 10.0);
    for k in 0..n_bodies {
        let m = rng.range(0.5, 2.0);
        let j = rng.range(0.05, 0.5);
        cols[3 * k].push((3 * k, c * m));
        cols[3 * k + 1].push((3 * k + 1, c * m));
        cols[3 * k + 2].push((3 * k + 2, c * j));
    }
    for (i, row) in rows.iter().enumerate() {
        let li = np + i;
        cols[li].push((li, 0.0));
        for &(p, bp) in row {
            cols[p].push((li, bp));
            cols[li].push((p, bp));
            if augmented {
                for &(q, bq) in row {
                    cols[q].push((p, bp * bq));
                }
            }
        }
    }
    let mut a = Csc {
        n,
        col_ptr: vec![0],
        ..Csc::default()
    };
    for col in &mut cols {
        col.sort_by_key(|&(i, _)| i);
        let mut last = usize::MAX;
        for &(i, v) in col.iter() {
            if i == last {
                *a.values.last_mut().expect("an entry was pushed") += v;
            } else {
                a.row_idx.push(i);
                a.values.push(v);
                last = i;
            }
        }
        a.col_ptr.push(a.row_idx.len());
    }
    a
}

/// The `n × n` matrix of the entries `(row, column, value)`, each
/// position at most once.
pub(crate) fn csc_of_entries(n: usize, mut entries: Vec<(usize, usize, f64)>) -> Csc {
    entries.sort_by_key(|&(i, j, _)| (j, i));
    let mut a = Csc {
        n,
        col_ptr: vec![0; n + 1],
        ..Csc::default()
    };
    for &(i, j, v) in &entries {
        a.col_ptr[j + 1] += 1;
        a.row_idx.push(i);
        a.values.push(v);
    }
    for j in 0..n {
        a.col_ptr[j + 1] += a.col_ptr[j];
    }
    a
}

/// A vector of `n` entries in `[-1, 1)`.
pub(crate) fn vector(n: usize, seed: u64) -> Vec<f64> {
    let mut rng = Lcg::new(seed.wrapping_add(17));
    (0..n).map(|_| rng.range(-1.0, 1.0)).collect()
}

/// `‖A x − b‖∞ / (‖A‖∞ ‖x‖∞ + ‖b‖∞)`.
pub(crate) fn relative_residual(a: &Csc, x: &[f64], b: &[f64]) -> f64 {
    let mut ax = vec![0.0; a.n];
    a.mul(x, &mut ax);
    let mut row_sums = vec![0.0; a.n];
    for j in 0..a.n {
        for k in a.col_ptr[j]..a.col_ptr[j + 1] {
            row_sums[a.row_idx[k]] += a.values[k].abs();
        }
    }
    let norm = |v: &[f64]| v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let r = ax
        .iter()
        .zip(b)
        .fold(0.0f64, |m, (p, q)| m.max((p - q).abs()));
    r / (norm(&row_sums) * norm(x) + norm(b))
}

/// `‖x − y‖∞ / ‖y‖∞`.
pub(crate) fn relative_difference(x: &[f64], y: &[f64]) -> f64 {
    let d = x
        .iter()
        .zip(y)
        .fold(0.0f64, |m, (p, q)| m.max((p - q).abs()));
    d / y.iter().fold(0.0f64, |m, q| m.max(q.abs()))
}
