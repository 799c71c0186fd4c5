"""Model.check() is `mstar check`: its report text, figure by figure."""

import mstar
from conftest import MODELS


def test_check_is_the_cli_report(check_cli):
    for name in ("four-bar.toml", "parallelogram-third-crank.toml", "spatial/bricard.toml"):
        cli = check_cli(MODELS / name)
        report = mstar.load(MODELS / name).check()
        assert report["report"] == cli.stdout, name
        assert report["can_run"] == (cli.code == 0), name


def test_check_figures():
    r = mstar.load(MODELS / "parallelogram-third-crank.toml").check()
    assert (r["coordinates"], r["constraints"]) == (12, 12)
    assert r["rank"] == 11 and r["degrees_of_freedom"] == 1
    assert r["redundant_constraints"] == ["right-top"]
    assert r["minimum_norm"] is True and r["can_run"] is True and r["error"] is None
    assert r["start_error"] is None
    owner, row, value = r["position_violation"]
    assert (owner, row) == ("middle-ground", "middle-ground.y") and value < 1e-15
    assert set(r["projection"]) == {"position", "velocity"}


def test_check_refusing_redundant_constraints(check_cli):
    args = ["--set", "simulation.redundant=refuse"]
    cli = check_cli(MODELS / "parallelogram-third-crank.toml", *args)
    r = mstar.load(MODELS / "parallelogram-third-crank.toml").check(redundant="refuse")
    assert cli.code == 1 and r["can_run"] is False
    assert r["report"] == cli.stdout
    assert r["error"] == cli.python_error()
    assert r["start_error"] == (
        "at start-up (t = 0): the KKT matrix is singular with the redundant constraints of "
        "right-top: their multipliers are undetermined"
    )


def test_check_places_a_kkt_solver_that_does_not_fit(check_cli):
    """A KKT solver the model does not fit (ldlt with a damper): the error
    at the setting that chose it, as `mstar check` prints it."""
    path = MODELS / "crank-and-spring.toml"
    # (A string as Python passes it: a TOML string, quoted.)
    cli = check_cli(path, "--set", 'simulation.kkt="ldlt"')
    r = mstar.load(path).check(kkt="ldlt")
    assert cli.code == 1 and r["can_run"] is False
    assert r["report"] == cli.stdout
    assert r["error"] == cli.python_error()
    assert "kkt" in r["error"] and "needs a symmetric iteration matrix" in r["error"]
