"""The samples of a run: :class:`Result` and its :class:`Stats`."""

from __future__ import annotations

import html
from dataclasses import dataclass
from typing import Any, Dict, List, Optional

import numpy as np


@dataclass(frozen=True)
class Stats:
    """A run's figures, as ``mstar run``'s summary gives them.

    For a partial result (a failed or interrupted run) only ``steps`` and
    ``wall_time`` are known; the others are None.
    """

    #: Accepted steps.
    steps: int
    #: Stepping time, s (from the initial state on, as ``mstar run``'s
    #: ``wall time``).
    wall_time: float
    #: Rejected step attempts.
    rejected: Optional[int] = None
    #: Newton iterations over all attempts.
    newton_iterations: Optional[int] = None
    #: The most Newton iterations of an accepted step.
    max_newton_iterations: Optional[int] = None
    #: Numeric factorizations of the KKT matrix.
    factorizations: Optional[int] = None
    #: Smallest and largest step size used, s.
    h_min_used: Optional[float] = None
    h_max_used: Optional[float] = None
    #: Time reached, s.
    t: Optional[float] = None
    #: The largest local error estimate as a ratio to the tolerance.
    max_error_ratio: Optional[float] = None
    #: ``mstar run``'s warning when the run went beyond the error tolerance
    #: (it exits 3 then; in Python's words, one line per finding), else None.
    warning: Optional[str] = None


