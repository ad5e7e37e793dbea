"""The detector's sensor: expected photo-electrons → ADC counts, with opt-in effects.

The radiometric chain (``gonio.radiometry``) says how many signal electrons a sample's
exposure is expected to produce; this module turns them into what the detector reports.
Each effect is applied only when the scene lists it (`SensorEffects`), in the order the
charge meets them (docs/explanations/sensor.md has the equations):

1. dark current: ``dark_current_e_s · t`` electrons join the signal;
2. shot noise: signal and dark electrons are Poisson with those means (streams `SHOT`
   and `DARK`), otherwise they are their expected values;
3. saturation: the well holds at most ``full_well_e`` electrons; fuller ones are clipped
   and flagged;
4. read noise: the amplifier adds N(0, read_noise_e²) electrons (stream `READ`);
5. conversion: counts = electrons / gain, gain = full_well_e / (2**adc_bits − 1);
6. quantization: the ADC rounds to the nearest code in [0, max_count]; with saturation
   on, a code at max_count is flagged too.

With no effects a reading is ``signal_e / gain`` exactly: no draws, no clipping. Every
random number comes from `sim.virtual.physics.streams.Streams`, keyed by the sample's index and the
exposure's position among its A averages, so a sample reads the same alone or in a batch
and a resumed run equals an uninterrupted one.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass, fields
from typing import NamedTuple, Self

import numpy as np
from numpy.typing import ArrayLike, NDArray

from drivers.values import Reading
from gonio.errors import DomainError
from sim.virtual.physics.streams import DARK, READ, SHOT, Streams

__all__ = ["SensorEffects", "SensorSpec", "Summary", "read_out", "readings", "summarize"]

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

#: ADC resolutions accepted (codes must stay exact integers in float64).
MAX_ADC_BITS = 32


@dataclass(frozen=True)
class SensorSpec:
    """A sensor's electrical constants.

    ``full_well_e``: electrons a pixel (well) holds, > 0; ``adc_bits``: ADC resolution,
    1 to 32, the full well maps to the top code; ``read_noise_e``: the amplifier's noise,
    electrons rms, ≥ 0; ``dark_current_e_s``: thermal electrons per second, ≥ 0.
    """

    full_well_e: float
    adc_bits: int
    read_noise_e: float
    dark_current_e_s: float

    def __post_init__(self) -> None:
        if isinstance(self.adc_bits, bool) or not isinstance(self.adc_bits, int | np.integer):
            raise TypeError(f"adc_bits must be an int, got {self.adc_bits!r}")
        if not 1 <= self.adc_bits <= MAX_ADC_BITS:
            raise DomainError(f"adc_bits must be in [1, {MAX_ADC_BITS}], got {self.adc_bits}")
        _check_real("full_well_e", self.full_well_e, positive=True)
        _check_real("read_noise_e", self.read_noise_e)
        _check_real("dark_current_e_s", self.dark_current_e_s)

    @property
    def max_count(self) -> int:
        """The top ADC code, 2**adc_bits − 1."""
        return (1 << int(self.adc_bits)) - 1

    @property
    def gain_e_per_count(self) -> float:
        """Electrons per count: the full well spans the ADC's range."""
        return float(self.full_well_e) / self.max_count


def _check_real(name: str, value: object, *, positive: bool = False) -> None:
    if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
        raise TypeError(f"{name} must be a number, got {value!r}")
    number = float(value)
    if not math.isfinite(number) or number < 0.0 or (positive and number == 0.0):
        raise DomainError(f"{name} must be finite and {'> 0' if positive else '>= 0'}, got {value}")


@dataclass(frozen=True)
class SensorEffects:
    """Which sensor effects to model (each off unless asked for)."""

    shot_noise: bool = False
    read_noise: bool = False
    dark_current: bool = False
    quantization: bool = False
    saturation: bool = False

    @classmethod
    def none(cls) -> Self:
        """No effect: readings are the exact expected counts."""
        return cls()

    @classmethod
    def all(cls) -> Self:
        """Every sensor effect."""
        return cls(**dict.fromkeys(cls.names(), True))

    @classmethod
    def names(cls) -> tuple[str, ...]:
        """The effect names, as a scene's ``effects`` list spells them."""
        return tuple(f.name for f in fields(cls))

    @classmethod
    def from_names(cls, names: Iterable[str]) -> Self:
        """The sensor effects among ``names`` (a scene's effect list; names of other
        effects, e.g. ``source_drift``, are left to their own modules)."""
        wanted = set(names)
        return cls(**{name: name in wanted for name in cls.names()})

    @property
    def random(self) -> bool:
        """Whether any effect draws random numbers."""
        return self.shot_noise or self.read_noise


