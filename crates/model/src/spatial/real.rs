//! Numbers that carry their own derivatives (forward-mode automatic
//! differentiation), so that every spatial element is written once, as a
//! function of its coordinates and time, and its first and second derivatives
//! are exact (not finite differences): [`Dual`] carries a gradient, [`Jet`] a
//! gradient and a Hessian.
//!
//! Elements are written generically over [`Real`]; `f64` is a [`Real`] with
//! no derivatives.

use std::ops::{Add, Div, Mul, Neg, Sub};

/// A number the spatial elements compute with: `f64`, [`Dual`] or [`Jet`].
pub(crate) trait Real:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    /// A constant.
    fn cst(x: f64) -> Self;
    /// The value, without derivatives.
    fn value(&self) -> f64;
    /// `self · k` for a constant `k` (cheaper than a product of two numbers).
    fn scale(self, k: f64) -> Self;
    /// `f(self)` from `f`, `f'` and `f''` at the value (the chain rule).
    fn chain(self, f: f64, f1: f64, f2: f64) -> Self;

    /// `√x`.
    fn sqrt(self) -> Self {
        let s = self.value().sqrt();
        self.chain(s, 0.5 / s, -0.25 / (s * s * s))
    }

    /// `sin x`.
    fn sin(self) -> Self {
        let (s, c) = self.value().sin_cos();
        self.chain(s, c, -s)
    }

    /// `cos x`.
    fn cos(self) -> Self {
        let (s, c) = self.value().sin_cos();
        self.chain(c, -s, -c)
    }

    /// `atan x`.
    fn atan(self) -> Self {
        let x = self.value();
        let d = 1.0 / (1.0 + x * x);
        self.chain(x.atan(), d, -2.0 * x * d * d)
    }

    /// The angle of `(x, y)`, `atan2(y, x)`, smooth away from the origin: the
    /// branch is chosen by the values so that no quotient is large.
    fn atan2(y: Self, x: Self) -> Self {
        let (yv, xv) = (y.value(), x.value());
        if xv.abs() >= yv.abs() {
            let branch = if xv >= 0.0 {
                0.0
            } else if yv >= 0.0 {
                std::f64::consts::PI
            } else {
                -std::f64::consts::PI
            };
            (y / x).atan() + Self::cst(branch)
        } else {
            let half = std::f64::consts::FRAC_PI_2.copysign(yv);
            Self::cst(half) - (x / y).atan()
        }
    }
}

impl Real for f64 {
    fn cst(x: f64) -> Self {
        x
    }
    fn value(&self) -> f64 {
        *self
    }
    fn scale(self, k: f64) -> Self {
        self * k
    }
    fn chain(self, f: f64, _: f64, _: f64) -> Self {
        f
    }
}

/// The most variables a derivative carries: two rigid bodies' coordinates
/// (7 each) and time.
pub(crate) const VARS: usize = 15;
/// The index of time among the variables of a [`Jet`].
pub(crate) const TIME: usize = 14;

/// A value with its gradient over [`VARS`] variables.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Dual<const N: usize> {
    pub(crate) v: f64,
    pub(crate) g: [f64; N],
}

impl<const N: usize> Dual<N> {
    /// The variable number `k` at the value `v`.
    pub(crate) fn var(v: f64, k: usize) -> Self {
        let mut g = [0.0; N];
        g[k] = 1.0;
        Self { v, g }
    }
}

impl<const N: usize> Add for Dual<N> {
    type Output = Self;
    fn add(mut self, o: Self) -> Self {
        self.v += o.v;
        self.g.iter_mut().zip(&o.g).for_each(|(a, b)| *a += b);
        self
    }
}

impl<const N: usize> Sub for Dual<N> {
    type Output = Self;
    fn sub(mut self, o: Self) -> Self {
        self.v -= o.v;
        self.g.iter_mut().zip(&o.g).for_each(|(a, b)| *a -= b);
        self
    }
}

impl<const N: usize> Neg for Dual<N> {
    type Output = Self;
    fn neg(self) -> Self {
        self.scale(-1.0)
    }
}

impl<const N: usize> Mul for Dual<N> {
    type Output = Self;
    fn mul(self, o: Self) -> Self {
        let mut g = [0.0; N];
        for k in 0..N {
            g[k] = self.v * o.g[k] + o.v * self.g[k];
        }
        Self { v: self.v * o.v, g }
    }
}

impl<const N: usize> Div for Dual<N> {
    type Output = Self;
    fn div(self, o: Self) -> Self {
        let r = 1.0 / o.v;
        self * o.chain(r, -r * r, 2.0 * r * r * r)
    }
}

impl<const N: usize> Real for Dual<N> {
    fn cst(x: f64) -> Self {
        Self { v: x, g: [0.0; N] }
    }
    fn value(&self) -> f64 {
        self.v
    }
    fn scale(mut self, k: f64) -> Self {
        self.v *= k;
        self.g.iter_mut().for_each(|a| *a *= k);
        self
    }
    fn chain(mut self, f: f64, f1: f64, _: f64) -> Self {
        self.v = f;
        self.g.iter_mut().for_each(|a| *a *= f1);
        self
    }
}

/// The entries of a symmetric `VARS × VARS` matrix on and above its diagonal.
const PACKED: usize = VARS * (VARS + 1) / 2;

