"""Spatial models made in code: :class:`Builder` mirrors the Rust
``mstar::model::spatial::SpatialBuilder`` and the ``mstar.spatial/1`` model
format (``docs/model-format.md``), with the conventions of
:mod:`mstar.planar`.

::

    from mstar import spatial

    b = spatial.Builder()
    bar = b.rigid_body("bar", mass=1.0, inertia=(1e-4, 1 / 12, 1 / 12), position=(0.5, 0.0, 0.0))
    b.spherical("shoulder", spatial.ground(0.0, 0.0, 0.0), bar.at(-0.5, 0.0, 0.0))
    result = b.build().run(t_end=1.0, h=1e-3)

Points are ``body.at(sx, sy, sz)`` (body axes from the centre of mass;
``(0, 0, 0)`` for a point mass) or :func:`ground` ``(x, y, z)`` (global).
Orientations are Euler parameters ``(e0, e1, e2, e3)`` (body to global;
:func:`euler_parameters` makes them from an axis and an angle). Functions of
time are numbers or :mod:`mstar.planar`'s :func:`~mstar.planar.constant`,
:func:`~mstar.planar.linear`, :func:`~mstar.planar.sine`,
:func:`~mstar.planar.table`. Coordinates are named ``<body>.x``, ``.y``,
``.z``, ``.e0`` … ``.e3`` as in model files.
"""

from __future__ import annotations

import math
from typing import Any as _Any
from typing import Optional, Sequence, Tuple, Union

import numpy as _np

from ._errors import translated as _translated
from ._literal import number as _number
from ._literal import numbers_of as _numbers_of
from ._model import Model
from ._native import SpatialBody as Body
from ._native import SpatialBuilder as _SpatialBuilder
from ._native import SpatialPoint as Point
from ._native import TimeFunction
from ._native import spatial_ground as _ground
from .planar import _function

__all__ = ["Body", "Builder", "Point", "euler_parameters", "ground"]

#: A function of time: a number is a constant.
Function = Union[float, TimeFunction]
Vector = Tuple[float, float, float]


def ground(x: float = 0.0, y: float = 0.0, z: float = 0.0) -> Point:
    """The fixed point ``(x, y, z)`` of the ground (global)."""
    return _ground(_number(x, "x"), _number(y, "y"), _number(z, "z"))


def euler_parameters(axis: Sequence[float], angle: float) -> Tuple[float, float, float, float]:
    """The Euler parameters of the rotation by ``angle`` (rad) about
    ``axis``: ``(cos(angle/2), sin(angle/2)·axis/|axis|)``."""
    a = _numbers_of(axis, "axis", 3)
    n = math.sqrt(sum(c * c for c in a))
    if n == 0.0:
        raise ValueError("axis: expected a non-zero direction, got (0, 0, 0)")
    half = 0.5 * _number(angle, "angle")
    s = math.sin(half) / n
    return (math.cos(half), a[0] * s, a[1] * s, a[2] * s)


def _point(p: _Any, name: str) -> Point:
    if not isinstance(p, Point):
        raise TypeError(f"{name}: expected a point (body.at(sx, sy, sz) or ground(x, y, z)), got {type(p).__name__}")
    return p


def _axes(axes: _Any, name: str = "axes") -> Tuple[list, list]:
    """Two directions, one in each side's axes."""
    if isinstance(axes, _np.ndarray) and axes.shape == (2, 3):
        axes = list(axes)
    if not isinstance(axes, (list, tuple)) or len(axes) != 2:
        raise TypeError(f"{name}: expected two directions ((ax, ay, az), (bx, by, bz)), got {type(axes).__name__}")
    return (_numbers_of(axes[0], f"{name}[0]", 3), _numbers_of(axes[1], f"{name}[1]", 3))


