//! Spatial joints and drivers, each written once as `Φ(q_A, q_B, t)` over
//! numbers that carry their derivatives ([`Real`]): `B`, `Φ_t`, the
//! constraint Hessian and the acceleration right-hand side are exact
//! (`docs/theory.md`, "Spatial joints"; the primitive constraints are Haug's,
//! 1989, §9.2-9.4). Each also tells its rows as sums and dot products of
//! tracked vectors ([`SpatialJoint::tracked_rows`], `hessian.rs`): the same
//! `Φ`, `B` and contracted Hessian without dual numbers, which Newton's
//! iterations use.
//!
//! Body A's axes are `(f_A, g_A, h_A)` (orthonormal, `h_A` the joint axis),
//! body B's likewise; `x_A`, `x_B` the joint points, `d = x_B − x_A`.

use std::fmt::Debug;

use super::frame::{D15, Frame, J15, of_time};
use super::hessian::{Rows, Tracked};
use super::real::Real;
use super::rotation::{V3, dot, sub};
use crate::planar::TimeFunction;

/// A spatial constraint element: its rows and its `Φ` over any [`Real`]
/// (the two generic evaluations are one function, see [`joint_evals!`]).
pub(crate) trait SpatialJoint: Send + Sync + Debug {
    /// The element's type, as model files name it.
    fn kind(&self) -> &'static str;
    /// The suffixes of its rows' names (`.x`, `.y`, …).
    fn row_names(&self) -> &'static [&'static str];
    /// `Φ` with its gradient over both bodies and time.
    fn eval_dual(&self, t: D15, a: &Frame<D15>, b: &Frame<D15>, out: &mut [D15]);
    /// `Φ` with its gradient and Hessian.
    fn eval_jet(&self, t: J15, a: &Frame<J15>, b: &Frame<J15>, out: &mut [J15]);
    /// `Φ` in plain numbers.
    fn eval_f64(&self, t: f64, a: &Frame<f64>, b: &Frame<f64>, out: &mut [f64]);
    /// Its rows as sums of tracked vectors and their dot products
    /// (`hessian.rs`), at time `t` and the frames' state, told to `rows`;
    /// `false` when the element has no such form (then dual numbers and
    /// jets give its gradient and Hessian).
    fn tracked_rows(
        &self,
        _t: f64,
        _a: &Frame<f64>,
        _b: &Frame<f64>,
        _rows: &mut dyn Rows,
    ) -> bool {
        false
    }
    /// Whether it prescribes a motion (its effort is `−λ`).
    fn is_driver(&self) -> bool {
        false
    }
    /// Its points in the axes of body A and body B (a driver's are those of
    /// the joint it drives), for drawings.
    fn points(&self) -> [[f64; 3]; 2];
    /// The joint points when it is a plain spherical joint, which has a
    /// hand-written fast path (`spherical.rs`).
    fn spherical_points(&self) -> Option<&[[f64; 3]; 2]> {
        None
    }
}

/// Implements the evaluations of [`SpatialJoint`] by the type's generic
/// `phi`.
macro_rules! joint_evals {
    () => {
        fn eval_dual(&self, t: D15, a: &Frame<D15>, b: &Frame<D15>, out: &mut [D15]) {
            self.phi(t, a, b, out)
        }
        fn eval_jet(&self, t: J15, a: &Frame<J15>, b: &Frame<J15>, out: &mut [J15]) {
            self.phi(t, a, b, out)
        }
        fn eval_f64(&self, t: f64, a: &Frame<f64>, b: &Frame<f64>, out: &mut [f64]) {
            self.phi(t, a, b, out)
        }
    };
}

/// Unit vector of `a` (`None` for a zero or non-finite vector).
pub(crate) fn unit(a: [f64; 3]) -> Option<[f64; 3]> {
    let n = dot(a, a).sqrt();
    (n > 0.0 && n.is_finite()).then(|| [a[0] / n, a[1] / n, a[2] / n])
}

