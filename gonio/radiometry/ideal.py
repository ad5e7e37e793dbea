"""The ideal radiometric chain: source → irradiance → radiance → detector power → electrons.

Units: lengths in the dataclasses are millimetres (converted to metres where a
result is per m²), irradiance W/m², intensity W/sr, solid angle sr, power W,
responsivity A/W, exposure s. Directions are sample-frame unit vectors (..., 3)
(z = normal) pointing away from the surface: ``wi`` toward the light, ``wo``
toward the detector. BRDF values f are in sr⁻¹ (cosine excluded).

Power into the detector's aperture, ideal geometry (no effects):

    Φ = K(source, optics, wi) · f(wi, wo) · c(source, wo) · Ω  =  f · G

* collimated beam (irradiance E0 ⟂ beam, diameter D), the detector's view
  overfilled (it sees the whole lit ellipse, area πD²/(4 cos θi), irradiance
  E0 cos θi): K = E0 πD²/4, c = cos θo;
* isotropic point source (intensity I at distance r along wi) flooding the sample,
  the detector seeing its field of view (diameter F, area πF²/(4 cos θo) on the
  sample): K = I cos θi / r² · πF²/4, c = 1.

The inverse is f = Φ / G. See docs/explanations/radiometry.md for the derivation and the limits
of the ideal geometry.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal, TypeAlias

import numpy as np

from gonio.errors import DomainError
from gonio.radiometry._checks import (
    cosine,
    direction,
    direction_pair,
    positive,
    positive_array,
    spread,
)
from gonio.types import ArrayLike, FloatArray

#: The elementary charge q (C), exact in the SI.
ELEMENTARY_CHARGE = 1.602176634e-19
#: Metres per millimetre.
MM = 1e-3


@dataclass(frozen=True)
class CollimatedSource:
    """A distant collimated beam: irradiance E0 (W/m², measured ⟂ to the beam) and
    beam diameter D (mm)."""

    irradiance_w_m2: float
    beam_diameter_mm: float

    def __post_init__(self) -> None:
        for name in ("irradiance_w_m2", "beam_diameter_mm"):
            object.__setattr__(
                self, name, positive(f"CollimatedSource.{name}", getattr(self, name))
            )


@dataclass(frozen=True)
class PointSource:
    """An isotropic point source of intensity I (W/sr) at distance r (mm) from the
    sample centre, along wi."""

    intensity_w_sr: float
    distance_mm: float

    def __post_init__(self) -> None:
        for name in ("intensity_w_sr", "distance_mm"):
            object.__setattr__(self, name, positive(f"PointSource.{name}", getattr(self, name)))


Source: TypeAlias = CollimatedSource | PointSource


@dataclass(frozen=True)
class DetectorOptics:
    """A distant detector: aperture Ω (sr, seen from the sample, ≤ 2π) around wo and a
    circular field of view of diameter F (mm) ⟂ wo, i.e. an ellipse of semi-axes
    F/(2 cos θo) (along wo's azimuth) × F/2 on the sample."""

    aperture_sr: float
    fov_diameter_mm: float

    def __post_init__(self) -> None:
        for name in ("aperture_sr", "fov_diameter_mm"):
            object.__setattr__(self, name, positive(f"DetectorOptics.{name}", getattr(self, name)))
        if self.aperture_sr > 2.0 * math.pi:
            raise DomainError(f"DetectorOptics.aperture_sr must be ≤ 2π, got {self.aperture_sr}")


SourceKind: TypeAlias = Literal["collimated", "point"]


def _check_source(source: object) -> Source:
    if not isinstance(source, CollimatedSource | PointSource):
        raise DomainError(f"source must be a CollimatedSource or a PointSource, got {source!r}")
    return source


def source_kind(source: Source) -> SourceKind:
    """The kind of a source: "collimated" or "point"."""
    return "collimated" if isinstance(_check_source(source), CollimatedSource) else "point"


def _check_optics(optics: object) -> DetectorOptics:
    if not isinstance(optics, DetectorOptics):
        raise DomainError(f"optics must be a DetectorOptics, got {optics!r}")
    return optics


def irradiance(source: Source, wi: ArrayLike) -> FloatArray:
    """Irradiance at the sample centre (W/m²), shape wi.shape[:-1].

    Collimated: E0 · max(cos θi, 0). Point source: I · max(cos θi, 0) / r², r in metres.
    """
    return _irradiance(_check_source(source), direction("wi", wi))


def prefactor(source: Source, optics: DetectorOptics, wi: ArrayLike) -> FloatArray:
    """K (W): collimated E0 πD²/4 (independent of wi); point I cos θi / r² · πF²/4."""
    return prefactor_checked(_check_source(source), _check_optics(optics), direction("wi", wi))


def view_weight(source: Source, wo: ArrayLike) -> FloatArray:
    """c (dimensionless): cos θo for a collimated beam, 1 for a point source."""
    return view_weight_checked(_check_source(source), direction("wo", wo))


def geometric_factor(
    source: Source, optics: DetectorOptics, wi: ArrayLike, wo: ArrayLike
) -> FloatArray:
    """G = K · c · Ω (W·sr), so that Φ = f · G; shape broadcast(wi, wo)[:-1]."""
    a, b = direction_pair(wi, wo)
    return geometric_checked(_check_source(source), _check_optics(optics), a, b)


def radiant_power(
    source: Source, optics: DetectorOptics, f: ArrayLike, wi: ArrayLike, wo: ArrayLike
) -> FloatArray:
    """Φ = f · G (W) for BRDF values f (sr⁻¹) of shape G's, or G's + (3,) for RGB."""
    a, b = direction_pair(wi, wo)
    return radiant_power_checked(_check_source(source), _check_optics(optics), f, a, b)


# The same on inputs already checked (directions from `direction_pair`): the forward
# chain checks once at its entry, not in every step (a check costs ~20 µs on a pair).
def _irradiance(source: Source, a: FloatArray) -> FloatArray:
    ci = cosine(a)
    if isinstance(source, CollimatedSource):
        return source.irradiance_w_m2 * ci
    r = source.distance_mm * MM
    return source.intensity_w_sr * ci / (r * r)


def prefactor_checked(source: Source, optics: DetectorOptics, a: FloatArray) -> FloatArray:
    if isinstance(source, CollimatedSource):
        d = source.beam_diameter_mm * MM
        return np.full(a.shape[:-1], source.irradiance_w_m2 * math.pi * d * d / 4.0)
    f = optics.fov_diameter_mm * MM
    return _irradiance(source, a) * (math.pi * f * f / 4.0)


def view_weight_checked(source: Source, b: FloatArray) -> FloatArray:
    co = cosine(b)
    return co if isinstance(source, CollimatedSource) else np.ones_like(co)


def geometric_checked(
    source: Source, optics: DetectorOptics, a: FloatArray, b: FloatArray
) -> FloatArray:
    """`geometric_factor` of a checked, broadcast direction pair."""
    return np.asarray(
        prefactor_checked(source, optics, a) * view_weight_checked(source, b) * optics.aperture_sr,
        dtype=np.float64,
    )


def radiant_power_checked(
    source: Source, optics: DetectorOptics, f: ArrayLike, a: FloatArray, b: FloatArray
) -> FloatArray:
    """`radiant_power` of a checked, broadcast direction pair."""
    g = geometric_checked(source, optics, a, b)
    values = np.asarray(f, dtype=np.float64)
    return np.asarray(values * spread(values, g), dtype=np.float64)


def brdf_from_power(
    power: ArrayLike,
    source: Source,
    optics: DetectorOptics,
    wi: ArrayLike,
    wo: ArrayLike,
    *,
    fill: float = 0.0,
) -> FloatArray:
    """f = Φ / G (sr⁻¹), the inverse of `radiant_power`; ``fill`` where G = 0 (a grazing
    direction: the measurement carries no information about f there)."""
    g = geometric_factor(source, optics, wi, wo)
    p = np.asarray(power, dtype=np.float64)
    gs = spread(p, g)
    return np.asarray(np.where(gs > 0.0, p / np.where(gs > 0.0, gs, 1.0), fill), dtype=np.float64)


def electrons(power_w: ArrayLike, exposure_s: ArrayLike, responsivity_a_w: ArrayLike) -> FloatArray:
    """Photo-electrons N = Φ t R / q for power Φ (W), exposure t (s), responsivity R (A/W)."""
    t = positive_array("exposure_s", exposure_s)
    r = positive_array("responsivity_a_w", responsivity_a_w)
    return np.asarray(np.asarray(power_w, dtype=np.float64) * t * r / ELEMENTARY_CHARGE)


def power_from_electrons(
    electrons: ArrayLike, exposure_s: ArrayLike, responsivity_a_w: ArrayLike
) -> FloatArray:
    """Φ = N q / (t R) (W), the inverse of `electrons`."""
    t = positive_array("exposure_s", exposure_s)
    r = positive_array("responsivity_a_w", responsivity_a_w)
    return np.asarray(np.asarray(electrons, dtype=np.float64) * ELEMENTARY_CHARGE / (t * r))


def signal_rate(
    counts: ArrayLike, exposure_s: ArrayLike, dark_counts: ArrayLike = 0.0
) -> FloatArray:
    """Dark-subtracted signal rate (counts/s): (counts − dark) / t."""
    t = positive_array("exposure_s", exposure_s)
    c = np.asarray(counts, dtype=np.float64)
    return np.asarray((c - np.asarray(dark_counts, dtype=np.float64)) / t, dtype=np.float64)
