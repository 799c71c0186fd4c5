//! `mstar.planar.Builder`: [`mstar::planar::PlanarBuilder`] from Python,
//! element by element, with bodies as handles and points as `body.at(sx, sy)`
//! or `ground(x, y)`.

use mstar::planar::{self as planar, At, BodyId, Coordinate};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::ModelError;
use crate::model::NativeModel;

/// A body of a builder (what `rigid_body` and `point_mass` return).
#[pyclass(module = "mstar._native", frozen, from_py_object)]
#[derive(Clone, Debug)]
pub(crate) struct Body {
    id: BodyId,
    name: String,
}

#[pymethods]
impl Body {
    /// The point at local offset `(sx, sy)` of the body (`(0, 0)`, the
    /// centre of mass, for a point mass).
    #[pyo3(signature = (sx = 0.0, sy = 0.0))]
    fn at(&self, sx: f64, sy: f64) -> Point {
        Point(At::Body(self.id, [sx, sy]))
    }

    /// The body's name.
    #[getter]
    fn name(&self) -> &str {
        &self.name
    }

    fn __repr__(&self) -> String {
        format!("Body({:?})", self.name)
    }
}

/// A point a joint or a force attaches to: `body.at(sx, sy)` or
/// `ground(x, y)`.
#[pyclass(module = "mstar._native", frozen, from_py_object)]
#[derive(Clone, Copy, Debug)]
pub(crate) struct Point(At);

/// The fixed point `(x, y)` of the ground.
#[pyfunction]
#[pyo3(signature = (x = 0.0, y = 0.0))]
pub(crate) fn ground(x: f64, y: f64) -> Point {
    Point(At::Ground([x, y]))
}

/// A function of time for drivers and forces: a number is a constant.
#[pyclass(module = "mstar._native", frozen, from_py_object)]
#[derive(Clone, Debug)]
pub(crate) struct TimeFunction(planar::TimeFunction);

#[pymethods]
impl TimeFunction {
    /// `f(t) = value`.
    #[staticmethod]
    fn constant(value: f64) -> Self {
        Self(planar::TimeFunction::Constant(value))
    }

    /// `f(t) = value + rate · t`.
    #[staticmethod]
    fn linear(value: f64, rate: f64) -> Self {
        Self(planar::TimeFunction::Linear { value, rate })
    }

    /// `f(t) = offset + amplitude · sin(omega t + phase)`.
    #[staticmethod]
    #[pyo3(signature = (offset, amplitude, omega, phase = 0.0))]
    fn sine(offset: f64, amplitude: f64, omega: f64, phase: f64) -> Self {
        Self(planar::TimeFunction::Sine {
            offset,
            amplitude,
            omega,
            phase,
        })
    }

    /// Piecewise linear through `(t, value)` points (times increasing),
    /// constant outside them.
    #[staticmethod]
    fn table(points: Vec<(f64, f64)>) -> Self {
        Self(planar::TimeFunction::Table(points))
    }

    fn __repr__(&self) -> String {
        format!("TimeFunction({:?})", self.0)
    }
}

/// A number (a constant) or a [`TimeFunction`].
#[derive(FromPyObject)]
pub(crate) enum FunctionArg {
    Function(TimeFunction),
    Number(f64),
}

impl FunctionArg {
    /// The function (a number: a constant).
    pub(crate) fn get(self) -> planar::TimeFunction {
        match self {
            Self::Function(f) => f.0,
            Self::Number(c) => planar::TimeFunction::Constant(c),
        }
    }
}

/// `x`, `y` or `theta`.
fn coordinate(name: &str) -> PyResult<Coordinate> {
    match name {
        "x" => Ok(Coordinate::X),
        "y" => Ok(Coordinate::Y),
        "theta" => Ok(Coordinate::Theta),
        _ => Err(PyValueError::new_err(format!(
            "coordinate: expected 'x', 'y' or 'theta', got '{name}'"
        ))),
    }
}

/// A planar mechanism assembled element by element
/// ([`mstar::planar::PlanarBuilder`]); `build()` checks it as a whole.
#[pyclass(module = "mstar._native")]
#[derive(Debug, Default)]
pub(crate) struct PlanarBuilder(planar::PlanarBuilder);

#[pymethods]
impl PlanarBuilder {
    #[new]
    fn new() -> Self {
        Self::default()
    }

    /// Sets gravity (default `(0, -9.81)` m/s²).
    fn gravity(&mut self, gx: f64, gy: f64) {
        self.0.gravity(gx, gy);
    }