/// An orthonormal triad `(f, g, h)` with `h` along the unit vector `h`.
pub(crate) fn triad(h: [f64; 3]) -> [[f64; 3]; 3] {
    // The coordinate axis least aligned with h, made orthogonal to it.
    let k = (0..3)
        .min_by(|&i, &j| h[i].abs().total_cmp(&h[j].abs()))
        .unwrap_or(0);
    let mut e = [0.0; 3];
    e[k] = 1.0;
    let c = dot(e, h);
    let f = unit(sub(e, [h[0] * c, h[1] * c, h[2] * c])).unwrap_or([1.0, 0.0, 0.0]);
    let g = super::rotation::cross(h, f);
    [f, g, h]
}

/// The frame-relative geometry of a joint: its points and each body's triad
/// (body axes), `[f, g, h]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Geometry {
    pub(crate) points: [[f64; 3]; 2],
    pub(crate) axes: [[[f64; 3]; 3]; 2],
}

impl Geometry {
    fn d<T: Real>(&self, a: &Frame<T>, b: &Frame<T>) -> V3<T> {
        sub(b.point(self.points[1]), a.point(self.points[0]))
    }

    fn ax<T: Real>(&self, fr: &Frame<T>, side: usize, k: usize) -> V3<T> {
        fr.axis(self.axes[side][k])
    }

    /// `d` as a tracked vector.
    fn tracked_d(&self, a: &Frame<f64>, b: &Frame<f64>) -> Tracked {
        Tracked::point(b, 1, self.points[1]).minus(&Tracked::point(a, 0, self.points[0]))
    }

    /// Axis `k` of side `side` as a tracked vector.
    fn tracked_ax(&self, fr: &Frame<f64>, side: usize, k: usize) -> Tracked {
        Tracked::axis(fr, side, self.axes[side][k])
    }

    /// [`coincide`](Self::coincide) from row `row`.
    fn tracked_coincide(&self, a: &Frame<f64>, b: &Frame<f64>, row: usize, rows: &mut dyn Rows) {
        rows.vector(row, -1.0, &self.tracked_d(a, b));
    }

    /// [`parallel`](Self::parallel) from row `row`.
    fn tracked_parallel(&self, a: &Frame<f64>, b: &Frame<f64>, row: usize, rows: &mut dyn Rows) {
        let axis = self.tracked_ax(a, 0, 2);
        rows.dot(row, 1.0, &axis, &self.tracked_ax(b, 1, 0));
        rows.dot(row + 1, 1.0, &axis, &self.tracked_ax(b, 1, 1));
    }

    /// [`on_line`](Self::on_line) from row `row`.
    fn tracked_on_line(&self, a: &Frame<f64>, b: &Frame<f64>, row: usize, rows: &mut dyn Rows) {
        let d = self.tracked_d(a, b);
        rows.dot(row, 1.0, &self.tracked_ax(a, 0, 0), &d);
        rows.dot(row + 1, 1.0, &self.tracked_ax(a, 0, 1), &d);
    }

    /// `x_A − x_B` (3 rows).
    fn coincide<T: Real>(&self, a: &Frame<T>, b: &Frame<T>, out: &mut [T]) {
        let d = self.d(a, b);
        for k in 0..3 {
            out[k] = -d[k];
        }
    }

    /// `h_A · f_B`, `h_A · g_B`: the axes stay parallel (2 rows).
    fn parallel<T: Real>(&self, a: &Frame<T>, b: &Frame<T>, out: &mut [T]) {
        let h = self.ax(a, 0, 2);
        out[0] = dot(h, self.ax(b, 1, 0));
        out[1] = dot(h, self.ax(b, 1, 1));
    }

    /// `f_A · d`, `g_A · d`: B's point stays on A's axis line (2 rows).
    fn on_line<T: Real>(&self, a: &Frame<T>, b: &Frame<T>, out: &mut [T]) {
        let d = self.d(a, b);
        out[0] = dot(self.ax(a, 0, 0), d);
        out[1] = dot(self.ax(a, 0, 1), d);
    }
}

/// Spherical (ball) joint: the points coincide, `Φ = x_A − x_B` (3 rows).
#[derive(Clone, Debug)]
pub(crate) struct Spherical(pub(crate) Geometry);

impl Spherical {
    fn phi<T: Real>(&self, _: T, a: &Frame<T>, b: &Frame<T>, out: &mut [T]) {
        self.0.coincide(a, b, out);
    }
}

