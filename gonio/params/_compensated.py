"""Error-free float64 arithmetic for the few places that need more than float64.

Dekker's product and Knuth's sum (exact transformations under round-to-nearest,
no FMA needed) give ‖ω‖² − 1 of a float64 direction to about ε², which lets the
halfway vector of two nearly opposite directions be computed from the exactly
normalized directions.
"""

from __future__ import annotations

from gonio.types import FloatArray

_SPLITTER = 134217729.0  # 2**27 + 1, Veltkamp's constant for float64


def _split(a: FloatArray) -> tuple[FloatArray, FloatArray]:
    c = _SPLITTER * a
    hi = c - (c - a)
    return hi, a - hi


def _square(a: FloatArray) -> tuple[FloatArray, FloatArray]:
    """(p, e) with p + e = a² exactly."""
    p = a * a
    hi, lo = _split(a)
    return p, ((hi * hi - p) + 2.0 * hi * lo) + lo * lo


def _two_sum(a: FloatArray, b: FloatArray) -> tuple[FloatArray, FloatArray]:
    """(s, e) with s + e = a + b exactly."""
    s = a + b
    bb = s - a
    return s, (a - (s - bb)) + (b - bb)


def norm_defect(x: FloatArray, y: FloatArray, z: FloatArray) -> FloatArray:
    """x² + y² + z² − 1 to an absolute error of a few ε², for ‖(x, y, z)‖ ≈ 1."""
    px, ex = _square(x)
    py, ey = _square(y)
    pz, ez = _square(z)
    s, e1 = _two_sum(px, py)
    s, e2 = _two_sum(s, pz)
    # s is within a few ulps of 1, so s − 1 is exact (Sterbenz).
    return (s - 1.0) + (((e1 + e2) + (ex + ey)) + ez)
