"""A driver configuration's field described for the file that gives it: `described`
makes a `dataclasses.field`'s ``metadata`` of what the field is (one sentence, the
reference of the configuration file shows it) and the bounds a value must keep, so a
configuration's dataclass declares each field, default and bound once and a file
format (`gonio.rig`'s rig file) reads them from it.

Bounds take pydantic's and JSON Schema's names (``gt``, ``ge``, ``lt``, ``le``,
``min_length``); ``items`` bounds each item of a tuple. The driver's own checks
(``__post_init__``) refuse a value made in code; the bounds tell a file's reader.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

#: The bounds `described` takes.
BOUNDS = frozenset({"gt", "ge", "lt", "le", "min_length"})


def described(
    doc: str, *, items: Mapping[str, float] | None = None, **bounds: float
) -> dict[str, Any]:
    """The metadata of a configuration field: ``doc`` (what it is, in a sentence) and its
    ``bounds`` (and its items', ``items``); ``ValueError`` for an unknown bound."""
    unknown = (set(bounds) | set(items or {})) - BOUNDS
    if unknown:
        raise ValueError(f"unknown bounds {sorted(unknown)}; expected some of {sorted(BOUNDS)}")
    return {"doc": doc, "bounds": dict(bounds), "items": dict(items or {})}
