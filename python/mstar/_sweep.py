"""``mstar.sweep``: a model file run for many values of its keys, the runs
on all cores with the GIL released (``mstar sweep``; ``docs/sweeps.md``)."""

from __future__ import annotations

import csv
import os
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

from ._literal import toml_literal
from ._native import sweep as _sweep


class Sweep:
    """What :func:`sweep` did: the summary table and where the runs are.

    Attributes:
        dir: the output directory (``runs/<index>.csv`` per run).
        summary_path: the summary CSV file of the shard that ran.
        runs: the plan's number of runs (all shards).
        ran: runs run by this call; ``skipped``: complete from an earlier one.
        failed: ``(index, message)`` of each failed run of the shard.
        beyond: ``(index, warning)`` of each run of the shard that reached its
            end with steps beyond the error tolerance (status
            ``beyond tolerance: …``; ``mstar run`` exits 3 for it).
    """

    def __init__(self, out: Path, raw: Dict[str, Any]) -> None:
        self.dir = out
        self.summary_path = Path(raw["summary"])
        self.runs: int = raw["runs"]
        self.ran: int = raw["ran"]
        self.skipped: int = raw["skipped"]
        self.failed: List[Tuple[int, str]] = list(raw["failed"])
        self.beyond: List[Tuple[int, str]] = list(raw.get("beyond", []))

    @property
    def summary(self) -> List[Dict[str, str]]:
        """The summary's rows (``docs/sweeps.md``, "Output"), one dict per
        run in index order, the values as written (strings)."""
        with open(self.summary_path, newline="") as f:
            return list(csv.DictReader(f))

    def run_csv(self, index: int) -> Path:
        """The CSV file of run ``index`` (``.partial.csv`` for a failed run)."""
        done = self.dir / "runs" / f"{index}.csv"
        return done if done.exists() else self.dir / "runs" / f"{index}.partial.csv"

    def to_pandas(self) -> Any:
        """The summary as a pandas DataFrame (needs pandas)."""
        try:
            import pandas
        except ImportError as e:  # pragma: no cover - depends on the environment
            raise ImportError("Sweep.to_pandas needs pandas: pip install pandas") from e
        return pandas.read_csv(self.summary_path)

    def __repr__(self) -> str:
        return f"<mstar.Sweep {str(self.dir)!r}: {self.runs} runs, {len(self.failed)} failed>"


def sweep(
    model: Union[str, "os.PathLike[str]"],
    params: Dict[str, Sequence[Any]],
    out: Union[str, "os.PathLike[str]"],
    *,
    zip: bool = False,
    jobs: Optional[int] = None,
    shard: Optional[Tuple[int, int]] = None,
) -> Sweep:
    """Runs the model file ``model`` for the values ``params`` (dotted keys,
    array elements by name: ``{"body.upper.mass": [1, 2], "simulation.h":
    [1e-3, 5e-4]}``), every combination (or, with ``zip=True``, the i-th
    values together), into the directory ``out``, exactly as ``mstar sweep
    MODEL --set KEY=V1,V2 ... --out OUT`` does: ``jobs`` runs at once (default
    one per core), only the runs of ``shard = (i, n)`` when given, runs
    complete from an earlier call skipped. A failed run does not stop the
    others: it is in :attr:`Sweep.failed` and the summary.

    Raises:
        ModelError: the model file does not read, a key leads nowhere, zipped
            lists differ in length, a bad shard — with ``mstar sweep``'s message.
        OSError: a file cannot be written.
    """
    items = [
        (key, [toml_literal(v, "a swept value", lists=True) for v in values])
        for key, values in params.items()
    ]
    out_path = Path(os.fspath(out))
    raw = _sweep(os.fspath(model), items, os.fspath(out_path), zip, jobs, shard)
    return Sweep(out_path, raw)
