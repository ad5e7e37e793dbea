"""The interface every analytic BRDF model implements, and parameter checking.

A model is created from named parameters (`gonio.brdf.create`), keeps them in
``params`` and evaluates ``f(wi, wo)`` in sr⁻¹, without the cosine factor, for
unit directions of shape (..., 3) in the sample frame (z = normal, both pointing
away from the surface). Pairs with a direction below the horizon (z < 0) give 0.

Colour: a parameter listed in a model's ``colour_params`` may be a scalar (grey)
or a length-3 sequence (RGB). If any is RGB the model `is_rgb` and `eval`
returns a trailing axis of 3; grey parameters then apply to every channel.
"""

from __future__ import annotations

import math
import os
from abc import ABC, abstractmethod
from collections.abc import Callable, Sequence
from typing import ClassVar, TypeAlias, TypeVar

import numpy as np

from gonio.brdf.geometry import Pair, pair
from gonio.errors import DomainError, GonioError
from gonio.types import ArrayLike, FloatArray

#: A colour parameter as stored in ``params``: a float (grey) or three floats (RGB).
Colour: TypeAlias = float | tuple[float, float, float]
#: Any stored parameter value.
ParamValue: TypeAlias = float | tuple[float, float, float] | str
#: ε (sr⁻¹) of the logarithmic scale of BRDF values, log(f + ε): what a reconstruction
#: interpolates (`gonio.reconstruct.transforms`, ``log``) and whose interpolation error
#: the adaptive planner's density follows (`gonio.planner.adaptive`). Below it, values
#: count linearly, not in log.
LOG_FLOOR = 1e-2
#: The largest value a measured-material file may give (sr⁻¹, and for its other
#: densities: an NDF, a factor). The sharpest BRDF a tabulated file can hold is a mirror
#: spread over its finest bin: about 1/(cos θ · Δω), and MERL's finest bin (θh below
#: 0.011°) spans about 5·10⁻⁷ sr of outgoing directions, so about 2·10⁶ sr⁻¹ at normal
#: incidence and 10⁸ at cos θ = 0.02 (the other formats' bins are coarser). Beyond this
#: a value is no reflectance (it would return more than 10⁸ times the light over a
#: steradian) but a damaged file; within it, any sum of values over samples and solid
#: angles stays many orders from float64's range.
MAX_FILE_VALUE = 1e8


def beyond_bound(values: FloatArray) -> str | None:
    """Why ``values`` (a material file's, NaN for missing ones) exceed
    `MAX_FILE_VALUE` in magnitude, in a message's words ("value 1e+307 (12 such)"), or
    None when none does."""
    magnitude = np.abs(values)
    over = magnitude > MAX_FILE_VALUE
    if not over.any():
        return None
    worst = float(np.nanmax(np.where(over, magnitude, 0.0)))
    return (
        f"values up to {worst:.3g} ({int(over.sum())} beyond {MAX_FILE_VALUE:g}); expected "
        f"at most {MAX_FILE_VALUE:g} (sr⁻¹: above any mirror tabulated on a file's grid)"
    )


class BRDF(ABC):
    """An analytic BRDF f(wi, wo) in sr⁻¹ (cosine factor excluded).

    Class attributes, fixed per model family:
        name: registry name.
        reciprocal: f(wi, wo) = f(wo, wi) for every pair.
        physically_based: reciprocal, non-negative and energy conserving
            (directional albedo ≤ 1) whenever its weights are admissible
            (see each model); tests hold these models to that.
        colour_params: the parameters that may be RGB.
    """

    name: ClassVar[str]
    reciprocal: ClassVar[bool] = True
    physically_based: ClassVar[bool]
    colour_params: ClassVar[tuple[str, ...]] = ()

    def __init__(self, params: dict[str, ParamValue]) -> None:
        self.params: dict[str, ParamValue] = dict(params)
        self.is_rgb: bool = any(isinstance(params.get(p), tuple) for p in self.colour_params)

    @property
    def isotropic(self) -> bool:
        """f is invariant under a common rotation of wi and wo about the normal."""
        return True

    def eval(self, wi: ArrayLike, wo: ArrayLike) -> FloatArray:
        """f(wi, wo) in sr⁻¹, shape broadcast(wi, wo)[:-1], plus (3,) if `is_rgb`.

        ``wi`` points toward the light, ``wo`` toward the detector; both are unit
        vectors (..., 3) in the sample frame. 0 where either has z < 0.
        """
        p = pair(wi, wo)
        value = self._eval(p)
        above = p.above[..., None] if self.is_rgb else p.above
        shape = p.shape + ((3,) if self.is_rgb else ())
        out = np.asarray(np.where(above, value, 0.0), dtype=np.float64)
        return out if out.shape == shape else np.broadcast_to(out, shape).copy()

    def colour(self, key: str) -> FloatArray:
        """A colour parameter as an array of shape () or (3,)."""
        return np.asarray(self.params[key], dtype=np.float64)

    def spread(self, geometric: FloatArray) -> FloatArray:
        """A colourless factor of shape S, given a trailing axis to meet (3,) colours."""
        return geometric[..., None] if self.is_rgb else geometric

    @abstractmethod
    def _eval(self, p: Pair) -> FloatArray:
        """f on the pair; values where ``p.above`` is False are discarded (must be finite)."""

    def __repr__(self) -> str:
        args = ", ".join(f"{k}={v!r}" for k, v in self.params.items())
        return f"{type(self).__name__}({args})"


# -- parameter checking ------------------------------------------------------------------


def scalar(
    name: str,
    value: object,
    *,
    low: float = -math.inf,
    low_open: bool = False,
    high: float = math.inf,
) -> float:
    """``value`` as a finite float in [low, high] (or (low, high] with ``low_open``)."""
    if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
        raise DomainError(f"parameter {name} must be a number, got {value!r}")
    v = float(value)
    if not math.isfinite(v):
        raise DomainError(f"parameter {name} must be finite, got {v}")
    if v < low or (low_open and v == low) or v > high:
        lo = "(" if low_open else "["
        raise DomainError(f"parameter {name} must lie in {lo}{low}, {high}], got {v}")
    return v


def colour(
    name: str,
    value: object,
    *,
    low: float = -math.inf,
    low_open: bool = False,
    high: float = math.inf,
) -> Colour:
    """A scalar (grey) or a length-3 sequence (RGB), each entry checked as `scalar`."""
    if isinstance(value, str) or not isinstance(value, Sequence | np.ndarray):
        return scalar(name, value, low=low, low_open=low_open, high=high)
    items = list(np.asarray(value).ravel()) if isinstance(value, np.ndarray) else list(value)
    if len(items) != 3 or (isinstance(value, np.ndarray) and value.ndim != 1):
        raise DomainError(f"colour parameter {name} must be a scalar or 3 values, got {value!r}")
    r, g, b = (
        scalar(f"{name}[{j}]", x, low=low, low_open=low_open, high=high)
        for j, x in enumerate(items)
    )
    return (r, g, b)


T = TypeVar("T")


def read_path(path: object, read: Callable[[str], T]) -> tuple[str, T]:
    """(``path`` as a string, ``read(path)``) for a tabulated model's ``path``
    parameter: anything but a file name is refused, and the reader's `GonioError` is
    prefixed "parameter path:" so that a scene file's error points at the parameter."""
    if not isinstance(path, str | os.PathLike):
        raise GonioError(f"parameter path must be a file name, got {path!r}")
    name = os.fspath(path)
    try:
        return name, read(name)
    except GonioError as exc:
        raise GonioError(f"parameter path: {exc}") from None
