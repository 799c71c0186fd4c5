"""Planar models made in code: :class:`Builder` mirrors the Rust
``mstar::planar::PlanarBuilder``.

::

    from mstar import planar

    b = planar.Builder()
    bar = b.rigid_body("bar", mass=1.0, inertia=1 / 12, pose=(0.5, 0.0, 0.0))
    b.revolute("hinge", planar.ground(0.0, 0.0), bar.at(-0.5, 0.0))
    result = b.build().run(t_end=1.0, h=1e-3)

Points are ``body.at(sx, sy)`` (local offsets; ``(0, 0)`` for a point mass)
or :func:`ground` ``(x, y)``. Functions of time (drivers, forces, torques)
are numbers (constants) or :func:`constant`, :func:`linear`, :func:`sine`,
:func:`table`. Coordinates are named ``<body>.x``, ``<body>.y``,
``<body>.theta`` as in model files.
"""

from __future__ import annotations

from typing import Any as _Any
from typing import Optional, Sequence, Tuple, Union

from ._errors import translated as _translated
from ._literal import number as _number
from ._literal import numbers_of as _numbers_of
from ._model import Model
from ._native import Body, Point, TimeFunction
from ._native import PlanarBuilder as _PlanarBuilder
from ._native import ground as _ground

__all__ = ["Body", "Builder", "Point", "TimeFunction", "constant", "ground", "linear", "sine", "table"]

#: A function of time: a number is a constant.
Function = Union[float, TimeFunction]


def ground(x: float = 0.0, y: float = 0.0) -> Point:
    """The fixed point ``(x, y)`` of the ground."""
    return _ground(_number(x, "x"), _number(y, "y"))


def constant(value: float) -> TimeFunction:
    """``f(t) = value``."""
    return TimeFunction.constant(_number(value, "value"))


def linear(value: float, rate: float) -> TimeFunction:
    """``f(t) = value + rate·t``."""
    return TimeFunction.linear(_number(value, "value"), _number(rate, "rate"))


def sine(offset: float, amplitude: float, omega: float, phase: float = 0.0) -> TimeFunction:
    """``f(t) = offset + amplitude·sin(omega·t + phase)``."""
    return TimeFunction.sine(
        _number(offset, "offset"), _number(amplitude, "amplitude"), _number(omega, "omega"), _number(phase, "phase")
    )


def table(points: Sequence[Tuple[float, float]]) -> TimeFunction:
    """Piecewise linear through ``(t, value)`` points (times increasing),
    constant before the first and after the last; a list of pairs or an
    ``n × 2`` array."""
    try:
        rows = list(points)
    except TypeError:
        raise TypeError(f"points: expected (t, value) pairs, got {type(points).__name__}") from None
    pairs = [tuple(_numbers_of(p, f"points[{i}]", 2)) for i, p in enumerate(rows)]
    return TimeFunction.table(pairs)


def _function(f: _Any, name: str) -> Union[float, TimeFunction]:
    """A function-of-time argument: a :class:`TimeFunction` or a number."""
    return f if isinstance(f, TimeFunction) else _number(f, name)


def _point(p: _Any, name: str) -> Point:
    if not isinstance(p, Point):
        raise TypeError(f"{name}: expected a point (body.at(sx, sy) or ground(x, y)), got {type(p).__name__}")
    return p


