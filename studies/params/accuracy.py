"""How precisely each parametrization can carry a direction pair, and how precisely it does.

`error_envelope` is the closed-form estimate derived in docs/explanations/parametrizations.md: a
component recovered as sqrt(t²) from a difference of O(1) float64 quantities is known
to about c·ε/(t + sqrt(c·ε)) (c·ε/t when t ≫ √(c·ε), √(c·ε) at t = 0), where t is
the smallest direction z (orthographic) or hz = (ωi·n + ωo·n)/2 (hybrid); spherical
and Rusinkiewicz keep a few ε everywhere.

`extreme_study` measures the float64 round trip near each named extreme and, with
the mpmath reference (`studies.params.exact`, test extra), the bound float64
coordinates impose there.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gonio.params import cases, condition_number, get, singular_values, tangent_jacobian
from gonio.types import FloatArray
from studies.params import exact

EPS = float(np.finfo(np.float64).eps)  # 2⁻⁵², one ulp of 1
#: Multiples of ε in the envelope: a few roundings in the O(1) terms (see the docs);
#: calibrated on 4.8 million pairs near the horizon (elevations 0 and 1e-17 … 1e-2),
#: where the worst measured errors reach 0.77 of it.
FLOOR_ULPS = 16.0
SQRT_ULPS = 16.0


def error_envelope(name: str, wi: FloatArray, wo: FloatArray) -> FloatArray:
    """Estimated round-trip error of ``name`` at each pair (radians, ≈ Euclidean)."""
    wi, wo = np.asarray(wi, np.float64), np.asarray(wo, np.float64)
    floor = FLOOR_ULPS * EPS * np.ones(np.broadcast_shapes(wi.shape[:-1], wo.shape[:-1]))
    if name in ("spherical", "rusinkiewicz"):
        return floor
    if name == "orthographic":
        t = np.minimum(wi[..., 2], wo[..., 2])
    elif name == "hybrid":
        t = 0.5 * (wi[..., 2] + wo[..., 2])
    else:
        raise KeyError(name)
    ce = SQRT_ULPS * EPS
    return np.asarray(floor + ce / (np.maximum(t, 0.0) + np.sqrt(ce)), dtype=np.float64)


@dataclass(frozen=True)
class ExtremeRow:
    """One cell of the accuracy study: worst cases over ``samples`` pairs."""

    parametrization: str
    extreme: str
    distance: float
    samples: int
    measured: float  # worst float64 round-trip error
    bound: float  # worst error float64 coordinates impose (mpmath), NaN if not computed
    pair_ratio: float  # worst measured / bound taken pair by pair, NaN if not computed

    @property
    def ratio(self) -> float:
        """Worst measured over worst bound in the cell."""
        return self.measured / self.bound if self.bound > 0 else float("nan")


def measured_errors(name: str, wi: FloatArray, wo: FloatArray) -> FloatArray:
    """The float64 round-trip error of ``name`` at each pair."""
    p = get(name)
    a, b = p.inverse(p.forward(wi, wo))
    return cases.roundtrip_error(wi, wo, a, b)


def extreme_study(
    names: list[str], samples: int = 32, seed: int = 0, with_bound: bool = True
) -> list[ExtremeRow]:
    """Worst measured error (and bound) per parametrization, extreme and distance."""
    rows = []
    for extreme in cases.EXTREMES:
        for distance in cases.DISTANCES:
            wi, wo = cases.near(extreme, distance, samples, seed)
            for name in names:
                errors = measured_errors(name, wi, wo)
                bound = pair_ratio = float("nan")
                if with_bound:
                    bounds = exact.roundtrip_bounds(name, wi, wo)
                    bound = float(bounds.max())
                    pair_ratio = float(np.max(errors / bounds))
                rows.append(
                    ExtremeRow(
                        name, extreme, distance, samples, float(errors.max()), bound, pair_ratio
                    )
                )
    return rows


#: Distances (radians) of `path_study`: two per decade, 1e-1 … 1e-12.
PATH_DISTANCES: tuple[float, ...] = tuple(float(10.0 ** (-i / 2)) for i in range(2, 25))


@dataclass(frozen=True)
class PathRow:
    """One point of the conditioning study: ``samples`` one-parameter paths (fixed seed,
    so each path keeps its other parameters) at ``distance`` from ``extreme``."""

    parametrization: str
    extreme: str
    distance: float
    samples: int
    sigma_max: float  # median over the paths of the tangent Jacobian's largest singular value
    sigma_min: float  # median of the smallest
    cond: float  # median condition number σmax/σmin
    cond_worst: float  # largest condition number over the paths
    roundtrip: float  # worst float64 round-trip error
    bound: float  # worst error float64 coordinates impose (mpmath), NaN if not computed


def path_study(
    names: list[str],
    extremes: list[str] | None = None,
    distances: tuple[float, ...] = PATH_DISTANCES,
    samples: int = 16,
    seed: int = 0,
    with_bound: bool = False,
) -> list[PathRow]:
    """Conditioning (`gonio.params.conditioning`) and round-trip error along paths
    approaching each extreme (`cases.near` with one seed: the same paths at every
    distance), per parametrization."""
    rows = []
    for extreme in extremes or list(cases.EXTREMES):
        for distance in distances:
            wi, wo = cases.near(extreme, distance, samples, seed)
            for name in names:
                jacobian = tangent_jacobian(name, wi, wo)
                s, cond = singular_values(jacobian), condition_number(jacobian)
                bound = float("nan")
                if with_bound:
                    bound = float(exact.roundtrip_bounds(name, wi, wo).max())
                rows.append(
                    PathRow(
                        name,
                        extreme,
                        distance,
                        samples,
                        float(np.median(s[:, 0])),
                        float(np.median(s[:, -1])),
                        float(np.median(cond)),
                        float(cond.max()),
                        float(measured_errors(name, wi, wo).max()),
                        bound,
                    )
                )
    return rows
