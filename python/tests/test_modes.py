"""`Model.modes()` against closed forms and against `mstar modes`: the
double pendulum of point masses (ω² = (g/l)(2 ∓ √2), from m l² [2 1; 1 1]
θ̈ + m g l [2 0; 0 1] θ = 0), the damped mode (the roots of m s² + c s + k =
0), the CSV of the command bit for bit, the errors in Python's words.

Tolerances: the modes are linear algebra on the linearization at an
equilibrium found to ‖r‖∞ ≤ 1e-11 of the force scale: 1e-9 relative.
"""

from __future__ import annotations

import csv
import math
import subprocess

import numpy as np
import pytest

import mstar
from conftest import MODELS

DOUBLE = MODELS / "double-pendulum-modes.toml"
DAMPED = MODELS / "damped-mode.toml"


def test_the_double_pendulum_s_two_frequencies():
    modes = mstar.load(DOUBLE).modes()
    assert isinstance(modes, mstar.Modes) and len(modes) == 2 and modes.dof == 2
    g, l = 9.81, 1.0
    for k, sign in ((0, -1.0), (1, 1.0)):
        omega = math.sqrt(g / l * (2.0 + sign * math.sqrt(2.0)))
        assert abs(modes.frequency_hz[k] - omega / math.tau) <= 1e-9 * omega
        assert modes.kind[k] == "oscillating" and modes.damping_ratio[k] == 0.0
    # The hanging state: the lower mass 2 m below the pivot.
    assert abs(modes.u[modes.coords.index("lower.y")] + 2.0) <= 1e-10
    # Unit modal mass, M = diag(m) = identity here.
    for k in range(2):
        phi = modes.shapes[k]
        assert abs(np.vdot(phi, phi).real - 1.0) <= 1e-12
    # The lower mode swings both masses the same way, the upper one apart.
    x1, x2 = modes.coords.index("upper.x"), modes.coords.index("lower.x")
    assert modes.shapes[0][x1].real * modes.shapes[0][x2].real > 0
    assert modes.shapes[1][x1].real * modes.shapes[1][x2].real < 0
    assert "mode 2" in repr(modes)


def test_a_damped_mode_is_a_complex_pair():
    m, k, c = 2.0, 50.0, 3.0
    modes = mstar.load(DAMPED).modes()
    assert len(modes) == 1 and modes.damped
    s = modes.s[0]
    want = complex(-c / (2 * m), math.sqrt(k / m - (c / (2 * m)) ** 2))
    assert abs(s - want) <= 1e-9 * abs(want)
    assert abs(modes.damping_ratio[0] - c / (2 * math.sqrt(k * m))) <= 1e-9
    assert modes.shape(1)["slider.x"].real > 0


def test_the_same_numbers_as_the_command(cli, tmp_path):
    out = tmp_path / "modes.csv"
    proc = subprocess.run([str(cli), "modes", str(DOUBLE), "--out", str(out)], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    with open(out, newline="") as f:
        rows = list(csv.reader(f))
    header, rows = rows[0], rows[1:]
    modes = mstar.load(DOUBLE).modes()
    assert len(rows) == len(modes)
    for k, row in enumerate(rows):
        assert float(row[1]) == modes.frequency_hz[k] and float(row[2]) == modes.damping_ratio[k]
        for name, value in zip(header[3:], row[3:]):
            assert float(value) == modes.shape(k + 1)[name[len("u:"):]].real, name


def test_count_about_and_method():
    model = mstar.load(DOUBLE)
    assert len(model.modes(count=1)) == 1
    initial = model.modes(about="initial")
    # Released from 0.3 and −0.2 rad: another state, other frequencies.
    assert initial.about == "initial" and initial.u[0] != model.modes().u[0]
    dense, sparse = model.modes(method="dense"), model.modes(method="sparse")
    assert np.allclose(dense.frequency_hz, sparse.frequency_hz, rtol=1e-9, atol=0)
    heavier = model.modes(overrides={"gravity": [0.0, -4 * 9.81]})
    assert np.allclose(heavier.frequency_hz, 2 * dense.frequency_hz, rtol=1e-9, atol=0)


def test_errors_in_python_s_words():
    model = mstar.load(DOUBLE)
    with pytest.raises(mstar.ModelError, match="at most 2"):
        model.modes(count=3)
    with pytest.raises(ValueError, match="about"):
        model.modes(about="rest")
    with pytest.raises(ValueError, match="method"):
        model.modes(method="qr")
    with pytest.raises(ValueError, match="count"):
        model.modes(count=0)
    with pytest.raises(TypeError):
        model.modes(count="two")
    with pytest.raises(mstar.ModelError, match='method="dense"') as caught:
        mstar.load(DAMPED).modes(method="sparse")
    assert "--" not in str(caught.value)
    free = "format = \"mstar.planar/1\"\n[[point_mass]]\nname = \"p\"\nmass = 1.0\nposition = [0.0, 0.0]\n"
    with pytest.raises(mstar.EquilibriumError, match='about="initial"'):
        mstar.load(free).modes()
