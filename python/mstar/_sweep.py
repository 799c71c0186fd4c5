"""``mstar.sweep``: a model file run for many values of its keys, the runs
on all cores with the GIL released (``mstar sweep``; ``docs/sweeps.md``)."""

from __future__ import annotations

import csv
import os
import re
import shutil
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

from ._errors import RUN_RULES, SWEEP_RULES, python_message, translated
from ._literal import integer, toml_literal
from ._native import load_path as _load_path
from ._native import sweep as _sweep
from ._result import Result

#: The summary's columns that hold integers, and its text column.
_INTEGER_COLUMNS = ("index", "steps")
_TEXT_COLUMNS = ("status",)
_INTEGER = re.compile(r"[+-]?\d+")


def _typed(text: str, column: str) -> Any:
    """A summary field as Python sees it: None for an empty field, int for
    the integer columns and integer literals, bool, float, else the text
    (a quoted TOML string without its quotes)."""
    if column in _TEXT_COLUMNS:
        return text
    if text == "":
        return None
    if column in _INTEGER_COLUMNS or _INTEGER.fullmatch(text):
        return int(text)
    if text in ("true", "false"):
        return text == "true"
    try:
        return float(text)
    except ValueError:
        pass
    if len(text) >= 2 and text[0] == text[-1] == '"':
        return text[1:-1]
    return text


def _read_csv(path: Path) -> Tuple[List[str], np.ndarray]:
    """A run's CSV file: its header and its values (rows × columns)."""
    with open(path, newline="") as f:
        header = next(csv.reader(f))
    data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    return header, data.reshape(-1, len(header))


class Sweep:
    """What :func:`sweep` did: the summary table and where the runs are.

    Attributes:
        dir: the output directory (``runs/<index>.csv`` per run).
        model: the model file swept.
        summary_path: the summary CSV file of the shard that ran.
        runs: the plan's number of runs (all shards).
        ran: runs run by this call; ``skipped``: complete from an earlier one.
        failed: ``(index, message)`` of each failed run of the shard.
        beyond: ``(index, warning)`` of each run of the shard that reached its
            end with steps beyond the error tolerance (status
            ``beyond tolerance: …``; ``mstar run`` exits 3 for it).
            These messages name settings as Python arguments (``h=...``);
            the summary's ``status`` keeps the command line's text.
    """

    def __init__(self, out: Path, model: Path, raw: Dict[str, Any]) -> None:
        self.dir = out
        self.model = model
        self.summary_path = Path(raw["summary"])
        self.runs: int = raw["runs"]
        self.ran: int = raw["ran"]
        self.skipped: int = raw["skipped"]
        # The summary's status keeps the command line's words; these speak Python.
        self.failed: List[Tuple[int, str]] = [(i, python_message(m, RUN_RULES)) for i, m in raw["failed"]]
        self.beyond: List[Tuple[int, str]] = [(i, python_message(m, RUN_RULES)) for i, m in raw.get("beyond", [])]

    @property
    def summary(self) -> List[Dict[str, Any]]:
        """The summary's rows (``docs/sweeps.md``, "Output"), one dict per
        run in index order, by column name: ``index`` and ``steps`` ints,
        ``status`` a string, the swept values and figures numbers (int for
        an integer literal, else float), bools or strings as written; an
        empty field (a failed run's figures) is None."""
        with open(self.summary_path, newline="") as f:
            return [{k: _typed(v, k) for k, v in row.items()} for row in csv.DictReader(f)]

    def _index(self, index: Any) -> int:
        i = integer(index, "index")
        if not 0 <= i < self.runs:
            raise IndexError(f"index: run {i} is not in this sweep (runs 0 to {self.runs - 1})")
        return i

    def run_csv(self, index: int) -> Optional[Path]:
        """The CSV file of run ``index``: ``runs/<index>.csv`` when it
        reached its end, ``runs/<index>.partial.csv`` (the samples before the
        failure) when it failed, None when it has not run (another shard's,
        or interrupted) — never a path that does not exist.

        Raises:
            IndexError: ``index`` is not a run of the plan.
        """
        i = self._index(index)
        for name in (f"{i}.csv", f"{i}.partial.csv"):
            path = self.dir / "runs" / name
            if path.exists():
                return path
        return None

    def result(self, index: int) -> Result:
        """Run ``index``'s samples as a :class:`Result` (read from its CSV
        file: the rows the model's ``[output]`` keeps; ``stats`` has the
        summary's ``steps`` and ``wall_time``, the others None; a failed
        run's samples before the failure; the constraint rows named as the
        model file names them).

        Raises:
            IndexError: ``index`` is not a run of the plan.
            FileNotFoundError: the run has not run here.
        """
        i = self._index(index)
        path = self.run_csv(i)
        if path is None:
            raise FileNotFoundError(f"run {i} has no CSV file in {self.dir / 'runs'}: it has not run here")
        header, data = _read_csv(path)
        row = next((r for r in self.summary if r.get("index") == i), {})
        raw = _raw(header, data, row)
        # The CSV numbers the multipliers; the model file names their rows.
        names = _load_path(os.fspath(self.model)).constraints
        if len(names) == len(raw["constraints"]):
            raw["constraints"] = names
        return Result(raw)

    def to_pandas(self) -> Any:
        """The summary as a pandas DataFrame (needs pandas)."""
        try:
            import pandas
        except ImportError as e:  # pragma: no cover - depends on the environment
            raise ImportError("Sweep.to_pandas needs pandas: pip install pandas") from e
        return pandas.read_csv(self.summary_path)

    def __repr__(self) -> str:
        return f"<mstar.Sweep {str(self.dir)!r}: {self.runs} runs, {len(self.failed)} failed>"


