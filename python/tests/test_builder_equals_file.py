"""A model built with mstar.planar.Builder is the model file it mirrors:
the same coordinates, constraint rows and runs, bit for bit."""

import math

import numpy as np
import pytest

import mstar
from conftest import MODELS
from mstar import planar

ARRAYS = ("t", "u", "v", "a", "lam", "energy", "iterations", "residual", "constraint")


def assert_equal_runs(a: mstar.Result, b: mstar.Result) -> None:
    assert a.coords == b.coords
    assert a.constraints == b.constraints
    for key in ARRAYS:
        x, y = getattr(a, key), getattr(b, key)
        assert x.shape == y.shape, key
        assert np.array_equal(x, y), key


def pendulum() -> mstar.Model:
    """models/pendulum.toml."""
    b = planar.Builder().gravity(0.0, -10.0)
    bob = b.rigid_body("bob", mass=1.0, inertia=0.0, pose=(1.0, 0.0, math.pi / 2))
    b.revolute("hinge", planar.ground(0.0, 0.0), bob.at(0.0, 1.0))
    return b.build()


def four_bar() -> mstar.Model:
    """models/four-bar.toml."""
    b = planar.Builder()
    crank = b.rigid_body("crank", mass=0.4, inertia=1.3333333333333e-3,
                         pose=(0.0877582561890, 0.0479425538604, 0.5))
    coupler = b.rigid_body("coupler", mass=1.2, inertia=0.036,
                           pose=(0.3974365149734, 0.2977551462310, 0.7381223365325))
    rocker = b.rigid_body("rocker", mass=1.0, inertia=2.0833333333333e-2,
                          pose=(0.6096782587844, 0.2498125923706, 1.5320736152650))
    b.revolute("O2", planar.ground(0.0, 0.0), crank.at(-0.1, 0.0))
    b.revolute("A", crank.at(0.1, 0.0), coupler.at(-0.3, 0.0))
    b.revolute("B", coupler.at(0.3, 0.0), rocker.at(0.25, 0.0))
    b.revolute("O4", planar.ground(0.6, 0.0), rocker.at(-0.25, 0.0))
    b.driver("motor", crank, "theta", planar.linear(0.5, 2.0))
    return b.build()


def test_the_pendulum_built_in_python_is_the_file():
    built = pendulum().run(t_end=10.0, h=0.01)
    filed = mstar.load(MODELS / "pendulum.toml").run()
    assert len(filed) == 1001
    assert_equal_runs(built, filed)


def test_the_four_bar_built_in_python_is_the_file():
    model = four_bar()
    assert model.origin == "<builder>"
    assert model.constraints == mstar.load(MODELS / "four-bar.toml").constraints
    built = model.run(t_end=2.0, h=1e-3, rho=0.8)
    filed = mstar.load(MODELS / "four-bar.toml").run(rho=0.8)
    assert_equal_runs(built, filed)


def test_a_builder_model_checks_settings_as_a_file_does(run_cli):
    path = MODELS / "pendulum.toml"
    cli = run_cli(path, "--set", "simulation.h=-1.0")
    with pytest.raises(mstar.ModelError) as e:
        pendulum().run(h=-1.0)
    # The file's message names the file and the --set that gave the value;
    # the builder's, the builder and the setting.
    assert cli.error().startswith(f"{path}: --set simulation.h=-1.0: "), cli.error()
    assert str(e.value) == cli.python_error().replace(str(path), "<builder>")