impl SpatialJoint for Spherical {
    fn points(&self) -> [[f64; 3]; 2] {
        self.0.points
    }
    fn kind(&self) -> &'static str {
        "spherical"
    }
    fn spherical_points(&self) -> Option<&[[f64; 3]; 2]> {
        Some(&self.0.points)
    }
    fn row_names(&self) -> &'static [&'static str] {
        &[".x", ".y", ".z"]
    }
    fn tracked_rows(&self, _: f64, a: &Frame<f64>, b: &Frame<f64>, rows: &mut dyn Rows) -> bool {
        self.0.tracked_coincide(a, b, 0, rows);
        true
    }
    joint_evals!();
}

/// Revolute joint: the points coincide and the axes stay parallel (5 rows).
#[derive(Clone, Debug)]
pub(crate) struct Revolute(pub(crate) Geometry);

impl Revolute {
    fn phi<T: Real>(&self, _: T, a: &Frame<T>, b: &Frame<T>, out: &mut [T]) {
        self.0.coincide(a, b, &mut out[..3]);
        self.0.parallel(a, b, &mut out[3..5]);
    }
}

impl SpatialJoint for Revolute {
    fn points(&self) -> [[f64; 3]; 2] {
        self.0.points
    }
    fn kind(&self) -> &'static str {
        "revolute"
    }
    fn row_names(&self) -> &'static [&'static str] {
        &[".x", ".y", ".z", ".axis_f", ".axis_g"]
    }
    fn tracked_rows(&self, _: f64, a: &Frame<f64>, b: &Frame<f64>, rows: &mut dyn Rows) -> bool {
        self.0.tracked_coincide(a, b, 0, rows);
        self.0.tracked_parallel(a, b, 3, rows);
        true
    }
    joint_evals!();
}

/// Cylindrical joint: the axes stay parallel and B's point stays on A's axis
/// line (4 rows: rotation about and sliding along the axis are free).
#[derive(Clone, Debug)]
pub(crate) struct Cylindrical(pub(crate) Geometry);

impl Cylindrical {
    fn phi<T: Real>(&self, _: T, a: &Frame<T>, b: &Frame<T>, out: &mut [T]) {
        self.0.parallel(a, b, &mut out[..2]);
        self.0.on_line(a, b, &mut out[2..4]);
    }
}

impl SpatialJoint for Cylindrical {
    fn points(&self) -> [[f64; 3]; 2] {
        self.0.points
    }
    fn kind(&self) -> &'static str {
        "cylindrical"
    }
    fn row_names(&self) -> &'static [&'static str] {
        &[".axis_f", ".axis_g", ".line_f", ".line_g"]
    }
    fn tracked_rows(&self, _: f64, a: &Frame<f64>, b: &Frame<f64>, rows: &mut dyn Rows) -> bool {
        self.0.tracked_parallel(a, b, 0, rows);
        self.0.tracked_on_line(a, b, 2, rows);
        true
    }
    joint_evals!();
}

/// Prismatic joint: a cylindrical joint whose rotation about the axis is
/// locked at the initial relative orientation, `f_A · g_B⁰ = 0` with `g_B⁰`
/// the body-B vector along `g_A` at the start (5 rows).
#[derive(Clone, Debug)]
pub(crate) struct Prismatic {
    pub(crate) geometry: Geometry,
    /// `g_A` at the start, in body B's axes.
    pub(crate) g_b0: [f64; 3],
}

impl Prismatic {
    fn phi<T: Real>(&self, t: T, a: &Frame<T>, b: &Frame<T>, out: &mut [T]) {
        Cylindrical(self.geometry).phi(t, a, b, &mut out[..4]);
        out[4] = dot(self.geometry.ax(a, 0, 0), b.axis(self.g_b0));
    }
}

impl SpatialJoint for Prismatic {
    fn points(&self) -> [[f64; 3]; 2] {
        self.geometry.points
    }
    fn kind(&self) -> &'static str {
        "prismatic"
    }
    fn row_names(&self) -> &'static [&'static str] {
        &[".axis_f", ".axis_g", ".line_f", ".line_g", ".twist"]
    }
    fn tracked_rows(&self, _: f64, a: &Frame<f64>, b: &Frame<f64>, rows: &mut dyn Rows) -> bool {
        let g = &self.geometry;
        g.tracked_parallel(a, b, 0, rows);
        g.tracked_on_line(a, b, 2, rows);
        rows.dot(
            4,
            1.0,
            &g.tracked_ax(a, 0, 0),
            &Tracked::axis(b, 1, self.g_b0),
        );
        true
    }
    joint_evals!();
}

