"""A model's linear state-space model: :class:`StateSpace` (``mstar
linearize``; ``docs/analysis.md``, "Linear state-space models")."""

from __future__ import annotations

import json
import os
from typing import Any, Dict, List, Union

import numpy as np


class StateSpace:
    """``ẋ = A x + B p + xdot0``, ``y = C x + D p + y0`` about a state at
    rest, in a minimal set of coordinates (:meth:`mstar.Model.linearize`;
    the fields of the JSON file ``mstar linearize --out`` writes, with the
    matrices as numpy arrays):

    - ``A``, ``B``, ``C``, ``D``: the matrices (``x = [q, q̇]`` the states,
      ``p`` the inputs' changes, ``y`` the outputs' changes);
    - ``states``, ``inputs``, ``outputs``, ``coordinates``: the names of the
      states, the input keys, the output columns and the model's
      coordinates;
    - ``N`` (n_coords × n_q): ``δu = N δq`` maps the independent
      coordinates back to all of them;
    - ``u0``, ``lambda0``, ``y0``, ``xdot0``, ``input_values``, ``t0``,
      ``about``: the operating point, the outputs there, the drift (zero at
      an equilibrium) and the inputs' values in the file.

    ``warnings`` lists what the linearization warned about (a neutral
    equilibrium, the file's warnings).
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    N: np.ndarray

    def __init__(self, text: str, warnings: List[str]) -> None:
        self._json = text
        self.fields: Dict[str, Any] = json.loads(text)
        self.warnings = list(warnings)
        for key, value in self.fields.items():
            if key in ("A", "B", "C", "D", "N"):
                cols = {"A": "states", "B": "inputs", "C": "states", "D": "inputs", "N": "states"}[key]
                width = len(self.fields[cols]) if key != "N" else len(self.fields["states"]) // 2
                value = np.array(value, dtype=float).reshape(len(value), width)
            elif key in ("u0", "lambda0", "y0", "xdot0", "input_values"):
                value = np.array(value, dtype=float)
            setattr(self, key, value)

    def to_json(self) -> str:
        """The JSON text ``mstar linearize --out`` writes, as is."""
        return self._json

    def write(self, path: Union[str, "os.PathLike[str]"]) -> None:
        """Writes :meth:`to_json` to ``path``."""
        with open(path, "w", encoding="utf-8") as f:
            f.write(self._json)

    def __repr__(self) -> str:
        return (f"<mstar.StateSpace about the {self.fields.get('about')}: {len(self.fields['states'])} states, "
                f"{len(self.fields['inputs'])} inputs, {len(self.fields['outputs'])} outputs>")
