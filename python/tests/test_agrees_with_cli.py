"""A model run from Python is `mstar run`'s run, bit for bit: every standard
CSV column (t, u, v, a, λ, energy, iterations, residual, constraint) of every
row, compared as exact floats (the CSV writes shortest round-trip numbers),
for planar and spatial models, settings given as keywords or left to the
file, and a model with minimum-norm multipliers."""

import pytest

import mstar
from conftest import MODELS, assert_same_columns

CASES = [
    # (model, t_end or None for the file's, Python settings, CLI arguments)
    ("pendulum.toml", None, {}, []),
    ("four-bar.toml", 1.0, {}, []),
    ("slider-crank.toml", 0.5, {"rho": 0.8}, ["--set", "simulation.rho=0.8"]),
    ("double-pendulum.json", 0.5, {"rho": 0.7}, ["--set", "simulation.rho=0.7"]),
    ("four-bar.toml", 0.5, {"integrator": "hht"}, ["--set", "simulation.integrator=hht"]),
    ("parallelogram-third-crank.toml", 0.5, {}, []),
    ("crank-and-spring.toml", 0.3, {"h": 2e-3}, ["--h", "2e-3"]),
    ("spatial/top.toml", 0.2, {}, []),
    ("spatial/slider-crank.toml", 0.2, {"error_control": "adaptive"}, ["--adaptive"]),
]


@pytest.mark.parametrize("name,t_end,settings,args", CASES, ids=[f"{c[0]}-{i}" for i, c in enumerate(CASES)])
def test_run_matches_the_cli_bit_for_bit(run_cli, name, t_end, settings, args):
    path = MODELS / name
    # Every step a row, as in a Result (a file's [output] every may thin them).
    cli_args = list(args) + ["--set", "output.every=1"]
    if t_end is not None:
        cli_args += ["--t-end", repr(t_end)]
    cli = run_cli(path, *cli_args)
    assert cli.code in (0, 3), cli.stderr  # 3: beyond the error tolerance
    result = mstar.load(path).run(t_end=t_end, **settings)
    assert_same_columns(result, cli)
    assert result.stats.steps == len(result) - 1


def test_toml_text_runs_as_its_file():
    path = MODELS / "four-bar.toml"
    from_text = mstar.load(path.read_text()).run(t_end=0.3)
    from_file = mstar.load(str(path)).run(t_end=0.3)
    for key in ("t", "u", "v", "a", "lam", "energy"):
        assert (getattr(from_text, key) == getattr(from_file, key)).all(), key
