"""A lock-in amplifier behind a chopped source: what it reads of a photodiode's signal,
with the sensor's noise, through its output filter, and when it overloads.

The chopper passes the light for ``duty`` of each period; the photodiode's current is
then a square wave between the background ``B`` (dark current and ambient light, e/s)
and ``S + B`` (``S``: the source's signal while open, e/s). The lock-in multiplies it by
its reference and low-pass filters it with ``slope_db_oct`` / 6 cascaded RC stages of
time constant τ; its output R is the rms amplitude of the fundamental,
``√2 sin(π duty) / π · S`` (0.450 S at 50 %): the background, constant, is rejected.
The shot noise of the whole current (one-sided density ``2 (duty S + B)`` (e/s)²/Hz)
passes the filter's equivalent noise bandwidth ENBW (1/4τ, 1/8τ, 3/32τ, 5/64τ at 6, 12,
18 and 24 dB/oct): X and Y each carry a Gaussian noise of σ = √(2 (duty S + B) ENBW),
and R = √(X² + Y²). A reading at or above the sensitivity's full scale overloads and is
clipped to 110 % of it. A reading is independent of the previous one when taken at
least the settle time apart (`drivers.pymeasure.config.settle_tau`: 10.1 τ at 24
dB/oct), which is what a reading costs.

Signals are in electrons per second; ``gain`` turns them into the instrument's unit
(V per e/s: the transimpedance times the elementary charge).

`read_out` is the same model vectorized over samples and their readings, for a scene
whose detector is a lock-in (``detector.kind: lockin``): the time constant the scene
gives, or the one the PyMeasure driver sets for the exposure (the longest whose settle
time, `drivers.pymeasure.SETTLE_TAU` τ, fits in it; continuous here, where the
instrument has a list); each reading then takes `reading_s` (the exposure, or the
settle time if longer). The scene's effects: ``shot_noise`` (the noise above, X and Y
from the streams' ``LOCKIN_X`` and ``LOCKIN_Y`` channels), ``dark_current`` (the
background B), ``saturation`` (the overload); ``read_noise`` and ``quantization`` are
an ADC's and do not apply. The reading's phase is atan2(Y, X) plus the scene's drift.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from drivers.pymeasure import SETTLE_TAU, settle_tau
from gonio.radiometry import ELEMENTARY_CHARGE
from gonio.scene import DetectorSpec
from gonio.types import FloatArray
from sim.virtual.physics.streams import LOCKIN_X, LOCKIN_Y, Streams

#: The equivalent noise bandwidth × τ of 1–4 cascaded RC stages.
ENBW_TAU = {6: 1 / 4, 12: 1 / 8, 18: 3 / 32, 24: 5 / 64}


@dataclass(frozen=True)
class LockIn:
    """A lock-in's settings (see the module docstring): ``time_constant_s`` (τ, s),
    ``slope_db_oct`` (6, 12, 18 or 24), ``sensitivity`` (full scale, in the output's
    unit), ``gain`` (output unit per e/s), the chopper's open fraction ``duty``."""

    time_constant_s: float
    sensitivity: float
    gain: float = 1.0
    slope_db_oct: int = 24
    duty: float = 0.5

    def __post_init__(self) -> None:
        if self.slope_db_oct not in ENBW_TAU:
            raise ValueError(f"slope_db_oct must be 6, 12, 18 or 24, got {self.slope_db_oct}")
        for name in ("time_constant_s", "sensitivity", "gain"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be > 0, got {value!r}")
        if not 0 < self.duty < 1:
            raise ValueError(f"duty must be in (0, 1), got {self.duty!r}")

    @property
    def enbw_hz(self) -> float:
        """The output filter's equivalent noise bandwidth (Hz)."""
        return ENBW_TAU[self.slope_db_oct] / self.time_constant_s

    @property
    def settle_s(self) -> float:
        """The time to 99 % of a step: the least spacing of independent readings (s)."""
        return settle_tau(self.slope_db_oct) * self.time_constant_s

    @property
    def fundamental(self) -> float:
        """R per unit of the open-chopper signal: the rms of the square wave's
        fundamental, √2 sin(π duty) / π."""
        return math.sqrt(2.0) * math.sin(math.pi * self.duty) / math.pi

    def expected(self, signal_e_s: float) -> float:
        """The noise-free R of a signal ``signal_e_s`` (e/s while open), output unit."""
        return self.gain * self.fundamental * signal_e_s

    def sigma(self, signal_e_s: float, background_e_s: float = 0.0) -> float:
        """The standard deviation of X (and of Y) from the shot noise, output unit."""
        mean_current = self.duty * signal_e_s + background_e_s
        return self.gain * math.sqrt(2.0 * max(mean_current, 0.0) * self.enbw_hz)

    def read(
        self,
        signal_e_s: float,
        background_e_s: float,
        rng: np.random.Generator,
        n: int = 1,
    ) -> tuple[np.ndarray, np.ndarray]:
        """``n`` independent readings of R (output unit) and whether each overloaded."""
        sigma = self.sigma(signal_e_s, background_e_s)
        x = self.expected(signal_e_s) + sigma * rng.standard_normal(n)
        y = sigma * rng.standard_normal(n)
        r = np.hypot(x, y)
        overloaded = r >= self.sensitivity
        return np.where(overloaded, 1.1 * self.sensitivity, r), overloaded

    def snr(self, signal_e_s: float, background_e_s: float = 0.0) -> float:
        """The signal-to-noise ratio of one reading (expected R over σ)."""
        sigma = self.sigma(signal_e_s, background_e_s)
        return math.inf if sigma == 0 else self.expected(signal_e_s) / sigma


def time_constant_s(spec: DetectorSpec, exposure_s: FloatArray) -> FloatArray:
    """τ (s) of readings of ``exposure_s`` (s): the scene's, or the longest whose settle
    time fits the exposure."""
    exposure = np.asarray(exposure_s, dtype=np.float64)
    if spec.time_constant_s is not None:
        return np.full_like(exposure, spec.time_constant_s)
    return exposure / SETTLE_TAU[spec.slope_db_oct]


def reading_s(spec: DetectorSpec, exposure_s: FloatArray) -> FloatArray:
    """How long one reading of ``exposure_s`` (s) takes (s): the exposure, or the output
    filter's settle time (`drivers.pymeasure.SETTLE_TAU` τ) when that is longer."""
    exposure = np.asarray(exposure_s, dtype=np.float64)
    settle = SETTLE_TAU[spec.slope_db_oct] * time_constant_s(spec, exposure)
    return np.maximum(exposure, settle)


def gain_v(spec: DetectorSpec) -> float:
    """Volts per e/s: the transimpedance times the elementary charge."""
    return spec.transimpedance_v_a * ELEMENTARY_CHARGE


def expected_v(spec: DetectorSpec, signal_e_s: FloatArray) -> FloatArray:
    """The noise-free R (V) of an open-chopper signal (e/s)."""
    fundamental = math.sqrt(2.0) * math.sin(math.pi * spec.duty) / math.pi
    return np.asarray(gain_v(spec) * fundamental * np.asarray(signal_e_s), dtype=np.float64)


def read_out(
    signal_e_s: FloatArray,
    exposure_s: FloatArray,
    t_mid_s: FloatArray,
    spec: DetectorSpec,
    effects: tuple[str, ...],
    streams: Streams,
    index: np.ndarray,
    *,
    start: int = 0,
) -> tuple[FloatArray, np.ndarray, FloatArray]:
    """A readings of each of N samples (module docstring): R (V), overloaded, and the
    phase (°), each (N, A), of open-chopper signals ``signal_e_s`` (e/s, (N, A)) read with
    exposures ``exposure_s`` (s, (N,)) at run times ``t_mid_s`` (s, (N, A)); ``index``
    (N,) the samples' random streams, from draw ``start``."""
    signal = np.asarray(signal_e_s, dtype=np.float64)
    n, a = signal.shape
    x = expected_v(spec, signal)
    y = np.zeros_like(x)
    if "shot_noise" in effects:
        background = spec.dark_current_e_s if "dark_current" in effects else 0.0
        enbw = ENBW_TAU[spec.slope_db_oct] / time_constant_s(spec, exposure_s)
        current = np.maximum(spec.duty * signal + background, 0.0)
        sigma = gain_v(spec) * np.sqrt(2.0 * current * np.asarray(enbw).reshape(-1, 1))
        idx = np.asarray(index, dtype=np.int64)
        x = x + sigma * streams.normal(idx, LOCKIN_X, a, start=start)
        y = sigma * streams.normal(idx, LOCKIN_Y, a, start=start)
    r = np.hypot(x, y)
    drift = spec.phase_drift_deg_per_hour * np.asarray(t_mid_s, dtype=np.float64) / 3600.0
    phase = (np.degrees(np.arctan2(y, x)) + drift + 180.0) % 360.0 - 180.0
    overloaded = np.zeros((n, a), dtype=np.bool_)
    if "saturation" in effects:
        assert spec.sensitivity_v is not None  # required for a lock-in by the scene
        overloaded = r >= spec.sensitivity_v
        r = np.where(overloaded, 1.1 * spec.sensitivity_v, r)
    return r, overloaded, phase