def read_out(
    signal_e: ArrayLike,
    exposure_s: ArrayLike,
    spec: SensorSpec,
    effects: SensorEffects,
    streams: Streams,
    index: ArrayLike,
    *,
    start: int = 0,
) -> tuple[FloatArray, BoolArray]:
    """What the sensor reports for A exposures of each of N samples.

    ``signal_e`` (N, A): expected signal electrons of each exposure; ``exposure_s`` (N,)
    or a scalar: seconds per exposure; ``index`` (N,) (or a scalar when N = 1): the
    samples' indices, which key their random streams (draw ``start`` + a of a stream goes
    to exposure a: a sample measured again continues its streams with ``start`` past the
    draws already used). Returns ``counts`` (N, A) float64 and ``saturated`` (N, A) bool.
    Only the effects in ``effects`` are applied (see the module docstring); with none, ``counts`` is
    ``signal_e / gain`` exactly and ``saturated`` is all False.
    """
    signal = np.asarray(signal_e, dtype=np.float64)
    if signal.ndim != 2:
        raise DomainError(f"signal_e must have shape (N, A), got {signal.shape}")
    n, a = signal.shape
    if signal.size and not (signal.min() >= 0.0 and signal.max() < math.inf):
        raise DomainError("signal_e must be finite and >= 0")
    t = np.asarray(exposure_s, dtype=np.float64)
    if t.shape not in ((), (n,)):
        raise DomainError(f"exposure_s must be a scalar or have shape ({n},), got {t.shape}")
    if t.size and not (t.min() >= 0.0 and t.max() < math.inf):
        raise DomainError("exposure_s must be finite and >= 0")
    idx = np.asarray(index)
    if idx.ndim == 0 and n == 1:
        idx = idx.reshape(1)
    if idx.shape != (n,):
        raise DomainError(f"index must have shape ({n},), got {idx.shape}")

    full_well = float(spec.full_well_e)
    cap = _poisson_cap(full_well) if effects.saturation else math.inf
    electrons = signal
    if effects.shot_noise:
        mean = np.minimum(signal, cap) if signal.size and signal.max() > cap else signal
        electrons = streams.poisson(idx, SHOT, mean, start=start)
    if effects.dark_current:
        dark = np.empty((n, a))
        dark[:] = (float(spec.dark_current_e_s) * t).reshape(-1, 1)
        if effects.shot_noise:
            if dark.size and dark.max() > cap:
                np.minimum(dark, cap, out=dark)
            dark = streams.poisson(idx, DARK, dark, start=start)
        electrons = electrons + dark
    if effects.saturation:
        saturated = electrons >= full_well
        electrons = np.minimum(electrons, full_well)
    else:
        saturated = np.zeros((n, a), dtype=bool)
    if effects.read_noise:
        electrons = electrons + float(spec.read_noise_e) * streams.normal(idx, READ, a, start=start)
    counts = electrons / spec.gain_e_per_count
    if effects.quantization:
        top = float(spec.max_count)
        counts = np.rint(counts)
        np.maximum(counts, 0.0, out=counts)
        np.minimum(counts, top, out=counts)
        if effects.saturation:
            saturated |= counts >= top
    return counts, saturated


def _poisson_cap(full_well: float) -> float:
    """A mean above which a Poisson count is ≥ ``full_well`` for every uniform the
    streams can produce (P < Φ(−10) ≈ 1e-23 < 2⁻⁵³), so with saturation on, capping the
    mean there changes no reading (the quantile is monotone in the mean), and means beyond
    float64's integer range are harmless."""
    return full_well + 10.0 * math.sqrt(full_well) + 100.0


class Summary(NamedTuple):
    """Per-sample statistics of A exposures, the fields of `drivers.values.Reading`."""

    value: FloatArray
    """Mean counts (N,)."""
    std: FloatArray
    """Sample standard deviation (ddof = 1) of the A counts, 0 when A = 1 (N,)."""
    n: NDArray[np.int64]
    """A, per sample (N,)."""
    saturated: BoolArray
    """Whether any exposure saturated (N,)."""


def summarize(counts: ArrayLike, saturated: ArrayLike) -> Summary:
    """Mean, std (ddof = 1, or 0 for one exposure), count and any-saturated per sample
    of ``counts`` / ``saturated`` (N, A), as `read_out` returns them."""
    c = np.asarray(counts, dtype=np.float64)
    s = np.asarray(saturated, dtype=bool)
    if c.ndim != 2 or s.shape != c.shape:
        raise DomainError(f"counts and saturated must both be (N, A), got {c.shape}, {s.shape}")
    n, a = c.shape
    if a == 0:
        raise DomainError("a reading needs at least one exposure (A >= 1)")
    value = c.mean(axis=1) if a > 1 else c[:, 0].copy()
    std = c.std(axis=1, ddof=1) if a > 1 else np.zeros(n)
    return Summary(value, std, np.full(n, a, dtype=np.int64), np.asarray(s.any(axis=1)))


def readings(
    counts: ArrayLike, saturated: ArrayLike, started_s: ArrayLike, ended_s: ArrayLike
) -> list[Reading]:
    """One `drivers.values.Reading` per sample (with the raw counts), stamped with the
    times (s) its first exposure started and its last ended (N,)."""
    c = np.asarray(counts, dtype=np.float64)
    summary = summarize(c, saturated)
    n = len(c)
    started = np.broadcast_to(np.asarray(started_s, dtype=np.float64), (n,))
    ended = np.broadcast_to(np.asarray(ended_s, dtype=np.float64), (n,))
    return [
        Reading(value=v, std=sd, n=k, saturated=sat, started_s=t0, ended_s=t1, raw=tuple(raw))
        for v, sd, k, sat, t0, t1, raw in zip(
            summary.value.tolist(),
            summary.std.tolist(),
            summary.n.tolist(),
            summary.saturated.tolist(),
            started.tolist(),
            ended.tolist(),
            c.tolist(),
            strict=True,
        )
    ]
