"""The error a run's values share through its reference readings.

Every value of a run is divided by the reference rate S(t) interpolated linearly in
run time between the K calibration readings (`gonio.analysis.calibrated`), so an error
δ_k in reading k moves sample i by −w_ik δ_k/S_k of its value, w_ik its interpolation
weight. The samples' σ count that error as their own, independent of the others'; a fit
needs it as what it is, one error shared by every sample near reading k. The dark
readings' errors are additive, small against the signal, and are left to σ.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gonio.analysis.calibrated import Calibrated, calibrate
from gonio.analysis.measured import kept
from gonio.radiometry.series import CalibrationSeries
from gonio.store.read import Run, open_run
from gonio.types import FloatArray


@dataclass(frozen=True)
class SharedError:
    """``weights`` (N, K): each sample's reference rate as a combination of the K
    readings; ``relative`` (K,): each reading's relative 1σ."""

    weights: FloatArray
    relative: FloatArray

    def __len__(self) -> int:
        return len(self.weights)

    @classmethod
    def common(cls, samples: int, relative: float) -> SharedError:
        """One scale error shared by all ``samples`` alike."""
        return cls(np.ones((samples, 1)), np.array([float(relative)]))

    def take(self, index: slice | np.ndarray) -> SharedError:
        """The rows of the samples ``index`` picks."""
        return SharedError(self.weights[index], self.relative)


def shared_error(run: Run | str, calibrated: Calibrated | None = None) -> SharedError:
    """The shared calibration error of a run's samples, in the order and selection of
    `gonio.analysis.measured.Measured.from_run` (`kept`); ``calibrated``: the run's
    `calibrate`, when the caller has it already."""
    if not isinstance(run, Run):
        run = open_run(run)
    calibrated = calibrate(run) if calibrated is None else calibrated
    keep = kept(calibrated)
    s = run.samples
    t = (0.5 * (s["started_s"] + s["ended_s"]))[keep]
    return calibration_error(calibrated.series, t)


def calibration_error(series: CalibrationSeries, t: FloatArray) -> SharedError:
    """The shared error of values divided by ``series``' reference rate interpolated at
    run times ``t`` (s, (N,))."""
    k = len(series.t)
    eye = np.eye(k)
    weights = np.stack([np.interp(t, series.t, eye[j]) for j in range(k)], axis=1)
    return SharedError(
        weights=np.asarray(weights, dtype=np.float64),
        relative=np.asarray(np.sqrt(series.rate_var) / series.rate, dtype=np.float64),
    )