/// Universal (Cardan) joint: the points coincide and the two cross axes
/// (`h_A`, `h_B`) stay perpendicular (4 rows).
#[derive(Clone, Debug)]
pub(crate) struct Universal(pub(crate) Geometry);

impl Universal {
    fn phi<T: Real>(&self, _: T, a: &Frame<T>, b: &Frame<T>, out: &mut [T]) {
        self.0.coincide(a, b, &mut out[..3]);
        out[3] = dot(self.0.ax(a, 0, 2), self.0.ax(b, 1, 2));
    }
}

impl SpatialJoint for Universal {
    fn points(&self) -> [[f64; 3]; 2] {
        self.0.points
    }
    fn kind(&self) -> &'static str {
        "universal"
    }
    fn row_names(&self) -> &'static [&'static str] {
        &[".x", ".y", ".z", ".cross"]
    }
    fn tracked_rows(&self, _: f64, a: &Frame<f64>, b: &Frame<f64>, rows: &mut dyn Rows) -> bool {
        self.0.tracked_coincide(a, b, 0, rows);
        rows.dot(
            3,
            1.0,
            &self.0.tracked_ax(a, 0, 2),
            &self.0.tracked_ax(b, 1, 2),
        );
        true
    }
    joint_evals!();
}

/// Weld: the points coincide and the relative orientation stays the initial
/// one, `x_A · y_B⁰ = y_A · z_B⁰ = z_A · x_B⁰ = 0` with `x_B⁰, y_B⁰, z_B⁰` the
/// body-B vectors along A's axes at the start (6 rows).
#[derive(Clone, Debug)]
pub(crate) struct Weld {
    pub(crate) geometry: Geometry,
    /// A's axes x, y, z at the start, in body B's axes.
    pub(crate) a_in_b: [[f64; 3]; 3],
}

impl Weld {
    fn phi<T: Real>(&self, _: T, a: &Frame<T>, b: &Frame<T>, out: &mut [T]) {
        self.geometry.coincide(a, b, &mut out[..3]);
        let e = |k: usize| {
            let mut v = [0.0; 3];
            v[k] = 1.0;
            a.axis(v)
        };
        for k in 0..3 {
            out[3 + k] = dot(e(k), b.axis(self.a_in_b[(k + 1) % 3]));
        }
    }
}

impl SpatialJoint for Weld {
    fn points(&self) -> [[f64; 3]; 2] {
        self.geometry.points
    }
    fn kind(&self) -> &'static str {
        "weld"
    }
    fn row_names(&self) -> &'static [&'static str] {
        &[".x", ".y", ".z", ".rx", ".ry", ".rz"]
    }
    fn tracked_rows(&self, _: f64, a: &Frame<f64>, b: &Frame<f64>, rows: &mut dyn Rows) -> bool {
        self.geometry.tracked_coincide(a, b, 0, rows);
        for k in 0..3 {
            let mut e = [0.0; 3];
            e[k] = 1.0;
            let other = Tracked::axis(b, 1, self.a_in_b[(k + 1) % 3]);
            rows.dot(3 + k, 1.0, &Tracked::axis(a, 0, e), &other);
        }
        true
    }
    joint_evals!();
}

/// Distance (a massless rod): `Φ = ½(|x_B − x_A|² − L²)` (1 row).
#[derive(Clone, Debug)]
pub(crate) struct Distance {
    pub(crate) geometry: Geometry,
    pub(crate) length: f64,
}

impl Distance {
    fn phi<T: Real>(&self, _: T, a: &Frame<T>, b: &Frame<T>, out: &mut [T]) {
        let d = self.geometry.d(a, b);
        out[0] = (dot(d, d) - T::cst(self.length * self.length)).scale(0.5);
    }
}

