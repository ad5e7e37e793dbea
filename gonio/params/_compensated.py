"""Error-free float64 arithmetic for the few places that need more than float64.

Knuth's two-sum and Dekker's two-product (exact transformations under
round-to-nearest, no FMA needed) carry the halfway and back vectors of a pair as
unevaluated sums hi + lo. Two things then become possible that plain float64 cannot do:

- compute h and k of the *exactly normalized* directions: a float64 direction is unit
  only to about ε, and that defect, divided by ‖h‖ near opposite directions or by the
  small z near the horizon, is otherwise what limits the round trip;
- norms √(Σ (hi + lo)²) to within about half an ulp, so that coordinates such as ‖h̄‖
  near 1 are as close to correctly rounded as float64 allows.

Used only on the subsets of pairs near the extremes that need it.
"""

from __future__ import annotations

import numpy as np

from gonio.types import FloatArray

_SPLITTER = 134217729.0  # 2**27 + 1, Veltkamp's constant for float64

#: A double-double number as an unevaluated sum (hi, lo), |lo| ≤ ulp(hi)/2 or so.
DD = tuple[FloatArray, FloatArray]


def two_sum(a: FloatArray, b: FloatArray) -> DD:
    """(s, e) with s + e = a + b exactly."""
    s = a + b
    bb = s - a
    return s, (a - (s - bb)) + (b - bb)


def _split(a: FloatArray) -> DD:
    c = _SPLITTER * a
    hi = c - (c - a)
    return hi, a - hi


def two_square(a: FloatArray) -> DD:
    """(p, e) with p + e = a² exactly."""
    p = a * a
    hi, lo = _split(a)
    return p, ((hi * hi - p) + 2.0 * hi * lo) + lo * lo


def two_prod(a: FloatArray, b: FloatArray) -> DD:
    """(p, e) with p + e = a·b exactly."""
    p = a * b
    ah, al = _split(a)
    bh, bl = _split(b)
    return p, ((ah * bh - p) + ah * bl + al * bh) + al * bl


def dot2(a: FloatArray, b: FloatArray, c: FloatArray, d: FloatArray) -> DD:
    """a·b + c·d as a double-double (error a few ε² relative to |ab| + |cd|)."""
    p, e = two_prod(a, b)
    q, f = two_prod(c, d)
    s, g = two_sum(p, q)
    return s, g + (e + f)


def one_minus_norm2(x: DD, y: DD) -> FloatArray:
    """1 − (x² + y²) for double-double x, y, to a few ε² absolute."""
    px, ex = two_square(x[0])
    py, ey = two_square(y[0])
    s, e = two_sum(px, py)
    tail = e + ex + ey + 2.0 * (x[0] * x[1] + y[0] * y[1])
    return np.asarray((1.0 - s) - tail, dtype=np.float64)


def norm_defect(x: FloatArray, y: FloatArray, z: FloatArray) -> FloatArray:
    """x² + y² + z² − 1 to an absolute error of a few ε², for ‖(x, y, z)‖ ≈ 1."""
    px, ex = two_square(x)
    py, ey = two_square(y)
    pz, ez = two_square(z)
    s, e1 = two_sum(px, py)
    s, e2 = two_sum(s, pz)
    # s is within a few ulps of 1, so s − 1 is exact (Sterbenz).
    return (s - 1.0) + (((e1 + e2) + (ex + ey)) + ez)


def exact_halfway_and_back(
    wi: tuple[FloatArray, ...], wo: tuple[FloatArray, ...]
) -> tuple[DD, DD, DD, DD, DD, DD]:
    """h = (ω̂i + ω̂o)/2 and k = (ω̂i − ω̂o)/2 of ω̂ = ω/‖ω‖, each component as (hi, lo).

    With d = ‖ω‖² − 1 (known to ε²), ω̂ = ω (1 − d/2) to O(ε²); the sums ωi ± ωo are
    kept exactly by two-sum and the normalization enters the low parts.
    """
    di = 0.25 * norm_defect(*wi)
    do = 0.25 * norm_defect(*wo)
    halves, backs = [], []
    for a, b in zip(wi, wo, strict=True):
        s, e = two_sum(a, b)
        halves.append((0.5 * s, 0.5 * e - (di * a + do * b)))
        s, e = two_sum(a, -b)
        backs.append((0.5 * s, 0.5 * e - (di * a - do * b)))
    return (*halves, *backs)  # type: ignore[return-value]


def norm(*parts: DD) -> FloatArray:
    """√(Σ (hi + lo)²) to within about half an ulp (one Newton step in double-double)."""
    s_hi = np.zeros_like(parts[0][0])
    s_lo = np.zeros_like(parts[0][0])
    for hi, lo in parts:
        p, e = two_square(hi)
        s_hi, t = two_sum(s_hi, p)
        s_lo = s_lo + (t + e + 2.0 * hi * lo)
    r = np.sqrt(s_hi)
    p, e = two_square(r)
    # s_hi − p is exact (p is within an ulp or two of s_hi).
    residual = ((s_hi - p) - e) + s_lo
    return np.asarray(np.where(r > 0.0, r + residual / (2.0 * np.where(r > 0.0, r, 1.0)), r))
