"""mstar's exceptions, and their messages put in Python's words.

The library's messages are the command line's, and some name its options
(``--set``, ``--h``, ``--out`` ...). :data:`RULES` maps each such phrase to
the Python argument that does the same (``h=``, ``overrides=``, ``out=`` ...);
:func:`translated` applies it to an exception raised by the native module.
"""

from __future__ import annotations

import re
from contextlib import contextmanager
from typing import Iterator, List, Tuple

from ._native import EquilibriumError, Error, IntegrationError, ModelError

#: ``(pattern, replacement)`` in order, for every call (``re.sub`` syntax).
RULES: List[Tuple[str, str]] = [
    (r"\(on the command line: --set simulation\.redundant=minimum-norm\)",
     '(in Python: redundant="minimum-norm")'),
    (r"--set simulation\.integrator=([\w-]+)", r'integrator="\1"'),
    (r"--set simulation\.(\w+)=", r"\1="),
    (r"\(given by --set\)", "(given by a setting or overrides=)"),
    (r"--h-max (\S+)", r"h_max=\1"),
    (r"--h (\S+)", r"h=\1"),
    (r"--t-end (\S+)", r"t_end=\1"),
    (r"--adaptive", 'error_control="adaptive"'),
    (r"--strict", 'error_control="strict"'),
]

#: Further rules for a model's runs and checks: another ``--set KEY=VALUE``
#: is an entry of ``overrides=``.
RUN_RULES: List[Tuple[str, str]] = [
    (r"--set (?!simulation\.)([^=\s]+)=", r'overrides["\1"]='),
]

#: Further rules for :meth:`mstar.Model.modes` and
#: :meth:`mstar.Model.linearize`: their options as arguments.
MODES_RULES: List[Tuple[str, str]] = [
    (r"--outputs ('[^']*')", r"outputs=[\1]"),
    (r"--inputs ('[^']*')", r"inputs=[\1]"),
    (r"--outputs", "outputs="),
    (r"--inputs", "inputs="),
    (r"--about initial", 'about="initial"'),
    (r"--count (\d+)", r"count=\1"),
    (r"use the dense method", 'use method="dense"'),
    (r"try the dense method", 'try method="dense"'),
]

#: Further rules for :func:`mstar.sweep`: its ``--set KEY=V1,V2`` is an entry
#: of ``params``, ``--out``, ``--jobs``, ``--shard``, ``--zip`` arguments.
SWEEP_RULES: List[Tuple[str, str]] = [
    (r"give at least one --set KEY=V1,V2,…", "give at least one key in params"),
    (r"in one --set \S+=V1,V2,…", "in one entry of params"),
    (r"--set ([^=\s]+)=\S*?:", r'params["\1"]:'),
    (r"give another --out, or remove the directory to start afresh",
     "give another out=, or overwrite=True to replace its plan"),
    (r"--shard (\d+)/(\d+)", r"shard=(\1, \2)"),
    (r"the same mstar sweep command with its --shard", "the same mstar.sweep call with its shard="),
    (r"the same command with their --shard", "the same mstar.sweep call with their shard="),
    (r"mstar sweep … --shard I/N", "mstar.sweep(..., shard=(i, n))"),
    (r"--shard", "shard="),
    (r"--jobs (\S+?):", r"jobs=\1:"),
    (r"--zip", "zip=True"),
    (r"or use --grid", "or zip=False"),
]


def python_message(message: str, extra: List[Tuple[str, str]] = ()) -> str:  # type: ignore[assignment]
    """``message`` with the command line's options put as Python arguments."""
    for pattern, replacement in list(extra) + RULES:
        message = re.sub(pattern, replacement, message)
    return message


@contextmanager
def translated(extra: List[Tuple[str, str]] = ()) -> Iterator[None]:  # type: ignore[assignment]
    """Re-raises an :class:`Error` from the block with its message in
    Python's words (:func:`python_message`); its attributes stay."""
    try:
        yield
    except Error as e:
        if e.args and isinstance(e.args[0], str):
            e.args = (python_message(e.args[0], extra),) + e.args[1:]
        raise


__all__ = ["EquilibriumError", "Error", "IntegrationError", "MODES_RULES", "ModelError", "python_message", "translated"]
