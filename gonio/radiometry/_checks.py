"""Input checks shared by the radiometry modules: positive numbers, directions, RGB axes."""

from __future__ import annotations

import math

import numpy as np

from gonio.directions import UNIT_TOLERANCE, as_direction_pair, in_upper_hemisphere
from gonio.errors import DomainError
from gonio.types import ArrayLike, FloatArray


def positive(name: str, value: object) -> float:
    """``value`` as a positive finite float, else a one-line `DomainError` naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
        raise DomainError(f"{name} must be a positive finite number, got {value!r}")
    v = float(value)
    if not (math.isfinite(v) and v > 0.0):
        raise DomainError(f"{name} must be a positive finite number, got {v}")
    return v


def positive_array(name: str, value: ArrayLike) -> FloatArray:
    """``value`` as a float64 array whose entries are all positive and finite."""
    try:
        a = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise DomainError(f"{name} must be positive finite numbers, got {value!r}") from None
    if not np.all(np.isfinite(a) & (a > 0.0)):
        bad = a[~(np.isfinite(a) & (a > 0.0))].ravel()[0]
        raise DomainError(f"{name} must be positive finite numbers, got {bad}")
    return a


def _check_unit_upper(name: str, w: FloatArray) -> None:
    ok = in_upper_hemisphere(w[..., 0], w[..., 1], w[..., 2])
    if not np.all(ok):
        bad = ~np.asarray(ok)
        index = np.unravel_index(int(np.argmax(bad)), bad.shape) if bad.ndim else ()
        raise DomainError(
            f"{name}: {int(np.count_nonzero(bad))} of {bad.size} directions are not unit "
            f"vectors in the closed upper hemisphere (tolerance {UNIT_TOLERANCE:.1e}); "
            f"first: {w[index].tolist()}"
        )


def direction(name: str, w: ArrayLike) -> FloatArray:
    """A direction array (..., 3), float64, checked unit and in the closed upper hemisphere."""
    a = np.asarray(w, dtype=np.float64)
    if a.ndim == 0 or a.shape[-1] != 3:
        raise DomainError(f"{name} must have a last axis of length 3, got shape {a.shape}")
    _check_unit_upper(name, a)
    return a


def direction_pair(wi: ArrayLike, wo: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """``wi``, ``wo`` broadcast against each other and checked as `direction`."""
    a, b = as_direction_pair(wi, wo)
    _check_unit_upper("wi", a)
    _check_unit_upper("wo", b)
    return a, b


def spread(values: FloatArray, geometry: FloatArray) -> FloatArray:
    """``geometry`` given a trailing axis when ``values`` carries an RGB axis of 3.

    ``values`` is RGB when it has one more axis than ``geometry`` and that axis is 3
    long (a model's ``eval`` output on the same pairs); otherwise plain broadcasting.
    """
    if values.ndim == geometry.ndim + 1 and values.shape[-1] == 3:
        return geometry[..., None]
    return geometry


def cosine(w: FloatArray) -> FloatArray:
    """max(z, 0): the cosine to the normal, clamped at the horizon."""
    return np.asarray(np.maximum(w[..., 2], 0.0), dtype=np.float64)
