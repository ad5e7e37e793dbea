"""Argument types shared by the subcommands: each refuses a bad value in argparse's one
line (exit 2), before any work."""

from __future__ import annotations

import argparse
import math

from gonio.config import MAX_INTEGER, MAX_SECONDS


def add_alignment(p: argparse.ArgumentParser) -> None:
    """``--alignment FILE``: re-derive the run's pairs with a later alignment file."""
    p.add_argument(
        "--alignment",
        type=str,
        default=None,
        metavar="FILE",
        help="an alignment file to re-derive the run's direction pairs "
        "with, from its stored joint angles (default: the alignment the run's rig file named)",
    )


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


def finite_degrees(text: str) -> float:
    """A finite angle in degrees."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an angle in degrees, got {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"expected a finite angle in degrees, got {text!r}")
    return value


def seed(text: str) -> int:
    """A whole number ≥ 0 below 2**63 (a random seed, as the run file stores it)."""
    try:
        value = int(text)
    except ValueError:
        value = -1
    if not 0 <= value <= MAX_INTEGER:
        raise argparse.ArgumentTypeError(f"expected a whole number ≥ 0 below 2**63, got {text!r}")
    return value
