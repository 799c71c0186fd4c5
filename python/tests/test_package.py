"""The package's face: its version, a namespace of its own names only, and
sweeps with typed summaries, results as Result objects, run files that
exist, and overwrite=True."""

from __future__ import annotations

import re
from importlib import metadata
from pathlib import Path

import numpy as np
import pytest

import mstar
from conftest import MODELS, ROOT

MODEL = MODELS / "double-pendulum.toml"


def test_the_version_is_the_workspace_s():
    cargo = (ROOT / "Cargo.toml").read_text()
    version = re.search(r'^\[workspace\.package\][^\[]*?^version = "([^"]+)"', cargo, re.M | re.S).group(1)
    assert mstar.__version__ == version
    assert metadata.version("mstar") == version


def test_the_namespace_is_the_api():
    public = {n for n in dir(mstar) if not n.startswith("_")}
    # Submodules appear once imported (mstar.planar, mstar.spatial).
    assert public - {"planar", "spatial"} == set(mstar.__all__) - {"__version__"}
    for leaked in ("Any", "Dict", "List", "os", "warnings", "annotations", "toml_literal"):
        assert not hasattr(mstar, leaked), leaked
    for name in ("Model", "Result", "Sweep", "load", "sweep"):
        assert getattr(mstar, name).__module__ == "mstar", name


@pytest.fixture(scope="module")
def swept(tmp_path_factory) -> mstar.Sweep:
    out = tmp_path_factory.mktemp("sweep")
    params = {"body.upper.mass": [1.0, 2.0], "simulation.h": [1e-3, -1.0], "simulation.t_end": [0.02]}
    return mstar.sweep(MODEL, params, out, jobs=1)


def test_summary_values_have_their_types(swept):
    rows = swept.summary
    assert [r["index"] for r in rows] == [0, 1, 2, 3]
    assert [r["body.upper.mass"] for r in rows] == [1.0, 1.0, 2.0, 2.0]
    assert [r["simulation.h"] for r in rows] == [1e-3, -1.0, 1e-3, -1.0]
    ok, failed = rows[0], rows[1]
    assert ok["status"] == "ok" and ok["steps"] == 20 and isinstance(ok["steps"], int)
    assert isinstance(ok["t"], float) and ok["t"] == 0.02
    assert isinstance(ok["wall_time_s"], float)
    # A failed run (h < 0 is refused): its status, no figures.
    assert failed["status"].endswith("h: must be positive, in s (got -1)")
    assert failed["steps"] is None and failed["t"] is None
    assert [i for i, _ in swept.failed] == [1, 3]


def test_results_of_a_sweep_are_its_runs(swept):
    r = swept.result(2)
    assert isinstance(r, mstar.Result)
    # Run 2 is upper.mass = 2, h = 1e-3: the same run from a model.
    direct = mstar.load(MODEL).run(t_end=0.02, h=1e-3, overrides={"body.upper.mass": 2.0})
    assert r.columns() == direct.columns()
    assert r.coords == direct.coords and r.constraints == direct.constraints
    assert np.array_equal(r["lambda:elbow.x"], direct["lambda:elbow.x"])
    for name in r.columns():
        assert np.array_equal(r[name], direct[name]), name
    assert r.iterations.dtype == np.int64
    assert r.stats.steps == 20
    assert r.reaction("elbow")["fx"].shape == (21,)


def test_run_csv_never_names_a_missing_file(swept, tmp_path):
    assert swept.run_csv(0) == swept.dir / "runs" / "0.csv"
    # A failed run that failed before its first sample has no file at all.
    path = swept.run_csv(1)
    assert path is None or path.exists()
    with pytest.raises(IndexError, match="run 4 is not in this sweep"):
        swept.run_csv(4)
    # A shard's sweep: the other shard's runs have no file here.
    half = mstar.sweep(MODEL, {"simulation.t_end": [0.01, 0.02]}, tmp_path, shard=(0, 2))
    assert half.run_csv(0).exists() and half.run_csv(1) is None
    with pytest.raises(FileNotFoundError, match="run 1 has no CSV file"):
        half.result(1)


def test_overwrite_replaces_another_plan(tmp_path: Path):
    first = mstar.sweep(MODEL, {"simulation.t_end": [0.01, 0.02]}, tmp_path)
    (tmp_path / "notes.txt").write_text("mine")
    with pytest.raises(mstar.ModelError):
        mstar.sweep(MODEL, {"simulation.t_end": [0.03]}, tmp_path)
    again = mstar.sweep(MODEL, {"simulation.t_end": [0.03]}, tmp_path, overwrite=True)
    assert (first.runs, again.runs, again.ran) == (2, 1, 1)
    assert [r["simulation.t_end"] for r in again.summary] == [0.03]
    assert not (tmp_path / "runs" / "1.csv").exists()
    assert (tmp_path / "notes.txt").read_text() == "mine"
