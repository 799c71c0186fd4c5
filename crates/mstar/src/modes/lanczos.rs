//! The sparse path of [`super::modes`]: shift-invert Lanczos in the `M`
//! inner product, each step one solve with the factored KKT matrix
//! `[K − σM, Bᵀ; B, 0]`.
//!
//! The operator `T x = y`, `[K − σM, Bᵀ; B, 0] [y; μ] = [M x; 0]`, maps
//! into the tangent space `B y = 0` and is self-adjoint there in the `M`
//! inner product when `K` and `M` are symmetric; its eigenvalues are
//! `θ = 1/(ω² − σ)`, so the modes nearest the shift `σ` (the lowest, for
//! `σ ≤ 0` near 0) are its largest and converge first. The Krylov basis is
//! kept `M`-orthonormal by full reorthogonalization (Gram–Schmidt twice),
//! and the Ritz values come from the projected matrix `H = Qᵀ M T Q`.

use std::collections::HashMap;

use mstar_kkt::{KktOptions, KktSolver};
use mstar_linearize::Linearization;
use nalgebra::{DMatrix, SymmetricEigen};

use super::{Method, Mode, Modes, ModesError, RIGID, blocks, mode, omega2_ref, top_left};

/// Ritz pairs are converged when their residual `‖T φ − θ φ‖_M` is below
/// this fraction of `|θ|`: the eigenvalue `ω²` is then accurate to its
/// square (`10⁻²⁰`) relative to the gap, far below the solves' round-off.
const TOL: f64 = 1e-10;

/// A failed shift: the linearization back, for another, and why.
type Retry = Box<(Linearization, ModesError)>;

/// The shift-invert operator: the KKT matrix at `σ`, factored.
struct ShiftInvert {
    lin: Linearization,
    solver: KktSolver,
    sigma: f64,
    rhs: Vec<f64>,
}

impl ShiftInvert {
    /// Factors `[K − σM, Bᵀ; B, 0]`.
    fn new(mut lin: Linearization, sigma: f64) -> Result<Self, Retry> {
        lin.assemble(&blocks(1.0, 0.0, -sigma));
        let solver = match KktSolver::new(lin.kkt(), &KktOptions::default()) {
            Ok(s) => s,
            Err(e) => return Err(Box::new((lin, e.into()))),
        };
        let mut op = Self {
            rhs: vec![0.0; lin.kkt().n],
            lin,
            solver,
            sigma,
        };
        if let Err(e) = op.solver.factor(&op.lin.kkt().values) {
            return Err(Box::new((op.lin, e.into())));
        }
        Ok(op)
    }

    /// `M x`.
    fn mass_times(&self, x: &[f64], out: &mut [f64]) {
        out.fill(0.0);
        let pattern = self.lin.mass_pattern();
        for (&(i, j), &m) in pattern.entries.iter().zip(self.lin.mass()) {
            out[i] += m * x[j];
        }
    }

    /// `T x`.
    fn apply(&mut self, x: &[f64]) -> Result<Vec<f64>, ModesError> {
        let n = x.len();
        let mut mx = vec![0.0; n];
        self.mass_times(x, &mut mx);
        self.rhs[..n].copy_from_slice(&mx);
        self.rhs[n..].fill(0.0);
        self.solver.solve_in_place(&mut self.rhs)?;
        Ok(self.rhs[..n].to_vec())
    }

    /// `xᵀ M y`.
    fn inner(&self, x: &[f64], y: &[f64]) -> f64 {
        let pattern = self.lin.mass_pattern();
        pattern
            .entries
            .iter()
            .zip(self.lin.mass())
            .map(|(&(i, j), &m)| x[i] * m * y[j])
            .sum()
    }
}

