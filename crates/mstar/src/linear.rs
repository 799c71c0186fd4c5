//! Linear state-space models `ẋ = A x + B p`, `y = C x + D p` of a
//! constrained mechanism about a state at rest (`docs/analysis.md`, "Linear
//! state-space models").
//!
//! About the operating point `(t₀, u₀, u̇ = 0, λ₀)` the equations of motion
//! `M ü + Bᵀλ = g(u, u̇, t; p)`, `Φ(u, t) = 0` linearize to
//!
//! ```text
//! M δü + C δu̇ + K δu + Bᵀ δλ = E δp,     B δu = 0,
//! C = −∂g/∂u̇,   K = Σ λᵢ ∂²Φᵢ/∂u² − ∂g/∂u,   E = ∂g/∂p
//! ```
//!
//! (the tangent of `mstar_linearize`, eqs. 6-7, with the geometric stiffness
//! that makes a hanging pendulum stable). The constraints are eliminated by
//! choosing independent coordinates `q` among `u` with a column-pivoted
//! (complete-pivoting) Gauss–Jordan factorization of `B`: the pivot columns
//! are the dependent coordinates `u_d`, the others the independent ones, and
//! `δu = N δq` with `N = [I; −B_d⁻¹ B_i]` (rows permuted back to the model's
//! order), so that `B N = 0`. Projecting with `Nᵀ` removes `λ`:
//!
//! ```text
//! M_r q̈ + C_r q̇ + K_r q = E_r p,   M_r = NᵀMN, C_r = NᵀCN, K_r = NᵀKN, E_r = NᵀE
//! x = [q; q̇],   A = [[0, I], [−M_r⁻¹K_r, −M_r⁻¹C_r]],   B = [0; M_r⁻¹E_r].
//! ```
//!
//! The matrices are dense (`O(n³)`): models of at most [`MAX_COORDS`]
//! coordinates. Outputs are columns of `mstar run`; `C` and `D` are their
//! derivatives along each state and input, by central differences (see
//! [`state_space`]).

mod model_file;

pub use model_file::{About, FromFile, Request, from_file};

use mstar_model::sensor::Sensor;
use mstar_model::{Pattern, SampleRef, System};
use nalgebra::{DMatrix, DVector};

use crate::columns::{Columns, OutputColumns, Selection};
use crate::run::ModelLookup;

/// The most coordinates a state-space model is formed for: the matrices are
/// dense and factored in `O(n³)`, and a model is for control design of a
/// small mechanism. Larger ones: `mstar modes` for its vibration, or a
/// smaller model of the part that matters.
pub const MAX_COORDS: usize = 400;

/// The `format` field of the JSON file.
pub const FORMAT: &str = "mstar.linear/1";

/// The state `(t₀, u₀, u̇ = 0, λ₀)` a model is linearized about.
#[derive(Clone, Debug, PartialEq)]
pub struct OperatingPoint {
    /// What it is, for the file: `"equilibrium"` or `"initial"`.
    pub about: String,
    /// Time, s (drivers are held there).
    pub t: f64,
    /// Coordinates `u₀`.
    pub u: Vec<f64>,
    /// Multipliers `λ₀` (those of the equilibrium, or of the acceleration
    /// problem at `u₀`).
    pub lambda: Vec<f64>,
    /// Accelerations `ü₀` (zero at an equilibrium).
    pub a: Vec<f64>,
}

/// An input `p`: a value of the model (a force or torque) and the
/// generalized force per unit of it, `∂g/∂p` at the operating point.
#[derive(Clone, Debug, PartialEq)]
pub struct Input {
    /// The model file's key (`force.push.fx`).
    pub key: String,
    /// Its value in the model (`p = 0` of the linear model is this value).
    pub value: f64,
    /// `∂g/∂p`, one per coordinate.
    pub force: Vec<f64>,
}

