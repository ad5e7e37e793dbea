"""The calibration's scale error over many seeds, fast: the reference standard and dark
readings a run's calibrations take, simulated vectorized (`sim.virtual.simulate.simulate_standard`,
the engine's readings bit for bit), journaled as the engine journals them, turned into
the run's `CalibrationSeries` by `gonio.analysis.calibrated.calibration_series`, and
compared with the reference rate the simulator knows.

The scale error of a run is the mean over its samples (``samples`` run times spread
evenly between the first and the last calibration) of S_true(t)/S(t) − 1, S(t) the
interpolated reference rate every value is divided by; its predicted 1σ comes from
`gonio.analysis.shared.calibration_error` (the weights averaged over the samples, the
readings' relative errors).

The dark readings' rounding to ADC codes is an error shared by every calibration of a
run, whose variance is its mean square over where the dark level lies within its code
(`gonio.radiometry.series.rounding_var`): with ``dark_step`` the dark current is raised
per seed by a uniform fraction of one code, so the seeds sample that position as the
variance assumes (a shipped scene's dark level sits at one place, the same every seed).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np

from gonio.acquire.reference import CALIBRATION_INDEX, reference_pose
from gonio.analysis.calibrated import calibration_series
from gonio.analysis.shared import calibration_error
from gonio.radiometry.series import CalibrationSeries, student_variance
from gonio.rig.model import Rig
from gonio.scene import Scene
from gonio.store.read import Event
from gonio.types import FloatArray
from sim.virtual.devices.detector import sensor_of
from sim.virtual.physics.optics import SceneOptics
from sim.virtual.physics.sensor import Summary
from sim.virtual.simulate import expected_rate, simulate_standard


class _Optics(SceneOptics):
    """The scene's optics with the (seed-free) geometric power of each pose kept."""

    def __init__(self, scene: Scene, rig: Rig) -> None:
        super().__init__(scene, rig)
        self._kept: dict[tuple[float, ...], FloatArray] = {}

    def geometric_power(self, wi: FloatArray, wo: FloatArray, target: str = "sample") -> FloatArray:
        key = (*np.ravel(wi).tolist(), *np.ravel(wo).tolist(), float(target == "sample"))
        if key not in self._kept:
            self._kept[key] = super().geometric_power(wi, wo, target)  # type: ignore[arg-type]
        return self._kept[key]


@dataclass(frozen=True)
class ScaleErrors:
    """Per seed: the run's scale error and its predicted 1σ."""

    error: FloatArray
    sigma: FloatArray
    #: The same runs under the former model (`linear`), when asked for.
    linear: ScaleErrors | None = None
    #: The same runs' σ from the pooled noise model as estimated, without Student's
    #: factor ν/(ν − 2) (`gonio.analysis.calibrated.noise_model`).
    unexpanded: FloatArray | None = None

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
    optics: SceneOptics | None = None,
) -> tuple[Event, ...]:
    """The ``calibration`` events of a run calibrated ``calibrations`` times, every
    ``interval_s`` s (each a reference reading, then a dark reading right after)."""
    pose = reference_pose(rig)
    wi, wo = rig.forward(pose[None, :])
    busy = (exposure_s + rig.spec.detector.readout_s) * averages
    k = np.arange(calibrations)
    start = np.asarray(1.0 + interval_s * k, dtype=np.float64)
    ref = simulate_standard(
        rig,
        scene,
        pose,
        start,
        exposure_s,
        averages,
        CALIBRATION_INDEX + 2 * k,
        seed=seed,
        optics=optics,
    )
    dark_start = np.asarray(start + busy + rig.spec.settle_s, dtype=np.float64)
    off = simulate_standard(
        rig,
        scene,
        pose,
        dark_start,
        exposure_s,
        averages,
        CALIBRATION_INDEX + 2 * k + 1,
        seed=seed,
        light_on=False,
        optics=optics,
    )
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
    rig: Rig,
    scene: Scene,
    seeds: range,
    *,
    samples: int = 50,
    dark_step: bool = False,
    linear: bool = False,
    **schedule: Any,
) -> ScaleErrors:
    """The scale error and its predicted σ of one simulated run per seed (the module);
    ``schedule``: `calibration_events`' keywords; ``linear``: also under the former
    model (`linear_model`)."""
    pose = reference_pose(rig)
    optics = _Optics(scene, rig)
    exposure = float(schedule.get("exposure_s", 0.05))
    code_e_s = sensor_of(scene)[0].gain_e_per_count / exposure  # one code of dark, e/s
    errors, sigmas, before, bare = [], [], [], []
    for seed in seeds:
        run_scene = scene
        if dark_step:
            step = np.random.default_rng([seed, 1]).uniform()
            current = scene.detector.dark_current_e_s + step * code_e_s
            detector = scene.detector.model_copy(update={"dark_current_e_s": current})
            run_scene = scene.model_copy(update={"detector": detector})
        events = calibration_events(rig, run_scene, seed, optics=optics, **schedule)
        series = calibration_series(events)
        t = np.linspace(series.t[0], series.t[-1], samples)
        truth = expected_rate(rig, scene, pose, t, optics=optics)
        errors.append(float(np.mean(truth / series.rate_at(t) - 1.0)))
        shared = calibration_error(series, t)
        mean_weights = shared.weights.mean(axis=0)
        sigmas.append(float(np.sqrt(np.sum((mean_weights * shared.relative) ** 2))))
        bare.append(_unexpanded(series, t))
        if linear:
            before.append(linear_model(series, events, t, truth))
    former = None
    if linear:
        former = ScaleErrors(np.array([b[0] for b in before]), np.array([b[1] for b in before]))
    return ScaleErrors(np.array(errors), np.array(sigmas), former, np.array(bare))


def _unexpanded(series: CalibrationSeries, t: FloatArray) -> float:
    """The scale's σ with the readings' variances divided by Student's factor again (the
    darks' degrees of freedom those of the references, as `calibration_events` takes
    them: one factor for both)."""
    factor = student_variance(series.noise_dof)
    bare = dataclasses.replace(series, rate_var=series.rate_var / factor)
    shared = calibration_error(bare, t)
    return float(np.sqrt(np.sum((shared.weights.mean(axis=0) * shared.relative) ** 2)))


def linear_model(
    series: CalibrationSeries, events: tuple[Event, ...], t: FloatArray, truth: FloatArray
) -> tuple[float, float]:
    """(scale error, predicted σ) as the calibration had them before the spline, the
    dark's rounding term and the pooled noise model: S(t) interpolated linearly between
    the readings, each reading's error from its own spread and its dark's, the only one."""
    k = len(series.t)
    eye = np.eye(k)
    weights = np.stack([np.interp(t, series.t, eye[j]) for j in range(k)], axis=1)
    error = float(np.mean(truth / (weights @ series.rate) - 1.0))
    own = []
    for e in events:
        r, d = e.data["reference"], e.data["dark"]
        dark = 0.0 if d is None else d["std"] ** 2 / d["n"]
        own.append((r["std"] ** 2 / r["n"] + dark) / r["exposure_s"] ** 2)
    relative = np.sqrt(own) / series.rate
    return error, float(np.sqrt(np.sum((weights.mean(axis=0) * relative) ** 2)))
