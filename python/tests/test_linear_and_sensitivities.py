"""`Model.linearize()` and `Model.run(sensitivities=…)` against closed
forms and against the command line (`mstar linearize`, `mstar run
--sensitivity`).

- The paper's pendulum (1 kg, 1 m, g = 10) about its hanging equilibrium:
  `A = [[0, 1], [−g/l, 0]]` in (θ, θ̇) (θ̈ = −(g/l) θ linearized). The
  matrices are formed from the model's exact Jacobians: round-off, 1e-9.
- The same pendulum's sensitivities to the bob's mass: the motion does not
  depend on it (∂u/∂m = 0) and the rod's force is proportional to it
  (∂λ/∂m = λ/m). The step's residual is linear in m, so the central
  differences of its partials are exact up to round-off: 1e-8 relative.
"""

from __future__ import annotations

import csv
import json
import subprocess

import numpy as np
import pytest

import mstar
from conftest import MODELS

PENDULUM = MODELS / "pendulum.toml"


def test_the_hanging_pendulum_s_state_space_model(cli, tmp_path):
    model = mstar.load(PENDULUM)
    ss = model.linearize(outputs=["u:bob.theta"])
    assert isinstance(ss, mstar.StateSpace)
    assert ss.A.shape == (2, 2) and ss.B.shape == (2, 0) and ss.C.shape == (1, 2)
    assert np.allclose(ss.A, [[0.0, 1.0], [-10.0, 0.0]], rtol=0, atol=1e-9), ss.A
    # θ is the only independent coordinate: C picks it, N maps it to u.
    assert np.allclose(ss.C, [[1.0, 0.0]], rtol=0, atol=1e-12)
    assert ss.N.shape == (3, 1) and ss.states[0].endswith("theta")
    out = tmp_path / "ss.json"
    proc = subprocess.run([str(cli), "linearize", str(PENDULUM), "--outputs", "u:bob.theta", "--out", str(out)],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert json.loads(out.read_text()) == ss.fields
    assert "2 states" in repr(ss)


def test_linearize_errors():
    model = mstar.load(PENDULUM)
    with pytest.raises(ValueError, match="about"):
        model.linearize(about="rest")
    with pytest.raises(mstar.ModelError, match="names no column") as caught:
        model.linearize(outputs=["u:nothing.x"])
    assert "outputs=['u:nothing.x']" in str(caught.value) and "--" not in str(caught.value)
    with pytest.raises(TypeError, match="outputs"):
        model.linearize(outputs="u:bob.theta")
    with pytest.raises(mstar.ModelError, match="model file"):
        mstar.load(PENDULUM.read_text()).linearize()


def test_sensitivities_to_the_bob_s_mass():
    model = mstar.load(PENDULUM)
    result = model.run(t_end=0.5, sensitivities=["body.bob.mass"])
    for c in result.coords:
        column = result[f"d(u:{c})/d(body.bob.mass)"]
        assert np.all(np.isfinite(column))
        assert np.max(np.abs(column)) <= 1e-8, c
    for row in result.constraints:
        lam = result[f"lambda:{row}"]
        dlam = result[f"d(lambda:{row})/d(body.bob.mass)"]
        assert np.all(np.abs(dlam - lam / 1.0) <= 1e-8 * np.max(np.abs(lam))), row


def test_sensitivity_columns_equal_the_command_s(cli, tmp_path):
    out = tmp_path / "run.csv"
    proc = subprocess.run([str(cli), "run", str(PENDULUM), "--t-end", "0.2", "--sensitivity", "body.bob.mass",
                           "--out", str(out)], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    with open(out, newline="") as f:
        rows = list(csv.reader(f))
    header, data = rows[0], np.array(rows[1:], dtype=float)
    result = mstar.load(PENDULUM).run(t_end=0.2, sensitivities=["body.bob.mass"])
    names = [n for n in header if n.startswith("d(")]
    assert names and all(n in result.extra_names for n in names)
    for n in names:
        assert np.array_equal(result[n], data[:, header.index(n)]), n


def test_sensitivity_errors():
    model = mstar.load(PENDULUM)
    with pytest.raises(mstar.ModelError, match="mass"):
        model.run(t_end=0.1, sensitivities=["body.bob.mas"])
    with pytest.raises(mstar.ModelError, match="twice"):
        model.run(t_end=0.1, sensitivities=["body.bob.mass", "body.bob.mass"])
    with pytest.raises(mstar.ModelError, match="fixed steps"):
        model.run(t_end=0.1, error_control="adaptive", sensitivities=["body.bob.mass"])
    with pytest.raises(mstar.ModelError, match="file"):
        mstar.load(PENDULUM.read_text()).run(t_end=0.1, sensitivities=["body.bob.mass"])


DOUBLE = MODELS / "double-pendulum.toml"
KEYS = ["body.lower.mass", "body.upper.mass"]


def test_the_adjoint_gradient_equals_the_forward_sensitivities():
    # One backward pass against one forward column per key: the same
    # derivatives of the discrete solution. The model runs modified Newton,
    # and the two runs refactor at other steps, so their states differ
    # within the Newton tolerance (1e-10 here; 3e-12 measured) and the
    # derivatives by as much relative to their size: 1e-8 allows it.
    model = mstar.load(DOUBLE)
    g = model.gradient("final:u:lower.x", KEYS, t_end=0.2)
    assert isinstance(g, mstar.Gradient) and list(g.gradient) == KEYS and g.steps == 200
    forward = model.run(t_end=0.2, sensitivities=KEYS)
    assert abs(g.value - forward["lower.x"][-1]) <= 1e-10
    for key in KEYS:
        want = forward[f"d(u:lower.x)/d({key})"][-1]
        assert abs(g.gradient[key] - want) <= 1e-8 * abs(want), key
    total = model.gradient("sum:u:lower.x", KEYS, t_end=0.2)
    for key in KEYS:
        want = np.sum(forward[f"d(u:lower.x)/d({key})"])
        assert abs(total.gradient[key] - want) <= 1e-8 * abs(want), key
    # A fit to the run itself: Ψ and the gradient 2 Σ (y − d) ∂y/∂p vanish
    # to the runs' difference (1e-10 per sample at most).
    fit = model.gradient("fit:u:lower.x", KEYS, measured=forward["lower.x"], t_end=0.2)
    assert fit.value <= 201 * 1e-20
    for key in KEYS:
        scale = np.sum(np.abs(forward[f"d(u:lower.x)/d({key})"]))
        assert abs(fit.gradient[key]) <= 2e-10 * scale, key


def test_the_gradient_equals_the_command_s(cli, tmp_path):
    out = tmp_path / "g.json"
    proc = subprocess.run([str(cli), "run", str(DOUBLE), "--t-end", "0.2", "--objective", "final:u:lower.x",
                           "--gradient", *KEYS, "--gradient-out", str(out)], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    written = json.loads(out.read_text())
    g = mstar.load(DOUBLE).gradient("final:u:lower.x", KEYS, t_end=0.2)
    assert written["value"] == g.value and written["gradient"] == g.gradient


def test_gradient_errors():
    model = mstar.load(DOUBLE)
    with pytest.raises(ValueError, match="objective"):
        model.gradient("last:u:lower.x", KEYS, t_end=0.1)
    with pytest.raises(ValueError, match="measured"):
        model.gradient("fit:u:lower.x", KEYS, t_end=0.1)
    with pytest.raises(mstar.ModelError, match="state column"):
        model.gradient("final:u:nothing.x", KEYS, t_end=0.1)
    with pytest.raises(mstar.ModelError, match="fixed steps"):
        model.gradient("final:u:lower.x", KEYS, t_end=0.1, error_control="adaptive")
    with pytest.raises(mstar.ModelError, match="params"):
        model.gradient("final:u:lower.x", [], t_end=0.1)
