"""Rehearsal: the real `DynamixelBus` driving the byte-level emulator over a pty, with
the simulated detector looking through the read-back positions — the whole real driver
path, no hardware."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from sim.devices.instrument import SimulatedInstrument, rehearsal
from sim.scene import load_scene
from tests.gonio.rig.helpers import RIGS

SCENES = Path(__file__).resolve().parents[3] / "configs" / "scenes"


@pytest.mark.parametrize("rig_name", list(RIGS))
def test_rehearsal_measures_like_the_simulation(rig_name: str) -> None:
    rig = RIGS[rig_name]
    scene = load_scene(SCENES / "matte.yaml").with_effects([])
    ticks = np.array([a.resolution_rad for a in rig.bus_axes()])
    rng = np.random.default_rng(4)
    targets = [rng.uniform(0.6 * rig.limits[:, 0], 0.6 * rig.limits[:, 1]) for _ in range(3)]
    with rehearsal(scene, rig, speedup=40.0) as r, SimulatedInstrument(scene, rig) as sim:
        assert r.bus.axes == rig.axes
        for target in targets:
            r.bus.move_to(dict(zip(rig.axes, target.tolist(), strict=True)))
            r.bus.wait_settled(10.0)
            read_back = np.array(list(r.bus.positions().values()))
            assert np.all(np.abs(read_back - target) <= 2.5 * ticks)
            reading = r.detector.measure(0.01)
            # The simulation at the read-back pose gives the same reading.
            _, expected, _ = sim.measure_target(0, read_back.tolist(), 0.01, 1)
            assert reading.value == pytest.approx(expected.value, rel=1e-12)
        assert r.emulator.stats.instructions["SYNC_WRITE"] >= 3