/// A linear state-space model (`docs/analysis.md` documents each field as
/// written to JSON). Matrices are row-major.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct StateSpace {
    /// `"equilibrium"` or `"initial"`.
    pub about: String,
    /// The time of the operating point, s.
    pub t0: f64,
    /// State names: `u:<coordinate>` for each independent coordinate (its
    /// deviation `δq`), then `v:<coordinate>` (its velocity).
    pub states: Vec<String>,
    /// Input keys.
    pub inputs: Vec<String>,
    /// Input values in the model (the linear model's `p = 0`).
    pub input_values: Vec<f64>,
    /// Output column names.
    pub outputs: Vec<String>,
    /// `ẋ = A x + B p`.
    #[serde(rename = "A")]
    pub a: Vec<Vec<f64>>,
    /// Input matrix.
    #[serde(rename = "B")]
    pub b: Vec<Vec<f64>>,
    /// `y = y0 + C x + D p`.
    #[serde(rename = "C")]
    pub c: Vec<Vec<f64>>,
    /// Feedthrough.
    #[serde(rename = "D")]
    pub d: Vec<Vec<f64>>,
    /// Every coordinate of the model, the rows of `N`.
    pub coordinates: Vec<String>,
    /// `δu = N δq`: one row per coordinate, one column per independent one.
    #[serde(rename = "N")]
    pub n: Vec<Vec<f64>>,
    /// `u₀`.
    pub u0: Vec<f64>,
    /// `λ₀`, named by `lambda` columns of `mstar run`.
    pub lambda0: Vec<f64>,
    /// The outputs at the operating point.
    pub y0: Vec<f64>,
    /// `ẋ` at `x = 0`, `p = 0`: zero (to the equilibrium's tolerance) about
    /// an equilibrium; about another state, the drift the model leaves out.
    pub xdot0: Vec<f64>,
}

/// Why no state-space model was formed.
#[derive(Debug, thiserror::Error)]
pub enum LinearError {
    /// More coordinates than [`MAX_COORDS`].
    #[error(
        "the model has {n} coordinates, more than the {max} a dense state-space model is formed for: linearize a smaller model of the part that matters, or use `mstar modes` for the vibration of a large one"
    )]
    TooLarge {
        /// Coordinates of the model.
        n: usize,
        /// The limit.
        max: usize,
    },
    /// `B` has dependent rows.
    #[error(
        "the constraint rows {} are redundant (B has rank {rank} < {m} rows at the operating point): the independent coordinates are not defined; remove the redundant joints (mstar check names them) and run again",
        .rows.join(", ")
    )]
    Redundant {
        /// Rows left without a pivot.
        rows: Vec<String>,
        /// Rank of `B`.
        rank: usize,
        /// Rows of `B`.
        m: usize,
    },
    /// No degree of freedom.
    #[error(
        "the mechanism has no degree of freedom at the operating point (the constraints fix every coordinate): a state-space model needs at least one; free a driver or a joint"
    )]
    NoFreedom,
    /// `M_r` is not positive definite.
    #[error(
        "the mass matrix is singular on the constraints' tangent space (NᵀMN is not positive definite): some motion of the independent coordinates {} has no inertia; give the bodies mass and inertia",
        .states.join(", ")
    )]
    SingularMass {
        /// The independent coordinates.
        states: Vec<String>,
    },
    /// The acceleration problem `[M Bᵀ; B 0]` is singular.
    #[error(
        "the acceleration problem [M Bᵀ; B 0] is singular at the initial pose: redundant constraints or a coordinate without mass; run `mstar check`"
    )]
    Singular,
    /// An output pattern that names no column, or a column that is no
    /// function of the state.
    #[error("--outputs {0}")]
    Output(String),
    /// The model file or an input key cannot be read.
    #[error("{0}")]
    File(#[from] mstar_file::FileError),
    /// No equilibrium to linearize about.
    #[error("{0} (or linearize about the file's initial pose: --about initial)")]
    NoEquilibrium(Box<crate::equilibrium::EquilibriumError>),
    /// A driver's key named as an input.
    #[error(
        "--inputs {key}: a driver prescribes a coordinate's position, and a step in a position is an impulse: it enters the equations through its first and second time derivatives, which ẋ = A x + B p has no place for; drive the coordinate with a force or torque (a [[force]] of type force or torque, or a stiff spring-damper whose end you move) and name its value instead"
    )]
    DriverInput {
        /// The key.
        key: String,
    },
    /// An input that changes something other than the loads.
    #[error(
        "--inputs {key}: changing it changes {what}, not only the loads: inputs are force and torque values (e.g. force.push.fx, force.motor.function.constant)"
    )]
    NotALoad {
        /// The key.
        key: String,
        /// What it changes.
        what: String,
    },
}

impl LinearError {
    /// Whether it is the model file's or the request's fault (a file that
    /// cannot be read, a key or a column that is wrong), not the
    /// mechanism's (`mstar linearize` exits with 2 then, else 1).
    #[must_use]
    pub fn is_usage(&self) -> bool {
        matches!(
            self,
            Self::File(_) | Self::Output(_) | Self::DriverInput { .. } | Self::NotALoad { .. }
        )
    }
}

