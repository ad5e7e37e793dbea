"""The simulated photometer's sensor: what one exposure reads (counts) from the signal,
with noise, dark counts and gain, clipped at full scale; and a ``MEAS``'s answer."""

from __future__ import annotations

import random
import statistics
from collections.abc import Callable

Signal = float | Callable[[float], float]


class Sensor:
    """The counts of an exposure: ``signal`` (counts/s, times the exposure; or a callable
    taking the exposure in s and giving its counts) plus Gaussian noise of ``noise_std``
    counts (from ``random.Random(seed)``) and ``dark`` counts, times the gain, clipped
    to ``full_scale`` (None: never) with the saturated flag."""

    def __init__(
        self, signal: Signal, noise_std: float, dark: float, full_scale: float | None, seed: int
    ) -> None:
        self.signal = signal
        self.noise_std = noise_std
        self.dark = dark
        self.full_scale = full_scale
        self._rng = random.Random(seed)

    def counts(self, exposure_s: float, gain: int) -> tuple[float, bool]:
        """One exposure of ``exposure_s`` (s): its counts and whether it saturated."""
        signal = self.signal
        counts = float(signal(exposure_s)) if callable(signal) else signal * exposure_s
        return self.scaled(counts, False, gain)

    def scaled(self, counts: float, saturated: bool, gain: int) -> tuple[float, bool]:
        """Noise, dark and gain added to a signal's ``counts``; clipped at full scale."""
        if saturated and self.full_scale is not None:
            return self.full_scale, True
        if self.noise_std:
            counts += self._rng.gauss(0.0, self.noise_std)
        counts = (counts + self.dark) * gain
        if self.full_scale is not None and counts >= self.full_scale:
            return self.full_scale, True
        return counts, False

    def answer(self, exposure_s: float, count: int, gain: int) -> str:
        """A ``MEAS``'s answer: ``VAL`` of one exposure, or the mean and standard
        deviation of ``count``; ``ERR signal failed`` when the signal raises."""
        values: list[float] = []
        saturated = False
        for _ in range(count):
            try:
                counts, sat = self.counts(exposure_s, gain)
            except Exception as exc:  # a test's signal ran out of values, say
                return f"ERR signal failed: {type(exc).__name__}"
            saturated = saturated or sat
            values.append(counts)
        status = "SAT" if saturated else "OK"
        if count == 1:
            return f"VAL {values[0]!r} {status}"
        mean, std = statistics.fmean(values), statistics.stdev(values)
        return f"VAL {mean!r} {status} {std!r}"