impl SpatialJoint for Distance {
    fn points(&self) -> [[f64; 3]; 2] {
        self.geometry.points
    }
    fn kind(&self) -> &'static str {
        "distance"
    }
    fn row_names(&self) -> &'static [&'static str] {
        &[""]
    }
    fn tracked_rows(&self, _: f64, a: &Frame<f64>, b: &Frame<f64>, rows: &mut dyn Rows) -> bool {
        let d = self.geometry.tracked_d(a, b);
        rows.dot(0, 0.5, &d, &d);
        rows.constant(0, -0.5 * self.length * self.length);
        true
    }
    joint_evals!();
}

/// A driver of a joint's rotation about its axis: `Φ = sin(θ − f(t))`, with
/// `θ` the angle from `f_A` to B's initial `f_A` about `h_A` (zero in the
/// initial pose): `Φ = s cos f − c sin f`, `c = f_A · f_B⁰`, `s = g_A · f_B⁰`.
/// Near the solution `∂Φ/∂θ = 1`, so `λ` is minus the driving torque.
#[derive(Clone, Debug)]
pub(crate) struct AngleDriver {
    pub(crate) geometry: Geometry,
    /// `f_A` at the start, in body B's axes.
    pub(crate) f_b0: [f64; 3],
    pub(crate) f: TimeFunction,
}

impl AngleDriver {
    /// `(cos θ, sin θ)`.
    pub(crate) fn cos_sin<T: Real>(&self, a: &Frame<T>, b: &Frame<T>) -> (T, T) {
        let fb = b.axis(self.f_b0);
        let g = &self.geometry;
        (dot(g.ax(a, 0, 0), fb), dot(g.ax(a, 0, 1), fb))
    }

    fn phi<T: Real>(&self, t: T, a: &Frame<T>, b: &Frame<T>, out: &mut [T]) {
        let (c, s) = self.cos_sin(a, b);
        let f = of_time(&self.f, t);
        out[0] = s * f.cos() - c * f.sin();
    }
}

impl SpatialJoint for AngleDriver {
    fn points(&self) -> [[f64; 3]; 2] {
        self.geometry.points
    }
    fn kind(&self) -> &'static str {
        "angle driver"
    }
    fn row_names(&self) -> &'static [&'static str] {
        &[""]
    }
    fn is_driver(&self) -> bool {
        true
    }
    fn tracked_rows(&self, t: f64, a: &Frame<f64>, b: &Frame<f64>, rows: &mut dyn Rows) -> bool {
        // Φ = s cos f − c sin f with c = f_A · f_B⁰, s = g_A · f_B⁰.
        let (sin, cos) = of_time(&self.f, t).sin_cos();
        let fb = Tracked::axis(b, 1, self.f_b0);
        let g = &self.geometry;
        rows.dot(0, cos, &g.tracked_ax(a, 0, 1), &fb);
        rows.dot(0, -sin, &g.tracked_ax(a, 0, 0), &fb);
        true
    }
    joint_evals!();
}

/// A driver of a joint's translation along its axis: `Φ = h_A · d − f(t)`.
#[derive(Clone, Debug)]
pub(crate) struct SlideDriver {
    pub(crate) geometry: Geometry,
    pub(crate) f: TimeFunction,
}

impl SlideDriver {
    fn phi<T: Real>(&self, t: T, a: &Frame<T>, b: &Frame<T>, out: &mut [T]) {
        let g = &self.geometry;
        out[0] = dot(g.ax(a, 0, 2), g.d(a, b)) - of_time(&self.f, t);
    }
}

impl SpatialJoint for SlideDriver {
    fn points(&self) -> [[f64; 3]; 2] {
        self.geometry.points
    }
    fn kind(&self) -> &'static str {
        "translation driver"
    }
    fn row_names(&self) -> &'static [&'static str] {
        &[""]
    }
    fn is_driver(&self) -> bool {
        true
    }
    fn tracked_rows(&self, t: f64, a: &Frame<f64>, b: &Frame<f64>, rows: &mut dyn Rows) -> bool {
        let g = &self.geometry;
        rows.dot(0, 1.0, &g.tracked_ax(a, 0, 2), &g.tracked_d(a, b));
        rows.constant(0, -of_time(&self.f, t));
        true
    }
    joint_evals!();
}
