"""Shared fixtures: the repository's models and the `mstar` command-line
program whose runs the package must reproduce bit for bit.

The program is `$MSTAR_CLI` when set (`.ci/run` sets it), else the newest of
`target/release/mstar` and `target/debug/mstar`; without one the tests that
compare fail, saying how to build it.
"""

from __future__ import annotations

import csv
import math
import os
import re
import subprocess
from pathlib import Path
from typing import List

import pytest

ROOT = Path(__file__).resolve().parents[2]
MODELS = ROOT / "models"


def _cli() -> Path:
    if os.environ.get("MSTAR_CLI"):
        return Path(os.environ["MSTAR_CLI"]).resolve()
    built = [ROOT / "target" / p / "mstar" for p in ("release", "debug")]
    built = [p for p in built if p.exists()]
    if not built:
        pytest.fail("no mstar program: run `cargo build -p mstar-cli` or set MSTAR_CLI")
    return max(built, key=lambda p: p.stat().st_mtime)


@pytest.fixture(scope="session")
def cli() -> Path:
    return _cli()


class CliRun:
    """One `mstar run` / `mstar check`: exit code, output, and the CSV's
    columns (exact floats: the CSV writes shortest round-trip numbers)."""

    def __init__(self, proc: subprocess.CompletedProcess, csv_path: Path | None) -> None:
        self.code = proc.returncode
        self.stdout = proc.stdout
        self.stderr = proc.stderr
        self.header: List[str] = []
        self.rows: List[List[float]] = []
        if csv_path is not None and csv_path.exists():
            with open(csv_path, newline="") as f:
                reader = csv.reader(f)
                self.header = next(reader)
                self.rows = [[float(x) for x in row] for row in reader]

    def column(self, name: str) -> List[float]:
        i = self.header.index(name)
        return [row[i] for row in self.rows]

    def error(self) -> str:
        """The text after `error: ` on standard error."""
        lines = [l for l in self.stderr.splitlines() if l.startswith("error: ")]
        assert len(lines) == 1, self.stderr
        return lines[0][len("error: "):]

    def python_error(self, rules=None) -> str:
        """:meth:`error` as the package words it: the command line's options
        as Python arguments (mstar._errors), checked to name none."""
        from mstar._errors import RUN_RULES, python_message

        message = python_message(self.error(), RUN_RULES if rules is None else rules)
        assert_no_cli_options(message)
        return message


#: The command line's options, which Python messages must not name.
CLI_OPTIONS = re.compile(r"--(set|out|h|h-max|t-end|adaptive|strict|jobs|shard|zip|grid|output-every)\b")


def assert_no_cli_options(message: str) -> None:
    found = CLI_OPTIONS.search(message)
    assert found is None, f"{found.group(0)} in {message!r}"


@pytest.fixture
def run_cli(cli: Path, tmp_path: Path):
    """`mstar run MODEL --out tmp.csv ARGS...`; the CSV (or, after a failure,
    the partial one) is read."""

    def run(model: os.PathLike | str, *args: str) -> CliRun:
        out = tmp_path / "out.csv"
        proc = subprocess.run(
            [str(cli), "run", str(model), "--out", str(out), *args],
            capture_output=True, text=True, cwd=tmp_path,
        )
        partial = tmp_path / "out.partial.csv"
        return CliRun(proc, out if out.exists() else partial)

    return run


@pytest.fixture
def check_cli(cli: Path, tmp_path: Path):
    def check(model: os.PathLike | str, *args: str) -> CliRun:
        proc = subprocess.run(
            [str(cli), "check", str(model), *args], capture_output=True, text=True, cwd=tmp_path
        )
        return CliRun(proc, None)

    return check


def same(a: float, b: float) -> bool:
    """Bit-for-bit equality, NaN equal to NaN (−0 is written as 0)."""
    return (math.isnan(a) and math.isnan(b)) or a == b


def assert_same_columns(result, cli_run: CliRun) -> None:
    """Every CSV column of the CLI's run (the standard ones, reactions,
    efforts, ...) equals the result's of the same name exactly."""
    names = result.columns()
    assert cli_run.header == names
    assert len(cli_run.rows) == len(result), (len(cli_run.rows), len(result))
    for name in names:
        ours = [float(x) for x in result[name]]
        theirs = cli_run.column(name)
        bad = [k for k, (x, y) in enumerate(zip(ours, theirs)) if not same(x, y)]
        assert not bad, f"{name}: row {bad[0]}: python {ours[bad[0]]!r}, cli {theirs[bad[0]]!r} ({len(bad)} rows differ)"
