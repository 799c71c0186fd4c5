//! Spatial forces, each written once as the generalized force
//! `g(q_A, q_B, q̇_A, q̇_B, t)` on its two bodies over numbers that carry
//! their derivatives: `∂g/∂u` and `∂g/∂u̇` are exact (`docs/theory.md`,
//! "Spatial forces"). A force `f` at a body point `s` acts on the body's
//! coordinates as `[f; J(p, s)ᵀ f]`, a torque `n` (global axes) as
//! `[0; 2 E(p)ᵀ n]`.

use std::fmt::Debug;

use super::frame::{D28, Frame};
use super::joints::Geometry;
use super::real::Real;
use super::rotation::{V3, dot, scale, sub};
use crate::planar::TimeFunction;

/// A spatial load element.
pub(crate) trait SpatialLoad: Send + Sync + Debug {
    /// The element's type, as model files name it.
    fn kind(&self) -> &'static str;
    /// Adds its generalized forces on A (`ga`, 3 or 7 values) and B (`gb`),
    /// with their derivatives.
    fn eval_dual(&self, t: f64, a: &Frame<D28>, b: &Frame<D28>, ga: &mut [D28], gb: &mut [D28]);
    /// The same in plain numbers.
    fn eval_f64(&self, t: f64, a: &Frame<f64>, b: &Frame<f64>, ga: &mut [f64], gb: &mut [f64]);
    /// The points it acts at on each side (zero when it has none).
    fn points(&self) -> [[f64; 3]; 2] {
        [[0.0; 3]; 2]
    }
    /// Its potential energy (0 for non-conservative loads).
    fn potential(&self, _a: &Frame<f64>, _b: &Frame<f64>) -> f64 {
        0.0
    }
    /// Whether its forces derive from [`potential`](Self::potential) alone
    /// (default: no; an undamped spring does).
    fn conservative(&self) -> bool {
        false
    }
}

macro_rules! load_evals {
    () => {
        fn eval_dual(
            &self,
            t: f64,
            a: &Frame<D28>,
            b: &Frame<D28>,
            ga: &mut [D28],
            gb: &mut [D28],
        ) {
            self.forces(t, a, b, ga, gb)
        }
        fn eval_f64(&self, t: f64, a: &Frame<f64>, b: &Frame<f64>, ga: &mut [f64], gb: &mut [f64]) {
            self.forces(t, a, b, ga, gb)
        }
    };
}

/// Three time functions as a vector.
fn vector<T: Real>(f: &[TimeFunction; 3], t: f64) -> V3<T> {
    std::array::from_fn(|k| T::cst(f[k].eval(t).0))
}

/// A force on a point of body A, in global or body axes, as functions of
/// time.
#[derive(Clone, Debug)]
pub(crate) struct PointForce {
    pub(crate) point: [f64; 3],
    pub(crate) f: [TimeFunction; 3],
    /// Whether `f` is in A's body axes (turns with it).
    pub(crate) body_axes: bool,
}

impl PointForce {
    fn forces<T: Real>(&self, t: f64, a: &Frame<T>, _: &Frame<T>, ga: &mut [T], _: &mut [T]) {
        let f: V3<T> = vector(&self.f, t);
        let f = if self.body_axes {
            match &a.p {
                Some(p) => super::rotation::rotate(p, f),
                None => f,
            }
        } else {
            f
        };
        a.add_force(self.point, f, ga);
    }
}

impl SpatialLoad for PointForce {
    fn kind(&self) -> &'static str {
        "force"
    }
    fn points(&self) -> [[f64; 3]; 2] {
        [self.point, [0.0; 3]]
    }
    load_evals!();
}

/// A torque on body A, in global or body axes, as functions of time.
#[derive(Clone, Debug)]
pub(crate) struct Torque {
    pub(crate) n: [TimeFunction; 3],
    pub(crate) body_axes: bool,
}

impl Torque {
    fn forces<T: Real>(&self, t: f64, a: &Frame<T>, _: &Frame<T>, ga: &mut [T], _: &mut [T]) {
        let n: V3<T> = vector(&self.n, t);
        let n = match (&a.p, self.body_axes) {
            (Some(p), true) => super::rotation::rotate(p, n),
            _ => n,
        };
        a.add_torque(n, ga);
    }
}

