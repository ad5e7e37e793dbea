"""The calibration's scale error over many seeds, fast: the reference standard and dark
readings a run's calibrations take, simulated vectorized (`sim.simulate.simulate_standard`,
the engine's readings bit for bit), journaled as the engine journals them, turned into
the run's `CalibrationSeries` by `gonio.analysis.calibrated.calibration_series`, and
compared with the reference rate the simulator knows.

The scale error of a run is the mean over its samples (``samples`` run times spread
evenly between the first and the last calibration) of S_true(t)/S(t) − 1, S(t) the
interpolated reference rate every value is divided by; its predicted 1σ comes from
`gonio.analysis.shared.calibration_error` (the weights averaged over the samples, the
readings' relative errors).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from gonio.acquire.reference import CALIBRATION_INDEX, reference_pose
from gonio.analysis.calibrated import calibration_series
from gonio.analysis.shared import calibration_error
from gonio.rig.model import Rig
from gonio.store.read import Event
from gonio.types import FloatArray
from sim.physics.sensor import Summary
from sim.scene import Scene
from sim.simulate import expected_rate, simulate_standard


@dataclass(frozen=True)
class ScaleErrors:
    """Per seed: the run's scale error and its predicted 1σ."""

    error: FloatArray
    sigma: FloatArray

    @property
    def z(self) -> FloatArray:
        return np.asarray(self.error / self.sigma, dtype=np.float64)

    def spread(self) -> dict[str, float]:
        """The z-scores' mean, standard deviation (ddof 1) and RMS about 0."""
        z = self.z
        return {
            "mean": float(np.mean(z)),
            "std": float(np.std(z, ddof=1)),
            "rms": float(np.sqrt(np.mean(z**2))),
        }


def _reading(summary: Summary, j: int, exposure: float, start: float, end: float) -> dict[str, Any]:
    return {
        "value": float(summary.value[j]),
        "n": int(summary.n[j]),
        "saturated": bool(summary.saturated[j]),
        "std": float(summary.std[j]),
        "exposure_s": exposure,
        "started_s": float(start),
        "ended_s": float(end),
    }


def calibration_events(
    rig: Rig,
    scene: Scene,
    seed: int,
    *,
    calibrations: int = 3,
    interval_s: float = 20.0,
    exposure_s: float = 0.05,
    averages: int = 16,
    dark: bool = True,
) -> tuple[Event, ...]:
    """The ``calibration`` events of a run calibrated ``calibrations`` times, every
    ``interval_s`` s (each a reference reading, then a dark reading right after)."""
    pose = reference_pose(rig)
    wi, wo = rig.forward(pose[None, :])
    busy = (exposure_s + rig.spec.detector.readout_s) * averages
    k = np.arange(calibrations)
    start = np.asarray(1.0 + interval_s * k, dtype=np.float64)
    ref = simulate_standard(
        rig, scene, pose, start, exposure_s, averages, CALIBRATION_INDEX + 2 * k, seed=seed
    )
    dark_start = np.asarray(start + busy + rig.spec.settle_s, dtype=np.float64)
    off = simulate_standard(
        rig, scene, pose, dark_start, exposure_s, averages, CALIBRATION_INDEX + 2 * k + 1,
        seed=seed, light_on=False,
    )  # fmt: skip
    events = []
    for j in range(calibrations):
        data = {
            "k": j,
            "albedo": rig.spec.reference.albedo,
            "source_kind": rig.source_kind,
            "wi": wi[0].tolist(),
            "wo": wo[0].tolist(),
            "reference": _reading(ref, j, exposure_s, start[j], start[j] + busy),
            "dark": (
                _reading(off, j, exposure_s, dark_start[j], dark_start[j] + busy) if dark else None
            ),
        }
        events.append(Event(j, 1, "calibration", None, float(start[j]), "", data))
    return tuple(events)


def scale_errors(
    rig: Rig, scene: Scene, seeds: range, *, samples: int = 50, **schedule: Any
) -> ScaleErrors:
    """The scale error and its predicted σ of one simulated run per seed (the module);
    ``schedule``: `calibration_events`' keywords."""
    pose = reference_pose(rig)
    errors, sigmas = [], []
    for seed in seeds:
        series = calibration_series(calibration_events(rig, scene, seed, **schedule))
        t = np.linspace(series.t[0], series.t[-1], samples)
        truth = expected_rate(rig, scene, pose, t)
        errors.append(float(np.mean(truth / np.interp(t, series.t, series.rate) - 1.0)))
        shared = calibration_error(series, t)
        mean_weights = shared.weights.mean(axis=0)
        sigmas.append(float(np.sqrt(np.sum((mean_weights * shared.relative) ** 2))))
    return ScaleErrors(np.array(errors), np.array(sigmas))
