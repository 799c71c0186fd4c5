"""Python values (numpy's included) as numbers and as the TOML literals a
``--set KEY=VALUE`` override takes; a value of the wrong type is a
``TypeError`` that names the argument."""

from __future__ import annotations

import numbers
from typing import Any, List

import numpy as np


def scalar(value: Any) -> Any:
    """``value`` as a plain Python bool, int or float when it is a number of
    any kind (numpy scalars and 0-d arrays included); else unchanged."""
    if isinstance(value, np.ndarray) and value.ndim == 0:
        value = value[()]
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, numbers.Integral):
        return int(value)
    if isinstance(value, numbers.Real):
        return float(value)
    return value


def _shown(value: Any) -> str:
    """``value``'s type and (shortened) repr, for a message."""
    text = repr(value)
    if len(text) > 40:
        text = text[:37] + "..."
    return f"{type(value).__name__} {text}"


def number(value: Any, name: str) -> float:
    """``value`` (any real number, numpy's included, not a bool) as a float.

    Raises:
        TypeError: ``name: expected a number, got str 'abc'``.
    """
    plain = scalar(value)
    if isinstance(plain, bool) or not isinstance(plain, (int, float)):
        raise TypeError(f"{name}: expected a number, got {_shown(value)}")
    return float(plain)


def numbers_of(value: Any, name: str, length: int) -> List[float]:
    """``value`` (a list, tuple or 1-d array of ``length`` numbers) as floats.

    Raises:
        TypeError: not a sequence of numbers, or of another length.
    """
    if isinstance(value, np.ndarray):
        items = list(value.reshape(-1)) if value.ndim == 1 else None
    elif isinstance(value, (list, tuple)):
        items = list(value)
    else:
        items = None
    if items is None or len(items) != length:
        raise TypeError(f"{name}: expected {length} numbers, got {_shown(value)}")
    return [number(v, f"{name}[{i}]") for i, v in enumerate(items)]


def toml_literal(value: Any, what: str, lists: bool = False) -> str:
    """``value`` (a bool, a number of any kind or a string; with ``lists``,
    also a list, tuple or numpy array of them, nested) as a TOML literal;
    ``what`` names it in the TypeError for anything else."""
    plain = scalar(value)
    if isinstance(plain, bool):
        return "true" if plain else "false"
    if isinstance(plain, (int, float)):
        return repr(plain)  # round-trips; inf and nan are TOML too
    if isinstance(plain, str):
        escaped = plain.replace("\\", "\\\\").replace('"', '\\"')
        return f'"{escaped}"'
    if lists and isinstance(plain, np.ndarray) and plain.ndim >= 1 and plain.dtype != object:
        plain = plain.tolist()  # nested lists of Python numbers
    elif lists and isinstance(plain, np.ndarray) and plain.ndim == 1:
        plain = list(plain)
    if lists and isinstance(plain, (list, tuple)):
        return "[" + ", ".join(toml_literal(v, what, lists) for v in plain) + "]"
    kinds = "a number, a bool, a string or a list of them" if lists else "a number, a bool or a string"
    raise TypeError(f"{what}: expected {kinds}, got {_shown(value)}")


def integer(value: Any, name: str) -> int:
    """``value`` (an integer of any kind, numpy's included, not a bool) as an int.

    Raises:
        TypeError: ``name: expected an integer, got float 1.5``.
    """
    plain = scalar(value)
    if isinstance(plain, bool) or not isinstance(plain, int):
        raise TypeError(f"{name}: expected an integer, got {_shown(value)}")
    return plain
