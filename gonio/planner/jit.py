"""The compiler of the planner's inner loops: numba's ``njit``, cached on disk (the first
run compiles for some seconds, later ones load), no fast-math (IEEE arithmetic as numpy's:
a compiled move time equals `gonio.rig.travel.TravelModel.time` bit for bit).

The loops compiled are the sequential ones, where each step depends on the last (the
local search, the nearest-neighbour construction, the choice of poses along an order);
everything else stays vectorized numpy.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar, cast

from numba import njit

F = TypeVar("F", bound=Callable[..., Any])


def compiled(function: F) -> F:
    """``function`` compiled by numba (nopython, cached), with its Python signature."""
    return cast(F, njit(cache=True, nogil=True)(function))
