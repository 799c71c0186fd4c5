"""`Model.equilibrium()` against closed forms and against `mstar
equilibrium`: the paper's pendulum hangs straight down with the hinge
carrying its weight; a bar on a torsional spring settles at the root of
`k φ = m g (l/2) cos φ`; the errors (no equilibrium, a neutral direction)
carry their findings; `write_model` writes a file that starts at rest.

Tolerances: the solver stops at ‖r‖∞ ≤ 1e-11 F (F the weights, 10-20 N)
after a quadratic Newton step, so a coordinate is off by about 1e-11 F /
k_min (k_min ≥ 10 N/m or N m/rad here): 1e-10 allows a factor ten of
round-off; 1e-9 where the reference is a bisection to 1e-13.
"""

from __future__ import annotations

import math
import subprocess

import numpy as np
import pytest

import mstar
import mstar.planar
from conftest import MODELS

PENDULUM = MODELS / "pendulum.toml"

BAR = """format = "mstar.planar/1"
gravity = [0.0, -9.81]

[[body]]
name = "bar"
mass = 2.0
inertia = {j}
pose = [0.5, 0.0, 0.0]

[[joint]]
name = "hinge"
type = "revolute"
bodies = ["ground", "bar"]
points = [[0.0, 0.0], [-0.5, 0.0]]

[[force]]
name = "spring"
type = "rotational-spring-damper"
bodies = ["ground", "bar"]
stiffness = 20.0
""".format(j=2.0 / 12.0)

POINT_MASS = """format = "mstar.planar/1"
gravity = [0.0, -9.81]

[[point_mass]]
name = "slider"
mass = 1.0
position = [0.0, 0.0]
"""

GUIDE = """
[[joint]]
name = "guide"
type = "prismatic"
bodies = ["ground", "slider"]
points = [[0.0, 0.0], [0.0, 0.0]]
axis = [1.0, 0.0]
"""


def test_the_pendulum_hangs_straight_down():
    eq = mstar.load(PENDULUM).equilibrium()
    assert isinstance(eq, mstar.Equilibrium)
    assert abs(eq["bob.x"]) <= 1e-10 and abs(eq["bob.y"] + 1.0) <= 1e-10
    theta = math.remainder(eq["bob.theta"], math.tau)
    assert abs(theta) <= 1e-10
    # m g = 1 kg · 10 m/s², carried upward by the hinge, nothing sideways.
    hinge = eq.reaction("hinge")
    assert abs(hinge["fy"] - 10.0) <= 1e-9 and abs(hinge["fx"]) <= 1e-9
    assert eq.u.shape == (3,) and eq.lam.shape == (2,)
    assert eq.result["v:bob.x"][0] == 0.0 and len(eq.result) == 1
    assert eq.iterations >= 1 and eq.residual <= 1e-9
    assert "Equilibrium" in repr(eq)


def test_a_duplicated_hinge_is_left_out_and_shares_the_weight():
    """The pendulum's hinge given twice: solved without the dependent rows,
    named in `redundant`; the minimum-norm multipliers split m g = 10 N
    equally; the hanging pendulum is stable."""
    second = (
        '\n[[joint]]\nname = "hinge2"\ntype = "revolute"\n'
        'bodies = ["ground", "bob"]\npoints = [[0.0, 0.0], [0.0, 1.0]]\n'
    )
    eq = mstar.load(PENDULUM.read_text() + second).equilibrium()
    assert eq.redundant == ["hinge2.x", "hinge2.y"]
    assert eq.stable is True
    for hinge in ("hinge", "hinge2"):
        assert abs(eq.reaction(hinge)["fy"] - 5.0) <= 1e-9
    assert abs(eq["bob.y"] + 1.0) <= 1e-10


def test_a_start_near_upright_ends_at_the_stable_equilibrium():
    """The paper's pendulum started 0.3 rad from upright: the search leaves
    the unstable upright equilibrium for the hanging one."""
    text = PENDULUM.read_text().replace(
        "pose = [1.0, 0.0, 1.5707963267948966]",
        "pose = [{}, {}, {}]".format(math.sin(0.3), math.cos(0.3), math.pi - 0.3),
    )
    assert text != PENDULUM.read_text()
    eq = mstar.load(text).equilibrium()
    assert eq.stable is True and eq.redundant == []
    assert abs(eq["bob.x"]) <= 1e-10 and abs(eq["bob.y"] + 1.0) <= 1e-10


