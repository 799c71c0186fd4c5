//! A joint's `Φ`, gradient and Hessian contracted with its multipliers,
//! `Σ_r μ_r ∂²Φ_r/∂q²`, over its 14 local coordinates, written out from the
//! joints' building blocks instead of dual numbers (`docs/theory.md`,
//! "Spatial bodies", Derivatives).
//!
//! Every spatial joint's row is a constant plus linear functions and dot
//! products of
//! *tracked vectors*: body points `x = r + A(p) s`, body axes `A(p) a`, and
//! their differences. `A(p) s` is a homogeneous quadratic in `p`
//! (`rotation.rs`), so a tracked vector `w` has the Jacobian
//! `[I, J(p, s)]` on its body's coordinates and the constant second
//! derivatives `Σ_k y_k ∂²(A s)_k/∂p² = H(y, s)`,
//! `H(y, s) = 2 [y·s, (s × y)ᵀ; s × y, y sᵀ + s yᵀ − (y·s) I]`
//! (`spherical.rs`). Then, by the product rule,
//! `∇²(x·y) = J_xᵀ J_y + J_yᵀ J_x + Σ_k y_k ∇²x_k + Σ_k x_k ∇²y_k`.
//!
//! A joint tells its rows to a [`Rows`]: [`Gradient`] sums `Φ` and `B`,
//! [`Contracted`] the Hessian. The dual numbers and jets remain the
//! reference: the tests compare every joint kind with them, and a joint
//! without this form uses them.

use super::frame::{Frame, SIDE};
use super::rotation::{V3, point_jacobian};

/// The local coordinates of a joint: side A's at `0..7`, side B's at `7..14`.
const LOCAL: usize = 2 * SIDE;

/// `c` times `H(y, s)`, the contracted second derivative of `A(p) s`
/// (module documentation), as a 4 × 4 block.
pub(crate) fn contracted_rotation(y: V3<f64>, s: V3<f64>, c: f64) -> [[f64; 4]; 4] {
    let ys = y[0] * s[0] + y[1] * s[1] + y[2] * s[2];
    let sxy = [
        s[1] * y[2] - s[2] * y[1],
        s[2] * y[0] - s[0] * y[2],
        s[0] * y[1] - s[1] * y[0],
    ];
    let k = 2.0 * c;
    let mut h = [[0.0; 4]; 4];
    h[0][0] = k * ys;
    for i in 0..3 {
        h[0][1 + i] = k * sxy[i];
        h[1 + i][0] = k * sxy[i];
        for j in 0..3 {
            let d = if i == j { ys } else { 0.0 };
            h[1 + i][1 + j] = k * (y[i] * s[j] + s[i] * y[j] - d);
        }
    }
    h
}

/// One quadratic part of a tracked vector: `c A(p) s` on a side's Euler
/// parameters.
#[derive(Clone, Copy, Debug)]
struct Curvature {
    side: usize,
    c: f64,
    s: V3<f64>,
}

/// A vector of a joint with its Jacobian over the local coordinates and its
/// quadratic parts (module documentation).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Tracked {
    value: V3<f64>,
    jac: [[f64; LOCAL]; 3],
    /// Bit `s`: the vector depends on side `s`'s coordinates.
    sides: u8,
    parts: [Option<Curvature>; 2],
}

impl Tracked {
    fn on(side: usize, value: V3<f64>) -> Self {
        Self {
            value,
            jac: [[0.0; LOCAL]; 3],
            sides: 1 << side,
            parts: [None; 2],
        }
    }

    /// Writes `J(p, s)` and the part `A(p) s` when the side rotates.
    fn rotating(mut self, f: &Frame<f64>, side: usize, s: V3<f64>) -> Self {
        if let Some(p) = &f.p {
            let j = point_jacobian(p, s);
            for k in 0..3 {
                self.jac[k][SIDE * side + 3..SIDE * side + 7].copy_from_slice(&j[k]);
            }
            self.parts[0] = Some(Curvature { side, c: 1.0, s });
        }
        self
    }

    /// The point `s` of side `side` (`r + A(p) s`; for the ground, the
    /// global point `s`, whose coordinates no row is kept for).
    pub(crate) fn point(f: &Frame<f64>, side: usize, s: V3<f64>) -> Self {
        let mut t = Self::on(side, f.point(s));
        for k in 0..3 {
            t.jac[k][SIDE * side + k] = 1.0;
        }
        t.rotating(f, side, s)
    }

    /// The body vector `a` of side `side` in global axes, `A(p) a`.
    pub(crate) fn axis(f: &Frame<f64>, side: usize, a: V3<f64>) -> Self {
        Self::on(side, f.axis(a)).rotating(f, side, a)
    }

    /// `self − o`, for vectors of one part each (a point of each side).
    pub(crate) fn minus(&self, o: &Self) -> Self {
        let mut t = *self;
        for k in 0..3 {
            t.value[k] -= o.value[k];
            for (x, y) in t.jac[k].iter_mut().zip(&o.jac[k]) {
                *x -= y;
            }
        }
        t.sides |= o.sides;
        t.parts[1] = o.parts[0].map(|p| Curvature { c: -p.c, ..p });
        t
    }