    /// Adds a rigid body: mass (kg), inertia about the centre of mass
    /// (kg m²), pose `(x, y, theta)`, velocity `(vx, vy, omega)`.
    #[pyo3(signature = (name, *, mass, inertia, pose, velocity = (0.0, 0.0, 0.0)))]
    fn rigid_body(
        &mut self,
        name: &str,
        mass: f64,
        inertia: f64,
        pose: [f64; 3],
        velocity: (f64, f64, f64),
    ) -> Body {
        let body = planar::RigidBody {
            mass,
            inertia,
            pose,
            velocity: velocity.into(),
        };
        let id = self.0.rigid_body(name, body);
        Body {
            id,
            name: name.to_string(),
        }
    }

    /// Adds a point mass: mass (kg), position `(x, y)`, velocity `(vx, vy)`.
    #[pyo3(signature = (name, *, mass, position, velocity = (0.0, 0.0)))]
    fn point_mass(
        &mut self,
        name: &str,
        mass: f64,
        position: [f64; 2],
        velocity: (f64, f64),
    ) -> Body {
        let point = planar::PointMass {
            mass,
            position,
            velocity: velocity.into(),
        };
        let id = self.0.point_mass(name, point);
        Body {
            id,
            name: name.to_string(),
        }
    }

    /// A revolute joint: the points `a` and `b` coincide.
    fn revolute(&mut self, name: &str, a: Point, b: Point) {
        self.0.revolute(name, a.0, b.0);
    }

    /// A distance joint (massless rod): `a` and `b` stay `length` apart.
    fn distance(&mut self, name: &str, a: Point, b: Point, length: f64) {
        self.0.distance(name, a.0, b.0, length);
    }

    /// A weld: the points coincide and the relative angle stays.
    fn weld(&mut self, name: &str, a: Point, b: Point) {
        self.0.weld(name, a.0, b.0);
    }

    /// A prismatic joint: `b` slides along the line through `a` with
    /// direction `axis` (in `a`'s body frame, or global for the ground).
    fn prismatic(&mut self, name: &str, a: Point, axis: [f64; 2], b: Point) {
        self.0.prismatic(name, a.0, axis, b.0);
    }

    /// A driver: `coordinate` (`"x"`, `"y"`, `"theta"`) of `body` = `f(t)`.
    fn driver(
        &mut self,
        name: &str,
        body: &Body,
        coordinate: &str,
        f: FunctionArg,
    ) -> PyResult<()> {
        let c = self::coordinate(coordinate)?;
        self.0.driver(name, body.id, c, f.get());
        Ok(())
    }

    /// A force `(fx(t), fy(t))` in global directions at a point.
    fn force(&mut self, name: &str, at: Point, fx: FunctionArg, fy: FunctionArg) {
        self.0.force(name, at.0, fx.get(), fy.get());
    }

    /// A torque `tau(t)` on a rigid body (counter-clockwise positive).
    fn torque(&mut self, name: &str, body: &Body, tau: FunctionArg) {
        self.0.torque(name, body.id, tau.get());
    }

    /// A linear spring-damper between two points: tension
    /// `stiffness (l - rest_length) + damping dl/dt`.
    #[pyo3(signature = (name, a, b, *, stiffness, rest_length, damping = 0.0))]
    fn spring(
        &mut self,
        name: &str,
        a: Point,
        b: Point,
        stiffness: f64,
        rest_length: f64,
        damping: f64,
    ) {
        let spring = planar::SpringDamper {
            stiffness,
            damping,
            rest_length,
        };
        self.0.spring(name, a.0, b.0, spring);
    }

    /// A rotational spring-damper between body `a` (`None`: the ground) and
    /// rigid body `b`, at rest at their initial relative angle.
    #[pyo3(signature = (name, a, b, *, stiffness, damping = 0.0))]
    fn rotational_spring(
        &mut self,
        name: &str,
        a: Option<&Body>,
        b: &Body,
        stiffness: f64,
        damping: f64,
    ) {
        let spring = planar::RotationalSpringDamper { stiffness, damping };
        self.0
            .rotational_spring(name, a.map(|a| a.id), b.id, spring);
    }

    /// Checks the model and makes it (`ModelError` with the builder's
    /// message when it is not valid).
    fn build(&self) -> PyResult<NativeModel> {
        let system = self
            .0
            .build()
            .map_err(|e| ModelError::new_err(crate::message(&e)))?;
        Ok(NativeModel::built(system))
    }
}
