"""numpy numbers are numbers everywhere: run settings, builder arguments,
sweep plans. Anything else is a TypeError, raised in Python, that names the
argument; a sweep refused so writes nothing."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import mstar
from conftest import MODELS, assert_same_columns
from mstar import planar

MODEL = MODELS / "four-bar.toml"
#: t_end = 0.05 s and h = 1e-3 s in numpy's types (0.05 and 1e-3 are exact
#: in float64; float32 values are read as the float32's exact value).
NUMPY_T_END = [np.float64(0.05), np.array(0.05), np.float64(0.05).reshape(())]


@pytest.fixture(scope="module")
def plain() -> mstar.Result:
    return mstar.load(MODEL).run(t_end=0.05, h=1e-3, rho=0.5, max_iterations=20)


@pytest.mark.parametrize("t_end", NUMPY_T_END, ids=["float64", "0-d array", "reshaped"])
def test_numpy_settings_run_as_floats(plain, t_end):
    r = mstar.load(MODEL).run(t_end=t_end, h=np.float64(1e-3), rho=np.float32(0.5), max_iterations=np.int64(20))
    # np.float32(0.5) is 0.5 exactly: the same run, bit for bit.
    assert np.array_equal(r.u, plain.u) and np.array_equal(r.lam, plain.lam)


def test_a_float32_setting_is_its_exact_value():
    h32 = np.float32(1e-3)  # 0.0010000000474974513
    r = mstar.load(MODEL).run(t_end=0.01, h=h32)
    assert r.t[1] == float(h32) != 1e-3


@pytest.mark.parametrize(
    "settings,message",
    [
        ({"t_end": "abc"}, "t_end: expected a number, got str 'abc'"),
        ({"h": [1e-3]}, "h: expected a number, got list [0.001]"),
        ({"h": True}, "h: expected a number, got bool True"),
        ({"rho": None, "tol": "1e-9"}, "tol: expected a number, got str '1e-9'"),
        ({"max_iterations": 2.5}, "max_iterations: expected an integer, got float 2.5"),
        ({"integrator": ["hht"]}, "integrator: expected a number, a bool or a string, got list ['hht']"),
    ],
)
def test_settings_of_the_wrong_type_are_type_errors(settings, message):
    with pytest.raises(TypeError) as e:
        mstar.load(MODEL).run(**settings)
    assert str(e.value) == message


def test_overrides_take_numpy_numbers(run_cli):
    path = MODELS / "pendulum.toml"
    heavy = mstar.load(path).run(t_end=0.1, overrides={"body.bob.mass": np.float64(2.0), "output.every": 1})
    cli = run_cli(path, "--t-end", "0.1", "--set", "body.bob.mass=2.0", "--set", "output.every=1")
    assert_same_columns(heavy, cli)
    # A 2-d array for a key that takes a list of points.
    points = np.array([[0.5, 0.0, 0.0], [0.0, -0.5, 0.0]], dtype=np.float32)
    path = MODELS / "spatial" / "double-pendulum.toml"
    arrayed = mstar.load(path).run(t_end=0.05, overrides={"joint.elbow.points": points})
    listed = mstar.load(path).run(t_end=0.05, overrides={"joint.elbow.points": [[0.5, 0.0, 0.0], [0.0, -0.5, 0.0]]})
    assert np.array_equal(arrayed.u, listed.u)  # 0.5 and 0.0 are exact in float32
    with pytest.raises(TypeError, match=r"overrides\['body.bob.mass'\]: expected a number"):
        mstar.load(MODELS / "pendulum.toml").run(overrides={"body.bob.mass": object()})


def pendulum(**kinds) -> mstar.Model:
    """models/pendulum.toml built with the numbers given (as numpy types)."""
    f = kinds.get("f", float)
    b = planar.Builder().gravity(f(0.0), f(-10.0))
    bob = b.rigid_body("bob", mass=f(1.0), inertia=f(0.0), pose=np.array([1.0, 0.0, math.pi / 2]),
                       velocity=[f(0.0), f(0.0), f(0.0)])
    b.revolute("hinge", planar.ground(f(0.0), np.int64(0)), bob.at(f(0.0), f(1.0)))
    return b.build()


def test_builders_take_numpy_numbers():
    filed = mstar.load(MODELS / "pendulum.toml").run(t_end=0.2)
    for f in (np.float64, np.float32, np.int64, np.array):
        built = pendulum(f=f).run(t_end=0.2, h=0.01)
        assert np.array_equal(built.u, filed.u), f


def test_builder_numbers_of_the_wrong_type_are_type_errors():
    b = planar.Builder()
    with pytest.raises(TypeError, match="^mass: expected a number, got str '1'$"):
        b.rigid_body("a", mass="1", inertia=1.0, pose=(0, 0, 0))
    with pytest.raises(TypeError, match=r"^pose: expected 3 numbers, got tuple \(0, 0\)$"):
        b.rigid_body("a", mass=1.0, inertia=1.0, pose=(0, 0))
    with pytest.raises(TypeError, match=r"^pose\[2\]: expected a number, got str 'x'$"):
        b.rigid_body("a", mass=1.0, inertia=1.0, pose=np.array([0, 0, "x"], dtype=object))
    p = b.point_mass("p", mass=1.0, position=(0, 0))
    with pytest.raises(TypeError, match="^length: expected a number"):
        b.distance("d", planar.ground(), p.at(), "1")
    with pytest.raises(TypeError, match="^f: expected a number, got str"):
        b.driver("d", p, "x", "sin(t)")
    with pytest.raises(TypeError, match=r"^b: expected a point"):
        b.revolute("r", planar.ground(), p)
    assert planar.table(np.array([[0.0, 1.0], [1.0, 2.0]])) is not None
    with pytest.raises(TypeError, match=r"^points\[1\]: expected 2 numbers"):
        planar.table([(0.0, 1.0), (1.0,)])


def test_a_numpy_sweep_plan_is_the_plain_one(tmp_path: Path):
    model = MODELS / "double-pendulum.toml"
    plain = mstar.sweep(model, {"body.upper.mass": [1.0, 2.0], "simulation.t_end": [0.02]}, tmp_path / "a")
    numpy = mstar.sweep(
        model, {"body.upper.mass": np.array([1.0, 2.0]), "simulation.t_end": [np.float64(0.02)]},
        tmp_path / "b", jobs=np.int64(1),
    )
    assert (tmp_path / "a" / "sweep.toml").read_text() == (tmp_path / "b" / "sweep.toml").read_text()
    assert "np." not in (tmp_path / "b" / "sweep.toml").read_text()
    assert numpy.summary[1]["body.upper.mass"] == 2.0
    for i in range(2):
        assert plain.run_csv(i).read_bytes() == numpy.run_csv(i).read_bytes()


def test_a_bad_sweep_value_writes_nothing(tmp_path: Path):
    out = tmp_path / "s"
    with pytest.raises(TypeError, match=r"^params\['body.upper.mass'\]: expected a number, a bool, a string"):
        mstar.sweep(MODELS / "double-pendulum.toml", {"body.upper.mass": [1.0, {"a": 1}]}, out)
    with pytest.raises(TypeError, match=r"^params\['body.upper.mass'\]: expected a list of values, got float"):
        mstar.sweep(MODELS / "double-pendulum.toml", {"body.upper.mass": 1.0}, out)
    # A dict or a set would iterate as its keys.
    for value in ({"a": 1}, {1.0, 2.0}):
        with pytest.raises(TypeError, match=r"^params\['body.upper.mass'\]: expected a list of values, got (dict|set)"):
            mstar.sweep(MODELS / "double-pendulum.toml", {"body.upper.mass": value}, out)
    assert not out.exists()
    # The folder is free for the good plan.
    s = mstar.sweep(MODELS / "double-pendulum.toml", {"body.upper.mass": [1.0], "simulation.t_end": [0.01]}, out)
    assert s.ran == 1 and s.failed == []
