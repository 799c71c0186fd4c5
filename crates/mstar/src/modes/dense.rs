//! The dense path of [`super::modes`]: a null-space basis of `B` and a dense
//! eigensolver on the reduced matrices.

use mstar_linearize::Linearization;
use mstar_model::Pattern;
use nalgebra::{Cholesky, Complex, DMatrix, DVector, Dyn, SymmetricEigen};

use super::{Method, Mode, ModeKind, Modes, ModesError, RIGID, blocks, mode, omega2_ref, top_left};

/// Relative size below which `C_r` counts as zero and `K_r − K_rᵀ` as
/// round-off: the finite-difference defaults of the `System` trait leave
/// `≈ 10⁻¹⁰` of the entries' size.
const NEGLIGIBLE: f64 = 1e-8;

/// The modes by the dense path; `lin` holds the evaluated state.
pub(super) fn modes(mut lin: Linearization, count: usize) -> Result<Modes, ModesError> {
    let (n, m) = (lin.n_coords(), lin.n_constraints());
    let mass = from_pattern(lin.mass_pattern(), lin.mass(), n);
    let b = from_pattern(lin.b_pattern(), lin.b(), m);
    let k = kkt_block(&mut lin, (1.0, 0.0), n);
    let c = kkt_block(&mut lin, (0.0, 1.0), n);
    let z = null_space(&b, n);
    let dof = z.ncols();
    if count > dof {
        return Err(ModesError::TooMany {
            count,
            dof,
            n,
            rank: n - dof,
        });
    }
    if count == 0 {
        return Ok(Modes {
            modes: Vec::new(),
            dof,
            damped: false,
            method: Method::Dense,
        });
    }
    let zt = z.transpose();
    let mut m_r = &zt * &mass * &z;
    m_r = (&m_r + m_r.transpose()) * 0.5;
    let k_r = &zt * &k * &z;
    let c_r = &zt * &c * &z;
    let chol = Cholesky::new(m_r.clone()).ok_or(ModesError::SingularMass)?;
    let omega2_zero = RIGID * omega2_ref(k.amax(), mass.amax());
    let scale = (k_r.amax() * m_r.amax()).sqrt();
    let damped = c_r.amax() > NEGLIGIBLE * scale
        || (&k_r - k_r.transpose()).amax() > NEGLIGIBLE * k_r.amax();
    let reduced = if damped {
        first_order(&m_r, &c_r, &k_r, count, omega2_zero)?
    } else {
        symmetric(&chol, &k_r, count, omega2_zero)
    };
    let modes = reduced
        .into_iter()
        .map(|(s, x)| expand(s, &z, &m_r, &x, omega2_zero))
        .collect();
    Ok(Modes {
        modes,
        dof,
        damped,
        method: Method::Dense,
    })
}

/// A dense `rows × n` matrix from values on a pattern (repeated entries
/// add).
fn from_pattern(pattern: &Pattern, values: &[f64], rows: usize) -> DMatrix<f64> {
    let mut a = DMatrix::zeros(rows, pattern.ncols);
    for (&(i, j), &v) in pattern.entries.iter().zip(values) {
        a[(i, j)] += v;
    }
    a
}

/// `c_u K + c_v C` as a dense matrix, from the KKT matrix so assembled.
fn kkt_block(lin: &mut Linearization, (c_u, c_v): (f64, f64), n: usize) -> DMatrix<f64> {
    lin.assemble(&blocks(c_u, c_v, 0.0));
    let mut a = DMatrix::zeros(n, n);
    for (i, j, v) in top_left(lin.kkt(), n) {
        a[(i, j)] += v;
    }
    a
}

/// An orthonormal basis (columns) of the null space of the `m × n` matrix
/// `b`: the right singular vectors whose singular values are below
/// `10⁻¹⁰ σ_max` (redundant constraints have singular values at the
/// round-off level, `≈ 10⁻¹⁶ σ_max`). `b` is padded with zero rows to at
/// least `n` rows so that the SVD returns all `n` right singular vectors.
fn null_space(b: &DMatrix<f64>, n: usize) -> DMatrix<f64> {
    if b.nrows() == 0 || n == 0 {
        return DMatrix::identity(n, n);
    }
    let mut padded = DMatrix::zeros(b.nrows().max(n), n);
    padded.rows_mut(0, b.nrows()).copy_from(b);
    let svd = padded.svd(false, true);
    let sigma_max = svd.singular_values.amax();
    let Some(v_t) = svd.v_t else {
        return DMatrix::identity(n, n);
    };
    let null: Vec<usize> = (0..n)
        .filter(|&i| svd.singular_values[i] <= 1e-10 * sigma_max)
        .collect();
    let mut z = DMatrix::zeros(n, null.len());
    for (col, &i) in null.iter().enumerate() {
        z.set_column(col, &v_t.row(i).transpose());
    }
    z
}

/// A reduced mode: its eigenvalue `s` and complex shape in the null-space
/// basis.
type Reduced = ((f64, f64), DVector<Complex<f64>>);

