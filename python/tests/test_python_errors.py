"""Exceptions that speak Python: mstar.Error and its kinds, named `mstar.*`;
the command line's options in messages become Python arguments (each rule
of mstar._errors checked on a real error or on the library's text)."""

from __future__ import annotations

from pathlib import Path

import pytest

import mstar
from conftest import MODELS, assert_no_cli_options
from mstar._errors import RULES, RUN_RULES, SWEEP_RULES, python_message


@pytest.mark.parametrize("name", ["Error", "ModelError", "IntegrationError"])
def test_exceptions_live_in_mstar(name):
    kind = getattr(mstar, name)
    assert kind.__module__ == "mstar"
    assert kind.__qualname__ == name
    assert issubclass(kind, mstar.Error) and issubclass(kind, Exception)


def test_a_setting_s_override_names_the_keyword():
    with pytest.raises(mstar.ModelError) as e:
        mstar.load(MODELS / "four-bar.toml").run(no_such_key=1)
    assert "unknown key 'no_such_key' (given by a setting or overrides=)" in str(e.value)
    assert_no_cli_options(str(e.value))


def test_an_override_names_overrides():
    with pytest.raises(mstar.ModelError) as e:
        mstar.load(MODELS / "pendulum.toml").run(overrides={"body.bob.mas": 2.0})
    assert "unknown key 'mas' (given by a setting or overrides=)" in str(e.value)
    assert_no_cli_options(str(e.value))


def test_refused_redundant_constraints_say_how_in_python():
    with pytest.raises(mstar.IntegrationError) as e:
        mstar.load(MODELS / "parallelogram-third-crank.toml").run(redundant="refuse", t_end=0.01)
    assert '(in Python: redundant="minimum-norm")' in str(e.value)
    assert_no_cli_options(str(e.value))


def test_a_sweep_into_another_plan_s_folder_says_overwrite(tmp_path: Path):
    model = MODELS / "double-pendulum.toml"
    mstar.sweep(model, {"simulation.t_end": [0.01]}, tmp_path)
    with pytest.raises(mstar.ModelError) as e:
        mstar.sweep(model, {"simulation.t_end": [0.02]}, tmp_path)
    assert str(e.value).endswith("give another out=, or overwrite=True to replace its plan")
    assert_no_cli_options(str(e.value))


def test_sweep_argument_errors_name_the_arguments(tmp_path: Path):
    model = MODELS / "double-pendulum.toml"
    cases = [
        ({"params": {}}, "give at least one key in params"),
        ({"params": {"simulation.t_end": [0.01, 0.02], "simulation.h": [1e-3, 2e-3, 3e-3]}, "zip": True},
         "zip=True pairs the i-th values"),
        ({"params": {"simulation.t_end": [0.01]}, "shard": (3, 2)}, "shard=(3, 2): "),
    ]
    for kwargs, words in cases:
        with pytest.raises(mstar.ModelError) as e:
            mstar.sweep(model, out=tmp_path / "s", **kwargs)
        assert words in str(e.value), str(e.value)
        assert_no_cli_options(str(e.value))


# Messages of the library that a test cannot easily provoke, with their
# Python wording (the library's text as in crates/mstar/src).
TEXTS = [
    ("rerun with --h 0.005 or smaller", RUN_RULES, "rerun with h=0.005 or smaller"),
    ("rerun with --h 1e-3 --h-max 1e-3", RUN_RULES, "rerun with h=1e-3 h_max=1e-3"),
    ("rerun with --h 1e-3 --set simulation.h_max=1e-3", RUN_RULES, "rerun with h=1e-3 h_max=1e-3"),
    ("or with --adaptive (--strict stops at the first such step)", RUN_RULES,
     'or with error_control="adaptive" (error_control="strict" stops at the first such step)'),
    ("try --set simulation.integrator=generalized-alpha", RUN_RULES, 'try integrator="generalized-alpha"'),
    ("try --set simulation.rho=0.9", RUN_RULES, "try rho=0.9"),
    ("--set body.x.mass=abc: why", RUN_RULES, 'overrides["body.x.mass"]=abc: why'),
    ("--set body.x.mass=1,2: why", SWEEP_RULES, 'params["body.x.mass"]: why'),
    ("the key k is given twice: give all its values in one --set k=V1,V2,…", SWEEP_RULES,
     "the key k is given twice: give all its values in one entry of params"),
    ("--jobs 0: must be positive", SWEEP_RULES, "jobs=0: must be positive"),
    ("run that shard here (the same mstar sweep command with its --shard)", SWEEP_RULES,
     "run that shard here (the same mstar.sweep call with its shard=)"),
    ("run the shards that are missing (the same command with their --shard)", SWEEP_RULES,
     "run the shards that are missing (the same mstar.sweep call with their shard=)"),
    ("(or use --grid for every combination)", SWEEP_RULES, "(or zip=False for every combination)"),
    ("no shard summaries to merge: run mstar sweep … --shard I/N first", SWEEP_RULES,
     "no shard summaries to merge: run mstar.sweep(..., shard=(i, n)) first"),
]


@pytest.mark.parametrize("text,rules,expected", TEXTS)
def test_the_table_words_each_option(text, rules, expected):
    assert python_message(text, rules) == expected
    assert_no_cli_options(python_message(text, rules))


def test_every_rule_is_used():
    texts = [t for t, _, _ in TEXTS] + ["(given by --set)", "--t-end 2",
            "(on the command line: --set simulation.redundant=minimum-norm)",
            "give another --out, or remove the directory to start afresh", "--zip", "--shard 0/4",
            "nothing to sweep: give at least one --set KEY=V1,V2,…"]
    for pattern, _ in RULES + RUN_RULES + SWEEP_RULES:
        import re

        assert any(re.search(pattern, t) for t in texts), pattern
