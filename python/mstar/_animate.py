"""``mstar.animate``: a result drawn as ``mstar animate`` draws it (GIF,
HTML page or PNG frame), by that command run in a child process (it installs
signal handlers of its own, which must not outlive it in this one)."""

from __future__ import annotations

import csv
import os
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any, List, Optional, Union

import numpy as np

from ._errors import RUN_RULES, Error, ModelError, python_message

#: The output option of ``mstar animate`` for each file extension.
_OPTIONS = {".html": "--html", ".htm": "--html", ".gif": "--gif", ".png": "--png"}


def _write_csv(result: Any, path: Path) -> None:
    """The result's columns as ``mstar run --out`` writes them (names and
    values; numbers in round-trip form)."""
    data = np.column_stack(
        [result.t, result.u, result.v, result.a, result.lam, result.energy, result.iterations,
         result.residual, result.constraint, result.extra]
    )
    with open(path, "w", newline="") as f:
        csv.writer(f, lineterminator="\n").writerow(result.columns())
        for row in data:
            f.write(",".join(repr(float(x)) for x in row))
            f.write("\n")


def _model_file(result: Any, folder: Path) -> Path:
    """The file of the result's model: its path, or its TOML text written
    to ``folder``.

    Raises:
        ValueError: a builder's model or a result without one (no file to draw).
    """
    model = result._model
    if model is None or model._source is None:
        raise ValueError(
            "animate: this result's model has no model file (a builder's, or a sweep's result): "
            "load the model from a file, or run `mstar animate MODEL RESULTS.csv` on the sweep's run file"
        )
    if model._is_path:
        return Path(model._source).resolve()
    path = folder / "model.toml"
    path.write_text(model._source)
    return path


def _run_animate(args: List[str]) -> None:
    """``mstar animate ARGS`` in a child process.

    Raises:
        ModelError: exit 2 (the model cannot be read); Error: another failure.
    """
    proc = subprocess.run(
        [sys.executable, "-m", "mstar._cli", "animate", *args], capture_output=True, text=True
    )
    if proc.returncode == 0:
        return
    lines = [l[len("error: "):] for l in proc.stderr.splitlines() if l.startswith("error: ")]
    message = python_message(lines[0] if lines else proc.stderr.strip(), RUN_RULES)
    raise (ModelError if proc.returncode == 2 else Error)(message)


def animate(
    result: Any,
    out: Union[str, "os.PathLike[str]"],
    *,
    at: Optional[float] = None,
    size: Optional[str] = None,
    view: Optional[str] = None,
    fps: Optional[int] = None,
) -> Path:
    """Draws ``result`` (a :class:`mstar.Result` of a model loaded from a
    file or TOML text) into ``out``, as ``mstar animate MODEL RESULTS.csv
    --html/--gif/--png OUT`` does, by the file's extension: ``.html`` (a
    self-contained page: play/pause, time slider), ``.gif`` (animated) or
    ``.png`` (the frame at ``at``, s). ``size`` is ``"WIDTHxHEIGHT"``,
    ``view`` a spatial model's projection (``"oblique"``, ``"xz"``, ``"yz"``,
    ``"xy"``), ``fps`` the GIF's frames per second. Returns ``out``.

    Raises:
        ValueError: another extension, or a builder's model (no file to draw).
        ModelError: the model file cannot be read; mstar.Error: the drawing
            failed (the command's message).
    """
    out_path = Path(os.fspath(out))
    option = _OPTIONS.get(out_path.suffix.lower())
    if option is None:
        raise ValueError(f"out: expected a name ending in .html, .gif or .png, got {str(out_path)!r}")
    with tempfile.TemporaryDirectory(prefix="mstar-animate-") as folder:
        model = _model_file(result, Path(folder))
        results = Path(folder) / "results.csv"
        _write_csv(result, results)
        args = [str(model), str(results), option, str(out_path.resolve())]
        for name, value in (("--at", at), ("--size", size), ("--view", view), ("--fps", fps)):
            if value is not None:
                args += [name, str(value)]
        for override in result._overrides:
            args += ["--set", override]
        _run_animate(args)
    return out_path


def html_page(result: Any) -> str:
    """The text of ``mstar animate --html``'s page for ``result``."""
    with tempfile.TemporaryDirectory(prefix="mstar-page-") as folder:
        path = Path(folder) / "page.html"
        animate(result, path)
        return path.read_text()
