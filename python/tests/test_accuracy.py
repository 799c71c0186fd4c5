"""A run beyond the error tolerance warns as `mstar run` does (which exits 3
for it): mstar.AccuracyWarning, one per line of the CLI's warning, in
Python's words; none for a run within the tolerance."""

import warnings

import pytest

import mstar
from conftest import MODELS, assert_no_cli_options
from mstar._errors import RUN_RULES, python_message


def test_a_run_beyond_the_tolerance_warns_as_the_cli(run_cli):
    path = MODELS / "pendulum.toml"
    cli = run_cli(path, "--h", "0.2", "--t-end", "1", "--set", "output.every=1")
    assert cli.code == 3, cli.stderr
    theirs = [l[len("warning: "):] for l in cli.stderr.splitlines() if l.startswith("warning: ")]
    assert theirs
    with pytest.warns(mstar.AccuracyWarning) as record:
        result = mstar.load(path).run(h=0.2, t_end=1.0)
    ours = [str(w.message) for w in record if issubclass(w.category, mstar.AccuracyWarning)]
    assert ours == [python_message(w, RUN_RULES) for w in theirs]
    assert result.stats.warning == "\n".join(ours)
    for message in ours:
        assert_no_cli_options(message)
    assert "rerun with h=" in ours[0]


def test_a_run_within_the_tolerance_is_silent(run_cli):
    path = MODELS / "pendulum.toml"
    cli = run_cli(path, "--t-end", "0.5")
    assert cli.code == 0
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        result = mstar.load(path).run(t_end=0.5)
    assert result.stats.warning is None