/// A value with its gradient and (symmetric) Hessian over [`VARS`]
/// variables. The Hessian is kept on and above its diagonal, row by row
/// (`h[k VARS − k (k + 1)/2 + l]` for `k ≤ l`): half the products and half
/// the bytes that a `Jet` passed by value copies.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Jet {
    pub(crate) v: f64,
    pub(crate) g: [f64; VARS],
    h: [f64; PACKED],
}

impl Jet {
    /// The variable number `k` at the value `v`.
    pub(crate) fn var(v: f64, k: usize) -> Self {
        let mut j = Self::cst(v);
        j.g[k] = 1.0;
        j
    }

    /// `∂²/∂x_a ∂x_b`.
    pub(crate) fn hess(&self, a: usize, b: usize) -> f64 {
        let (k, l) = if a <= b { (a, b) } else { (b, a) };
        self.h[k * VARS - k * (k + 1) / 2 + l]
    }

    fn combine(mut self, o: &Self, f: impl Fn(f64, f64) -> f64) -> Self {
        self.v = f(self.v, o.v);
        for k in 0..VARS {
            self.g[k] = f(self.g[k], o.g[k]);
        }
        for (a, &b) in self.h.iter_mut().zip(&o.h) {
            *a = f(*a, b);
        }
        self
    }
}

impl Add for Jet {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        self.combine(&o, |a, b| a + b)
    }
}

impl Sub for Jet {
    type Output = Self;
    fn sub(self, o: Self) -> Self {
        self.combine(&o, |a, b| a - b)
    }
}

impl Neg for Jet {
    type Output = Self;
    fn neg(self) -> Self {
        self.scale(-1.0)
    }
}

impl Mul for Jet {
    type Output = Self;
    fn mul(self, o: Self) -> Self {
        let mut out = Self::cst(self.v * o.v);
        let mut p = 0;
        for k in 0..VARS {
            out.g[k] = self.v * o.g[k] + o.v * self.g[k];
            for l in k..VARS {
                out.h[p] =
                    self.v * o.h[p] + o.v * self.h[p] + self.g[k] * o.g[l] + o.g[k] * self.g[l];
                p += 1;
            }
        }
        out
    }
}

impl Div for Jet {
    type Output = Self;
    fn div(self, o: Self) -> Self {
        let r = 1.0 / o.v;
        self * o.chain(r, -r * r, 2.0 * r * r * r)
    }
}

impl Real for Jet {
    fn cst(x: f64) -> Self {
        Self {
            v: x,
            g: [0.0; VARS],
            h: [0.0; PACKED],
        }
    }
    fn value(&self) -> f64 {
        self.v
    }
    fn scale(mut self, k: f64) -> Self {
        self.v *= k;
        self.g.iter_mut().for_each(|a| *a *= k);
        self.h.iter_mut().for_each(|a| *a *= k);
        self
    }
    fn chain(self, f: f64, f1: f64, f2: f64) -> Self {
        let mut out = Self::cst(f);
        let mut p = 0;
        for k in 0..VARS {
            out.g[k] = f1 * self.g[k];
            for l in k..VARS {
                out.h[p] = f1 * self.h[p] + f2 * self.g[k] * self.g[l];
                p += 1;
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `f(x, y) = x² y + sin(x y) / y` against its derivatives by hand.
    #[test]
    fn jets_carry_exact_first_and_second_derivatives() {
        let f = |x: Jet, y: Jet| x * x * y + (x * y).sin() / y;
        let (x0, y0) = (0.7, 1.3);
        let j = f(Jet::var(x0, 0), Jet::var(y0, 1));
        let (s, c) = (x0 * y0).sin_cos();
        assert!((j.v - (x0 * x0 * y0 + s / y0)).abs() < 1e-15);
        assert!((j.g[0] - (2.0 * x0 * y0 + c)).abs() < 1e-14);
        let fy = x0 * x0 + x0 * c / y0 - s / (y0 * y0);
        assert!((j.g[1] - fy).abs() < 1e-14);
        assert!((j.hess(0, 0) - (2.0 * y0 - y0 * s)).abs() < 1e-14);
        let fxy = 2.0 * x0 - x0 * s;
        assert!((j.hess(0, 1) - fxy).abs() < 1e-14 && (j.hess(1, 0) - fxy).abs() < 1e-14);
        let fyy = -x0 * x0 * s / y0 - 2.0 * x0 * c / (y0 * y0) + 2.0 * s / (y0 * y0 * y0);
        assert!((j.hess(1, 1) - fyy).abs() < 1e-13);
        assert!(j.hess(2, 2) == 0.0 && j.g[3] == 0.0);
    }

    #[test]
    fn atan2_is_smooth_through_every_quadrant() {
        for k in 0..16 {
            let a = -3.0 + 0.4 * f64::from(k);
            let r = 1.7;
            let th = <Dual<2> as Real>::atan2(Dual::var(r * a.sin(), 1), Dual::var(r * a.cos(), 0));
            assert!((th.v - a.sin().atan2(a.cos())).abs() < 1e-14);
            // dθ/dx = −y/r², dθ/dy = x/r².
            assert!((th.g[0] + a.sin() / r).abs() < 1e-14);
            assert!((th.g[1] - a.cos() / r).abs() < 1e-14);
        }
    }
}
