"""A whole simulated session: the reference standard and a dark reading, the plan target
by target, the reference again, and the BRDF recovered through the calibration.

Everything goes through the `drivers.base` contract (`gonio.acquire`), as the engine
drives hardware: the reference standard read at the rig's calibration geometry before
and after (its exposure
halved until it does not saturate) with a dark reading (light off), the readings
carried back to BRDF values with directions from the read-back motor angles, the
source's drift divided out (`gonio.acquire.calibration`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from gonio.acquire.calibration import Calibration, read_dark, read_reference, reference_pose
from gonio.planner.plan import Plan
from gonio.types import FloatArray
from sim.devices.instrument import SimulatedInstrument
from sim.physics.optics import SceneOptics
from sim.record import SimRun
from sim.scene import Scene


@dataclass(frozen=True)
class Result:
    """A simulated run with its calibration and the BRDF it recovers."""

    plan: Plan
    scene: Scene
    run: SimRun
    wall_s: float
    calibration: Calibration
    brdf: FloatArray  # recovered at the read-back pairs
    truth: FloatArray  # the scene's model at the pairs actually measured
    wi: FloatArray  # from the read-back angles
    wo: FloatArray

    @property
    def reference_counts(self) -> float:
        """The first reading of the reference standard (counts)."""
        return self.calibration.first.value

    @property
    def reference_exposure_s(self) -> float:
        return self.calibration.exposure_s

    @property
    def reference_change(self) -> float:
        """Last / first dark-subtracted reference signal − 1 (the drift seen)."""
        return self.calibration.change

    @property
    def dark_rate(self) -> float:
        """Counts per second with the light off."""
        return self.calibration.dark_rate


def simulate_plan(plan: Plan, scene: Scene, seed: int | None = None) -> Result:
    """Measure ``plan`` in ``scene`` and recover the BRDF (see the module docstring)."""
    rig = plan.rig
    started = time.perf_counter()
    with SimulatedInstrument(scene, rig, seed=seed) as inst:
        devices = inst.devices()
        shortest, longest = devices.detector.exposure_range_s
        exposure = float(np.clip(np.median(plan.exposure_s), shortest, longest))
        pose = reference_pose(rig)
        first, exposure = read_reference(devices, rig, 0, pose, exposure)
        dark = read_dark(devices, rig, 1, pose, exposure)
        run = inst.run(plan)
        last, _ = read_reference(devices, rig, 2, pose, exposure)
    wall = time.perf_counter() - started
    calibration = Calibration.from_readings(rig, pose, exposure, first, dark, last)
    wi, wo = rig.forward(run.read_back)  # directions come from the read-back angles
    middle = (run.settled_s + run.end_s) / 2  # of each target's exposures
    recovered = calibration.brdf(run.value, run.exposure_s, wi, wo, middle)
    truth = SceneOptics(scene, rig).models["sample"](run.wi, run.wo)
    return Result(plan, scene, run, wall, calibration, recovered, truth, wi, wo)
