"""Loads in a Result: the reaction and effort columns `mstar run --out`
writes (every column compared with the CLI's in test_agrees_with_cli.py),
grouped by joint and driver, against a statics hand calculation."""

import numpy as np
import pytest

import mstar
from conftest import MODELS, assert_same_columns
from mstar import planar

MASS, LENGTH, G = 2.0, 1.0, 9.81


def held_bar() -> mstar.Result:
    """A uniform bar hinged at its left end to the ground and held
    horizontal by a driver of its angle: at rest, so statics gives every
    load exactly."""
    b = planar.Builder().gravity(0.0, -G)
    bar = b.rigid_body("bar", mass=MASS, inertia=MASS * LENGTH**2 / 12, pose=(LENGTH / 2, 0.0, 0.0))
    b.revolute("hinge", planar.ground(0.0, 0.0), bar.at(-LENGTH / 2, 0.0))
    b.driver("hold", bar, "theta", 0.0)
    return b.build().run(t_end=0.05, h=1e-3)


def test_reactions_and_efforts_of_a_held_bar_are_the_statics():
    r = held_bar()
    # Forces on the bar: the hinge's (fx, fy) at its left end, the driver's
    # torque τ about its centre, gravity. Σf = 0: fy = m g, fx = 0. Σ moments
    # about the centre: τ + (−L/2)·fy = 0, so τ = m g L/2 and the hinge's
    # moment about the centre is −m g L/2. The numbers are sums of a few
    # products of these: a few ulps.
    tol = 8 * np.finfo(float).eps * MASS * G
    hinge = r.reaction("hinge")
    assert sorted(hinge) == ["fx", "fy", "tau"]
    assert np.allclose(hinge["fx"], 0.0, rtol=0, atol=tol)
    assert np.allclose(hinge["fy"], MASS * G, rtol=0, atol=tol)
    assert np.allclose(hinge["tau"], -MASS * G * LENGTH / 2, rtol=0, atol=tol)
    assert np.allclose(r.effort("hold"), MASS * G * LENGTH / 2, rtol=0, atol=tol)
    # The driver's own reaction is its torque on the bar.
    hold = r.reaction("hold")
    assert np.array_equal(hold["tau"], r.effort("hold"))
    # The same columns by their CSV names.
    assert np.array_equal(r["reaction:hinge.fy"], hinge["fy"])
    assert np.array_equal(r["effort:hold"], r.effort("hold"))
    assert r.extra.shape == (len(r), 7)


def test_spatial_reactions_have_six_components(run_cli):
    path = MODELS / "spatial" / "double-pendulum.toml"
    r = mstar.load(path).run(t_end=0.02)
    assert sorted(r.reaction("elbow")) == ["fx", "fy", "fz", "tx", "ty", "tz"]
    assert np.array_equal(r.reaction("elbow")["fz"], r["reaction:elbow.fz"])
    cli = run_cli(path, "--t-end", "0.02", "--set", "output.every=1")
    assert_same_columns(r, cli)


def test_unknown_joints_and_drivers_are_key_errors():
    r = held_bar()
    with pytest.raises(KeyError, match="no joint 'nope': give one of hinge, hold"):
        r.reaction("nope")
    with pytest.raises(KeyError, match="no driver 'hinge': give one of hold"):
        r.effort("hinge")
    with pytest.raises(KeyError, match="no column"):
        r["reaction:hinge.fz"]


def test_to_pandas_has_the_loads():
    pd = pytest.importorskip("pandas")
    r = held_bar()
    frame = r.to_pandas()
    assert list(frame.columns) == r.columns()
    assert np.array_equal(frame["effort:hold"].to_numpy(), r.effort("hold"))