/// Undamped, symmetric: `K_r x = ω² M_r x` as the symmetric eigenproblem
/// of `L⁻¹ K_r L⁻ᵀ` (`M_r = L Lᵀ`); `s = iω` for `ω² ≥ 0`, `s = √(−ω²)`
/// (unstable) otherwise. The lowest `count` by `|ω²|`.
fn symmetric(
    chol: &Cholesky<f64, Dyn>,
    k_r: &DMatrix<f64>,
    count: usize,
    zero: f64,
) -> Vec<Reduced> {
    let l = chol.l();
    let w = l
        .solve_lower_triangular(k_r)
        .unwrap_or_else(|| DMatrix::zeros(k_r.nrows(), k_r.ncols()));
    let a = l
        .solve_lower_triangular(&w.transpose())
        .unwrap_or_else(|| DMatrix::zeros(k_r.nrows(), k_r.ncols()));
    let a = (&a + a.transpose()) * 0.5;
    let eig = SymmetricEigen::new(a);
    let mut order: Vec<usize> = (0..eig.eigenvalues.len()).collect();
    order.sort_by(|&i, &j| {
        eig.eigenvalues[i]
            .abs()
            .total_cmp(&eig.eigenvalues[j].abs())
    });
    let lt = l.transpose();
    order
        .into_iter()
        .take(count)
        .map(|i| {
            let w2 = eig.eigenvalues[i];
            let s = if w2.abs() <= zero {
                (0.0, 0.0)
            } else if w2 > 0.0 {
                (0.0, w2.sqrt())
            } else {
                ((-w2).sqrt(), 0.0)
            };
            let y = eig.eigenvectors.column(i).into_owned();
            let x = lt.solve_upper_triangular(&y).unwrap_or(y);
            (s, x.map(|v| Complex::new(v, 0.0)))
        })
        .collect()
}

/// Damped or unsymmetric: the eigenvalues of the first-order form
/// `[0 I; −M_r⁻¹K_r −M_r⁻¹C_r]` (one of each complex pair, `Im s > 0`, and
/// the real ones; of `2r` zero eigenvalues, `⌈r⌉` rigid modes), the lowest
/// `count` by `|s|`, each shape the null vector of `s² M_r + s C_r + K_r`.
fn first_order(
    m_r: &DMatrix<f64>,
    c_r: &DMatrix<f64>,
    k_r: &DMatrix<f64>,
    count: usize,
    zero: f64,
) -> Result<Vec<Reduced>, ModesError> {
    let d = m_r.nrows();
    let lu = m_r.clone().lu();
    let (Some(mk), Some(mc)) = (lu.solve(k_r), lu.solve(c_r)) else {
        return Err(ModesError::SingularMass);
    };
    let mut a = DMatrix::zeros(2 * d, 2 * d);
    a.view_mut((0, d), (d, d)).fill_with_identity();
    a.view_mut((d, 0), (d, d)).copy_from(&(-mk));
    a.view_mut((d, d), (d, d)).copy_from(&(-mc));
    let mut s: Vec<(f64, f64)> = a
        .complex_eigenvalues()
        .iter()
        .filter(|s| s.im >= 0.0)
        .map(|s| (s.re, s.im))
        .collect();
    s.sort_by(|a, b| a.0.hypot(a.1).total_cmp(&b.0.hypot(b.1)));
    let rigid = s.iter().filter(|s| s.0.hypot(s.1).powi(2) <= zero).count();
    // A rigid motion without damping is a double zero of the first-order
    // form (a Jordan block): report it once.
    let skip = rigid - rigid.div_ceil(2);
    let out = s
        .into_iter()
        .skip(skip)
        .take(count)
        .map(|s| (s, null_vector(m_r, c_r, k_r, s)))
        .collect();
    Ok(out)
}

/// The null vector of `Q(s) = s² M_r + s C_r + K_r`: its right singular
/// vector of the smallest singular value (a complex SVD, robust where an
/// inverse iteration on `Q(s)` would divide by round-off).
fn null_vector(
    m_r: &DMatrix<f64>,
    c_r: &DMatrix<f64>,
    k_r: &DMatrix<f64>,
    (re, im): (f64, f64),
) -> DVector<Complex<f64>> {
    let s = Complex::new(re, im);
    let d = m_r.nrows();
    let q = DMatrix::from_fn(d, d, |i, j| {
        s * s * m_r[(i, j)] + s * c_r[(i, j)] + Complex::new(k_r[(i, j)], 0.0)
    });
    let svd = q.svd(false, true);
    let smallest = svd.singular_values.imin();
    svd.v_t.map_or_else(
        || DVector::from_element(d, Complex::new(1.0, 0.0)),
        |v_t| v_t.row(smallest).transpose().map(|x| x.conj()),
    )
}

/// The mode in the model's coordinates: `φ = Z x` scaled to `φᴴ M φ =
/// xᴴ M_r x = 1`.
fn expand(
    s: (f64, f64),
    z: &DMatrix<f64>,
    m_r: &DMatrix<f64>,
    x: &DVector<Complex<f64>>,
    zero: f64,
) -> Mode {
    let xr = x.map(|c| c.re);
    let xi = x.map(|c| c.im);
    let modal_mass = xr.dot(&(m_r * &xr)) + xi.dot(&(m_r * &xi));
    let scale = if modal_mass > 0.0 {
        modal_mass.sqrt().recip()
    } else {
        1.0
    };
    let re = (z * xr * scale).as_slice().to_vec();
    let im = (z * xi * scale).as_slice().to_vec();
    let mut m = mode(s, zero, (re, im));
    if m.kind == ModeKind::Rigid {
        m.s = (0.0, 0.0);
    }
    m
}
