"""Argument types shared by the subcommands: each refuses a bad value in argparse's one
line (exit 2), before any work."""

from __future__ import annotations

import argparse
import math

from gonio.config import MAX_SECONDS


def positive(text: str, what: str = "a positive number", most: float = math.inf) -> float:
    """A positive number.

    ``most``: the largest accepted (none by default); the error then says it."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and 0 < value <= most):
        bound = "" if most == math.inf else f" of at most {most:g}"
        raise argparse.ArgumentTypeError(f"expected {what}{bound}, got {text!r}")
    return value


def positive_seconds(text: str) -> float:
    """A positive number of seconds, at most 1e9 (about the longest a clock can wait).

    The bound is `gonio.config.MAX_SECONDS`, as in the configuration files."""
    return positive(text, "a positive number of seconds", MAX_SECONDS)


def count(text: str, what: str, most: int) -> int:
    """A whole number in [1, ``most``] (``what`` names it in the error)."""
    try:
        value = int(text)
    except ValueError:
        value = 0
    if not 1 <= value <= most:
        raise argparse.ArgumentTypeError(
            f"expected a whole number of {what} in [1, {most:,}], got {text!r}"
        )
    return value


def seed(text: str) -> int:
    """A whole number ≥ 0 (a random seed)."""
    try:
        value = int(text)
    except ValueError:
        value = -1
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected a whole number ≥ 0, got {text!r}")
    return value
