"""`SimRun`: what a simulated acquisition produced, target by target (arrays)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gonio.types import FloatArray


@dataclass(frozen=True)
class SimRun:
    """Per target, in measuring order: the stream index, the joint angles commanded,
    read back (encoder) and true (what the optics saw), the pair actually measured
    (from the true angles), virtual times, and the reading. Angles rad, times s,
    readings in counts."""

    index: np.ndarray  # (N,) int64
    commanded: FloatArray  # (N, A)
    read_back: FloatArray  # (N, A)
    true: FloatArray  # (N, A)
    wi: FloatArray  # (N, 3)
    wo: FloatArray  # (N, 3)
    exposure_s: FloatArray  # (N,)
    averages: np.ndarray  # (N,)
    settled_s: FloatArray  # (N,) when the motors had settled (exposures start)
    end_s: FloatArray  # (N,) when the last exposure of the target ended
    value: FloatArray  # (N,) mean counts
    std: FloatArray  # (N,)
    saturated: np.ndarray  # (N,) bool

    def __len__(self) -> int:
        return len(self.index)

    @property
    def instrument_time_s(self) -> float:
        """Virtual time from the start of the run to the end of its last exposure."""
        return float(self.end_s[-1]) if len(self) else 0.0
