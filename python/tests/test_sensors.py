"""Sensors and column choice from Python (docs/model-format.md, "[[sensor]]",
"Binary output"): a model file's sensors are columns of the Result under the
CLI's names, equal to the CLI's CSV and .npz (read with numpy alone) and to
the kinematics worked out here from the coordinates; `[output] columns`
chooses the CLI's columns, and the .npz holds exactly those."""

from __future__ import annotations

import subprocess

import numpy as np

import mstar
from conftest import MODELS

SENSORS = """
[[sensor]]
name = "tip"
type = "position"
body = "coupler"
point = [0.3, 0.0]

[[sensor]]
name = "tip_v"
type = "velocity"
body = "coupler"
point = [0.3, 0.0]

[[sensor]]
name = "spin"
type = "angular-velocity"
body = "rocker"

[[sensor]]
name = "gap"
type = "distance"
bodies = ["ground", "coupler"]
points = [[0.6, 0.0], [0.3, 0.0]]

[[sensor]]
name = "drive"
type = "effort"
driver = "motor"
"""

CHOICE = '\n[output]\ncolumns = ["t", "sensor:*", "effort:motor"]\n'


def four_bar_with_sensors(tmp_path, choice=""):
    text = (MODELS / "four-bar.toml").read_text() + SENSORS + choice
    path = tmp_path / "four-bar-sensors.toml"
    path.write_text(text)
    return path


def test_sensors_are_result_columns_with_the_cli_names(tmp_path):
    r = mstar.load(four_bar_with_sensors(tmp_path)).run(t_end=0.1)
    x, y, th = r["u:coupler.x"], r["u:coupler.y"], r["u:coupler.theta"]
    vx, vy, w = r["v:coupler.x"], r["v:coupler.y"], r["v:coupler.theta"]
    # The point (0.3, 0) of the coupler: r + A s, and ṙ + ω × (A s).
    dx, dy = 0.3 * np.cos(th), 0.3 * np.sin(th)
    assert np.allclose(r["sensor:tip.x"], x + dx, rtol=0, atol=1e-13)
    assert np.allclose(r["sensor:tip.y"], y + dy, rtol=0, atol=1e-13)
    assert np.allclose(r["sensor:tip_v.x"], vx - w * dy, rtol=0, atol=1e-12)
    assert np.allclose(r["sensor:tip_v.y"], vy + w * dx, rtol=0, atol=1e-12)
    assert np.array_equal(r["sensor:spin.w"], r["v:rocker.theta"])
    assert np.allclose(r["sensor:gap"], np.hypot(x + dx - 0.6, y + dy), rtol=0, atol=1e-13)
    assert np.array_equal(r["sensor:drive"], r["effort:motor"])
    assert np.array_equal(r["effort:motor"], -r["lambda:motor"])


def test_the_cli_csv_and_npz_hold_the_chosen_columns_of_the_result(cli, tmp_path):
    path = four_bar_with_sensors(tmp_path, CHOICE)
    r = mstar.load(path).run(t_end=0.1)
    want = ["t", "effort:motor", "sensor:tip.x", "sensor:tip.y", "sensor:tip_v.x",
            "sensor:tip_v.y", "sensor:spin.w", "sensor:gap", "sensor:drive"]
    for ext in ("csv", "npz"):
        out = tmp_path / f"run.{ext}"
        proc = subprocess.run([str(cli), "run", str(path), "--t-end", "0.1", "--out", str(out)],
                              capture_output=True, text=True)
        assert proc.returncode == 0, proc.stderr
        if ext == "csv":
            names = out.read_text().splitlines()[0].split(",")
            data = np.loadtxt(out, delimiter=",", skiprows=1)
        else:
            run = np.load(out)
            names, data = list(run["columns"]), run["data"]
            assert data.dtype == np.float64
        assert names == want
        assert data.shape == (len(r), len(want))
        for k, name in enumerate(names):
            assert np.array_equal(data[:, k], r[name]), name
