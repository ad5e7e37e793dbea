"""A plan measured target by target on a `SimulatedInstrument` through the engine's
own step, without the engine: the oracle the vectorized `sim.virtual.simulate.simulate` and the
engine's runs are checked against (and the simulator benchmark's per-sample path)."""

from __future__ import annotations

import numpy as np

from gonio.acquire.measure import measure_target
from gonio.planner.model import Plan
from sim.virtual.devices.instrument import SimulatedInstrument
from sim.virtual.devices.position_error import planned_poses
from sim.virtual.record import SimRun


def measure_targets(
    instrument: SimulatedInstrument,
    plan: Plan,
    *,
    start: int = 0,
    stop: int | None = None,
    prepare: bool = True,
) -> SimRun:
    """Measure targets ``start``…``stop`` of ``plan`` one by one with ``instrument``,
    through the engine's step (`gonio.acquire.measure`; stream index = target index, so
    a run resumed at ``start`` equals the tail of a full run once the motors are where
    the full run had them). With ``prepare`` the detector first
    computes the optics at the poses the plan will reach, vectorized
    (`SimDetector.prepare`); the readings are the same either way."""
    stop = len(plan) if stop is None else stop
    if prepare:
        _, expected, _ = planned_poses(
            instrument.rig, plan.angles, instrument.scene, instrument.streams
        )
        instrument.detector.prepare(expected[start:stop])
    axes, settle = instrument.rig.axes, instrument.rig.spec.settle_s
    rows = [
        measure_target(
            instrument.devices(),
            i,
            dict(zip(axes, plan.angles[i].tolist(), strict=True)),
            float(plan.exposure_s[i]),
            int(plan.averages[i]),
            settle_s=settle,
        )
        for i in range(start, stop)
    ]
    n = len(axes)
    true = np.array([[m.true[a] for a in axes] for m in rows if m.true], dtype=np.float64)
    true = true.reshape(-1, n)  # every row has its true pose: this backend is simulated
    wi, wo = instrument.detector.chain.pairs(true)  # through the scene's misalignment
    return SimRun(
        index=np.arange(start, stop, dtype=np.int64),
        commanded=plan.angles[start:stop],
        read_back=np.array(
            [[m.read_back[a] for a in axes] for m in rows], dtype=np.float64
        ).reshape(-1, n),
        true=true,
        wi=wi,
        wo=wo,
        exposure_s=plan.exposure_s[start:stop],
        averages=plan.averages[start:stop],
        settled_s=np.array([m.settled_s for m in rows], dtype=np.float64),
        end_s=np.array([m.reading.ended_s for m in rows], dtype=np.float64),
        value=np.array([m.reading.value for m in rows], dtype=np.float64),
        std=np.array([m.reading.std for m in rows], dtype=np.float64),
        saturated=np.array([m.reading.saturated for m in rows], dtype=np.bool_),
    )
