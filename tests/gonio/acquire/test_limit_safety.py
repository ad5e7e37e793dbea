"""Limit safety under fuzzed plans: plans whose targets are random joint
angles — some beyond an axis's limits, some NaN or infinite — run through the engine on
the rehearsal backend (the real `DynamixelBus` through the unmodified SDK on the
byte-level emulator). The emulator's log of every Goal Position written holds none
outside the axis limits (in motor ticks, as the driver converts them), every target
outside them was skipped with its reason journaled, and every target inside was
measured."""

from __future__ import annotations

import dataclasses
import functools
import json
import math

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from drivers.dynamixel.axis import AxisConfig
from gonio.acquire.ending import Report
from gonio.acquire.engine import Engine
from gonio.acquire.runtime import RunTime
from gonio.planner.files import load_plan_source
from gonio.planner.model import ARRAYS, Plan
from gonio.rig.model import Rig
from gonio.scene import load_scene
from gonio.store.journal import Journal
from gonio.workflows.rehearsal import rehearsal_devices
from sim.rehearsal import RehearsalSide
from tests.conftest import CONFIGS, RIG_FILES

pytestmark = pytest.mark.pty

RIG = Rig.from_yaml(RIG_FILES["arch"])
AXES = RIG.bus_axes()
SCENE = load_scene(CONFIGS / "scenes" / "matte.yaml")
#: Targets per fuzzed plan, and how much faster than real time the rehearsal runs.
TARGETS, SPEEDUP = 6, 2000.0
#: A small real plan whose angles each example replaces.


@functools.cache
def base() -> Plan:
    """The shipped rehearsal plan, built once (when a test first runs, not at collection)."""
    return load_plan_source(CONFIGS / "plans" / "rehearsal.yaml", RIG_FILES["arch"]).build()


def inside(axis: AxisConfig) -> st.SearchStrategy[float]:
    return st.floats(axis.min_rad, axis.max_rad) | st.sampled_from([axis.min_rad, axis.max_rad])


def outside(axis: AxisConfig) -> st.SearchStrategy[float]:
    beyond = st.floats(1e-9, 1.0).flatmap(
        lambda d: st.sampled_from([axis.min_rad - d, axis.max_rad + d])
    )
    return beyond | st.sampled_from([math.nan, math.inf, -math.inf])


@st.composite
def pose(draw: st.DrawFn) -> list[float]:
    """Every axis within its limits; half the time one or more axes then spoiled."""
    angles = [draw(inside(a)) for a in AXES]
    if draw(st.booleans()):
        for j in draw(st.sets(st.integers(0, len(AXES) - 1), min_size=1)):
            angles[j] = draw(outside(AXES[j]))
    return angles


def _with_angles(plan: Plan, poses: list[list[float]]) -> Plan:
    first = {name: getattr(plan, name)[: len(poses)] for name in ARRAYS}
    return dataclasses.replace(plan, **{**first, "angles": np.array(poses, dtype=np.float64)})


def _acquire(plan: Plan) -> tuple[Report, list[int], dict[int, str], dict[int, list[int]]]:
    """Run ``plan`` on a fresh rehearsal: the report, the targets measured, the skip
    reasons by target and the goals each motor was sent (ticks)."""
    with rehearsal_devices(RIG, SCENE, None, SPEEDUP) as (devices, clock):
        side = devices.simulation
        assert isinstance(side, RehearsalSide)
        meta = {"axes": list(RIG.axes), "coordinate_names": list(plan.coordinate_names)}
        with Journal.create(None, meta, b"", durable=False) as journal:
            journal.start_session("now", {})
            engine = Engine(plan, devices, journal, side, RunTime(clock.now))
            report = engine.run()
            measured = [t for (t,) in journal.conn.execute("SELECT target FROM samples")]
            skips = {
                int(t): json.loads(data)["reason"]
                for t, data in journal.conn.execute(
                    "SELECT target, data FROM events WHERE kind = 'skip'"
                )
            }
        assert side.peers is not None
        goals = side.peers.emulator.goals_written()
    return report, measured, skips, goals


def _edges() -> list[list[float]]:
    """Named extremes: exactly at the limits, one ulp beyond, NaN and the infinities."""
    lo = [a.min_rad for a in AXES]
    hi = [a.max_rad for a in AXES]
    return [
        hi,
        [math.nextafter(hi[0], math.inf), *hi[1:]],
        lo,
        [*lo[:-1], math.nextafter(lo[-1], -math.inf)],
        [0.1, math.nan, 0.0, 0.0],
        [0.1, 0.0, math.inf, -math.inf],
    ]


@settings(max_examples=max(4, settings().max_examples // 25))
@given(st.lists(pose(), min_size=TARGETS, max_size=TARGETS))
@example(_edges())
def test_no_goal_outside_the_limits_ever_reaches_a_motor(poses: list[list[float]]) -> None:
    report, measured, skips, goals = _acquire(_with_angles(base(), poses))
    assert report.outcome == "completed", report.message
    ok = [all(a.contains(x) for a, x in zip(AXES, p, strict=True)) for p in poses]
    # Every target inside was measured; every one outside skipped, its reason journaled.
    assert measured == [i for i, good in enumerate(ok) if good]
    assert sorted(skips) == [i for i, good in enumerate(ok) if not good]
    for i, reason in skips.items():
        axis, angle = next((a, x) for a, x in zip(AXES, poses[i], strict=True) if not a.contains(x))
        assert reason.startswith(f"axis {axis.name!r}: {angle!r} rad is outside its limits")
    # The emulator's log: every goal within the limits as the driver converts them, and
    # the goal of every target measured among them.
    for axis in AXES:
        low, high = axis.tick_limits()
        written = goals[axis.motor_id]
        assert written, axis.name
        assert all(low <= g <= high for g in written), (axis.name, low, high, written)
        assert all(axis.min_rad - 1e-12 <= axis.to_rad(g) <= axis.max_rad + 1e-12 for g in written)
        j = AXES.index(axis)
        for i in measured:
            assert min(max(axis.to_ticks(poses[i][j]), low), high) in written
