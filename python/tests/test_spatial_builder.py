"""A model built with mstar.spatial.Builder is the model file it mirrors:
the same coordinates, constraint rows and runs, bit for bit."""

import math

import numpy as np
import pytest

import mstar
from conftest import MODELS
from mstar import spatial
from test_builder_equals_file import assert_equal_runs


def double_pendulum() -> mstar.Model:
    """models/spatial/double-pendulum.toml."""
    b = spatial.Builder()
    upper = b.rigid_body("upper", mass=1.0, inertia=(6.6667e-5, 0.0833667, 0.0833667),
                         position=(0.5, 0.0, 0.0), orientation=(1.0, 0.0, 0.0, 0.0))
    lower = b.rigid_body("lower", mass=1.0, inertia=np.array([0.0833667, 6.6667e-5, 0.0833667]),
                         position=(1.0, 0.5, 0.0), velocity=(0.0, 0.0, -0.5),
                         angular_velocity=(-1.0, 0.0, 0.0))
    b.spherical("shoulder", spatial.ground(0.0, 0.0, 0.0), upper.at(-0.5, 0.0, 0.0))
    b.spherical("elbow", upper.at(0.5, 0.0, 0.0), lower.at(0.0, -0.5, 0.0))
    return b.build()


def test_the_spatial_double_pendulum_built_in_python_is_the_file():
    model = double_pendulum()
    filed = mstar.load(MODELS / "spatial" / "double-pendulum.toml")
    assert model.kind == "spatial"
    assert model.coords == filed.coords and model.constraints == filed.constraints
    built = model.run(t_end=0.5, h=1e-3)
    assert_equal_runs(built, filed.run(t_end=0.5))
    # The loads too.
    assert built.extra_names == filed.run(t_end=0.01).extra_names


def test_every_joint_type_builds():
    b = spatial.Builder().gravity(0.0, 0.0, -9.81)
    body = dict(mass=1.0, inertia=(0.1, 0.1, 0.1))
    z = ((0.0, 0.0, 1.0), (0.0, 0.0, 1.0))
    b1 = b.rigid_body("b1", position=(0.0, 0.0, 0.0), **body)
    b2 = b.rigid_body("b2", position=(1.0, 0.0, 0.0), **body)
    b3 = b.rigid_body("b3", position=(2.0, 0.0, 0.0), orientation=spatial.euler_parameters((0, 0, 1), 0.0), **body)
    b4 = b.rigid_body("b4", position=(3.0, 0.0, 0.0), **body)
    b5 = b.rigid_body("b5", position=(4.0, 0.0, 0.0), **body)
    p = b.point_mass("p", mass=0.5, position=(5.0, 0.0, 0.0))
    b.revolute("hinge", spatial.ground(0.0, 0.0, 0.0), b1.at(), z)
    b.prismatic("slide", b1.at(0.5, 0, 0), b2.at(-0.5, 0, 0), ((1.0, 0, 0), (1.0, 0, 0)))
    b.cylindrical("cyl", b2.at(0.5, 0, 0), b3.at(-0.5, 0, 0), ((1.0, 0, 0), (1.0, 0, 0)))
    b.universal("cardan", b3.at(0.5, 0, 0), b4.at(-0.5, 0, 0), ((0, 0, 1.0), (0, 1.0, 0)))
    b.weld("weld", b4.at(0.5, 0, 0), b5.at(-0.5, 0, 0))
    b.distance("rod", b5.at(0.5, 0, 0), p.at())
    b.driver("motor", "hinge", "angle", mstar.planar.linear(0.0, 1.0))
    b.force("push", p.at(), (0.0, 1.0, 0.0))
    b.torque("twist", b5, (0.0, 0.0, mstar.planar.sine(0.0, 0.1, 2.0)), axes="body")
    b.spring("spring", spatial.ground(0, 0, 1), b2.at(), stiffness=10.0)
    b.rotational_spring("rs", None, b1, z, stiffness=1.0)
    model = b.build()
    rows = model.constraints
    assert [r for r in rows if r.startswith("hinge.")] == [f"hinge.{s}" for s in ("x", "y", "z", "axis_f", "axis_g")]
    assert "rod" in rows and "motor" in rows and "weld.rz" in rows and "cardan.cross" in rows
    assert len([c for c in model.coords if c.startswith("p.")]) == 3


def test_spatial_builder_errors():
    b = spatial.Builder()
    bar = b.rigid_body("bar", mass=1.0, inertia=(0.1, 0.1, 0.1), position=(0, 0, 0))
    with pytest.raises(TypeError, match="^orientation: expected 4 numbers"):
        b.rigid_body("x", mass=1.0, inertia=(0.1, 0.1, 0.1), position=(0, 0, 0), orientation=(1, 0, 0))
    with pytest.raises(TypeError, match="^axes: expected two directions"):
        b.revolute("h", spatial.ground(), bar.at(), (0, 0, 1))
    with pytest.raises(ValueError, match="motion: expected 'angle' or 'translation', got 'spin'"):
        b.driver("d", "h", "spin", 0.0)
    b.rigid_body("bar", mass=1.0, inertia=(0.1, 0.1, 0.1), position=(1, 0, 0))  # a second 'bar'
    with pytest.raises(mstar.ModelError, match="'bar'"):
        b.build()


def test_euler_parameters_are_the_half_angle_formula():
    e = spatial.euler_parameters((0.0, 0.0, 2.0), math.pi / 2)
    # cos and sin of π/4 (each within an ulp), one division by |axis| = 2
    # (exact) and a product: a few ulps of 0.7.
    assert e == pytest.approx((math.sqrt(0.5), 0.0, 0.0, math.sqrt(0.5)), rel=0, abs=4 * 2.0**-52)