def test_overrides_change_the_model():
    eq = mstar.load(PENDULUM).equilibrium(overrides={"gravity": [0.0, -20.0]})
    assert abs(eq.reaction("hinge")["fy"] - 20.0) <= 1e-9
    with pytest.raises(ValueError, match="overrides"):
        eq.write_model("never.toml")


def test_a_bar_on_a_torsional_spring_settles_at_the_scalar_root():
    m, l, k, g = 2.0, 1.0, 20.0, 9.81
    f = lambda phi: k * phi - m * g * (l / 2) * math.cos(phi)  # noqa: E731
    lo, hi = 0.0, math.pi / 2
    while hi - lo > 1e-13:
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if f(mid) > 0 else (mid, hi)
    phi = 0.5 * (lo + hi)
    eq = mstar.load(BAR).equilibrium()
    assert abs(eq["bar.theta"] + phi) <= 1e-9
    assert abs(eq["bar.x"] - (l / 2) * math.cos(phi)) <= 1e-9
    assert abs(eq["bar.y"] + (l / 2) * math.sin(phi)) <= 1e-9


def test_a_spring_relaxed_at_the_initial_pose_cannot_be_rewritten(tmp_path):
    eq = mstar.load(BAR).equilibrium()
    with pytest.raises(mstar.ModelError, match="initial pose"):
        eq.write_model(tmp_path / "eq.toml")
    assert not (tmp_path / "eq.toml").exists()


def test_the_same_row_as_the_command(cli, tmp_path):
    out = tmp_path / "eq.csv"
    proc = subprocess.run([str(cli), "equilibrium", str(PENDULUM), "--out", str(out)],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    header, row = out.read_text().splitlines()
    eq = mstar.load(PENDULUM).equilibrium()
    assert header.split(",") == eq.columns()
    for name, value in zip(header.split(","), row.split(",")):
        assert eq[name] == float(value), name


def test_write_model_starts_at_rest(tmp_path):
    eq = mstar.load(PENDULUM).equilibrium()
    target = tmp_path / "eq.toml"
    eq.write_model(target)
    text = target.read_text()
    assert "# The paper's pendulum" in text  # comments kept
    run = mstar.load(target).run(t_end=0.1)
    # At rest it stays at rest: the pose moves by the equilibrium's
    # residual over the stiffness (1e-11) at most, not by g t²/2 = 0.05 m.
    assert np.max(np.abs(run.u - eq.u)) <= 1e-9
    with pytest.raises(FileExistsError):
        eq.write_model(target)
    eq.write_model(target, overwrite=True)
    with pytest.raises(ValueError, match="model file itself"):
        mstar.load(target).equilibrium().write_model(target, overwrite=True)


def test_a_builder_model_has_no_file_to_rewrite(tmp_path):
    b = mstar.planar.Builder()
    bob = b.point_mass("bob", mass=1.0, position=(1.0, 0.0))
    b.distance("rod", mstar.planar.ground(), bob.at(), 1.0)
    eq = b.build().equilibrium()
    assert abs(eq["bob.y"] + 1.0) <= 1e-10
    with pytest.raises(mstar.ModelError, match="builder"):
        eq.write_model(tmp_path / "eq.toml")


def test_a_free_body_has_no_equilibrium():
    with pytest.raises(mstar.EquilibriumError, match="no equilibrium") as caught:
        mstar.load(POINT_MASS).equilibrium()
    assert caught.value.kind == "not_found"
    assert caught.value.unbalanced[0][0] == "slider.y"
    assert isinstance(caught.value, mstar.Error)


def test_a_guided_slider_is_neutral_along_its_guide():
    with pytest.raises(mstar.EquilibriumError, match="neutral") as caught:
        mstar.load(POINT_MASS + GUIDE).equilibrium()
    e = caught.value
    assert e.kind == "neutral"
    assert [name for name, _ in e.direction] == ["slider.x"]
    assert isinstance(e.equilibrium, mstar.Equilibrium)
    assert abs(e.equilibrium["slider.y"]) <= 1e-10
