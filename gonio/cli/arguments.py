"""Argument types shared by the subcommands: each refuses a bad value in argparse's one
line (exit 2), before any work."""

from __future__ import annotations

import argparse
import math


def positive(text: str, what: str = "a positive number") -> float:
    """A positive number."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"expected {what}, got {text!r}")
    return value


def positive_seconds(text: str) -> float:
    """A positive number of seconds."""
    return positive(text, "a positive number of seconds")


def seed(text: str) -> int:
    """A whole number ≥ 0 (a random seed)."""
    try:
        value = int(text)
    except ValueError:
        value = -1
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected a whole number ≥ 0, got {text!r}")
    return value