/// A dense matrix from values on a pattern (duplicates summed).
fn dense(p: &Pattern, values: &[f64]) -> DMatrix<f64> {
    let mut a = DMatrix::zeros(p.nrows, p.ncols);
    for (&(i, j), &v) in p.entries.iter().zip(values) {
        a[(i, j)] += v;
    }
    a
}

/// `M`, `C`, `K`, `B` at the operating point, dense.
struct Tangent {
    m: DMatrix<f64>,
    c: DMatrix<f64>,
    k: DMatrix<f64>,
    b: DMatrix<f64>,
}

/// Evaluates a pattern-valued method into a dense matrix.
fn eval(p: Pattern, f: impl FnOnce(&mut [f64])) -> DMatrix<f64> {
    let mut values = vec![0.0; p.len()];
    f(&mut values);
    dense(&p, &values)
}

impl Tangent {
    /// The matrices of [`OperatingPoint`] `op` (velocities zero).
    fn at<S: System + ?Sized>(sys: &S, op: &OperatingPoint) -> Self {
        let (t, u) = (op.t, op.u.as_slice());
        let v = vec![0.0; u.len()];
        let m = eval(sys.mass_pattern(), |x| sys.mass_into(t, u, x));
        let b = eval(sys.b_pattern(), |x| sys.b_into(t, u, x));
        let hessian = eval(sys.hessian_pattern(), |x| {
            sys.hessian_into(t, u, &op.lambda, x);
        });
        let g_u = eval(sys.forces_du_pattern(), |x| sys.forces_du_into(t, u, &v, x));
        let g_v = eval(sys.forces_dv_pattern(), |x| sys.forces_dv_into(t, u, &v, x));
        Self {
            m,
            c: -g_v,
            k: hessian - g_u,
            b,
        }
    }
}

/// The accelerations and multipliers at rest at `(t, u)`: the solution of
/// `[M Bᵀ; B 0] [ü; λ] = [g; c]` (`c` the acceleration right-hand side at
/// `u̇ = 0`, `−Φ_tt`), for an operating point that is not an equilibrium.
///
/// # Errors
/// [`LinearError::TooLarge`]; [`LinearError::Singular`] when the matrix is.
///
/// # Panics
/// If `u` does not have one value per coordinate.
pub fn at_rest<S: System + ?Sized>(
    sys: &S,
    t: f64,
    u: &[f64],
) -> Result<OperatingPoint, LinearError> {
    let (n, m) = (sys.n_coords(), sys.n_constraints());
    if n > MAX_COORDS {
        return Err(LinearError::TooLarge { n, max: MAX_COORDS });
    }
    let v = vec![0.0; n];
    let mass = eval(sys.mass_pattern(), |x| sys.mass_into(t, u, x));
    let b = eval(sys.b_pattern(), |x| sys.b_into(t, u, x));
    let mut kkt = DMatrix::zeros(n + m, n + m);
    kkt.view_mut((0, 0), (n, n)).copy_from(&mass);
    kkt.view_mut((0, n), (n, m)).copy_from(&b.transpose());
    kkt.view_mut((n, 0), (m, n)).copy_from(&b);
    let mut rhs = DVector::zeros(n + m);
    let mut g = vec![0.0; n];
    sys.forces_into(t, u, &v, &mut g);
    let mut c = vec![0.0; m];
    sys.accel_rhs_into(t, u, &v, &mut c);
    rhs.rows_mut(0, n).copy_from_slice(&g);
    rhs.rows_mut(n, m).copy_from_slice(&c);
    let x = kkt.lu().solve(&rhs).ok_or(LinearError::Singular)?;
    if x.iter().any(|v| !v.is_finite()) {
        return Err(LinearError::Singular);
    }
    Ok(OperatingPoint {
        about: "initial".into(),
        t,
        u: u.to_vec(),
        lambda: x.rows(n, m).iter().copied().collect(),
        a: x.rows(0, n).iter().copied().collect(),
    })
}

