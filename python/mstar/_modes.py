"""A model's vibration modes: :class:`Modes` (``mstar modes``;
``docs/analysis.md``, "Vibration modes")."""

from __future__ import annotations

from typing import Any, Dict, List

import numpy as np


class Modes:
    """The lowest vibration modes of a model about a state at rest
    (:meth:`mstar.Model.modes`), lowest ``|s|`` first, as ``mstar modes``
    finds them.

    Arrays, one entry (row) per mode:

    - ``s`` (K,) complex: the eigenvalues, 1/s (``δu = φ e^{st}``; a complex
      pair is given once, ``Im s > 0``);
    - ``frequency_hz`` (K,): the undamped natural frequency ``|s|/2π``
      (0 for a rigid mode);
    - ``damping_ratio`` (K,): ``ζ = −Re(s)/|s|``;
    - ``shapes`` (K × n_coords) complex: the shapes in the model's
      coordinates, unit modal mass (``φᴴ M φ = 1``), each turned so that its
      largest component is real and positive (real for undamped modes);
    - ``kind``: ``"oscillating"``, ``"rigid"``, ``"overdamped"`` or
      ``"unstable"`` per mode.

    ``u`` and ``lam`` are the state the modes are about, ``coords`` its
    coordinates' names, ``dof`` the degrees of freedom, ``damped`` whether
    the first-order (damped or unsymmetric) form was solved, ``method``
    ``"dense"`` or ``"sparse"``, ``neutral`` whether the equilibrium found
    is neutral (its free direction a rigid mode).
    """

    s: np.ndarray
    frequency_hz: np.ndarray
    damping_ratio: np.ndarray
    shapes: np.ndarray
    kind: List[str]
    u: np.ndarray
    lam: np.ndarray
    coords: List[str]
    dof: int
    damped: bool
    method: str
    neutral: bool
    about: str

    def __init__(self, raw: Dict[str, Any], coords: List[str], about: str) -> None:
        self.s = raw["s_re"] + 1j * raw["s_im"]
        self.frequency_hz = raw["frequency_hz"]
        self.damping_ratio = raw["damping_ratio"]
        self.shapes = raw["shape"] + 1j * raw["shape_imag"]
        self.kind = list(raw["kind"])
        self.u = raw["u"]
        self.lam = raw["lam"]
        self.coords = list(coords)
        self.dof = int(raw["dof"])
        self.damped = bool(raw["damped"])
        self.method = str(raw["method"])
        self.neutral = bool(raw["neutral"])
        self.about = about

    def __len__(self) -> int:
        """The number of modes."""
        return len(self.s)

    def shape(self, k: int) -> Dict[str, complex]:
        """Mode ``k``'s shape (1 the lowest, as ``mstar modes`` numbers
        them) by coordinate name.

        Raises:
            IndexError: no mode ``k``.
        """
        if not 1 <= k <= len(self):
            raise IndexError(f"mode {k}: there are modes 1 to {len(self)}")
        return dict(zip(self.coords, self.shapes[k - 1]))

    def __repr__(self) -> str:
        lines = [f"<mstar.Modes: {len(self)} of {self.dof} degrees of freedom about the {self.about}"]
        for k, (f, z, kind) in enumerate(zip(self.frequency_hz, self.damping_ratio, self.kind), start=1):
            lines.append(f"  mode {k}: f = {f:.6g} Hz, ζ = {z:.3g} ({kind})")
        return "\n".join(lines) + ">"