    /// The local columns the vector depends on.
    fn columns(&self) -> impl Iterator<Item = usize> + use<> {
        let sides = self.sides;
        (0..2)
            .filter(move |s| sides & (1 << s) != 0)
            .flat_map(|s| SIDE * s..SIDE * s + SIDE)
    }
}

/// `Σ_r μ_r ∂²Φ_r/∂q²` of one joint over its local coordinates, summed term
/// by term.
#[derive(Clone, Debug)]
pub(crate) struct LocalHessian {
    h: [[f64; LOCAL]; LOCAL],
}

impl Default for LocalHessian {
    fn default() -> Self {
        Self {
            h: [[0.0; LOCAL]; LOCAL],
        }
    }
}

impl LocalHessian {
    /// Entry `(a, b)` of local coordinates.
    pub(crate) fn get(&self, a: usize, b: usize) -> f64 {
        self.h[a][b]
    }

    /// Adds `∇²(y · x)` for a constant `y`: `Σ c H(y, s)` over `x`'s parts.
    pub(crate) fn add_linear(&mut self, y: V3<f64>, x: &Tracked) {
        for part in x.parts.iter().flatten() {
            let block = contracted_rotation(y, part.s, part.c);
            let o = SIDE * part.side + 3;
            for (i, row) in block.iter().enumerate() {
                for (j, v) in row.iter().enumerate() {
                    self.h[o + i][o + j] += v;
                }
            }
        }
    }

    /// Adds `c ∇²(x · y)` (module documentation).
    pub(crate) fn add_dot(&mut self, c: f64, x: &Tracked, y: &Tracked) {
        if c == 0.0 {
            return;
        }
        for a in x.columns() {
            for b in y.columns() {
                let xy: f64 = (0..3).map(|k| x.jac[k][a] * y.jac[k][b]).sum();
                if xy != 0.0 {
                    self.h[a][b] += c * xy;
                    self.h[b][a] += c * xy;
                }
            }
        }
        let scaled = |v: V3<f64>| v.map(|e| c * e);
        self.add_linear(scaled(y.value), x);
        self.add_linear(scaled(x.value), y);
    }
}

/// What a joint's rows are made of, told row by row (each call adds to its
/// rows).
pub(crate) trait Rows {
    /// Rows `row..row + 3` get `c x`.
    fn vector(&mut self, row: usize, c: f64, x: &Tracked);
    /// Row `row` gets `c (x · y)`.
    fn dot(&mut self, row: usize, c: f64, x: &Tracked, y: &Tracked);
    /// Row `row` gets the constant `k`.
    fn constant(&mut self, row: usize, k: f64);
}

/// The most rows a joint has (the weld).
const ROWS: usize = 6;

/// `Φ` and its gradient over the local coordinates, summed from the rows.
#[derive(Clone, Debug)]
pub(crate) struct Gradient {
    phi: [f64; ROWS],
    grad: [[f64; LOCAL]; ROWS],
}

impl Default for Gradient {
    fn default() -> Self {
        Self {
            phi: [0.0; ROWS],
            grad: [[0.0; LOCAL]; ROWS],
        }
    }
}

impl Gradient {
    pub(crate) fn phi(&self, row: usize) -> f64 {
        self.phi[row]
    }

    /// `∂Φ_row/∂q_a`.
    pub(crate) fn grad(&self, row: usize, a: usize) -> f64 {
        self.grad[row][a]
    }
}

impl Rows for Gradient {
    fn vector(&mut self, row: usize, c: f64, x: &Tracked) {
        for k in 0..3 {
            self.phi[row + k] += c * x.value[k];
            for a in x.columns() {
                self.grad[row + k][a] += c * x.jac[k][a];
            }
        }
    }

    fn dot(&mut self, row: usize, c: f64, x: &Tracked, y: &Tracked) {
        let (xv, yv) = (x.value, y.value);
        self.phi[row] += c * (xv[0] * yv[0] + xv[1] * yv[1] + xv[2] * yv[2]);
        // ∇(x · y) = yᵀ J_x + xᵀ J_y.
        for (v, t) in [(yv, x), (xv, y)] {
            for a in t.columns() {
                self.grad[row][a] += c * (0..3).map(|k| v[k] * t.jac[k][a]).sum::<f64>();
            }
        }
    }

    fn constant(&mut self, row: usize, k: f64) {
        self.phi[row] += k;
    }
}

/// `Σ_r μ_r ∂²Φ_r/∂q²` from the rows and the multipliers `μ`.
#[derive(Debug)]
pub(crate) struct Contracted<'a> {
    pub(crate) mu: &'a [f64],
    pub(crate) h: LocalHessian,
}

impl Rows for Contracted<'_> {
    fn vector(&mut self, row: usize, c: f64, x: &Tracked) {
        let m = &self.mu[row..row + 3];
        self.h.add_linear([c * m[0], c * m[1], c * m[2]], x);
    }

    fn dot(&mut self, row: usize, c: f64, x: &Tracked, y: &Tracked) {
        self.h.add_dot(c * self.mu[row], x, y);
    }

    fn constant(&mut self, _: usize, _: f64) {}
}
