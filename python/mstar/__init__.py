"""mstar: time integration of constrained multibody systems, from Python.

Load a model file (``docs/model-format.md``) or build a model in code
(:mod:`mstar.planar`, :mod:`mstar.spatial`), run it with the GIL released,
and get numpy arrays::

    import mstar
    model = mstar.load("models/four-bar.toml")
    result = model.run(t_end=2.0)
    result["crank.theta"]          # a coordinate's column (u:crank.theta)
    result.reaction("O2")["fx"]    # a joint's load (reaction:O2.fx)
    rest = model.equilibrium()      # the static equilibrium (mstar equilibrium)
    model.modes(count=4)            # vibration modes about it (mstar modes)

The runs are those of ``mstar run`` bit for bit, and the errors carry the
messages it prints after ``error:``, with its options named as Python
arguments. The full API is in ``docs/python.md``.
"""

from ._animate import animate as animate
from ._equilibrium import Equilibrium as Equilibrium
from ._errors import EquilibriumError as EquilibriumError
from ._errors import Error as Error
from ._errors import IntegrationError as IntegrationError
from ._errors import ModelError as ModelError
from ._model import AccuracyWarning as AccuracyWarning
from ._model import Gradient as Gradient
from ._model import Model as Model
from ._model import ModelWarning as ModelWarning
from ._modes import Modes as Modes
from ._model import load as load
from ._native import __version__ as __version__
from ._linear import StateSpace as StateSpace
from ._result import Result as Result
from ._result import Stats as Stats
from ._sweep import Sweep as Sweep
from ._sweep import sweep as sweep

__all__ = [
    "AccuracyWarning",
    "Equilibrium",
    "EquilibriumError",
    "Error",
    "Gradient",
    "IntegrationError",
    "Model",
    "ModelError",
    "ModelWarning",
    "Modes",
    "Result",
    "StateSpace",
    "Stats",
    "Sweep",
    "__version__",
    "animate",
    "load",
    "sweep",
]

# Python's own exceptions and classes report the package, not the private
# module that defines them.
for _name in ("AccuracyWarning", "Equilibrium", "Gradient", "Model", "ModelWarning", "Modes", "Result", "StateSpace", "Stats", "Sweep", "animate", "load", "sweep"):
    globals()[_name].__module__ = __name__
del _name
