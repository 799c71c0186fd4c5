"""Models: :func:`load` (a model file or TOML text) and :class:`Model`
(its runs and checks)."""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass
from typing import Any, Dict, List, Optional, Union

import numpy as np

from ._errors import MODES_RULES, RUN_RULES, EquilibriumError, IntegrationError, python_message, translated
from ._literal import integer, number, toml_literal
from ._native import load_path as _load_path
from ._native import load_text as _load_text
from ._equilibrium import Equilibrium
from ._linear import StateSpace
from ._modes import Modes
from ._result import Result

#: The ``[simulation]`` keys that take a real number and an integer.
_REAL_KEYS = frozenset({"t_end", "h", "h_min", "h_max", "rho", "alpha", "beta", "gamma", "tol", "rtol", "atol"})
_INTEGER_KEYS = frozenset({"max_iterations"})


class AccuracyWarning(UserWarning):
    """A run that reached its end with steps beyond the error tolerance, or
    an energy drift beyond it (``mstar run`` warns and exits 3): the message
    says where and what to rerun with."""


class ModelWarning(UserWarning):
    """A value the model reader changed (``mstar run`` prints ``warning: ...``)."""


def _setting(key: str, value: Any) -> str:
    """``value`` of the ``[simulation]`` key ``key`` as a TOML literal: a
    number for the numeric keys (numpy's included), else a bool, number or
    string.

    Raises:
        TypeError: naming the argument (``t_end: expected a number, got str 'abc'``).
    """
    if key in _REAL_KEYS:
        return repr(number(value, key))
    if key in _INTEGER_KEYS:
        return repr(integer(value, key))
    return toml_literal(value, key)


def _overrides(settings: Dict[str, Any], overrides: Optional[Dict[str, Any]] = None) -> List[str]:
    """``simulation.key=value`` for each setting that is not None, then
    ``key=value`` for each of ``overrides`` (any dotted key of the file)."""
    given = [f"simulation.{k}={_setting(k, v)}" for k, v in settings.items() if v is not None]
    for key, value in (overrides or {}).items():
        if not isinstance(key, str):
            raise TypeError(f"overrides: expected str keys, got {type(key).__name__} {key!r}")
        given.append(f"{key}={toml_literal(value, f'overrides[{key!r}]', lists=True)}")
    return given


@dataclass(frozen=True)
class Gradient:
    """What :meth:`Model.gradient` computes."""

    #: The objective Ψ of the run.
    value: float
    #: dΨ/dp by key, in the order given.
    gradient: Dict[str, float]
    #: The samples' times, s (the start and the end of every step).
    times: np.ndarray
    #: The run's steps.
    steps: int


def _keys(keys: Optional[List[str]], name: str) -> List[str]:
    """``keys`` as a list of str (None: none).

    Raises:
        TypeError: naming the argument, for a str or a non-str entry.
    """
    if keys is None:
        return []
    if isinstance(keys, str):
        raise TypeError(f"{name}: expected a list of keys, got the str {keys!r} (write [{keys!r}])")
    out = list(keys)
    for k in out:
        if not isinstance(k, str):
            raise TypeError(f"{name}: expected str keys, got {type(k).__name__} {k!r}")
    return out