/// The independent coordinates and `N` (`n × r`, `B N = 0`, the identity on
/// the independent rows) by Gauss–Jordan elimination of `B` with complete
/// pivoting: at each step the largest remaining entry is the pivot (the
/// first of equals, in row then column order), its column a dependent
/// coordinate. A remaining entry below `10⁻¹⁰ max|B|` ends it: the rows
/// left are redundant.
///
/// # Errors
/// [`LinearError::Redundant`], naming the rows left.
fn tangent_basis<S: System + ?Sized>(
    sys: &S,
    b: &DMatrix<f64>,
) -> Result<(Vec<usize>, DMatrix<f64>), LinearError> {
    let (m, n) = b.shape();
    let mut r = b.clone();
    let tol = 1e-10 * b.amax();
    let (mut rows, mut dependent) = (Vec::new(), Vec::new());
    for _ in 0..m {
        let best = (0..m)
            .filter(|i| !rows.contains(i))
            .flat_map(|i| (0..n).map(move |j| (i, j)))
            .filter(|(_, j)| !dependent.contains(j))
            .fold(None, |best: Option<(usize, usize)>, (i, j)| match best {
                Some((bi, bj)) if r[(bi, bj)].abs() >= r[(i, j)].abs() => best,
                _ => Some((i, j)),
            });
        let Some((pi, pj)) = best.filter(|&(i, j)| r[(i, j)].abs() > tol) else {
            break;
        };
        let pivot = r[(pi, pj)];
        let row = r.row(pi) / pivot;
        r.set_row(pi, &row);
        for i in (0..m).filter(|&i| i != pi) {
            let f = r[(i, pj)];
            if f != 0.0 {
                let updated = r.row(i) - f * &row;
                r.set_row(i, &updated);
            }
        }
        rows.push(pi);
        dependent.push(pj);
    }
    if rows.len() < m {
        let left = (0..m).filter(|i| !rows.contains(i));
        return Err(LinearError::Redundant {
            rows: left.map(|i| sys.constraint_name(i)).collect(),
            rank: rows.len(),
            m,
        });
    }
    let independent: Vec<usize> = (0..n).filter(|j| !dependent.contains(j)).collect();
    // Row `rows[k]` of the reduced `B` reads `u_d[k] + Σ_j r[k, j] u_j = 0`.
    let mut basis = DMatrix::zeros(n, independent.len());
    for (col, &j) in independent.iter().enumerate() {
        basis[(j, col)] = 1.0;
        for (&row, &d) in rows.iter().zip(&dependent) {
            basis[(d, col)] = -r[(row, j)];
        }
    }
    Ok((independent, basis))
}

/// The reduced model: `A`, `B` and the maps from `(x, p)` to `δu`, `δu̇`,
/// `δü` and `δλ`.
struct Reduced {
    independent: Vec<usize>,
    basis: DMatrix<f64>,
    a: DMatrix<f64>,
    b: DMatrix<f64>,
    xdot0: DVector<f64>,
    /// `δλ = L [x; p]`.
    lambda_map: DMatrix<f64>,
}

/// Forms `A` and `B` from the tangent `t` and the input forces `e` (`n × k`).
fn reduce<S: System + ?Sized>(
    sys: &S,
    op: &OperatingPoint,
    t: &Tangent,
    e: &DMatrix<f64>,
) -> Result<Reduced, LinearError> {
    let (independent, basis) = tangent_basis(sys, &t.b)?;
    let r = independent.len();
    if r == 0 {
        return Err(LinearError::NoFreedom);
    }
    let nt = basis.transpose();
    let m_r = &nt * &t.m * &basis;
    let chol = m_r
        .clone()
        .cholesky()
        .ok_or_else(|| LinearError::SingularMass {
            states: independent.iter().map(|&j| sys.coord_name(j)).collect(),
        })?;
    let minus_k = chol.solve(&(&nt * &t.k * &basis));
    let minus_c = chol.solve(&(&nt * &t.c * &basis));
    let force = chol.solve(&(&nt * e));
    let k = e.ncols();
    let mut a = DMatrix::zeros(2 * r, 2 * r);
    a.view_mut((0, r), (r, r)).fill_with_identity();
    a.view_mut((r, 0), (r, r)).copy_from(&(-minus_k));
    a.view_mut((r, r), (r, r)).copy_from(&(-minus_c));
    let mut b = DMatrix::zeros(2 * r, k);
    b.view_mut((r, 0), (r, k)).copy_from(&force);
    // The drift: q̈₀ = M_r⁻¹ Nᵀ g(u₀) (Bᵀλ drops out, B N = 0).
    let n = sys.n_coords();
    let mut g = vec![0.0; n];
    sys.forces_into(op.t, &op.u, &vec![0.0; n], &mut g);
    let mut xdot0 = DVector::zeros(2 * r);
    xdot0
        .rows_mut(r, r)
        .copy_from(&chol.solve(&(&nt * DVector::from_vec(g))));
    let lambda_map = multipliers(t, &basis, &a, &b, e);
    Ok(Reduced {
        independent,
        basis,
        a,
        b,
        xdot0,
        lambda_map,
    })
}

