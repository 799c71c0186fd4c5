"""Python values as the TOML literals a ``--set KEY=VALUE`` override takes."""

from __future__ import annotations

from typing import Any


def toml_literal(value: Any, what: str, lists: bool = False) -> str:
    """``value`` (a bool, number or string; with ``lists``, also a list or
    tuple of them) as a TOML literal; ``what`` names it in the TypeError for
    anything else."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return repr(value)  # round-trips; inf and nan are TOML too
    if isinstance(value, str):
        escaped = value.replace("\\", "\\\\").replace('"', '\\"')
        return f'"{escaped}"'
    if lists and isinstance(value, (list, tuple)):
        return "[" + ", ".join(toml_literal(v, what, lists) for v in value) + "]"
    kinds = "a number, a bool, a string or a list of them" if lists else "a number, a bool or a string"
    raise TypeError(f"{what} must be {kinds}, not {type(value).__name__}")
