"""Direction arrays: the one place inputs of shape (..., 3) are checked and converted,
and where uniform directions are drawn (`uniform_cap`)."""

from __future__ import annotations

import math

import numpy as np

from gonio.errors import DomainError
from gonio.types import ArrayLike, BoolArray, FloatArray

#: How far from unit length (in ‖ω‖²) and below the horizon (in z) a float64 direction
#: may be: a few dozen roundings. Directions from trigonometry or rotation matrices are
#: within a few ε; anything else should be normalized first.
UNIT_TOLERANCE = 64.0 * float(np.finfo(np.float64).eps)

Components = tuple[FloatArray, FloatArray, FloatArray]


def as_direction_pair(wi: ArrayLike, wo: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """``wi``, ``wo`` as float64 arrays (..., 3) broadcast against each other.

    Raises ``DomainError`` when a last axis is not 3 long or the shapes do not broadcast.
    """
    a = np.asarray(wi, dtype=np.float64)
    b = np.asarray(wo, dtype=np.float64)
    if a.ndim == 0 or a.shape[-1] != 3 or b.ndim == 0 or b.shape[-1] != 3:
        raise DomainError(
            f"directions must have a last axis of length 3, got shapes {a.shape} and {b.shape}"
        )
    if a.shape != b.shape:
        try:
            a, b = np.broadcast_arrays(a, b)
        except ValueError:
            raise DomainError(
                f"direction arrays of shapes {a.shape} and {b.shape} do not broadcast"
            ) from None
    return a, b


def in_upper_hemisphere(x: FloatArray, y: FloatArray, z: FloatArray) -> BoolArray:
    """True where (x, y, z) is finite, unit to `UNIT_TOLERANCE` and has z ≥ −tolerance."""
    length2 = x * x
    length2 += y * y
    length2 += z * z
    ok = length2 >= 1.0 - UNIT_TOLERANCE
    ok &= length2 <= 1.0 + UNIT_TOLERANCE
    ok &= z >= -UNIT_TOLERANCE
    return ok


def pair_components(wi: ArrayLike, wo: ArrayLike) -> tuple[tuple[int, ...], Components, Components]:
    """(leading shape, (xi, yi, zi), (xo, yo, zo)) of a checked direction pair.

    The components are contiguous 1-d float64 arrays (leading axes flattened). Raises
    ``DomainError`` unless every direction is a finite unit vector in the closed upper
    hemisphere (to `UNIT_TOLERANCE`); the message names the first offending pair.
    """
    a, b = as_direction_pair(wi, wo)
    xi, yi, zi = np.ascontiguousarray(a.reshape(-1, 3).T)
    xo, yo, zo = np.ascontiguousarray(b.reshape(-1, 3).T)
    ok = in_upper_hemisphere(xi, yi, zi)
    ok &= in_upper_hemisphere(xo, yo, zo)
    lead = a.shape[:-1]
    if not ok.all():
        bad = ~ok
        index = tuple(int(i) for i in np.unravel_index(int(np.argmax(bad)), lead))
        where = f"first at index {index}" if index else "the pair"
        raise DomainError(
            f"{int(np.count_nonzero(bad))} of {bad.size} direction pairs are not unit vectors "
            f"in the closed upper hemisphere (|‖ω‖² − 1| ≤ {UNIT_TOLERANCE:.1e}, "
            f"z ≥ −{UNIT_TOLERANCE:.1e}); {where}: "
            f"wi = {a[index].tolist()}, wo = {b[index].tolist()}; "
            "normalize with w / np.linalg.norm(w, axis=-1, keepdims=True)"
        )
    return lead, (xi, yi, zi), (xo, yo, zo)


def uniform_cap(rng: np.random.Generator, n: int, theta_max: float) -> FloatArray:
    """``n`` unit directions uniform in solid angle over the cap θ ≤ ``theta_max`` (rad;
    at most the hemisphere)."""
    z = rng.uniform(max(math.cos(theta_max), 0.0), 1.0, n)
    phi = rng.uniform(0.0, 2.0 * math.pi, n)
    s = np.sqrt(np.maximum(1.0 - z * z, 0.0))
    return np.stack([s * np.cos(phi), s * np.sin(phi), z], axis=-1)