/// `δλ` as a linear map of `[x; p]`: the least-squares solution of
/// `Bᵀ δλ = E p − K δu − C δu̇ − M δü`, whose right-hand side lies in the
/// range of `Bᵀ` (its projection `Nᵀ·` is the reduced equation, zero), so
/// `δλ = (B Bᵀ)⁻¹ B (…)` is exact.
fn multipliers(
    t: &Tangent,
    basis: &DMatrix<f64>,
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    e: &DMatrix<f64>,
) -> DMatrix<f64> {
    let (n, r, k) = (basis.nrows(), basis.ncols(), e.ncols());
    let mut du = DMatrix::zeros(n, 2 * r + k);
    du.view_mut((0, 0), (n, r)).copy_from(basis);
    let mut dv = DMatrix::zeros(n, 2 * r + k);
    dv.view_mut((0, r), (n, r)).copy_from(basis);
    let da = basis * lower(a, b, r);
    let mut rhs = DMatrix::zeros(n, 2 * r + k);
    rhs.view_mut((0, 2 * r), (n, k)).copy_from(e);
    rhs -= &t.k * du + &t.c * dv + &t.m * da;
    let bbt = &t.b * t.b.transpose();
    let projected = &t.b * rhs;
    // `B B ᵀ` is regular: `B` has full row rank (checked by the basis).
    bbt.lu()
        .solve(&projected)
        .unwrap_or_else(|| DMatrix::from_element(t.b.nrows(), 2 * r + k, f64::NAN))
}

/// The rows of `[A B]` that give `q̈` (`r × (2r + k)`).
fn lower(a: &DMatrix<f64>, b: &DMatrix<f64>, r: usize) -> DMatrix<f64> {
    let k = b.ncols();
    let mut out = DMatrix::zeros(r, 2 * r + k);
    out.view_mut((0, 0), (r, 2 * r))
        .copy_from(&a.view((r, 0), (r, 2 * r)));
    out.view_mut((0, 2 * r), (r, k))
        .copy_from(&b.view((r, 0), (r, k)));
    out
}

/// The output columns: their names and how to evaluate them.
struct Outputs<'a> {
    sys: &'a dyn ModelLookup,
    columns: OutputColumns<'a>,
    /// Index of each output in the full row (`mstar run`'s header, then the
    /// extra columns).
    chosen: Vec<usize>,
    names: Vec<String>,
}

/// Columns that are not functions of the state.
const NOT_STATE: [&str; 4] = ["t", "iterations", "residual", "constraint"];

impl<'a> Outputs<'a> {
    /// Resolves the patterns (exact names or `*` globs), in the order given.
    fn new(
        sys: &'a dyn ModelLookup,
        sensors: &[Sensor],
        patterns: &[String],
    ) -> Result<Self, LinearError> {
        let columns =
            OutputColumns::new(sys, sensors).map_err(|e| LinearError::Output(e.to_string()))?;
        let mut all = crate::csv::header(sys);
        all.extend(columns.names());
        let mut chosen: Vec<usize> = Vec::new();
        for p in patterns {
            let s = Selection::new(&all, std::slice::from_ref(p))
                .map_err(|e| LinearError::Output(e.to_string()))?;
            for &i in s.indices() {
                if NOT_STATE.contains(&all[i].as_str()) {
                    return Err(LinearError::Output(format!(
                        "{p}: the column {} is not a function of the state (outputs are u:, v:, a:, lambda:, energy, reaction:, effort: and sensor: columns)",
                        all[i]
                    )));
                }
                if !chosen.contains(&i) {
                    chosen.push(i);
                }
            }
        }
        let names = chosen.iter().map(|&i| all[i].clone()).collect();
        Ok(Self {
            sys,
            columns,
            chosen,
            names,
        })
    }

    /// The derivative of the full row's column `i` along the direction
    /// `(δu, δu̇, δü, δλ)` when it is one of them (`u:`, `v:`, `a:`,
    /// `lambda:`), exactly.
    fn linear(&self, i: usize, d: [&DVector<f64>; 4]) -> Option<f64> {
        let n = self.sys.n_coords();
        let m = self.sys.n_constraints();
        // The header: `t`, then n each of u, v, a, then m multipliers.
        let at = i.checked_sub(1)?;
        let (block, k) = if at < 3 * n {
            (at / n, at % n)
        } else if at < 3 * n + m {
            (3, at - 3 * n)
        } else {
            return None;
        };
        Some(d[block][k])
    }