/// The modes by the sparse path; `lin` holds the evaluated state.
pub(super) fn modes(mut lin: Linearization, count: usize) -> Result<Modes, ModesError> {
    let (n, m) = (lin.n_coords(), lin.n_constraints());
    let dof = n.saturating_sub(m);
    if count > dof {
        return Err(ModesError::TooMany {
            count,
            dof,
            n,
            rank: n - dof,
        });
    }
    let k_max = check_symmetric(&mut lin)?;
    if count == 0 {
        return Ok(Modes {
            modes: Vec::new(),
            dof,
            damped: false,
            method: Method::Sparse,
        });
    }
    let m_max = lin.mass().iter().fold(0.0_f64, |a, x| a.max(x.abs()));
    let omega2 = omega2_ref(k_max, m_max);
    let start = start_vector(n);
    // σ = 0 unless the stiffness is singular on the tangent space (rigid
    // modes); then slightly below zero, where K − σM is regular.
    let (mut op, q0) = match shifted(lin, 0.0, &start) {
        Ok(found) => found,
        Err(retry) => shifted(retry.0, -1e-6 * omega2, &start).map_err(|retry| retry.1)?,
    };
    let ritz = lanczos(&mut op, q0, count, dof)?;
    let zero = RIGID * omega2;
    let mut modes: Vec<Mode> = ritz
        .into_iter()
        .map(|(theta, phi)| {
            let w2 = op.sigma + 1.0 / theta;
            let s = if w2.abs() <= zero {
                (0.0, 0.0)
            } else if w2 > 0.0 {
                (0.0, w2.sqrt())
            } else {
                ((-w2).sqrt(), 0.0)
            };
            let norm = op.inner(&phi, &phi).sqrt().recip();
            let shape: Vec<f64> = phi.iter().map(|x| x * norm).collect();
            mode(s, zero, (shape, vec![0.0; n]))
        })
        .collect();
    modes.sort_by(|a, b| a.frequency_hz.total_cmp(&b.frequency_hz));
    Ok(Modes {
        modes,
        dof,
        damped: false,
        method: Method::Sparse,
    })
}

/// Refuses damping (`C ≠ 0`) and an unsymmetric `K`; returns `max|K_ij|`.
fn check_symmetric(lin: &mut Linearization) -> Result<f64, ModesError> {
    let n = lin.n_coords();
    lin.assemble(&blocks(1.0, 0.0, 0.0));
    let mut k: HashMap<(usize, usize), f64> = HashMap::new();
    for (i, j, v) in top_left(lin.kkt(), n) {
        *k.entry((i, j)).or_insert(0.0) += v;
    }
    let k_max = k.values().fold(0.0_f64, |a, v| a.max(v.abs()));
    let asymmetry = k.iter().fold(0.0_f64, |a, (&(i, j), v)| {
        a.max((v - k.get(&(j, i)).copied().unwrap_or(0.0)).abs())
    });
    if asymmetry > 1e-8 * k_max {
        return Err(ModesError::SparseNeedsSymmetric(
            "has an unsymmetric stiffness (follower forces, or a mass matrix that depends on the coordinates)",
        ));
    }
    lin.assemble(&blocks(0.0, 1.0, 0.0));
    let m_max = lin.mass().iter().fold(0.0_f64, |a, x| a.max(x.abs()));
    let c_max = top_left(lin.kkt(), n).fold(0.0_f64, |a, (_, _, v)| a.max(v.abs()));
    if c_max > 1e-8 * (k_max * m_max).sqrt() {
        return Err(ModesError::SparseNeedsSymmetric("has dampers"));
    }
    Ok(k_max)
}

/// A start vector with every component nonzero and no structure a mode
/// could be orthogonal to by symmetry (the fractional parts of `i φ`,
/// `φ` the golden ratio).
fn start_vector(n: usize) -> Vec<f64> {
    let golden = 0.5 * (1.0 + 5.0_f64.sqrt());
    (0..n)
        .map(|i| ((i + 1) as f64 * golden).fract() - 0.5)
        .collect()
}