class Model:
    """A model to run: a model file's mechanism and ``[simulation]``, or a
    planar builder's (with the default settings).

    Made by :func:`load` or :meth:`mstar.planar.Builder.build`.
    """

    def __init__(self, native: Any, source: Optional[str] = None, is_path: bool = False) -> None:
        self._native = native
        #: The model file's path (``is_path``) or TOML text; None for a builder's.
        self._source = source
        self._is_path = is_path

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

    def check(self, overrides: Optional[Dict[str, Any]] = None, **settings: Any) -> Dict[str, Any]:
        """What ``mstar check`` reports, as a dict.

        Keys: ``coordinates``, ``constraints``, ``rank`` and
        ``degrees_of_freedom`` (None when the rank was not computed: the sparse elimination past its fill budget),
        ``redundant_constraints`` (joint names), ``minimum_norm``,
        ``position_violation`` and ``velocity_violation`` (``(owner, row,
        value)`` or None), ``projection`` (``{"position": (coordinate, by),
        "velocity": ...}`` or None when the start fails), ``start_error``,
        ``can_run``, ``error`` (the refusal of redundant constraints, or of a
        KKT solver that does not fit the model at the setting that chose it,
        as ``mstar check`` prints it, or None) and ``report`` (its text).
        ``settings`` override ``[simulation]`` keys, ``overrides`` any key
        (as :meth:`run`).

        Raises:
            ModelError: a setting out of range, with ``mstar check``'s message.
            TypeError: a setting of the wrong type.
        """
        given = _overrides(settings, overrides)
        with translated(RUN_RULES):
            report = self._native.check(given)
        for key in ("error", "start_error"):
            if isinstance(report.get(key), str):
                report[key] = python_message(report[key], RUN_RULES)
        return report

    def run(
        self,
        t_end: Optional[float] = None,
        h: Optional[float] = None,
        overrides: Optional[Dict[str, Any]] = None,
        sensitivities: Optional[List[str]] = None,
        **settings: Any,
    ) -> Result:
        """Runs the model, every accepted step a sample, with the GIL released.

        ``t_end``, ``h`` and ``settings`` override the keys of ``[simulation]``
        (``rho=0.8``, ``integrator="hht"``, ``error_control="adaptive"``, ...),
        as ``mstar run --set simulation.key=value`` does; None keeps the file's.
        Numbers may be numpy's (``np.float64``, ``np.int64``, 0-d arrays ...).
        ``overrides`` sets any key of a model file by its dotted path, as
        ``--set`` does: ``{"body.bob.mass": 2.0, "output.every": 1}``.
        ``sensitivities`` lists numeric keys of the model file (``mstar run
        --sensitivity KEY``, a model read from a file): the result gains the
        columns ``d(<column>)/d(<key>)`` of the coordinates, velocities,
        accelerations and multipliers, the exact derivatives of the
        discrete solution (``docs/analysis.md``, "Parameter
        sensitivities"); fixed steps only.

        Raises:
            TypeError: a number setting that is not a number (``t_end:
                expected a number, got str 'abc'``), a value of another type.
            ModelError: a setting that is unknown or out of range.
            IntegrationError: the start or a step failed, or redundant
                constraints were refused; ``e.partial`` is the :class:`Result`
                of the samples before.
            KeyboardInterrupt: Ctrl-C; ``e.partial`` as above.

        Warns:
            ModelWarning: the start's notes about the state given, as ``mstar
                run`` prints them: an initial pose far from a joint, given
                positions or velocities that the start changed to satisfy
                the joints.
            AccuracyWarning: the run went beyond the error tolerance (``mstar
                run``'s warning, in ``result.stats.warning`` too).
        """
        given = _overrides({"t_end": t_end, "h": h, **settings}, overrides)
        keys = _keys(sensitivities, "sensitivities")
        try:
            with translated(RUN_RULES):
                raw = self._native.run(given, keys)
        except (IntegrationError, KeyboardInterrupt) as e:
            partial = getattr(e, "partial", None)
            if isinstance(partial, dict):
                _warn_start_notes(partial.pop("notes", []))
                e.partial = Result(partial)  # type: ignore[union-attr]
            raise
        _warn_start_notes(raw.pop("notes", []))
        stats = raw["stats"]
        if isinstance(stats.get("warning"), str):
            lines = [python_message(l.removeprefix("warning: "), RUN_RULES) for l in stats["warning"].splitlines()]
            stats["warning"] = "\n".join(lines)
            for line in lines:
                warnings.warn(line, AccuracyWarning, stacklevel=2)
        return Result(raw, model=self, overrides=given)

    def equilibrium(self, overrides: Optional[Dict[str, Any]] = None) -> Equilibrium:
        """The static equilibrium from the model's initial pose, velocities
        zero and drivers held at ``t = 0``, as ``mstar equilibrium`` finds it
        (damped Newton on the KKT system of statics; ``docs/analysis.md``),
        with the GIL released. ``overrides`` sets any key of the model file,
        as for :meth:`run`.

        Raises:
            EquilibriumError: none was found (``e.kind == "not_found"``;
                ``e.unbalanced`` lists ``(coordinate, force)`` with the
                largest unbalanced generalized forces), or the one found is
                neutral (``e.kind == "neutral"``; ``e.direction`` lists
                ``(coordinate, component)`` of the free direction and
                ``e.equilibrium`` is the :class:`Equilibrium` found).
            ModelError: an override that is unknown or out of range.
        """
        given = _overrides({}, overrides)
        try:
            with translated(RUN_RULES):
                raw = self._native.equilibrium(given)
        except EquilibriumError as e:
            found = getattr(e, "equilibrium", None)
            if isinstance(found, dict):
                e.equilibrium = Equilibrium(found, self, given)  # type: ignore[attr-defined]
            raise
        return Equilibrium(raw, self, given)

    def gradient(
        self,
        objective: str,
        params: List[str],
        measured: Any = None,
        t_end: Optional[float] = None,
        h: Optional[float] = None,
        overrides: Optional[Dict[str, Any]] = None,
        **settings: Any,
    ) -> Gradient:
        """The gradient of a scalar objective over a run with respect to
        numeric keys of the model file, by the discrete adjoint, as ``mstar
        run --objective … --gradient …`` computes it (``docs/analysis.md``,
        "Adjoint gradients"), with the GIL released: one backward pass for
        all of ``params``.

        ``objective``: ``"final:COLUMN"`` (the column's value at the end),
        ``"sum:COLUMN"`` (its sum over the samples) or ``"fit:COLUMN"`` (the
        sum of squared differences to ``measured``, one value per sample:
        the start and every step), ``COLUMN`` a ``u:``, ``v:``, ``a:`` or
        ``lambda:`` column. ``t_end``, ``h``, ``overrides`` and
        ``settings`` as for :meth:`run`; fixed steps only; a model read from
        a file.

        Raises:
            ValueError: a malformed objective, ``measured`` missing for a
                fit or given for another objective.
            ModelError: a column that is not a state column, a key that
                names no number of the file, adaptive steps, a model not
                read from a file.
            IntegrationError: the run or the backward pass failed.
        """
        given = _overrides({"t_end": t_end, "h": h, **settings}, overrides)
        keys = _keys(params, "params")
        values = None if measured is None else [float(x) for x in np.asarray(measured, dtype=float).ravel()]
        with translated(RUN_RULES):
            raw = self._native.gradient(given, objective, keys, values)
        return Gradient(value=float(raw["value"]), gradient=dict(raw["gradient"]),
                        times=np.asarray(raw["times"]), steps=int(raw["steps"]))

    def linearize(
        self,
        inputs: Optional[List[str]] = None,
        outputs: Optional[List[str]] = None,
        about: str = "equilibrium",
        overrides: Optional[Dict[str, Any]] = None,
    ) -> StateSpace:
        """The linear state-space model ``ẋ = A x + B p``, ``y = C x + D p``
        about the state ``about`` names (``"equilibrium"`` or ``"initial"``),
        in a minimal set of coordinates, as ``mstar linearize`` forms it
        (``docs/analysis.md``, "Linear state-space models"): ``inputs`` are
        keys of the model file holding a force or torque value
        (``"force.push.fx"``), ``outputs`` columns of ``mstar run``
        (``"u:*.theta"``, ``"sensor:tip.x"``). A model read from a file.

        Raises:
            EquilibriumError: ``about="equilibrium"`` and none was found.
            ModelError: a key or column that is wrong, a driver key as an
                input, a model too large or without a state-space form, a
                model not read from a file.
            ValueError: an unknown ``about``.
        """
        given = _overrides({}, overrides)
        with translated(RUN_RULES + MODES_RULES):
            text, notes = self._native.linearize(
                given, _keys(inputs, "inputs"), _keys(outputs, "outputs"), about
            )
        return StateSpace(text, notes)

    def modes(
        self,
        count: Optional[int] = None,
        about: str = "equilibrium",
        method: str = "auto",
        overrides: Optional[Dict[str, Any]] = None,
    ) -> Modes:
        """The lowest ``count`` vibration modes (None: 10, or the degrees of
        freedom when fewer), as ``mstar modes`` finds them, with the GIL
        released: the motion linearized about the state ``about`` names,
        ``"equilibrium"`` (the static equilibrium :meth:`equilibrium` finds;
        a neutral one is used as it is, its free direction a rigid mode) or
        ``"initial"`` (the model's initial pose at rest), on the constraints'
        tangent space. ``method``: ``"auto"`` (dense up to 600 coordinates,
        sparse above), ``"dense"`` (any damping) or ``"sparse"``
        (shift-invert Lanczos; undamped, symmetric stiffness).
        ``overrides`` as for :meth:`run`.

        Raises:
            EquilibriumError: ``about="equilibrium"`` and none was found.
            ModelError: more modes asked for than there are degrees of
                freedom; a mass matrix singular on the constraints' tangent
                space; the sparse method on a damped model or not
                converging; an override unknown or out of range.
            ValueError: an unknown ``about`` or ``method``.
            TypeError: ``count`` not an integer.
        """
        if count is not None:
            count = integer(count, "count")
            if count < 1:
                raise ValueError(f"count: expected 1 or more, got {count}")
        given = _overrides({}, overrides)
        with translated(RUN_RULES + MODES_RULES):
            raw = self._native.modes(given, count, about, method)
        return Modes(raw, self.coords, about)

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
    return one_line and source.endswith((".toml", ".json", ".urdf"))


