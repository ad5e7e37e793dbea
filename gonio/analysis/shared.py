"""The error a run's values share through its reference readings.

Every value of a run is divided by the reference rate S(t) interpolated in run time
between the K calibration readings (`CalibrationSeries.weights`, linear in the
readings), so an error δ_k in reading k moves sample i by −w_ik δ_k/S_k of its value,
w_ik its interpolation weight. The samples' σ count that error as their own, independent
of the others'; a fit needs it as what it is, one error shared by every sample near
reading k. The dark readings' random errors are additive, small against the signal, and
are left to σ; their rounding to ADC codes is not random from reading to reading
(`gonio.radiometry.series.rounding_var`): one error δ of the dark rate, shared by every
reading and every sample, moves sample i by (s_i − S)/(S s_i)·δ of its value (s_i its
dark-subtracted rate: it enters s_i and S alike), a last column of the weights.

Over many simulated runs the scale error this predicts is the one measured
(`studies/calibration.py`, docs/results/calibration.md).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gonio.analysis.calibrated import Calibrated, calibrate, readings
from gonio.analysis.measured import kept
from gonio.radiometry import CalibrationSeries
from gonio.store import Run, open_run
from gonio.types import FloatArray


@dataclass(frozen=True)
class SharedError:
    """``weights`` (N, K): each sample's reference rate as a combination of the K
    readings; ``relative`` (K,): each reading's relative 1σ (an error of column k moves
    sample i by weights[i, k]·relative[k] of its value). With dark readings rounded to
    ADC codes, one more column: each sample's share of their common rounding error
    (module docstring), relative 1."""

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
    series = calibrated.series
    rate = readings(run)[0][keep] / s["exposure_s"][keep] - series.dark_at(t)
    return calibration_error(series, t, rate)


def calibration_error(
    series: CalibrationSeries, t: FloatArray, rate: FloatArray | None = None
) -> SharedError:
    """The shared error of values divided by ``series``' reference rate S(t) at run
    times ``t`` (s, (N,)); ``rate`` (counts/s, (N,)): the values' own dark-subtracted
    rates (None: values exact, only S(t) in error)."""
    weights = series.weights(t)
    relative = np.sqrt(series.rate_var) / series.rate
    rounding = series.dark_rounding_at(t)
    if np.any(rounding > 0):
        big_s = weights @ series.rate
        share = rounding / big_s
        if rate is not None:
            own = np.asarray(rate, dtype=np.float64)
            share = share * (own - big_s) / np.where(own != 0, own, np.inf)
        weights = np.column_stack([weights, share])
        relative = np.append(relative, 1.0)
    return SharedError(
        weights=np.asarray(weights, dtype=np.float64),
        relative=np.asarray(relative, dtype=np.float64),
    )
