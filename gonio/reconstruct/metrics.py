"""Error metrics of a candidate BRDF against a truth, split by the regions of
`gonio.reconstruct.regions` (docs/explanations/evaluation.md has the formulas).

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

from gonio.reconstruct.regions import NAMES as REGIONS
from gonio.reconstruct.regions import regions as region_masks
from gonio.types import FloatArray

__all__ = [
    "METRICS",
    "REGIONS",
    "TRUTH_FLOOR",
    "Scores",
    "region_masks",
    "relative_error",
    "scores",
]

#: Below this truth value (sr⁻¹) the relative error divides by it instead: the absolute
#: error in units of 10⁻⁴ sr⁻¹ (1/π ≈ 0.32 sr⁻¹ is a white Lambertian surface).
TRUTH_FLOOR = 1e-4

#: The metric names, in table order.
METRICS = ("log_rmse", "cos_log_rmse", "rel_rmse", "rel_median", "rel_p95")


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
    """The root mean square, scaled by the largest |x| so that tiny differences do not
    underflow to 0 when squared (nor huge ones overflow)."""
    top = float(np.max(np.abs(x))) if np.size(x) else 0.0
    if top == 0.0 or not math.isfinite(top):
        return top
    return top * math.sqrt(float(np.mean(np.square(np.asarray(x) / top))))