class Builder:
    """A planar mechanism assembled element by element; :meth:`build` checks
    it as a whole and makes a :class:`mstar.Model` (with the default
    ``[simulation]``; give settings to :meth:`mstar.Model.run`).

    Elements are added in order; the coordinates are numbered in the order
    the bodies are added (as in a model file), the constraint rows in the
    order of the joints, then the drivers.
    """

    def __init__(self) -> None:
        self._b = _PlanarBuilder()

    def gravity(self, gx: float, gy: float) -> "Builder":
        """Sets gravity, m/s² (default ``(0, -9.81)``)."""
        self._b.gravity(_number(gx, "gx"), _number(gy, "gy"))
        return self

    def rigid_body(
        self,
        name: str,
        *,
        mass: float,
        inertia: float,
        pose: Tuple[float, float, float],
        velocity: Tuple[float, float, float] = (0.0, 0.0, 0.0),
    ) -> Body:
        """Adds a rigid body: mass (kg), inertia about the centre of mass
        (kg m²; 0 when a joint fixes its angle), pose ``(x, y, theta)`` and
        velocity ``(vx, vy, omega)``."""
        return self._b.rigid_body(
            name,
            mass=_number(mass, "mass"),
            inertia=_number(inertia, "inertia"),
            pose=_numbers_of(pose, "pose", 3),
            velocity=tuple(_numbers_of(velocity, "velocity", 3)),
        )

    def point_mass(
        self,
        name: str,
        *,
        mass: float,
        position: Tuple[float, float],
        velocity: Tuple[float, float] = (0.0, 0.0),
    ) -> Body:
        """Adds a point mass: mass (kg), position ``(x, y)``, velocity."""
        return self._b.point_mass(
            name,
            mass=_number(mass, "mass"),
            position=_numbers_of(position, "position", 2),
            velocity=tuple(_numbers_of(velocity, "velocity", 2)),
        )

    def revolute(self, name: str, a: Point, b: Point) -> "Builder":
        """A revolute joint: the points ``a`` and ``b`` coincide (2 rows)."""
        self._b.revolute(name, _point(a, "a"), _point(b, "b"))
        return self

    def distance(self, name: str, a: Point, b: Point, length: float) -> "Builder":
        """A distance joint (massless rod): ``a`` and ``b`` stay ``length`` apart."""
        self._b.distance(name, _point(a, "a"), _point(b, "b"), _number(length, "length"))
        return self

    def weld(self, name: str, a: Point, b: Point) -> "Builder":
        """A weld: the points coincide and the relative angle stays."""
        self._b.weld(name, _point(a, "a"), _point(b, "b"))
        return self

    def prismatic(self, name: str, a: Point, axis: Tuple[float, float], b: Point) -> "Builder":
        """A prismatic joint: ``b`` slides along the line through ``a`` with
        direction ``axis`` (in ``a``'s body frame, or global for the ground);
        a rigid body ``b`` keeps its relative angle."""
        self._b.prismatic(name, _point(a, "a"), _numbers_of(axis, "axis", 2), _point(b, "b"))
        return self

    def driver(self, name: str, body: Body, coordinate: str, f: Function) -> "Builder":
        """A driver: ``coordinate`` (``"x"``, ``"y"`` or ``"theta"``) of
        ``body`` follows ``f(t)``.

        Raises:
            ValueError: another coordinate name.
        """
        self._b.driver(name, body, coordinate, _function(f, "f"))
        return self

    def force(self, name: str, at: Point, fx: Function, fy: Function) -> "Builder":
        """A force ``(fx(t), fy(t))`` in global directions at a point, N."""
        self._b.force(name, _point(at, "at"), _function(fx, "fx"), _function(fy, "fy"))
        return self

    def torque(self, name: str, body: Body, tau: Function) -> "Builder":
        """A torque ``tau(t)`` on a rigid body, N m (counter-clockwise positive)."""
        self._b.torque(name, body, _function(tau, "tau"))
        return self

    def spring(
        self, name: str, a: Point, b: Point, *, stiffness: float, rest_length: float, damping: float = 0.0
    ) -> "Builder":
        """A linear spring-damper between two points: tension
        ``stiffness·(l − rest_length) + damping·dl/dt``."""
        self._b.spring(
            name,
            _point(a, "a"),
            _point(b, "b"),
            stiffness=_number(stiffness, "stiffness"),
            rest_length=_number(rest_length, "rest_length"),
            damping=_number(damping, "damping"),
        )
        return self

    def rotational_spring(
        self, name: str, a: Optional[Body], b: Body, *, stiffness: float, damping: float = 0.0
    ) -> "Builder":
        """A rotational spring-damper between body ``a`` (None: the ground)
        and rigid body ``b``, at rest at their initial relative angle."""
        self._b.rotational_spring(
            name, a, b, stiffness=_number(stiffness, "stiffness"), damping=_number(damping, "damping")
        )
        return self

    def build(self) -> Model:
        """Checks the model and makes it.

        Raises:
            mstar.ModelError: the builder's message (duplicate names, a
                non-positive mass, a driver of a point mass's angle, ...).
        """
        with _translated():
            return Model(self._b.build())