impl SpatialLoad for Torque {
    fn kind(&self) -> &'static str {
        "torque"
    }
    load_evals!();
}

/// A translational spring-damper between two points: tension
/// `k (L − L₀) + c L̇ + f₀` along the line, pulling the points together when
/// positive.
#[derive(Clone, Debug)]
pub(crate) struct Spring {
    pub(crate) points: [[f64; 3]; 2],
    pub(crate) stiffness: f64,
    pub(crate) damping: f64,
    pub(crate) length: f64,
    pub(crate) preload: f64,
}

impl Spring {
    fn forces<T: Real>(&self, _: f64, a: &Frame<T>, b: &Frame<T>, ga: &mut [T], gb: &mut [T]) {
        let [sa, sb] = self.points;
        let d = sub(b.point(sb), a.point(sa));
        let l = dot(d, d).sqrt();
        let ld = dot(d, sub(b.point_velocity(sb), a.point_velocity(sa))) / l;
        let tension = (l - T::cst(self.length)).scale(self.stiffness)
            + ld.scale(self.damping)
            + T::cst(self.preload);
        let f = scale(d, tension / l);
        a.add_force(sa, f, ga);
        b.add_force(sb, scale(f, T::cst(-1.0)), gb);
    }
}

impl SpatialLoad for Spring {
    fn kind(&self) -> &'static str {
        "spring-damper"
    }
    fn points(&self) -> [[f64; 3]; 2] {
        self.points
    }
    load_evals!();
    fn potential(&self, a: &Frame<f64>, b: &Frame<f64>) -> f64 {
        let d = sub(b.point(self.points[1]), a.point(self.points[0]));
        let e = dot(d, d).sqrt() - self.length;
        0.5 * self.stiffness * e * e + self.preload * e
    }
    fn conservative(&self) -> bool {
        self.damping == 0.0
    }
}

/// A rotational spring-damper about a revolute axis `h_A`: the torque
/// `−k (θ − θ₀) − c θ̇` on B (and its opposite on A) about `h_A`, with `θ` the
/// angle about `h_A` from `f_A` to `f_B⁰` (B's vector along `f_A` in the
/// initial pose: `θ = 0` there), in `(−π, π]`, and
/// `θ̇ = h_A · (ω_B − ω_A)`.
#[derive(Clone, Debug)]
pub(crate) struct RotationalSpring {
    pub(crate) geometry: Geometry,
    /// `f_A` at the start, in body B's axes.
    pub(crate) f_b0: [f64; 3],
    pub(crate) stiffness: f64,
    pub(crate) damping: f64,
    pub(crate) angle: f64,
}

impl RotationalSpring {
    fn theta<T: Real>(&self, a: &Frame<T>, b: &Frame<T>) -> T {
        let g = &self.geometry;
        let fb = b.axis(self.f_b0);
        T::atan2(dot(a.axis(g.axes[0][1]), fb), dot(a.axis(g.axes[0][0]), fb))
    }

    fn forces<T: Real>(&self, _: f64, a: &Frame<T>, b: &Frame<T>, ga: &mut [T], gb: &mut [T]) {
        let h = a.axis(self.geometry.axes[0][2]);
        let rate = dot(h, sub(b.omega(), a.omega()));
        let tau = -(self.theta(a, b) - T::cst(self.angle)).scale(self.stiffness)
            - rate.scale(self.damping);
        let n = scale(h, tau);
        b.add_torque(n, gb);
        a.add_torque(scale(n, T::cst(-1.0)), ga);
    }
}

impl SpatialLoad for RotationalSpring {
    fn kind(&self) -> &'static str {
        "rotational spring-damper"
    }
    load_evals!();
    fn potential(&self, a: &Frame<f64>, b: &Frame<f64>) -> f64 {
        let e = self.theta(a, b) - self.angle;
        0.5 * self.stiffness * e * e
    }
    fn conservative(&self) -> bool {
        self.damping == 0.0
    }
}
