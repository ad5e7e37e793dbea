"""Input coercion and angle helpers shared by the parametrizations.

Inputs are converted to float64 once, here; the math modules work on component
arrays (x, y, z or the four coordinates) so that numpy's ufuncs stream over
contiguous memory.
"""

from __future__ import annotations

import numpy as np

from gonio.errors import DomainError
from gonio.types import ArrayLike, BoolArray, FloatArray

TWO_PI = 2.0 * np.pi


def as_coordinates(coords: ArrayLike, size: int) -> FloatArray:
    """A coordinate array of shape (..., size), float64."""
    c = np.asarray(coords, dtype=np.float64)
    if c.ndim == 0 or c.shape[-1] != size:
        raise DomainError(f"coordinates must have a last axis of length {size}, got {c.shape}")
    return c


def components(a: FloatArray) -> tuple[FloatArray, ...]:
    """The last axis split into contiguous 1-d component arrays (leading axes flattened,
    so that the math never meets numpy scalars)."""
    return tuple(np.ascontiguousarray(a.reshape(-1, a.shape[-1]).T))


def stack(lead: tuple[int, ...], *parts: FloatArray) -> FloatArray:
    """1-d component arrays joined along a new last axis, reshaped to ``lead`` + (n,)."""
    return np.stack(np.broadcast_arrays(*parts), axis=-1).reshape(*lead, len(parts))


def azimuth(y: FloatArray, x: FloatArray) -> FloatArray:
    """atan2(y, x) wrapped to [0, 2π); 0 where x = y = 0 (signed zeros included)."""
    # Adding +0.0 turns -0.0 into +0.0, so atan2(-0.0, -0.0) cannot give -π.
    return wrap_two_pi_in_place(np.arctan2(y + 0.0, x + 0.0))


def plane_polar(x: FloatArray, y: FloatArray) -> tuple[FloatArray, FloatArray]:
    """(‖(x, y)‖, azimuth) of tangent vectors; the azimuth is 0 where the norm is 0,
    also when x² + y² underflows for a nonzero vector (|x|, |y| below ~1e-154)."""
    r = x * x
    r += y * y
    np.sqrt(r, out=r)
    phi = wrap_two_pi_in_place(np.arctan2(y, x))  # signed zeros are settled below
    zero = r == 0.0
    if np.any(zero):
        phi[zero] = 0.0
    return r, phi


def subset(parts: tuple[FloatArray, ...], mask: BoolArray) -> tuple[FloatArray, ...]:
    """The rows of each component array where ``mask``."""
    return tuple(p[mask] for p in parts)


def wrap_two_pi_in_place(phi: FloatArray) -> FloatArray:
    """Angles in [-2π, 4π) wrapped to [0, 2π), in place (pass a temporary): values that
    round to 2π become 0, and -0.0 becomes 0.0."""
    np.add(phi, TWO_PI, out=phi, where=phi < 0.0)
    np.subtract(phi, TWO_PI, out=phi, where=phi >= TWO_PI)
    phi += 0.0
    return phi


def wrap_pi(phi: FloatArray) -> FloatArray:
    """Angles in [0, 2π) folded to [0, π) by subtracting π from the upper half."""
    # Exact by Sterbenz's lemma, and below π because 2π is exactly twice π in float64.
    return np.where(phi >= np.pi, phi - np.pi, phi)
