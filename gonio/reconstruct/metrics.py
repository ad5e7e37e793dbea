"""Error metrics of a candidate BRDF against a truth, and the regions they are split by
(docs/evaluation.md has the formulas).

For values c (candidate) and t (truth) in sr⁻¹ on the same pairs, every channel of an
RGB value counting as one term (means run over pairs × channels):

- ``log_rmse``      √mean[(ln(1 + c⁺) − ln(1 + t⁺))²], with x⁺ = max(x, 0);
- ``cos_log_rmse``  √mean[(ln(1 + c⁺ cos θi) − ln(1 + t⁺ cos θi))²], the cosine-weighted
  form of the data-driven BRDF literature;
- ``rel_rmse``      √mean(e²), ``rel_median`` median(e), ``rel_p95`` 95th percentile(e),
  with the relative error e = |c − t| / max(|t|, `TRUTH_FLOOR`).

A BRDF is not negative: a negative candidate value (noise through a linear interpolation)
is scored as 0 in the log metrics and as itself in the relative ones.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from gonio.types import BoolArray, FloatArray

#: Below this truth value (sr⁻¹) the relative error divides by it instead: the absolute
#: error in units of 10⁻⁴ sr⁻¹ (1/π ≈ 0.32 sr⁻¹ is a white Lambertian surface).
TRUTH_FLOOR = 1e-4

#: The metric names, in table order.
METRICS = ("log_rmse", "cos_log_rmse", "rel_rmse", "rel_median", "rel_p95")

#: The regions, in the order a pair in several is assigned: the first that matches.
REGIONS = ("grazing", "mirror", "retro", "rest")
#: Within this angle (degrees) of the mirror direction (ωo vs ωi mirrored about n): "mirror".
MIRROR_DEG = 10.0
#: Within this angle of retro-reflection (ωo vs ωi): "retro".
RETRO_DEG = 10.0
#: Either polar angle above this: "grazing".
GRAZING_DEG = 70.0


@dataclass(frozen=True)
class Scores:
    """The metrics over ``count`` pairs scored (None for each when there is none)."""

    count: int
    log_rmse: float | None
    cos_log_rmse: float | None
    rel_rmse: float | None
    rel_median: float | None
    rel_p95: float | None

    def to_json(self) -> dict[str, int | float | None]:
        return asdict(self)


def relative_error(candidate: FloatArray, truth: FloatArray) -> FloatArray:
    """e = |c − t| / max(|t|, `TRUTH_FLOOR`), elementwise."""
    return np.asarray(
        np.abs(candidate - truth) / np.maximum(np.abs(truth), TRUTH_FLOOR), dtype=np.float64
    )


def scores(candidate: FloatArray, truth: FloatArray, cos_theta_i: FloatArray) -> Scores:
    """The metrics of values (N,) or (N, C) against truth of the same shape, for pairs
    whose incident directions have cosines ``cos_theta_i`` (N,)."""
    c = np.asarray(candidate, dtype=np.float64)
    t = np.asarray(truth, dtype=np.float64)
    if c.shape != t.shape:
        raise ValueError(f"candidate {c.shape} and truth {t.shape} differ in shape")
    n = len(c)
    if n == 0:
        return Scores(0, None, None, None, None, None)
    cos = np.asarray(cos_theta_i, dtype=np.float64).reshape((n,) + (1,) * (c.ndim - 1))
    cp, tp = np.maximum(c, 0.0), np.maximum(t, 0.0)
    e = relative_error(c, t)
    return Scores(
        count=n,
        log_rmse=_rms(np.log1p(cp) - np.log1p(tp)),
        cos_log_rmse=_rms(np.log1p(cp * cos) - np.log1p(tp * cos)),
        rel_rmse=_rms(e),
        rel_median=float(np.median(e)),
        rel_p95=float(np.percentile(e, 95.0)),
    )


def _rms(x: FloatArray) -> float:
    return math.sqrt(float(np.mean(np.square(x))))


def region_masks(wi: FloatArray, wo: FloatArray) -> dict[str, BoolArray]:
    """One mask (N,) per region of `REGIONS`, disjoint and covering every pair:

    - ``grazing``: θi or θo above `GRAZING_DEG`;
    - ``mirror``: ωo within `MIRROR_DEG` of the mirror direction (−ωi,x, −ωi,y, ωi,z);
    - ``retro``: ωo within `RETRO_DEG` of ωi;
    - ``rest``: the others.

    A pair that matches several goes to the first in that order (near normal incidence
    the mirror and retro cones overlap: such pairs are "mirror").
    """
    wi = np.asarray(wi, dtype=np.float64).reshape(-1, 3)
    wo = np.asarray(wo, dtype=np.float64).reshape(-1, 3)
    cos_grazing = math.cos(math.radians(GRAZING_DEG))
    grazing = (wi[:, 2] < cos_grazing) | (wo[:, 2] < cos_grazing)
    mirrored = wi * np.array([-1.0, -1.0, 1.0])
    mirror = _angle(wo, mirrored) <= math.radians(MIRROR_DEG)
    retro = _angle(wo, wi) <= math.radians(RETRO_DEG)
    taken = grazing.copy()
    out = {"grazing": grazing}
    for name, mask in (("mirror", mirror), ("retro", retro)):
        out[name] = mask & ~taken
        taken |= mask
    out["rest"] = ~taken
    return out


def _angle(a: FloatArray, b: FloatArray) -> FloatArray:
    """The angle (rad) between unit directions, accurate near 0 (atan2 of |a×b|, a·b)."""
    cross = np.linalg.norm(np.cross(a, b), axis=-1)
    return np.asarray(np.arctan2(cross, np.sum(a * b, axis=-1)), dtype=np.float64)