class Result:
    """The samples of a run: the initial state and every accepted step.

    Arrays (numpy, one row per sample):

    - ``t`` (n_steps,), s;
    - ``u``, ``v``, ``a`` (n_steps × n_coords): coordinates, velocities,
      accelerations, columns in the order of ``coords``;
    - ``lam`` (n_steps × n_constraints): the multipliers λ, columns in the
      order of ``constraints``;
    - ``energy``, ``iterations``, ``residual``, ``constraint`` (n_steps,):
      the CSV's columns of the same names;
    - ``extra`` (n_steps × len(extra_names)): the columns ``mstar run
      --out`` writes after those, named in ``extra_names`` as in its CSV
      (``reaction:<joint>.fx`` …, ``effort:<driver>``).

    ``result[name]`` is one column by name (see :meth:`__getitem__`);
    :meth:`reaction` and :meth:`effort` group the loads by joint and driver.
    """

    t: np.ndarray
    u: np.ndarray
    v: np.ndarray
    a: np.ndarray
    lam: np.ndarray
    energy: np.ndarray
    iterations: np.ndarray
    residual: np.ndarray
    constraint: np.ndarray
    extra: np.ndarray
    extra_names: List[str]
    coords: List[str]
    constraints: List[str]
    stats: Stats

    def __init__(self, raw: Dict[str, Any], model: Any = None, overrides: Optional[List[str]] = None) -> None:
        #: The model that ran (None for a result read from a sweep's file)
        #: and its overrides, for :func:`mstar.animate` and Jupyter.
        self._model = model
        self._overrides = list(overrides or [])
        for key in ("t", "u", "v", "a", "lam", "energy", "iterations", "residual", "constraint"):
            setattr(self, key, raw[key])
        self.coords = list(raw["coords"])
        self.constraints = list(raw["constraints"])
        self.extra_names = list(raw.get("extra_names", []))
        # The standard columns' names as the library writes them (None: the
        # scheme above, built here).
        self._header = list(raw["header"]) if raw.get("header") is not None else None
        self.extra = raw.get("extra", np.empty((len(self.t), 0)))
        stats = dict(raw["stats"])
        stats.setdefault("steps", max(len(self.t) - 1, 0))
        self.stats = Stats(**stats)
        self._coord = {name: i for i, name in enumerate(self.coords)}
        self._row = {name: i for i, name in enumerate(self.constraints)}
        self._extra = {name: i for i, name in enumerate(self.extra_names)}

    def __len__(self) -> int:
        """The number of samples."""
        return len(self.t)

    def columns(self) -> List[str]:
        """The names of the columns ``mstar run --out`` writes, in its
        order: ``t``, ``u:<coord>``, ``v:<coord>``, ``a:<coord>``,
        ``lambda:<row>``, ``energy``, ``iterations``, ``residual``,
        ``constraint`` (as the library names them, ``mstar::csv::header``),
        then :attr:`extra_names`."""
        if self._header is not None:
            return self._header + self.extra_names
        names = ["t"]
        for prefix in ("u", "v", "a"):
            names += [f"{prefix}:{c}" for c in self.coords]
        rows = [f"lambda:{c}" for c in self.constraints]
        if len(set(rows)) < len(rows):  # (the library's rule for repeated row names)
            rows = [f"lambda:{i}" for i in range(len(self.constraints))]
        names += rows
        return names + ["energy", "iterations", "residual", "constraint"] + self.extra_names

    def _group(self, prefix: str, what: str) -> Dict[str, np.ndarray]:
        """The extra columns ``<prefix><component>``, by component."""
        found = {
            name[len(prefix):]: self.extra[:, i]
            for i, name in enumerate(self.extra_names)
            if name.startswith(prefix) and "." not in name[len(prefix):]
        }
        if not found:
            raise KeyError(f"no {what}")
        return found

    def reaction(self, joint: str) -> Dict[str, np.ndarray]:
        """The load joint (or driver) ``joint`` puts on its body, the
        columns ``reaction:<joint>.<c>`` by component ``c``: ``fx``, ``fy``,
        ``tau`` (planar; N, N m) or ``fx``, ``fy``, ``fz``, ``tx``, ``ty``,
        ``tz`` (spatial), each an array over the samples.

        Raises:
            KeyError: no joint of that name.
        """
        joints = sorted({n[len("reaction:"):].rsplit(".", 1)[0] for n in self.extra_names
                         if n.startswith("reaction:")})
        try:
            return self._group(f"reaction:{joint}.", f"joint '{joint}'")
        except KeyError:
            raise KeyError(f"no joint '{joint}': give one of {', '.join(joints) or '(none)'}") from None

    def effort(self, driver: str) -> np.ndarray:
        """The force (N) or torque (N m) driver ``driver`` applies along the
        coordinate it drives (the column ``effort:<driver>``).

        Raises:
            KeyError: no driver of that name.
        """
        name = f"effort:{driver}"
        if name not in self._extra:
            drivers = [n[len("effort:"):] for n in self.extra_names if n.startswith("effort:")]
            raise KeyError(f"no driver '{driver}': give one of {', '.join(drivers) or '(none)'}")
        return self.extra[:, self._extra[name]]

    def __getitem__(self, name: str) -> np.ndarray:
        """One column by name (a view into the arrays):

        - ``"t"``, ``"energy"``, ``"iterations"``, ``"residual"``,
          ``"constraint"``;
        - a coordinate's name (``"crank.theta"``): its positions, as
          ``"u:crank.theta"``; ``"v:..."`` and ``"a:..."`` its velocities and
          accelerations;
        - ``"lambda:<i>"`` (the CSV's, 0-based) or ``"lambda:<row name>"``
          (a name in ``constraints``): a multiplier;
        - a name in :attr:`extra_names` (``"reaction:O2.fx"``,
          ``"effort:motor"``, ...).

        Raises:
            KeyError: no column has that name.
        """
        if name in ("t", "energy", "iterations", "residual", "constraint"):
            return getattr(self, name)
        if name in self._extra:
            return self.extra[:, self._extra[name]]
        prefix, _, rest = name.partition(":")
        if name in self._coord:
            return self.u[:, self._coord[name]]
        if prefix in ("u", "v", "a") and rest in self._coord:
            return getattr(self, prefix)[:, self._coord[rest]]
        if prefix == "lambda":
            if rest in self._row:
                return self.lam[:, self._row[rest]]
            if rest.isdigit() and int(rest) < len(self.constraints):
                return self.lam[:, int(rest)]
        raise KeyError(
            f"no column '{name}': give t, energy, iterations, residual, constraint, "
            "a coordinate (e.g. "
            f"{self.coords[0] if self.coords else 'body.x'}), u:/v:/a:<coordinate>, "
            "lambda:<i> / lambda:<constraint row>, or reaction:<joint>.<component> / "
            "effort:<driver>"
        )

    def to_pandas(self) -> Any:
        """The samples as a ``pandas.DataFrame`` with the CSV's columns
        (:meth:`columns`).

        Raises:
            ImportError: pandas is not installed.
        """
        try:
            import pandas as pd
        except ImportError as e:
            raise ImportError(
                "Result.to_pandas() needs pandas, which is not installed: pip install pandas"
            ) from e
        data = np.column_stack(
            [self.t, self.u, self.v, self.a, self.lam, self.energy, self.iterations,
             self.residual, self.constraint, self.extra]
        ) if len(self.t) else np.empty((0, len(self.columns())))
        frame = pd.DataFrame(data, columns=self.columns())
        return frame.astype({"iterations": "int64"})

    def _repr_html_(self) -> Optional[str]:
        """The animation page of ``mstar animate --html`` (play/pause, time
        slider) in an iframe, for Jupyter; None (plain repr) when the result
        has no model file to draw (:func:`mstar.animate`)."""
        from ._animate import html_page

        try:
            page = html_page(self)
        except Exception:  # noqa: BLE001 - a repr never raises: the plain one instead
            return None
        escaped = html.escape(page, quote=True)
        return f'<iframe srcdoc="{escaped}" style="width: 100%; height: 560px; border: 0"></iframe>'

    def __repr__(self) -> str:
        end = f"t = {self.t[-1]} s" if len(self.t) else "no sample"
        return f"<mstar.Result: {len(self)} samples to {end}, {len(self.coords)} coordinates, {len(self.constraints)} constraints>"
