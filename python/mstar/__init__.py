"""mstar: time integration of constrained multibody systems, from Python.

Load a model file (``docs/model-format.md``) or build a planar model in code
(:mod:`mstar.planar`), run it with the GIL released, and get numpy arrays::

    import mstar
    model = mstar.load("models/four-bar.toml")
    result = model.run(t_end=2.0)
    result["crank.theta"]          # a coordinate's column (u:crank.theta)

The runs are those of ``mstar run`` bit for bit, and the errors carry the
messages it prints after ``error:``. The full API is in ``docs/python.md``.
"""

from __future__ import annotations

import os
import warnings
from typing import Any, Dict, List, Optional, Union

from ._native import IntegrationError, ModelError
from ._native import load_path as _load_path
from ._native import load_text as _load_text
from ._literal import toml_literal
from ._result import Result, Stats
from ._sweep import Sweep, sweep

__all__ = [
    "IntegrationError",
    "Model",
    "ModelError",
    "ModelWarning",
    "Result",
    "Stats",
    "Sweep",
    "load",
    "sweep",
]


class ModelWarning(UserWarning):
    """A value the model reader changed (``mstar run`` prints ``warning: ...``)."""


def _overrides(settings: Dict[str, Any]) -> List[str]:
    """``simulation.key=value`` for each setting that is not None."""
    return [
        f"simulation.{k}={toml_literal(v, 'a [simulation] setting')}"
        for k, v in settings.items()
        if v is not None
    ]


class Model:
    """A model to run: a model file's mechanism and ``[simulation]``, or a
    planar builder's (with the default settings).

    Made by :func:`load` or :meth:`mstar.planar.Builder.build`.
    """

    def __init__(self, native: Any) -> None:
        self._native = native

    @property
    def origin(self) -> str:
        """What names the model in messages: the path, ``<string>`` or ``<builder>``."""
        return self._native.origin

    @property
    def kind(self) -> str:
        """``"planar"`` or ``"spatial"``."""
        return self._native.kind

    @property
    def coords(self) -> List[str]:
        """The coordinates' names, in the order of the columns of ``Result.u``."""
        return self._native.coords

    @property
    def constraints(self) -> List[str]:
        """The constraint rows' names, in the order of ``Result.lam``'s columns."""
        return self._native.constraints

    @property
    def warnings(self) -> List[str]:
        """The reader's warnings (also issued as :class:`ModelWarning` by :func:`load`)."""
        return self._native.warnings

    def check(self, **settings: Any) -> Dict[str, Any]:
        """What ``mstar check`` reports, as a dict.

        Keys: ``coordinates``, ``constraints``, ``rank`` and
        ``degrees_of_freedom`` (None when the rank was not computed: the sparse elimination past its fill budget),
        ``redundant_constraints`` (joint names), ``minimum_norm``,
        ``position_violation`` and ``velocity_violation`` (``(owner, row,
        value)`` or None), ``projection`` (``{"position": (coordinate, by),
        "velocity": ...}`` or None when the start fails), ``start_error``,
        ``can_run``, ``error`` (the refusal of redundant constraints, as
        ``mstar check`` prints it, or None) and ``report`` (its text).
        ``settings`` override ``[simulation]`` keys.

        Raises:
            ModelError: a setting out of range, with ``mstar check``'s message.
        """
        return self._native.check(_overrides(settings))

    def run(
        self, t_end: Optional[float] = None, h: Optional[float] = None, **settings: Any
    ) -> Result:
        """Runs the model, every accepted step a sample, with the GIL released.

        ``t_end``, ``h`` and ``settings`` override the keys of ``[simulation]``
        (``rho=0.8``, ``integrator="hht"``, ``error_control="adaptive"``, ...),
        as ``mstar run --set simulation.key=value`` does; None keeps the file's.

        Raises:
            ModelError: a setting that is unknown or out of range.
            IntegrationError: the start or a step failed, or redundant
                constraints were refused; ``e.partial`` is the :class:`Result`
                of the samples before.
            KeyboardInterrupt: Ctrl-C; ``e.partial`` as above.
        """
        overrides = _overrides({"t_end": t_end, "h": h, **settings})
        try:
            raw = self._native.run(overrides)
        except (IntegrationError, KeyboardInterrupt) as e:
            partial = getattr(e, "partial", None)
            if isinstance(partial, dict):
                e.partial = Result(partial)  # type: ignore[union-attr]
            raise
        return Result(raw)

    def __repr__(self) -> str:
        return f"<mstar.Model {self.origin!r}: {self.kind}, {len(self.coords)} coordinates, {len(self.constraints)} constraints>"


def _is_path(source: Union[str, "os.PathLike[str]"]) -> bool:
    if not isinstance(source, str):
        return True
    if os.path.isfile(source):
        return True
    # A one-line name of a model file that is not there: read as a path, so
    # that the error says the file cannot be read (as `mstar run` does).
    one_line = "\n" not in source and "=" not in source
    return one_line and source.endswith((".toml", ".json"))


def load(source: Union[str, "os.PathLike[str]"]) -> Model:
    """Reads a model: a path (``str`` or ``os.PathLike``) when it names an
    existing file, or a one-line name ending in ``.toml`` / ``.json``; else
    the TOML text of a model (named ``<string>`` in messages).

    Raises:
        ModelError: the file cannot be read, or the model is not valid, with
            the message ``mstar run`` prints.
    """
    if _is_path(source):
        native = _load_path(os.fspath(source))
    else:
        native = _load_text(source)
    for w in native.warnings:
        warnings.warn(w, ModelWarning, stacklevel=2)
    return Model(native)