    /// The outputs at the state `(t, u, v, a, λ)`.
    fn values(&self, t: f64, z: [&[f64]; 4]) -> Vec<f64> {
        let [u, v, a, lambda] = z;
        let sys = self.sys;
        let mass = eval(sys.mass_pattern(), |x| sys.mass_into(t, u, x));
        let velocity = DVector::from_column_slice(v);
        let kinetic = 0.5 * velocity.dot(&(&mass * &velocity));
        let sample = SampleRef {
            t,
            u,
            v,
            a,
            lambda,
            kinetic,
            potential: sys.potential_energy(t, u),
            iterations: 0,
            residual: 0.0,
            constraint: 0.0,
        };
        let mut row = vec![t];
        row.extend(u.iter().chain(v).chain(a).chain(lambda));
        row.extend([sample.energy(), 0.0, 0.0, 0.0]);
        self.columns.values(&sample, &mut row);
        self.chosen.iter().map(|&i| row[i]).collect()
    }
}

/// The state-space model of `sys` about `op`, with the `inputs` and the
/// output columns `outputs` (names or `*` patterns of `mstar run`'s columns,
/// with the model file's `sensors`).
///
/// `C` and `D`: each output is evaluated at the operating point moved by
/// `± h` along the change `(δu, δu̇, δü, δλ)` that one state or input causes
/// (`h` from `output_step`: `ε^{1/3} L / max(‖δu‖∞, ‖δu̇‖∞)`,
/// `L = max(1, ‖u₀‖∞)`, along a state), and differenced:
/// the `u:`, `v:`, `a:` and `lambda:` columns, which are the state's own,
/// are taken exactly from the direction instead; the others have an error
/// `O(h²)` from truncation and `O(ε/h)` from round-off, about `10⁻¹⁰` of
/// the column's scale.
///
/// # Errors
/// [`LinearError`]: too large, redundant constraints, no freedom, a
/// singular reduced mass, an output that names no column.
///
/// # Panics
/// If `op` or an input has the wrong length.
pub fn state_space(
    sys: &dyn ModelLookup,
    op: &OperatingPoint,
    inputs: &[Input],
    outputs: &[String],
    sensors: &[Sensor],
) -> Result<StateSpace, LinearError> {
    let n = sys.n_coords();
    if n > MAX_COORDS {
        return Err(LinearError::TooLarge { n, max: MAX_COORDS });
    }
    let outs = Outputs::new(sys, sensors, outputs)?;
    let tangent = Tangent::at(sys, op);
    let mut e = DMatrix::zeros(n, inputs.len());
    for (k, input) in inputs.iter().enumerate() {
        e.set_column(k, &DVector::from_column_slice(&input.force));
    }
    let red = reduce(sys, op, &tangent, &e)?;
    let (c, d) = output_matrices(&outs, op, &red, inputs.len());
    let names: Vec<String> = red.independent.iter().map(|&j| sys.coord_name(j)).collect();
    let mut states: Vec<String> = names.iter().map(|s| format!("u:{s}")).collect();
    states.extend(names.iter().map(|s| format!("v:{s}")));
    let zeros = vec![0.0; n];
    Ok(StateSpace {
        about: op.about.clone(),
        t0: op.t,
        states,
        inputs: inputs.iter().map(|i| i.key.clone()).collect(),
        input_values: inputs.iter().map(|i| i.value).collect(),
        y0: outs.values(op.t, [&op.u, &zeros, &op.a, &op.lambda]),
        outputs: outs.names,
        a: rows(&red.a),
        b: rows(&red.b),
        c: rows(&c),
        d: rows(&d),
        coordinates: (0..n).map(|i| sys.coord_name(i)).collect(),
        n: rows(&red.basis),
        u0: op.u.clone(),
        lambda0: op.lambda.clone(),
        xdot0: red.xdot0.iter().copied().collect(),
    })
}

