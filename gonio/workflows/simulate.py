"""A whole simulated session: the acquisition engine on the simulated backend (the
same loop, journal and calibration as `gonio acquire`), and what it recovers.

`simulate_plan` runs `gonio.workflows.session.start` with the simulated backend into a
run journal (in memory unless ``output`` names a file), then derives the BRDF from the
raw counts through the journaled calibration readings (`gonio.analysis.calibrated`) and
evaluates the scene's model at the pairs the optics really saw (the true joint angles
the simulated backend journals), the truth to compare with.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gonio.acquire import Observer, Report
from gonio.analysis import Calibrated, calibrate, measured_pairs, truth_of
from gonio.config import spec_text
from gonio.errors import GonioError
from gonio.planner import Plan
from gonio.scene import Scene
from gonio.store import Run
from gonio.types import FloatArray
from gonio.workflows import session
from gonio.workflows.preflight import Files


@dataclass(frozen=True)
class Result:
    """A simulated run (its journal), the BRDF it recovers and the truth."""

    plan: Plan
    scene: Scene
    run: Run
    report: Report
    wall_s: float
    calibrated: Calibrated
    truth: FloatArray  # the scene's model at the pairs the optics saw
    wi: FloatArray  # from the read-back angles
    wo: FloatArray
    true_wi: FloatArray  # from the true joint angles
    true_wo: FloatArray

    @property
    def brdf(self) -> FloatArray:
        """Recovered at the read-back pairs (sr⁻¹)."""
        return self.calibrated.brdf

    @property
    def sigma(self) -> FloatArray:
        return self.calibrated.sigma

    @property
    def saturated(self) -> np.ndarray:
        return np.asarray(self.run.samples["saturated"])

    @property
    def reference_counts(self) -> float:
        """The first reading of the reference standard (counts)."""
        return float(self.run.of_kind("calibration")[0].data["reference"]["value"])

    @property
    def reference_exposure_s(self) -> float:
        return float(self.run.of_kind("calibration")[0].data["reference"]["exposure_s"])

    @property
    def reference_change(self) -> float:
        """Last / first dark-subtracted reference signal − 1 (the drift seen)."""
        rate = self.calibrated.series.rate
        return float(rate[-1] / rate[0] - 1.0)

    @property
    def dark_rate(self) -> float:
        """Counts per second with the light off (the first dark reading)."""
        return float(self.calibrated.series.dark_rate[0])


def simulate_plan(
    plan: Plan,
    scene: Scene,
    seed: int | None = None,
    *,
    files: Files | None = None,
    output: Path | None = None,
    overwrite: bool = False,
    progress: Observer | None = None,
) -> Result:
    """Measure ``plan`` in ``scene`` on the simulated backend and recover the BRDF.
    ``files``: the texts the run is made from (default: the plan's and rig's, and the
    scene as validated); ``output``: keep the run journal there."""
    if files is None:
        files = Files(
            None,
            plan.plan_text,
            plan.rig.source,
            plan.rig.text,
            None,
            spec_text(scene),
            plan.rig.alignment_text,
        )
    started = time.perf_counter()
    outcome = session.start(
        plan,
        files,
        scene=scene,
        output=output,
        overwrite=overwrite,
        seed=seed,
        progress=progress,
        force_simulated=True,
    )
    wall = time.perf_counter() - started
    run = outcome.run
    try:
        calibrated = calibrate(run)
    except GonioError:
        report = outcome.report
        if report.outcome != "completed" and report.message:
            # The run stopped before it could be calibrated: its reason is the cause.
            raise GonioError(f"the run ended early: {report.message}") from None
        raise
    wi, wo = run.directions()
    true_wi, true_wo = measured_pairs(run)
    return Result(
        plan=plan,
        scene=scene,
        run=run,
        report=outcome.report,
        wall_s=wall,
        calibrated=calibrated,
        truth=truth_of(run, at_true_pairs=True),
        wi=wi,
        wo=wo,
        true_wi=true_wi,
        true_wo=true_wo,
    )
