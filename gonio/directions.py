"""Direction arrays: the one place inputs of shape (..., 3) are checked and converted."""

from __future__ import annotations

import numpy as np

from gonio.errors import DomainError
from gonio.types import ArrayLike, FloatArray


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
