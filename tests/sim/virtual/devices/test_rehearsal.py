"""Rehearsal: the real `DynamixelBus` driving the byte-level emulator over a pty, with
the simulated detector looking through the read-back positions — the whole real driver
path, no hardware."""

from __future__ import annotations

import numpy as np
import pytest

from gonio.acquire.measure import measure_target
from gonio.rig.model import Rig
from gonio.scene import load_scene
from gonio.workflows.rehearsal import rehearsal_devices
from sim.rehearsal import RehearsalSide
from sim.virtual.devices.instrument import SimulatedInstrument
from tests.conftest import CONFIGS

SCENES = CONFIGS / "scenes"


def test_rehearsal_measures_like_the_simulation(rig: Rig) -> None:
    scene = load_scene(SCENES / "matte.yaml").with_effects([])
    ticks = np.array([a.resolution_rad for a in rig.bus_axes()])
    rng = np.random.default_rng(4)
    targets = [rng.uniform(0.6 * rig.limits[:, 0], 0.6 * rig.limits[:, 1]) for _ in range(3)]
    with (
        rehearsal_devices(rig, scene, None, 40.0) as (devices, _),
        devices,
        SimulatedInstrument(scene, rig) as sim,
    ):
        bus, detector = devices.bus, devices.detector
        side = devices.simulation
        assert isinstance(side, RehearsalSide) and side.peers is not None
        assert bus.axes == rig.axes
        for target in targets:
            bus.move_to(dict(zip(rig.axes, target.tolist(), strict=True)))
            bus.wait_settled(10.0)
            read_back = np.array(list(bus.positions().values()))
            assert np.all(np.abs(read_back - target) <= 2.5 * ticks)
            reading = detector.measure(0.01)
            # The simulation at the read-back pose gives the same reading.
            pose = dict(zip(rig.axes, read_back.tolist(), strict=True))
            expected = measure_target(sim.devices(), 0, pose, 0.01, 1, settle_s=0.0).reading
            assert reading.value == pytest.approx(expected.value, rel=1e-12)
        assert side.peers.emulator.stats.instructions["SYNC_WRITE"] >= 3
