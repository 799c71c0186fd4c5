"""Errors raise the exception of their kind with the message `mstar run` (or
`mstar check`) prints after `error: `; a failed run keeps its samples in
`e.partial`, equal bit for bit to the CLI's `<name>.partial.csv`."""

import pytest

import mstar
from conftest import MODELS, assert_same_columns

BAD_KEY = """format = "mstar.planar/1"

[[body]]
name = "bob"
mass = -1.0
inertia = 0.0
pose = [1.0, 0.0, 0.0]
"""


def test_a_missing_file_is_a_model_error(run_cli, tmp_path):
    cli = run_cli(tmp_path / "nope.toml")
    with pytest.raises(mstar.ModelError) as e:
        mstar.load(str(tmp_path / "nope.toml"))
    assert cli.code == 2
    assert str(e.value) == cli.python_error()


def test_a_value_out_of_range_is_a_model_error(run_cli, tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text(BAD_KEY)
    cli = run_cli(path)
    with pytest.raises(mstar.ModelError) as e:
        mstar.load(path)
    assert cli.code == 2
    assert str(e.value) == cli.python_error()
    # The same text, not a file: named <string>.
    with pytest.raises(mstar.ModelError) as e:
        mstar.load(BAD_KEY)
    assert str(e.value) == cli.python_error().replace(str(path), "<string>")


@pytest.mark.parametrize(
    "settings,args",
    [
        # (`--h -1` names the option instead: the CLI's own value. The
        # message quotes the --set as given: -1.0, as Python writes it.)
        ({"h": -1.0}, ["--set", "simulation.h=-1.0"]),
        # (A string as Python passes it: a TOML string, quoted.)
        ({"kkt": "nope"}, ["--set", 'simulation.kkt="nope"']),
        ({"integrator": "rk4"}, ["--set", "simulation.integrator=rk4"]),
        ({"no_such_key": 1}, ["--set", "simulation.no_such_key=1"]),
    ],
)
def test_bad_settings_are_model_errors(run_cli, settings, args):
    path = MODELS / "four-bar.toml"
    cli = run_cli(path, *args)
    with pytest.raises(mstar.ModelError) as e:
        mstar.load(path).run(**settings)
    assert cli.code == 2
    assert str(e.value) == cli.python_error()


def test_refused_redundant_constraints_are_an_integration_error(run_cli):
    path = MODELS / "parallelogram-third-crank.toml"
    cli = run_cli(path, "--set", "simulation.redundant=refuse")
    with pytest.raises(mstar.IntegrationError) as e:
        mstar.load(path).run(redundant="refuse")
    assert cli.code == 1
    assert str(e.value) == cli.python_error()
    assert len(e.value.partial) == 0


def test_a_failed_step_keeps_the_samples_before_it(run_cli):
    # The paper's undamped Newmark on the pendulum fails near t = 5.8 s
    # (its λ mode grows until Newton fails: docs/paper.md).
    path = MODELS / "pendulum.toml"
    cli = run_cli(path, "--set", "simulation.integrator=newmark")
    with pytest.raises(mstar.IntegrationError) as e:
        mstar.load(path).run(integrator="newmark")
    assert cli.code == 1
    assert str(e.value) == cli.python_error()
    message = str(e.value)
    assert message.startswith("step size too small at t = ")
    t_failed = float(message.removeprefix("step size too small at t = ").split(" ")[0])
    assert 5.5 < t_failed < 6.0, message
    partial = e.value.partial
    assert isinstance(partial, mstar.Result)
    assert t_failed - 0.1 < partial.t[-1] <= t_failed
    assert partial.stats.steps == len(partial) - 1
    assert_same_columns(partial, cli)


def test_a_builder_error_is_a_model_error():
    from mstar import planar

    b = planar.Builder()
    b.point_mass("p", mass=1.0, position=(0.0, 0.0))
    b.point_mass("p", mass=1.0, position=(1.0, 0.0))
    with pytest.raises(mstar.ModelError, match="'p'"):
        b.build()
    with pytest.raises(ValueError, match="coordinate: expected 'x', 'y' or 'theta', got 'z'"):
        planar.Builder().driver("d", b.point_mass("q", mass=1.0, position=(0, 0)), "z", 0.0)


def test_start_notes_are_model_warnings_with_the_cli_s_text(run_cli, tmp_path):
    """A pendulum given a radial velocity: the start changes it to satisfy
    the rod, and says so as `mstar run` does (`warning: …` there, a
    ModelWarning here, `mstar check` read as `Model.check()`)."""
    path = tmp_path / "radial.toml"
    text = (MODELS / "pendulum.toml").read_text().replace(
        "pose = [1.0, 0.0, 1.5707963267948966]",
        "pose = [1.0, 0.0, 1.5707963267948966]\nvelocity = [1.0, 0.5, 0.0]",
    )
    assert "velocity = " in text
    path.write_text(text)
    cli = run_cli(path, "--t-end", "0.01")
    said = [l.removeprefix("warning: ") for l in cli.stderr.splitlines() if "the start changed" in l]
    assert len(said) == 1, cli.stderr
    with pytest.warns(mstar.ModelWarning) as caught:
        mstar.load(path).run(t_end=0.01)
    notes = [str(w.message) for w in caught if "the start changed" in str(w.message)]
    assert notes == [said[0].replace("mstar check", "Model.check()")]
