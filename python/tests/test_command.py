"""The `mstar` command `pip install ./python` installs is the command-line
program: the same help, output, files and exit codes; the extension is
built for the stable ABI (abi3); mstar.animate draws the files `mstar
animate` draws, and a Result shows its animation in Jupyter."""

from __future__ import annotations

import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest

import mstar
from conftest import MODELS


@pytest.fixture(scope="module")
def script() -> str:
    """The `mstar` script of this environment (its scripts folder first:
    the tests may run without the environment activated)."""
    found = shutil.which("mstar", path=sysconfig.get_path("scripts"))
    assert found is not None, "no mstar script: pip install ./python"
    return found


def run(*argv, cwd=None) -> subprocess.CompletedProcess:
    return subprocess.run([str(a) for a in argv], capture_output=True, text=True, cwd=cwd)


def without_wall_time(text: str) -> list:
    return [l for l in text.splitlines() if not l.startswith("wall time:")]


def test_help_and_version_are_the_program_s(script, cli):
    for args in (["--help"], ["run", "--help"], ["--version"]):
        ours, theirs = run(script, *args), run(cli, *args)
        assert ours.returncode == theirs.returncode == 0, ours.stderr
        assert ours.stdout == theirs.stdout, args
    assert run(script, "--help").stdout.splitlines()[2] == "Usage: mstar <COMMAND>"


def test_a_run_is_the_program_s(script, cli, tmp_path):
    model = MODELS / "pendulum.toml"
    for folder in ("ours", "theirs"):
        (tmp_path / folder).mkdir()
    ours = run(script, "run", model, "--t-end", "0.01", "--out", "out.csv", cwd=tmp_path / "ours")
    theirs = run(cli, "run", model, "--t-end", "0.01", "--out", "out.csv", cwd=tmp_path / "theirs")
    assert ours.returncode == theirs.returncode == 0, ours.stderr
    assert without_wall_time(ours.stdout) == without_wall_time(theirs.stdout)
    assert (tmp_path / "ours" / "out.csv").read_bytes() == (tmp_path / "theirs" / "out.csv").read_bytes()
    # The report alone (no --out): the same lines, the same code.
    ours, theirs = run(script, "run", model, "--t-end", "0.01"), run(cli, "run", model, "--t-end", "0.01")
    assert without_wall_time(ours.stdout) == without_wall_time(theirs.stdout)


@pytest.mark.parametrize(
    "args",
    [
        ["check", "nope.toml"],  # a file that is not there: 2
        ["check", MODELS / "parallelogram-third-crank.toml", "--set", "simulation.redundant=refuse"],  # 1
        ["run", MODELS / "pendulum.toml", "--h", "0.2", "--t-end", "1"],  # beyond the tolerance: 3
        ["bogus"],  # clap's refusal: 2
        [],  # no command: clap's usage, 2
    ],
)
def test_failures_exit_with_the_program_s_codes(script, cli, tmp_path, args):
    ours, theirs = run(script, *args, cwd=tmp_path), run(cli, *args, cwd=tmp_path)
    assert ours.returncode == theirs.returncode != 0
    assert without_wall_time(ours.stderr) == without_wall_time(theirs.stderr)


def test_the_extension_is_abi3():
    native = Path(mstar._native.__file__).name
    if sys.platform.startswith("linux") or sys.platform == "darwin":
        assert native.endswith(".abi3.so"), native


def test_animate_writes_the_program_s_files(cli, tmp_path):
    model = MODELS / "four-bar.toml"
    result = mstar.load(model).run(t_end=0.3)
    ours, theirs = tmp_path / "py", tmp_path / "cli"
    ours.mkdir()
    theirs.mkdir()
    # The results file named as the one mstar.animate writes (the page
    # names it).
    proc = run(cli, "run", model, "--t-end", "0.3", "--set", "output.every=1", "--out", theirs / "results.csv")
    assert proc.returncode == 0, proc.stderr
    for name, extra in (("a.html", []), ("a.gif", []), ("a.png", ["--at", "0.1"])):
        assert mstar.animate(result, ours / name, at=0.1 if name.endswith("png") else None) == ours / name
        option = "--" + name.split(".")[1]
        proc = run(cli, "animate", model, theirs / "results.csv", option, theirs / name, *extra)
        assert proc.returncode == 0, proc.stderr
        assert (ours / name).read_bytes() == (theirs / name).read_bytes(), name


def test_jupyter_shows_the_animation_page():
    for name in ("four-bar.toml", "spatial/top.toml"):
        page = mstar.load(MODELS / name).run(t_end=0.05)._repr_html_()
        assert page.startswith("<iframe srcdoc=") and "mstar animate" in page and "&lt;svg" in page, name


def test_animate_refuses_what_it_cannot_draw(tmp_path):
    from mstar import planar

    b = planar.Builder()
    b.point_mass("p", mass=1.0, position=(0.0, 0.0))
    built = b.build().run(t_end=0.01, h=1e-3)
    with pytest.raises(ValueError, match="no model file"):
        mstar.animate(built, tmp_path / "a.html")
    assert built._repr_html_() is None
    result = mstar.load(MODELS / "pendulum.toml").run(t_end=0.01)
    with pytest.raises(ValueError, match=r"out: expected a name ending in \.html, \.gif or \.png"):
        mstar.animate(result, tmp_path / "a.mp4")
    with pytest.raises(mstar.Error, match="spatial"):
        mstar.animate(result, tmp_path / "a.html", view="xz")
