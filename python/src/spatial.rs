//! `mstar.spatial.Builder`: [`mstar::model::spatial::SpatialBuilder`] from
//! Python, with the conventions of the planar one (`builder.rs`): bodies as
//! handles, points as `body.at(sx, sy, sz)` or `ground(x, y, z)`, functions
//! of time as numbers or `TimeFunction`s.

use mstar::model::spatial::{
    self as sp, Attach, Axes, DriverKind, JointSpec, JointType, SpatialBodyId, SpatialInertia,
};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::ModelError;
use crate::builder::FunctionArg;
use crate::model::NativeModel;

/// A body of a spatial builder (what `rigid_body` and `point_mass` return).
#[pyclass(module = "mstar._native", frozen, from_py_object)]
#[derive(Clone, Debug)]
pub(crate) struct SpatialBody {
    id: SpatialBodyId,
    name: String,
}

#[pymethods]
impl SpatialBody {
    /// The point at local offset `(sx, sy, sz)` (body axes, from the centre
    /// of mass; `(0, 0, 0)` for a point mass).
    #[pyo3(signature = (sx = 0.0, sy = 0.0, sz = 0.0))]
    fn at(&self, sx: f64, sy: f64, sz: f64) -> SpatialPoint {
        SpatialPoint(Attach::Body(self.id), [sx, sy, sz])
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

/// A point of a body (local) or of the ground (global).
#[pyclass(module = "mstar._native", frozen, from_py_object)]
#[derive(Clone, Copy, Debug)]
pub(crate) struct SpatialPoint(Attach, [f64; 3]);

/// The fixed point `(x, y, z)` of the ground.
#[pyfunction]
#[pyo3(signature = (x = 0.0, y = 0.0, z = 0.0))]
pub(crate) fn spatial_ground(x: f64, y: f64, z: f64) -> SpatialPoint {
    SpatialPoint(Attach::Ground, [x, y, z])
}

/// `"spherical"`, `"revolute"`, ... as in model files.
fn joint_type(name: &str) -> PyResult<JointType> {
    JointType::ALL
        .into_iter()
        .find(|k| k.name() == name)
        .ok_or_else(|| {
            let names: Vec<_> = JointType::ALL.iter().map(|k| k.name()).collect();
            PyValueError::new_err(format!(
                "type: expected one of {}, got '{name}'",
                names.join(", ")
            ))
        })
}

/// `"global"` or `"body"`.
fn axes_of(name: &str) -> PyResult<Axes> {
    match name {
        "global" => Ok(Axes::Global),
        "body" => Ok(Axes::Body),
        _ => Err(PyValueError::new_err(format!(
            "axes: expected 'global' or 'body', got '{name}'"
        ))),
    }
}

/// Three functions of time.
fn functions([x, y, z]: [FunctionArg; 3]) -> [mstar::planar::TimeFunction; 3] {
    [x.get(), y.get(), z.get()]
}

/// A spatial mechanism assembled element by element
/// ([`mstar::model::spatial::SpatialBuilder`]); `build()` checks it.
#[pyclass(module = "mstar._native")]
#[derive(Debug, Default)]
pub(crate) struct SpatialBuilder(sp::SpatialBuilder);

#[pymethods]
impl SpatialBuilder {
    #[new]
    fn new() -> Self {
        Self::default()
    }

    /// Sets gravity, m/s² (default `(0, 0, -9.81)`).
    fn gravity(&mut self, g: [f64; 3]) {
        self.0.gravity(g);
    }

    /// Adds a rigid body: `inertia` the principal moments `[Jxx, Jyy, Jzz]`
    /// or the 3 × 3 tensor (body axes, about the centre of mass); Euler
    /// parameters `orientation`; velocity and angular velocity global.
    #[pyo3(signature = (name, *, mass, inertia, position, orientation, velocity, angular_velocity, tensor))]
    #[allow(clippy::too_many_arguments)]
    fn rigid_body(
        &mut self,
        name: &str,
        mass: f64,
        inertia: [f64; 3],
        position: [f64; 3],
        orientation: [f64; 4],
        velocity: [f64; 3],
        angular_velocity: [f64; 3],
        tensor: Option<[[f64; 3]; 3]>,
    ) -> SpatialBody {
        let inertia = tensor.map_or(SpatialInertia::Principal(inertia), SpatialInertia::Matrix);
        let body = sp::SpatialBody {
            mass,
            inertia,
            position,
            orientation,
            velocity,
            angular_velocity,
        };
        let id = self.0.body(name, body);
        SpatialBody {
            id,
            name: name.to_string(),
        }
    }

    /// Adds a point mass: mass (kg), position and velocity (global).
    #[pyo3(signature = (name, *, mass, position, velocity))]
    fn point_mass(
        &mut self,
        name: &str,
        mass: f64,
        position: [f64; 3],
        velocity: [f64; 3],
    ) -> SpatialBody {
        let point = sp::SpatialPointMass {
            mass,
            position,
            velocity,
        };
        let id = self.0.point_mass(name, point);
        SpatialBody {
            id,
            name: name.to_string(),
        }
    }

    /// A joint of type `kind` between the points `a` and `b`: `axes` a
    /// direction in each side's axes (revolute, prismatic, cylindrical,
    /// universal), `length` a distance joint's (None: the initial distance).
    #[pyo3(signature = (name, kind, a, b, axes, length))]
    fn joint(
        &mut self,
        name: &str,
        kind: &str,
        a: SpatialPoint,
        b: SpatialPoint,
        axes: Option<[[f64; 3]; 2]>,
        length: Option<f64>,
    ) -> PyResult<()> {
        let kind = joint_type(kind)?;
        let spec = JointSpec {
            kind,
            bodies: [a.0, b.0],
            points: [a.1, b.1],
            axes: axes.unwrap_or([[0.0, 0.0, 1.0]; 2]),
            length,
        };
        self.0.joint(name, spec);
        Ok(())
    }

    /// A driver of joint `joint`'s `"angle"` or `"translation"`: `f(t)`.
    fn driver(&mut self, name: &str, joint: &str, motion: &str, f: FunctionArg) -> PyResult<()> {
        let kind = match motion {
            "angle" => DriverKind::Angle,
            "translation" => DriverKind::Translation,
            _ => {
                return Err(PyValueError::new_err(format!(
                    "motion: expected 'angle' or 'translation', got '{motion}'"
                )));
            }
        };
        self.0.driver(name, joint, kind, f.get());
        Ok(())
    }

    /// A force `(fx, fy, fz)(t)` at the point `at` of a body, its components
    /// in `axes` (`"global"` or `"body"`).
    fn force(
        &mut self,
        name: &str,
        at: SpatialPoint,
        f: [FunctionArg; 3],
        axes: &str,
    ) -> PyResult<()> {
        let Attach::Body(body) = at.0 else {
            return Err(PyValueError::new_err(
                "at: expected a point of a body (body.at(sx, sy, sz)), got a point of the ground",
            ));
        };
        self.0.force(name, body, at.1, functions(f), axes_of(axes)?);
        Ok(())
    }

    /// A torque `(tx, ty, tz)(t)` on a rigid body, its components in `axes`.
    fn torque(
        &mut self,
        name: &str,
        body: &SpatialBody,
        n: [FunctionArg; 3],
        axes: &str,
    ) -> PyResult<()> {
        self.0.torque(name, body.id, functions(n), axes_of(axes)?);
        Ok(())
    }

    /// A linear spring-damper between two points: tension `stiffness (ℓ −
    /// rest_length) + damping ℓ̇ + preload` (rest length None: the initial one).
    #[pyo3(signature = (name, a, b, *, stiffness, damping, rest_length, preload))]
    #[allow(clippy::too_many_arguments)]
    fn spring(
        &mut self,
        name: &str,
        a: SpatialPoint,
        b: SpatialPoint,
        stiffness: f64,
        damping: f64,
        rest_length: Option<f64>,
        preload: f64,
    ) {
        let spring = sp::SpringDamper {
            stiffness,
            damping,
            rest_length,
            preload,
        };
        self.0.spring(name, [a.0, b.0], [a.1, b.1], spring);
    }

    /// A rotational spring-damper about the axis `axes[0]` of `a` (None: the
    /// ground) and `axes[1]` of `b`: torque `−stiffness (θ − angle) − damping θ̇`.
    #[pyo3(signature = (name, a, b, axes, *, stiffness, damping, angle))]
    #[allow(clippy::too_many_arguments)]
    fn rotational_spring(
        &mut self,
        name: &str,
        a: Option<&SpatialBody>,
        b: &SpatialBody,
        axes: [[f64; 3]; 2],
        stiffness: f64,
        damping: f64,
        angle: f64,
    ) {
        let side = |s: Option<&SpatialBody>| s.map_or(Attach::Ground, |s| Attach::Body(s.id));
        let spring = sp::RotationalSpringDamper {
            stiffness,
            damping,
            angle,
        };
        self.0
            .rotational_spring(name, [side(a), side(Some(b))], axes, spring);
    }

    /// Checks the model and makes it (`ModelError` with the builder's
    /// message when it is not valid).
    fn build(&self) -> PyResult<NativeModel> {
        let system = self
            .0
            .build()
            .map_err(|e| ModelError::new_err(crate::message(&e)))?;
        Ok(NativeModel::built_spatial(system))
    }
}
