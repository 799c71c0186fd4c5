"""Result: shapes, columns by name (coordinates, u:/v:/a:, lambda:<i> and
lambda:<row>), stats, to_pandas (and its ImportError without pandas)."""

import sys

import numpy as np
import pytest

import mstar
from conftest import MODELS


@pytest.fixture(scope="module")
def result() -> mstar.Result:
    return mstar.load(MODELS / "four-bar.toml").run(t_end=0.1)


def test_shapes(result):
    n, m = len(result.coords), len(result.constraints)
    assert (n, m) == (9, 9)
    assert result.t.shape == (101,)
    for key in ("u", "v", "a"):
        assert getattr(result, key).shape == (101, n)
    assert result.lam.shape == (101, m)
    for key in ("energy", "iterations", "residual", "constraint"):
        assert getattr(result, key).shape == (101,)
    assert result.iterations.dtype == np.int64
    assert result.t[0] == 0.0 and result.t[-1] == 0.1


def test_columns_by_name(result):
    i = result.coords.index("crank.theta")
    assert result["crank.theta"] is not None
    assert np.array_equal(result["crank.theta"], result.u[:, i])
    assert np.array_equal(result["u:crank.theta"], result.u[:, i])
    assert np.array_equal(result["v:crank.theta"], result.v[:, i])
    assert np.array_equal(result["a:crank.theta"], result.a[:, i])
    # The driver's row: by the CSV's index and by its name.
    row = result.constraints.index("motor")
    assert np.array_equal(result[f"lambda:{row}"], result.lam[:, row])
    assert np.array_equal(result["lambda:motor"], result.lam[:, row])
    assert np.array_equal(result["t"], result.t)
    assert np.array_equal(result["energy"], result.energy)
    # The driver turns the crank at 2 rad/s from 0.5 rad.
    assert np.allclose(result["crank.theta"], 0.5 + 2.0 * result.t, atol=1e-9)
    assert all(result[c].shape == (101,) for c in result.columns())


@pytest.mark.parametrize("name", ["nope", "u:nope", "x:crank.theta", "lambda:9", "lambda:-1", "crank"])
def test_unknown_columns_are_key_errors(result, name):
    with pytest.raises(KeyError, match="no column"):
        result[name]


def test_stats(result):
    s = result.stats
    assert s.steps == 100 == len(result) - 1
    assert s.newton_iterations >= s.steps
    assert s.factorizations >= 1
    assert s.wall_time > 0.0
    assert s.t == 0.1


def test_to_pandas(result):
    pd = pytest.importorskip("pandas")
    frame = result.to_pandas()
    assert list(frame.columns) == result.columns()
    assert np.array_equal(frame["u:crank.theta"].to_numpy(), result["crank.theta"])


def test_to_pandas_without_pandas(result, monkeypatch):
    monkeypatch.setitem(sys.modules, "pandas", None)  # import pandas fails
    with pytest.raises(ImportError, match="needs pandas, which is not installed: pip install pandas"):
        result.to_pandas()


def test_a_model_without_constraints_has_an_empty_lambda():
    from mstar import planar

    b = planar.Builder()
    b.point_mass("p", mass=2.0, position=(0.0, 0.0), velocity=(1.0, 0.0))
    r = b.build().run(t_end=0.01, h=1e-3)
    assert r.lam.shape == (11, 0)
    assert np.allclose(r["p.x"], r.t)