/// `C` and `D` by central differences of the outputs along each state and
/// input (see [`state_space`]).
fn output_matrices(
    outs: &Outputs<'_>,
    op: &OperatingPoint,
    red: &Reduced,
    k: usize,
) -> (DMatrix<f64>, DMatrix<f64>) {
    let (n, r) = red.basis.shape();
    let cols = 2 * r + k;
    let accel = &red.basis * lower(&red.a, &red.b, r);
    let length = op.u.iter().fold(1.0_f64, |l, x| l.max(x.abs()));
    let mut cd = DMatrix::zeros(outs.chosen.len(), cols);
    for col in 0..cols {
        let zero = DVector::zeros(n);
        let du = if col < r {
            red.basis.column(col).into_owned()
        } else {
            zero.clone()
        };
        let dv = if (r..2 * r).contains(&col) {
            red.basis.column(col - r).into_owned()
        } else {
            zero
        };
        let da = accel.column(col).into_owned();
        let dl = red.lambda_map.column(col).into_owned();
        let Some(h) = output_step(length, [&du, &dv, &da, &dl]) else {
            continue;
        };
        let at = |s: f64| {
            let shift = |x: &[f64], d: &DVector<f64>| -> Vec<f64> {
                x.iter().zip(d.iter()).map(|(x, d)| x + s * h * d).collect()
            };
            let v0 = vec![0.0; n];
            let (u, v) = (shift(&op.u, &du), shift(&v0, &dv));
            let (a, l) = (shift(&op.a, &da), shift(&op.lambda, &dl));
            outs.values(op.t, [&u, &v, &a, &l])
        };
        let (plus, minus) = (at(1.0), at(-1.0));
        for (i, (p, m)) in plus.iter().zip(&minus).enumerate() {
            // The state's own columns exactly, the others differenced.
            cd[(i, col)] = outs
                .linear(outs.chosen[i], [&du, &dv, &da, &dl])
                .unwrap_or((p - m) / (2.0 * h));
        }
    }
    let c = cd.columns(0, 2 * r).into_owned();
    let d = cd.columns(2 * r, k).into_owned();
    (c, d)
}

/// The step of the outputs' central differences along the direction
/// `(δu, δu̇, δü, δλ)` (`None`: it is zero). The columns are nonlinear in
/// `u` and `u̇` only (in `ü` and `λ` they are linear at a fixed `u`, `u̇`:
/// sensors' accelerations, reactions, efforts): where the direction moves
/// them, `ε^{1/3} L / max(‖δu‖∞, ‖δu̇‖∞)` balances truncation and
/// round-off; where it moves only `ü` and `λ` (an input), the difference is
/// exact and `L / max(‖δü‖∞, ‖δλ‖∞)` keeps the round-off at `ε`.
fn output_step(length: f64, d: [&DVector<f64>; 4]) -> Option<f64> {
    let [du, dv, da, dl] = d;
    let moving = du.amax().max(dv.amax());
    let linear = da.amax().max(dl.amax());
    if moving > 0.0 {
        Some(f64::EPSILON.cbrt() * length / moving)
    } else if linear > 0.0 {
        Some(length / linear)
    } else {
        None
    }
}

/// A matrix as rows.
fn rows(a: &DMatrix<f64>) -> Vec<Vec<f64>> {
    // (`+ 0.0` writes −0 as 0.)
    a.row_iter()
        .map(|r| r.iter().map(|x| x + 0.0).collect())
        .collect()
}

/// The input `key` from the model built with its value at `value ± h`
/// (`plus`, `minus`): `∂g/∂p = (g₊ − g₋) / 2h` at the operating point
/// (velocities zero). Forces and torques enter `g` linearly, so the
/// difference is exact up to round-off, `ε ‖g‖ / h`. The two models must
/// agree on the constraints and the mass matrix there.
///
/// # Errors
/// [`LinearError::NotALoad`] when they do not (a geometry or mass key).
///
/// # Panics
/// If the models differ in size from `op`.
pub fn input(
    key: &str,
    value: f64,
    h: f64,
    [plus, minus]: [&dyn System; 2],
    op: &OperatingPoint,
) -> Result<Input, LinearError> {
    let (t, u) = (op.t, op.u.as_slice());
    let n = u.len();
    let not_a_load = |what: &str| LinearError::NotALoad {
        key: key.to_string(),
        what: what.to_string(),
    };
    let same_size = |s: &dyn System| s.n_coords() == n && s.n_constraints() == op.lambda.len();
    if !(same_size(plus) && same_size(minus)) {
        return Err(not_a_load("the model's dimensions"));
    }
    let (mut phi_p, mut phi_m) = (
        vec![0.0; plus.n_constraints()],
        vec![0.0; minus.n_constraints()],
    );
    plus.phi_into(t, u, &mut phi_p);
    minus.phi_into(t, u, &mut phi_m);
    if phi_p.iter().zip(&phi_m).any(|(a, b)| a != b) {
        return Err(not_a_load(
            "the constraints (a driver or a joint's geometry)",
        ));
    }
    let mass_p = eval(plus.mass_pattern(), |x| plus.mass_into(t, u, x));
    let mass_m = eval(minus.mass_pattern(), |x| minus.mass_into(t, u, x));
    if mass_p != mass_m {
        return Err(not_a_load("the mass matrix"));
    }
    let v = vec![0.0; n];
    let (mut g_p, mut g_m) = (vec![0.0; n], vec![0.0; n]);
    plus.forces_into(t, u, &v, &mut g_p);
    minus.forces_into(t, u, &v, &mut g_m);
    Ok(Input {
        key: key.to_string(),
        value,
        force: g_p
            .iter()
            .zip(&g_m)
            .map(|(a, b)| (a - b) / (2.0 * h))
            .collect(),
    })
}

