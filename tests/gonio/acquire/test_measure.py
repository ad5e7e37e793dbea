"""`gonio.acquire.measure`: the per-target step through the device contract — limits
before anything moves, the settle dwell waited once, read-back positions."""

from __future__ import annotations

import math

import numpy as np
import pytest

from drivers.errors import LimitError
from gonio.acquire.measure import measure_target
from gonio.planner import build, load_plan
from gonio.rig.model import Rig
from gonio.scene import load_scene
from sim.virtual.devices.instrument import SimulatedInstrument
from tests.conftest import CONFIGS
from tests.support.measure import measure_targets

MATTE = load_scene(CONFIGS / "scenes" / "matte.yaml")


def test_a_pose_outside_the_limits_is_refused_before_the_backend_hears_of_it(
    rigs: dict[str, Rig],
) -> None:
    rig = rigs["arch"]
    with SimulatedInstrument(MATTE, rig) as inst:
        devices = inst.devices()
        home = dict(zip(rig.axes, rig.home.tolist(), strict=True))
        t = inst.clock.now()
        for bad in (math.radians(86.0), math.nan):
            with pytest.raises(LimitError, match="light_elevation"):
                measure_target(devices, 0, {**home, "light_elevation": bad}, 0.01, 1, settle_s=0.2)
        assert inst.clock.now() == t and inst.bus.positions() == home


def test_the_settle_dwell_is_waited_once_and_the_plan_predicts_the_run(rig: Rig) -> None:
    """Target by target the virtual time is exactly the plan's prediction: moves, one
    settle dwell per target and the exposures (the planner counts them the same way)."""
    spec, _ = load_plan(CONFIGS / "plans" / "quick.yaml")
    plan = build(spec, rig)
    with SimulatedInstrument(MATTE.with_effects([]), rig) as inst:
        run = measure_targets(inst, plan)
    settle = rig.spec.settle_s
    arrival = run.settled_s - settle  # when each move ended
    np.testing.assert_allclose(arrival, plan.arrival_s, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(
        run.end_s - run.settled_s, plan.exposure_s * plan.averages, rtol=1e-12
    )
    assert run.instrument_time_s == pytest.approx(plan.summary.total_s, rel=1e-12)