def _raw(header: List[str], data: np.ndarray, row: Dict[str, Any]) -> Dict[str, Any]:
    """A run's CSV columns as the dict :class:`Result` takes."""
    col = {name: j for j, name in enumerate(header)}
    coords = [n[2:] for n in header if n.startswith("u:")]
    lam = [n for n in header if n.startswith("lambda:")]
    end = col["constraint"] + 1
    raw: Dict[str, Any] = {
        name: data[:, col[name]].copy() for name in ("t", "energy", "residual", "constraint")
    }
    raw["iterations"] = data[:, col["iterations"]].astype(np.int64)
    for prefix in ("u", "v", "a"):
        raw[prefix] = data[:, [col[f"{prefix}:{c}"] for c in coords]]
    raw["lam"] = data[:, [col[n] for n in lam]]
    raw["coords"] = coords
    raw["constraints"] = [n[len("lambda:"):] for n in lam]
    raw["header"] = header[:end]
    raw["extra_names"] = header[end:]
    raw["extra"] = data[:, end:]
    steps = row.get("steps")
    raw["stats"] = {
        "steps": steps if isinstance(steps, int) else max(len(data) - 1, 0),
        "wall_time": row.get("wall_time_s") or 0.0,
    }
    return raw


def _sweep_files_removed(out: Path) -> None:
    """Removes a sweep's own files from ``out`` (``sweep.toml``, the
    summaries, ``runs/``), nothing else."""
    if not (out / "sweep.toml").exists():
        return
    shutil.rmtree(out / "runs", ignore_errors=True)
    for path in [out / "sweep.toml", *out.glob("summary*.csv")]:
        path.unlink()


def sweep(
    model: Union[str, "os.PathLike[str]"],
    params: Dict[str, Sequence[Any]],
    out: Union[str, "os.PathLike[str]"],
    *,
    zip: bool = False,
    jobs: Optional[int] = None,
    shard: Optional[Tuple[int, int]] = None,
    overwrite: bool = False,
) -> Sweep:
    """Runs the model file ``model`` for the values ``params`` (dotted keys,
    array elements by name: ``{"body.upper.mass": [1, 2], "simulation.h":
    [1e-3, 5e-4]}``; values numbers (numpy's too), bools, strings, lists of
    them, or a 1-d numpy array of values), every combination (or, with
    ``zip=True``, the i-th values together), into the directory ``out``,
    exactly as ``mstar sweep MODEL --set KEY=V1,V2 ... --out OUT`` does:
    ``jobs`` runs at once (default one per core), only the runs of ``shard =
    (i, n)`` when given, runs complete from an earlier call of the same plan
    skipped. ``out`` holding another plan is an error unless
    ``overwrite=True``, which first removes its sweep's files (``sweep.toml``,
    the summaries, ``runs/``) and runs the new plan afresh. A failed run does
    not stop the others: it is in :attr:`Sweep.failed` and the summary.

    Raises:
        TypeError: a value that is not a number, bool or string (checked
            before anything is written).
        ModelError: the model file does not read, a key leads nowhere, zipped
            lists differ in length, a bad shard, ``out`` holds another plan —
            with ``mstar sweep``'s message, its options named as arguments.
        OSError: a file cannot be written.
    """
    items = []
    for key, values in params.items():
        # (A dict or a set iterates as its keys, in no order the caller
        # wrote: neither is a list of values.)
        if isinstance(values, (str, bytes, dict, set, frozenset)) or not hasattr(values, "__iter__"):
            raise TypeError(f"params[{key!r}]: expected a list of values, got {type(values).__name__} {values!r}")
        items.append((key, [toml_literal(v, f"params[{key!r}]", lists=True) for v in values]))
    jobs = None if jobs is None else integer(jobs, "jobs")
    if shard is not None:
        shard = (integer(shard[0], "shard[0]"), integer(shard[1], "shard[1]"))
    out_path = Path(os.fspath(out))
    if overwrite:
        _sweep_files_removed(out_path)
    with translated(SWEEP_RULES):
        raw = _sweep(os.fspath(model), items, os.fspath(out_path), zip, jobs, shard)
    return Sweep(out_path, Path(os.fspath(model)), raw)
