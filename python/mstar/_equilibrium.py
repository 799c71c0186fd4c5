"""A model's static equilibrium: :class:`Equilibrium` (``mstar
equilibrium``; ``docs/analysis.md``)."""

from __future__ import annotations

import os
from typing import Any, Dict, List, Optional, Union

import numpy as np

from ._errors import RUN_RULES, translated
from ._result import Result


class Equilibrium:
    """The pose at which a model at rest stays at rest, with drivers held at
    ``t = 0`` (:meth:`mstar.Model.equilibrium`; the method is that of ``mstar
    equilibrium``, ``docs/analysis.md``).

    - ``u`` (n_coords,): the coordinates, in the order of ``coords``;
    - ``lam`` (n_constraints,): the multipliers λ, in the order of
      ``constraints``;
    - ``iterations`` (Newton steps accepted), ``damped`` (of those, damped
      ones), ``residual`` (‖r‖∞ of the force balance, N or N m) and
      ``constraint`` (‖Φ‖∞);
    - ``redundant``: the constraint rows left out of the solve because they
      repeat what the others impose (their multipliers are the
      minimum-norm ones), by name; empty without redundant constraints;
    - ``stable``: ``True`` when no mode about it grows, ``False`` for an
      unstable equilibrium (a maximum or saddle of the potential that the
      search could not leave for a stable one), ``None`` when not checked
      (above 600 coordinates);
    - ``result``: the same state as a one-sample :class:`mstar.Result` with
      every column ``mstar equilibrium --out`` writes (velocities and
      accelerations zero, ``energy`` the potential energy).

    ``eq[name]`` is one of those columns' value (a ``float``):
    ``eq["crank.theta"]``, ``eq["reaction:O2.fy"]``, ``eq["sensor:tip.x"]``.
    """

    u: np.ndarray
    lam: np.ndarray
    coords: List[str]
    constraints: List[str]
    iterations: int
    damped: int
    residual: float
    constraint: float
    redundant: List[str]
    stable: Optional[bool]
    result: Result

    def __init__(self, raw: Dict[str, Any], model: Any, overrides: List[str]) -> None:
        found = raw["equilibrium"]
        self.result = Result(raw, model=model, overrides=overrides)
        self._model = model
        self._overrides = list(overrides)
        self.u = self.result.u[0]
        self.lam = self.result.lam[0]
        self.coords = self.result.coords
        self.constraints = self.result.constraints
        self.iterations = int(found["iterations"])
        self.damped = int(found["damped"])
        self.residual = float(found["residual"])
        self.constraint = float(found["constraint"])
        self.redundant = list(found["redundant"])
        self.stable = found["stable"]

    def __getitem__(self, name: str) -> float:
        """One column's value by name (the names of
        :meth:`mstar.Result.__getitem__`).

        Raises:
            KeyError: no column has that name.
        """
        return float(self.result[name][0])

    def columns(self) -> List[str]:
        """The names of the columns ``mstar equilibrium --out`` writes."""
        return self.result.columns()

    def reaction(self, joint: str) -> Dict[str, float]:
        """The load joint (or driver) ``joint`` puts on its body at rest, by
        component (as :meth:`mstar.Result.reaction`).

        Raises:
            KeyError: no joint of that name.
        """
        return {c: float(x[0]) for c, x in self.result.reaction(joint).items()}

    def effort(self, driver: str) -> float:
        """The force or torque driver ``driver`` applies to hold the pose.

        Raises:
            KeyError: no driver of that name.
        """
        return float(self.result.effort(driver)[0])

    def write_model(self, path: Union[str, "os.PathLike[str]"], overwrite: bool = False) -> None:
        """Writes the model file with this equilibrium as its initial pose,
        everything else kept (``mstar equilibrium --write-model``): each
        body's ``pose`` (planar) or ``position`` and ``orientation``
        (spatial), each point mass's ``position``. The text is read back
        first and must be the same mechanism.

        Raises:
            ModelError: the model is not a TOML file or text (a builder's, a
                JSON or URDF file), or an element is defined from the initial
                pose (a joint's ``at``, a default length or rest angle), so
                moving the pose would change the mechanism.
            ValueError: the equilibrium was found with ``overrides``, which
                the written file would not have; or ``path`` is the model file.
            FileExistsError: ``path`` exists and ``overwrite`` is False.
        """
        if self._overrides:
            raise ValueError(
                "write_model: this equilibrium was found with overrides, which the written "
                "file would not have; put them in the model file and call equilibrium() again"
            )
        source = getattr(self._model, "_source", None)
        target = os.fspath(path)
        if getattr(self._model, "_is_path", False) and source is not None and os.path.exists(target) \
                and os.path.samefile(source, target):
            raise ValueError(f"write_model: {target} is the model file itself; give another path")
        if os.path.exists(target) and not overwrite:
            raise FileExistsError(f"write_model: {target} exists; give overwrite=True to replace it")
        with translated(RUN_RULES):
            text = self._model._native.text_with_pose([float(x) for x in self.u])
        with open(target, "w", encoding="utf-8") as f:
            f.write(text)

    def __repr__(self) -> str:
        shown = ", ".join(f"{c} = {x:.6g}" for c, x in zip(self.coords[:4], self.u[:4]))
        more = ", …" if len(self.coords) > 4 else ""
        return f"<mstar.Equilibrium: {shown}{more} ({self.iterations} Newton steps, ‖r‖∞ = {self.residual:.2e})>"