def _warn_start_notes(notes: List[str]) -> None:
    """The start's notes about the state given, as ``mstar run`` prints them
    before its first step (``mstar check`` is ``Model.check()`` here), as
    :class:`ModelWarning`."""
    for note in notes:
        text = note.removeprefix("note: ").removeprefix("warning: ")
        text = text.replace("mstar check", "Model.check()")
        warnings.warn(python_message(text, RUN_RULES), ModelWarning, stacklevel=3)


def load(source: Union[str, "os.PathLike[str]"]) -> Model:
    """Reads a model: a path (``str`` or ``os.PathLike``) when it names an
    existing file, or a one-line name ending in ``.toml`` / ``.json``; else
    the TOML text of a model (named ``<string>`` in messages).

    Raises:
        ModelError: the file cannot be read, or the model is not valid, with
            the message ``mstar run`` prints.
    """
    if not isinstance(source, (str, os.PathLike)):
        raise TypeError(f"source: expected a path or TOML text, got {type(source).__name__}")
    is_path = _is_path(source)
    with translated(RUN_RULES):
        if is_path:
            native = _load_path(os.fspath(source))
        else:
            native = _load_text(source)
    for w in native.warnings:
        warnings.warn(w, ModelWarning, stacklevel=2)
    return Model(native, os.fspath(source), is_path)
