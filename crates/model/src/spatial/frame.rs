//! Where a spatial element attaches, as numbers of any [`Real`] kind: a body's
//! position, Euler parameters and their rates, or the ground.

use super::real::{Dual, Jet, Real};
use super::rotation::{
    V3, add, apply, cst3, matrix, omega_global, point_jt, rotate, torque_global,
};
use crate::planar::TimeFunction;

/// The local variables of one side: coordinate `k` of side `s` is `7 s + k`.
pub(crate) const SIDE: usize = 7;

/// One side of an element: a body's coordinates (and rates), or the ground
/// (`r = 0`, no rotation, no motion).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Frame<T> {
    pub(crate) r: V3<T>,
    /// Euler parameters; `None` for the ground and for point masses.
    pub(crate) p: Option<[T; 4]>,
    /// The rates; `None` at rest (the ground, or an element evaluated
    /// without rates: the joints).
    rd: Option<V3<T>>,
    pd: Option<[T; 4]>,
    /// `A(p)` (`rotation::matrix`), formed once for the frame's points and
    /// axes; `None` with `p`.
    a: Option<[[T; 3]; 3]>,
}

impl<T: Real> Frame<T> {
    /// The ground.
    pub(crate) fn ground() -> Self {
        let z = cst3([0.0; 3]);
        Self {
            r: z,
            p: None,
            rd: None,
            pd: None,
            a: None,
        }
    }

    /// A body at the coordinates `q(0..3)` (and Euler parameters `q(3..7)`
    /// when `rigid`) moving at `qd(k)` (`None`: at rest), each number made
    /// where it is kept.
    pub(crate) fn with(
        rigid: bool,
        q: impl Fn(usize) -> T,
        qd: Option<impl Fn(usize) -> T>,
    ) -> Self {
        let p = rigid.then(|| [q(3), q(4), q(5), q(6)]);
        Self {
            r: [q(0), q(1), q(2)],
            rd: qd.as_ref().map(|qd| [qd(0), qd(1), qd(2)]),
            pd: qd
                .as_ref()
                .filter(|_| rigid)
                .map(|qd| [qd(3), qd(4), qd(5), qd(6)]),
            a: p.as_ref().map(matrix),
            p,
        }
    }

    /// The global position of the body point `s` (body axes, relative to
    /// the centre of mass); for the ground, `s` is a global point.
    pub(crate) fn point(&self, s: [f64; 3]) -> V3<T> {
        match &self.a {
            Some(a) => add(self.r, apply(a, s)),
            None => add(self.r, cst3(s)),
        }
    }

    /// The body vector `a` in global axes.
    pub(crate) fn axis(&self, a: [f64; 3]) -> V3<T> {
        match &self.a {
            Some(m) => apply(m, a),
            None => cst3(a),
        }
    }

    /// The velocity of the body point `s`: `ṙ + J(p, s) ṗ`.
    pub(crate) fn point_velocity(&self, s: [f64; 3]) -> V3<T> {
        match (&self.p, &self.pd) {
            (Some(p), Some(pd)) => {
                // J(p, s) ṗ is the derivative of the quadratic A(p) s along ṗ.
                let mid = |k: usize| p[k] + pd[k];
                let plus = rotate(&std::array::from_fn(mid), cst3(s));
                let (a, b) = (rotate(p, cst3(s)), rotate(pd, cst3(s)));
                let rate = |i: usize| plus[i] - a[i] - b[i];
                add(self.linear_rate(), [rate(0), rate(1), rate(2)])
            }
            _ => self.linear_rate(),
        }
    }

    /// `ṙ` (zero at rest).
    fn linear_rate(&self) -> V3<T> {
        self.rd.unwrap_or_else(|| cst3([0.0; 3]))
    }

    /// The angular velocity in global axes (zero without rotation).
    pub(crate) fn omega(&self) -> V3<T> {
        match (&self.p, &self.pd) {
            (Some(p), Some(pd)) => omega_global(p, pd),
            _ => cst3([0.0; 3]),
        }
    }

    /// Adds the generalized force of the force `f` at the body point `s` to
    /// `out` (3 or 7 values; nothing for the ground).
    pub(crate) fn add_force(&self, s: [f64; 3], f: V3<T>, out: &mut [T]) {
        for k in 0..3.min(out.len()) {
            out[k] = out[k] + f[k];
        }
        if let (Some(p), true) = (&self.p, out.len() == 7) {
            let q = point_jt(p, cst3(s), f);
            for k in 0..4 {
                out[3 + k] = out[3 + k] + q[k];
            }
        }
    }

    /// Adds the generalized force of the torque `n` (global axes) to `out`.
    pub(crate) fn add_torque(&self, n: V3<T>, out: &mut [T]) {
        if let (Some(p), true) = (&self.p, out.len() == 7) {
            let q = torque_global(p, n);
            for k in 0..4 {
                out[3 + k] = out[3 + k] + q[k];
            }
        }
    }
}

/// `f(t)` for a time `t` that may carry derivatives.
pub(crate) fn of_time<T: Real>(f: &TimeFunction, t: T) -> T {
    let (v, d1, d2) = f.eval(t.value());
    t.chain(v, d1, d2)
}

/// A gradient over a constraint's variables (two bodies and time).
pub(crate) type D15 = Dual<{ super::real::VARS }>;
/// A gradient over a load's variables (two bodies' coordinates and rates).
pub(crate) type D28 = Dual<28>;

/// The numbers a constraint is evaluated in.
pub(crate) type J15 = Jet;
