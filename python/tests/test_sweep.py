"""`mstar.sweep` against `mstar sweep`: the same plan gives the same summary
and run files, byte for byte but the wall-time column; errors carry the
command line's messages."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest

import mstar

from conftest import MODELS

MODEL = MODELS / "double-pendulum.toml"
PARAMS = {"body.upper.mass": [1.0, 2.0], "simulation.h": [1e-3, 5e-4]}


def _without_wall_time(path: Path) -> list[str]:
    """The summary's lines without their last column (the wall time)."""
    return [line.rsplit(",", 1)[0] for line in path.read_text().splitlines()]


def test_a_python_sweep_equals_the_command_line_s(cli: Path, tmp_path: Path) -> None:
    ours = mstar.sweep(MODEL, {**PARAMS, "simulation.t_end": [0.05]}, tmp_path / "py", jobs=2)
    assert (ours.runs, ours.ran, ours.skipped, ours.failed) == (4, 4, 0, [])
    proc = subprocess.run(
        [str(cli), "sweep", str(MODEL), "--set", "body.upper.mass=1.0,2.0",
         "--set", "simulation.h=0.001,0.0005", "--set", "simulation.t_end=0.05",
         "--jobs", "2", "--out", str(tmp_path / "cli")],
        capture_output=True, text=True,
    )
    assert proc.returncode == 0, proc.stderr
    theirs = tmp_path / "cli" / "summary.csv"
    assert _without_wall_time(ours.summary_path) == _without_wall_time(theirs)
    for i in range(4):
        assert ours.run_csv(i).read_bytes() == (tmp_path / "cli" / "runs" / f"{i}.csv").read_bytes()
    rows = ours.summary
    assert [r["body.upper.mass"] for r in rows] == [1.0, 1.0, 2.0, 2.0]
    # 0.05 s at h = 1e-3 and 5e-4: 50 and 100 steps, whatever the mass.
    assert [r["steps"] for r in rows] == [50, 100, 50, 100]


def test_a_rerun_skips_the_complete_runs(tmp_path: Path) -> None:
    params = {"body.upper.mass": [1.0, 2.0], "simulation.t_end": [0.02]}
    first = mstar.sweep(MODEL, params, tmp_path / "s")
    again = mstar.sweep(MODEL, params, tmp_path / "s")
    assert (first.ran, again.ran, again.skipped) == (2, 0, 2)


def test_a_key_that_leads_nowhere_is_the_command_line_s_error(cli: Path, tmp_path: Path) -> None:
    with pytest.raises(mstar.ModelError) as e:
        mstar.sweep(MODEL, {"body.uper.mass": [1.0]}, tmp_path / "py")
    proc = subprocess.run(
        [str(cli), "sweep", str(MODEL), "--set", "body.uper.mass=1.0", "--out", str(tmp_path / "cli")],
        capture_output=True, text=True,
    )
    assert proc.returncode == 2
    cli_error = [l for l in proc.stderr.splitlines() if l.startswith("error: ")][0][len("error: "):]
    from mstar._errors import SWEEP_RULES, python_message

    assert str(e.value) == python_message(cli_error, SWEEP_RULES)
    assert not (tmp_path / "py").exists()