/// The step of [`input`]'s difference for a key of value `value`:
/// `ε^{1/3} max(1, |value|)`.
#[must_use]
pub fn input_step(value: f64) -> f64 {
    f64::EPSILON.cbrt() * value.abs().max(1.0)
}

impl StateSpace {
    /// The model as JSON text (`docs/analysis.md`, "Linear state-space
    /// models"): one field a line, a matrix one row a line; a value that
    /// is not finite is written as `null`.
    #[must_use]
    pub fn to_json(&self) -> String {
        // Serializing plain vectors and strings does not fail.
        let json = |v: &dyn erased::Value| v.json();
        let fields: [(&str, String); 17] = [
            ("format", json(&FORMAT)),
            ("about", json(&self.about)),
            ("t0", json(&self.t0)),
            ("states", json(&self.states)),
            ("inputs", json(&self.inputs)),
            ("input_values", json(&self.input_values)),
            ("outputs", json(&self.outputs)),
            ("A", matrix(&self.a)),
            ("B", matrix(&self.b)),
            ("C", matrix(&self.c)),
            ("D", matrix(&self.d)),
            ("coordinates", json(&self.coordinates)),
            ("N", matrix(&self.n)),
            ("u0", json(&self.u0)),
            ("lambda0", json(&self.lambda0)),
            ("y0", json(&self.y0)),
            ("xdot0", json(&self.xdot0)),
        ];
        let body: Vec<String> = fields
            .iter()
            .map(|(k, v)| format!("  \"{k}\": {v}"))
            .collect();
        format!("{{\n{}\n}}\n", body.join(",\n"))
    }
}

/// A matrix as JSON, one row a line.
fn matrix(rows: &[Vec<f64>]) -> String {
    if rows.is_empty() {
        return "[]".into();
    }
    let lines: Vec<String> = rows.iter().map(|r| format!("    {}", r.json())).collect();
    format!("[\n{}\n  ]", lines.join(",\n"))
}

/// Compact JSON of the field types of [`StateSpace`].
mod erased {
    /// A value serde writes as JSON.
    pub trait Value {
        /// Compact JSON (empty only if serialization failed, which it does
        /// not for these types).
        fn json(&self) -> String;
    }

    impl<T: serde::Serialize> Value for T {
        fn json(&self) -> String {
            serde_json::to_string(self).unwrap_or_default()
        }
    }
}

use erased::Value as _;

#[cfg(test)]
mod tests {
    use super::*;
    use mstar_model::PendulumChain;

    /// `N` spans the null space of `B` (`B N = 0` to round-off of entries of
    /// order one), is the identity on the independent coordinates, and a
    /// repeated row of `B` is named redundant.
    #[test]
    fn the_basis_spans_the_null_space_of_b() {
        // (Only its constraint names are used.)
        let sys = PendulumChain::paper(1.0, 1.0, 10.0);
        let b = DMatrix::from_row_slice(2, 4, &[1.0, 2.0, 0.5, -1.0, 0.0, 3.0, 1.0, 0.25]);
        let (independent, n) = tangent_basis(&sys, &b).expect("full rank");
        assert_eq!(n.shape(), (4, 2));
        assert!((&b * &n).amax() < 1e-14, "B N = {}", &b * &n);
        for (col, &j) in independent.iter().enumerate() {
            for k in 0..2 {
                let want = if k == col { 1.0 } else { 0.0 };
                assert_eq!(n[(j, k)], want, "N[{j}, {k}]");
            }
        }
        // The pivots: 3 (row 1, column 1); then row 0 less twice the
        // scaled row 1 is [1, 0, −1/6, −7/6], whose largest is column 3.
        assert_eq!(independent, [0, 2]);
        let repeated = DMatrix::from_row_slice(2, 3, &[1.0, 0.0, 2.0, 1.0, 0.0, 2.0]);
        match tangent_basis(&sys, &repeated) {
            Err(LinearError::Redundant { rank, m, .. }) => assert_eq!((rank, m), (1, 2)),
            other => panic!("{other:?}"),
        }
    }
}
