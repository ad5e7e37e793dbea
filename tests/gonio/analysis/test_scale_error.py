"""The calibration's scale error is distributed as predicted, over 200 seeds per case
(tests/support/calibration.py: the calibrations simulated vectorized, the engine's
readings bit for bit): the z-scores (error / predicted σ) have a standard deviation and
an RMS within [0.8, 1.2] and a mean near 0, for the matte and the glossy scene, and with
the source drifting (the brushed-metal scene's drift: 0.5 % oscillation over 15 min)
between calibrations two minutes apart. The runs are long enough (21 calibrations of 64
exposures) for the errors not reduced by averaging to show: the dark readings'
rounding, drawn per seed where the dark level falls in its ADC code, and the drift's
bend between calibrations. Before the spline and the rounding term the spreads were
1.70 (matte), 1.28 (glossy) and an RMS of 3.11 with a mean of 2.83 (drift)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from gonio.rig.model import Rig
from gonio.scene import Scene
from tests.support.calibration import scale_errors
from tests.support.runs import scene_spec

SEEDS = range(200)
#: 21 calibrations of 64 exposures; the dark level's place in its code drawn per seed.
LONG: dict[str, Any] = {"calibrations": 21, "averages": 64, "dark_step": True}
#: The brushed-metal scene's drift (configs/scenes/brushed_metal.yaml).
DRIFT = {"rate_per_hour": 0.02, "amplitude": 0.005, "period_s": 900}


def scene(name: str, drift: dict[str, float] | None = None) -> Scene:
    spec = scene_spec(name)
    if drift is not None:
        spec["effects"]["source_drift"] = drift
    return Scene.model_validate(spec)


@pytest.mark.parametrize(
    ("name", "drift", "interval_s"),
    [("matte", None, 20.0), ("glossy_metal", None, 20.0), ("glossy_metal", DRIFT, 120.0)],
    ids=["matte", "glossy", "glossy-drift"],
)
def test_scale_error_is_distributed_as_predicted(
    rigs: dict[str, Rig], name: str, drift: dict[str, float] | None, interval_s: float
) -> None:
    errors = scale_errors(rigs["arch"], scene(name, drift), SEEDS, interval_s=interval_s, **LONG)
    spread = errors.spread()
    assert 0.8 <= spread["std"] <= 1.2, spread
    assert 0.8 <= spread["rms"] <= 1.2, spread
    assert abs(spread["mean"]) < 0.25, spread  # 3.5 standard errors of the mean
    assert np.all(errors.sigma > 0)