/// The operator at `σ` and the first Lanczos vector, `T x₀` normalized
/// (`T` projects the start onto the tangent space); the linearization
/// back on failure, for another shift.
fn shifted(
    lin: Linearization,
    sigma: f64,
    start: &[f64],
) -> Result<(ShiftInvert, Vec<f64>), Retry> {
    let mut op = ShiftInvert::new(lin, sigma)?;
    match op.apply(start) {
        Ok(q) => {
            let norm = op.inner(&q, &q).sqrt();
            // A start with no mass in the tangent space: M vanishes there.
            if !(norm > 0.0 && norm.is_finite()) {
                return Err(Box::new((op.lin, ModesError::SingularMass)));
            }
            Ok((op, q.iter().map(|x| x / norm).collect()))
        }
        Err(e) => Err(Box::new((op.lin, e))),
    }
}

/// Lanczos with full reorthogonalization from the `M`-unit vector `q0`
/// until the `count` largest `|θ|` have converged; returns them with their
/// Ritz vectors.
fn lanczos(
    op: &mut ShiftInvert,
    q0: Vec<f64>,
    count: usize,
    dof: usize,
) -> Result<Vec<(f64, Vec<f64>)>, ModesError> {
    let max_dim = dof.min(3 * count + 100);
    let mut q: Vec<Vec<f64>> = vec![q0];
    let mut h = DMatrix::<f64>::zeros(max_dim + 1, max_dim);
    for j in 0..max_dim {
        let mut w = op.apply(&q[j])?;
        for _pass in 0..2 {
            for (i, qi) in q.iter().enumerate() {
                let c = op.inner(qi, &w);
                h[(i, j)] += c;
                w.iter_mut().zip(qi).for_each(|(w, q)| *w -= c * q);
            }
        }
        let beta = op.inner(&w, &w).max(0.0).sqrt();
        h[(j + 1, j)] = beta;
        let dim = j + 1;
        let exhausted = dim == max_dim || beta <= 1e-14 * h[(0, 0)].abs().max(h.amax());
        if dim >= count && (dim % 5 == 0 || exhausted) {
            match converged(&h, &q, dim, count, beta) {
                Ok(found) => return Ok(found),
                Err(done) if exhausted => {
                    return Err(ModesError::NotConverged {
                        converged: done,
                        count,
                        steps: dim,
                    });
                }
                Err(_) => {}
            }
        }
        if exhausted {
            break;
        }
        q.push(w.iter().map(|x| x / beta).collect());
    }
    Err(ModesError::NotConverged {
        converged: 0,
        count,
        steps: q.len(),
    })
}

/// The Ritz pairs of the `count` largest `|θ|` of the projected matrix
/// `H` (its symmetric part, `dim × dim`) when their residual estimates
/// `β |y_last|` are all below [`TOL`] `|θ|`; else how many are.
fn converged(
    h: &DMatrix<f64>,
    q: &[Vec<f64>],
    dim: usize,
    count: usize,
    beta: f64,
) -> Result<Vec<(f64, Vec<f64>)>, usize> {
    let hj = h.view((0, 0), (dim, dim));
    let sym = (hj + hj.transpose()) * 0.5;
    let eig = SymmetricEigen::new(sym);
    let mut order: Vec<usize> = (0..dim).collect();
    order.sort_by(|&a, &b| {
        eig.eigenvalues[b]
            .abs()
            .total_cmp(&eig.eigenvalues[a].abs())
    });
    order.truncate(count);
    let done = order
        .iter()
        .filter(|&&i| {
            let theta = eig.eigenvalues[i];
            theta != 0.0 && beta * eig.eigenvectors[(dim - 1, i)].abs() <= TOL * theta.abs()
        })
        .count();
    if done < count {
        return Err(done);
    }
    let n = q[0].len();
    let pairs = order
        .into_iter()
        .map(|i| {
            let mut phi = vec![0.0; n];
            for (k, qk) in q.iter().take(dim).enumerate() {
                let y = eig.eigenvectors[(k, i)];
                phi.iter_mut().zip(qk).for_each(|(p, x)| *p += y * x);
            }
            (eig.eigenvalues[i], phi)
        })
        .collect();
    Ok(pairs)
}
