"""Calibration against a Lambertian reference: detector signal → BRDF without knowing
the instrument's constants.

A reference of albedo ρ (f = ρ/π) measured at (wi_ref, wo_ref) gives a dark-subtracted
signal rate s_ref (counts/s). The signal rate is s = f · G · R · g_adc / q, with
G = K c Ω the geometric factor of `gonio.radiometry.ideal`; every instrument constant
(E0 or I, D or F, Ω, responsivity R, ADC gain) is common to both readings, so

    f(wi, wo) = (ρ/π) · (s / s_ref) · (g(wi_ref, wo_ref) / g(wi, wo))

with g the geometric dependence left in G: cos θo for a collimated beam, cos θi for a
point source (whose 1/r² is the same for both readings: same source, same distance).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TypeAlias

import numpy as np

from gonio.errors import DomainError
from gonio.radiometry._checks import cosine, direction, direction_pair, positive, spread
from gonio.radiometry.ideal import SourceKind, signal_rate
from gonio.types import ArrayLike, FloatArray

#: A grey value or an RGB triple.
Channels: TypeAlias = float | tuple[float, float, float]


def relative_geometry(kind: SourceKind, wi: ArrayLike, wo: ArrayLike) -> FloatArray:
    """g: the direction dependence of G at fixed instrument (cos θo collimated, cos θi
    point), shape broadcast(wi, wo)[:-1]."""
    a, b = direction_pair(wi, wo)
    if kind == "collimated":
        return cosine(b)
    if kind == "point":
        return cosine(a)
    raise DomainError(f"source_kind must be 'collimated' or 'point', got {kind!r}")


def _channels(name: str, value: object, *, high: float = math.inf) -> Channels:
    if isinstance(value, tuple | list | np.ndarray):
        items = [positive(f"{name}[{j}]", x) for j, x in enumerate(np.ravel(value))]
        if len(items) != 3:
            raise DomainError(f"{name} must be a number or 3 numbers, got {value!r}")
        if max(items) > high:
            raise DomainError(f"{name} must be ≤ {high}, got {max(items)}")
        return (items[0], items[1], items[2])
    v = positive(name, value)
    if v > high:
        raise DomainError(f"{name} must be ≤ {high}, got {v}")
    return v


def _unit(name: str, value: object) -> tuple[float, float, float]:
    try:
        w = direction(name, np.asarray(value, dtype=np.float64))
    except (TypeError, ValueError) as err:
        if isinstance(err, DomainError):
            raise
        raise DomainError(f"{name} must be 3 numbers, got {value!r}") from None
    if w.shape != (3,):
        raise DomainError(f"{name} must be one direction of shape (3,), got shape {w.shape}")
    return (float(w[0]), float(w[1]), float(w[2]))


@dataclass(frozen=True)
class ReferenceCalibration:
    """A Lambertian reference of albedo ρ ∈ (0, 1] read at (wi, wo) with dark-subtracted
    signal rate s_ref > 0 (counts/s); grey, or RGB (3-tuples) for a 3-channel detector.

    `brdf` turns a sample's signal rate at (wi, wo) into f (sr⁻¹), see the module.
    """

    albedo: Channels
    signal_rate: Channels
    wi: tuple[float, float, float]
    wo: tuple[float, float, float]
    source_kind: SourceKind

    def __post_init__(self) -> None:
        object.__setattr__(
            self, "albedo", _channels("ReferenceCalibration.albedo", self.albedo, high=1.0)
        )
        object.__setattr__(
            self, "signal_rate", _channels("ReferenceCalibration.signal_rate", self.signal_rate)
        )
        object.__setattr__(self, "wi", _unit("ReferenceCalibration.wi", self.wi))
        object.__setattr__(self, "wo", _unit("ReferenceCalibration.wo", self.wo))
        if self.source_kind not in ("collimated", "point"):
            raise DomainError(
                "ReferenceCalibration.source_kind must be 'collimated' or 'point', "
                f"got {self.source_kind!r}"
            )
        if self.reference_geometry <= 0.0:
            raise DomainError(
                "ReferenceCalibration: the reference geometry is grazing "
                f"(g = 0 for a {self.source_kind} source): it carries no signal"
            )

    @classmethod
    def from_counts(
        cls,
        albedo: Channels,
        counts: ArrayLike,
        exposure_s: float,
        wi: ArrayLike,
        wo: ArrayLike,
        source_kind: SourceKind,
        dark_counts: ArrayLike = 0.0,
    ) -> ReferenceCalibration:
        """The calibration from a raw reading: s_ref = (counts − dark) / exposure."""
        rate = signal_rate(counts, exposure_s, dark_counts).ravel()
        if rate.size not in (1, 3):
            raise DomainError(f"reference counts must be 1 or 3 values, got {rate.size}")
        value: Channels = (
            float(rate[0]) if rate.size == 1 else (float(rate[0]), float(rate[1]), float(rate[2]))
        )
        return cls(albedo, value, _unit("wi", wi), _unit("wo", wo), source_kind)

    @property
    def reference_geometry(self) -> float:
        """g(wi_ref, wo_ref)."""
        return float(relative_geometry(self.source_kind, self.wi, self.wo))

    def brdf(
        self, signal_rate: ArrayLike, wi: ArrayLike, wo: ArrayLike, *, fill: float = 0.0
    ) -> FloatArray:
        """f = (ρ/π)(s/s_ref)(g_ref/g) (sr⁻¹) for dark-subtracted rates s (counts/s) of
        shape broadcast(wi, wo)[:-1] (+ (3,) for RGB); ``fill`` where g = 0."""
        g = relative_geometry(self.source_kind, wi, wo)
        s = np.asarray(signal_rate, dtype=np.float64)
        gs = spread(s, g)
        scale = (
            np.asarray(self.albedo, dtype=np.float64)
            / math.pi
            * self.reference_geometry
            / np.asarray(self.signal_rate, dtype=np.float64)
        )
        value = s * scale / np.where(gs > 0.0, gs, 1.0)
        return np.asarray(np.where(gs > 0.0, value, fill), dtype=np.float64)

    def brdf_from_counts(
        self,
        counts: ArrayLike,
        exposure_s: ArrayLike,
        wi: ArrayLike,
        wo: ArrayLike,
        dark_counts: ArrayLike = 0.0,
        *,
        fill: float = 0.0,
    ) -> FloatArray:
        """`brdf` of the rate (counts − dark) / exposure."""
        return self.brdf(signal_rate(counts, exposure_s, dark_counts), wi, wo, fill=fill)