class Builder:
    """A spatial mechanism assembled element by element; :meth:`build`
    checks it as a whole and makes a :class:`mstar.Model` (with the default
    ``[simulation]``; give settings to :meth:`mstar.Model.run`).

    Elements are added in order: the coordinates in the order of the
    bodies, the constraint rows in the order of the joints and drivers as
    added (a model file lists its joints, then its drivers), then each rigid
    body's normalization row.
    """

    def __init__(self) -> None:
        self._b = _SpatialBuilder()

    def gravity(self, gx: float, gy: float, gz: float) -> "Builder":
        """Sets gravity, m/s² (default ``(0, 0, -9.81)``)."""
        self._b.gravity([_number(gx, "gx"), _number(gy, "gy"), _number(gz, "gz")])
        return self

    def rigid_body(
        self,
        name: str,
        *,
        mass: float,
        inertia: _Any,
        position: Vector,
        orientation: Tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0),
        velocity: Vector = (0.0, 0.0, 0.0),
        angular_velocity: Vector = (0.0, 0.0, 0.0),
    ) -> Body:
        """Adds a rigid body: mass (kg); inertia about the centre of mass in
        body axes (kg m²), the principal moments ``(Jxx, Jyy, Jzz)`` or the
        3 × 3 tensor; position of the centre of mass (global, m);
        orientation as Euler parameters (body to global; normalized);
        velocity (m/s) and angular velocity (rad/s), global."""
        tensor = None
        shape = _np.shape(inertia) if isinstance(inertia, (list, tuple, _np.ndarray)) else None
        if shape == (3, 3):
            tensor = [_numbers_of(row, f"inertia[{i}]", 3) for i, row in enumerate(inertia)]
            moments = [tensor[0][0], tensor[1][1], tensor[2][2]]
        else:
            moments = _numbers_of(inertia, "inertia", 3)
        return self._b.rigid_body(
            name,
            mass=_number(mass, "mass"),
            inertia=moments,
            position=_numbers_of(position, "position", 3),
            orientation=_numbers_of(orientation, "orientation", 4),
            velocity=_numbers_of(velocity, "velocity", 3),
            angular_velocity=_numbers_of(angular_velocity, "angular_velocity", 3),
            tensor=tensor,
        )

    def point_mass(self, name: str, *, mass: float, position: Vector, velocity: Vector = (0.0, 0.0, 0.0)) -> Body:
        """Adds a point mass: mass (kg), position and velocity (global)."""
        return self._b.point_mass(
            name,
            mass=_number(mass, "mass"),
            position=_numbers_of(position, "position", 3),
            velocity=_numbers_of(velocity, "velocity", 3),
        )

    def _joint(self, kind: str, name: str, a: Point, b: Point, axes: _Any = None, length: Optional[float] = None) -> "Builder":
        given = None if axes is None else list(_axes(axes))
        size = None if length is None else _number(length, "length")
        self._b.joint(name, kind, _point(a, "a"), _point(b, "b"), given, size)
        return self

    def spherical(self, name: str, a: Point, b: Point) -> "Builder":
        """A spherical joint (ball joint): the points coincide (3 rows)."""
        return self._joint("spherical", name, a, b)

    def revolute(self, name: str, a: Point, b: Point, axes: Tuple[Vector, Vector]) -> "Builder":
        """A revolute joint (hinge): the points coincide and the axes (one
        direction in each side's axes, the same physical axis) stay parallel
        (5 rows)."""
        return self._joint("revolute", name, a, b, axes)

    def prismatic(self, name: str, a: Point, b: Point, axes: Tuple[Vector, Vector]) -> "Builder":
        """A prismatic joint: ``b``'s point stays on ``a``'s axis line, the
        axes parallel, no turn about them (5 rows)."""
        return self._joint("prismatic", name, a, b, axes)

    def cylindrical(self, name: str, a: Point, b: Point, axes: Tuple[Vector, Vector]) -> "Builder":
        """A cylindrical joint: as prismatic, but free to turn (4 rows)."""
        return self._joint("cylindrical", name, a, b, axes)

    def universal(self, name: str, a: Point, b: Point, axes: Tuple[Vector, Vector]) -> "Builder":
        """A universal (Cardan) joint: the points coincide and the two cross
        axes, one fixed in each body, stay perpendicular (4 rows)."""
        return self._joint("universal", name, a, b, axes)

    def weld(self, name: str, a: Point, b: Point) -> "Builder":
        """A weld: the points coincide and the relative orientation stays (6 rows)."""
        return self._joint("weld", name, a, b)

    def distance(self, name: str, a: Point, b: Point, length: Optional[float] = None) -> "Builder":
        """A distance joint (massless rod with ball ends): the points stay
        ``length`` apart (None: their initial distance; 1 row)."""
        return self._joint("distance", name, a, b, length=length)

    def driver(self, name: str, joint: str, motion: str, f: Function) -> "Builder":
        """A driver of the joint named ``joint``: its ``"angle"`` (revolute,
        cylindrical; rad from the initial pose) or ``"translation"``
        (prismatic, cylindrical; m along ``a``'s axis) follows ``f(t)``.

        Raises:
            ValueError: another ``motion``.
        """
        self._b.driver(name, joint, motion, _function(f, "f"))
        return self

    def force(
        self, name: str, at: Point, f: Tuple[Function, Function, Function], axes: str = "global"
    ) -> "Builder":
        """A force ``f = (fx(t), fy(t), fz(t))`` (N) at the point ``at`` of a
        body, in global axes or (``axes="body"``) the body's."""
        fs = self._three(f, "f")
        self._b.force(name, _point(at, "at"), fs, axes)
        return self

    def torque(self, name: str, body: Body, n: Tuple[Function, Function, Function], axes: str = "global") -> "Builder":
        """A torque ``n = (tx(t), ty(t), tz(t))`` (N m) on a rigid body."""
        self._b.torque(name, body, self._three(n, "n"), axes)
        return self

    @staticmethod
    def _three(f: _Any, name: str) -> list:
        if not isinstance(f, (list, tuple)) or len(f) != 3:
            raise TypeError(f"{name}: expected three components (numbers or functions of time), got {type(f).__name__}")
        return [_function(c, f"{name}[{i}]") for i, c in enumerate(f)]

    def spring(
        self,
        name: str,
        a: Point,
        b: Point,
        *,
        stiffness: float,
        damping: float = 0.0,
        rest_length: Optional[float] = None,
        preload: float = 0.0,
    ) -> "Builder":
        """A linear spring-damper between two points: tension
        ``stiffness·(ℓ − rest_length) + damping·dℓ/dt + preload`` (rest
        length None: the initial distance)."""
        self._b.spring(
            name, _point(a, "a"), _point(b, "b"),
            stiffness=_number(stiffness, "stiffness"), damping=_number(damping, "damping"),
            rest_length=None if rest_length is None else _number(rest_length, "rest_length"),
            preload=_number(preload, "preload"),
        )
        return self

    def rotational_spring(
        self,
        name: str,
        a: Optional[Body],
        b: Body,
        axes: Tuple[Vector, Vector],
        *,
        stiffness: float,
        damping: float = 0.0,
        angle: float = 0.0,
    ) -> "Builder":
        """A rotational spring-damper about the axis ``axes[0]`` of ``a``
        (None: the ground), ``axes[1]`` of ``b``: torque ``−stiffness·(θ −
        angle) − damping·dθ/dt``, θ from the initial pose."""
        self._b.rotational_spring(
            name, a, b, list(_axes(axes)),
            stiffness=_number(stiffness, "stiffness"), damping=_number(damping, "damping"),
            angle=_number(angle, "angle"),
        )
        return self

    def build(self) -> Model:
        """Checks the model and makes it.

        Raises:
            mstar.ModelError: the builder's message (duplicate names, axes
                that are not parallel, a non-positive mass, ...).
        """
        with _translated():
            return Model(self._b.build())
