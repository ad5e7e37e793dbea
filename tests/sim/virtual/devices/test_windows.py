"""`WindowOptics` computing a stream's windows ahead: the readings are bit for bit those
of a detector computing every read alone, whatever the effects, however the reads fall,
and when the motion changes after its windows were computed ahead; the simulated
instrument's stream finds nearly every window pose computed ahead."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gonio.rig.model import Rig
from gonio.scene import Scene, load_scene
from sim.clock import ManualClock
from sim.virtual.devices.detector import SimDetector
from sim.virtual.devices.instrument import SimulatedInstrument
from sim.virtual.devices.windows import FIRST_AHEAD
from sim.virtual.physics.streams import Streams
from tests.conftest import CONFIGS

GLOSSY = load_scene(CONFIGS / "scenes" / "glossy_metal.yaml")
#: Effects whose optics vary along a sweep (with the shipped scene's own, noise included).
EFFECTS: dict[str, dict[str, object]] = {
    "none": {},
    "shipped": GLOSSY.effects.model_dump(exclude_none=True),
    "blur": {"motion_blur": {"max_step_deg": 0.02}, "footprint": {}},
    "misaligned": {
        "misalignment": {"tilt_deg": 0.4, "zero_offset_deg": {"detector_elevation": 0.3}},
        "aperture_integration": {"order": 4},
    },
}


def scene(effects: dict[str, object]) -> Scene:
    """The gold scene with a narrow lobe (α 0.03) and ``effects``."""
    data = GLOSSY.model_dump()
    data["material"] = {"name": "cook_torrance", **data["material"]["params"], "alpha": 0.03}
    return Scene.model_validate({**data, "effects": effects})


class Sweep:
    """The detector arc from 20° at a speed that can change at a given time."""

    def __init__(self, rig: Rig) -> None:
        self.axes = rig.axes
        self.changes: list[tuple[float, float]] = [(0.0, 10.0)]  # (from t, speed °/s)

    def __call__(self, t: float) -> dict[str, float]:
        deg, last_t, last_v = 20.0, 0.0, 0.0
        for since, v in self.changes:
            if t < since:
                break
            deg += last_v * (since - last_t)
            last_t, last_v = since, v
        theta_o = math.radians(deg + last_v * (t - last_t))
        return dict(zip(self.axes, (math.radians(35.0), 0.0, -theta_o, 0.0), strict=True))


def read(
    rig: Rig, effects: dict[str, object], lookahead: bool, *, change_at: float | None = None
) -> tuple[SimDetector, list[tuple[float, float, float, bool]]]:
    """Two streams at 200 Hz (of 30 and 200 reads at irregular times, about 0.45 and
    3 s), the motion's speed reversed soon after ``change_at`` (s): after the windows
    around it were computed ahead."""
    clock, pose_at = ManualClock(0.0), Sweep(rig)
    det = SimDetector(
        scene(effects), rig, lambda: pose_at(clock.now()), clock=clock, streams=Streams(3),
        pose_at=pose_at, lookahead=lookahead,
    )  # fmt: skip
    steps = np.random.default_rng(1).uniform(0.0, 0.03, size=200)
    out = []
    with det:
        for sample in (0, 1):
            det.begin_sample(sample)
            det.start_stream(200.0, 0.004)
            for dt in steps[: 30 if sample == 0 else 200]:
                clock.advance(float(dt))
                late = change_at is not None and sample == 1 and clock.now() > change_at
                if late and not pose_at.changes[1:]:
                    pose_at.changes.append((clock.now() + 0.012, -10.0))
                for r in det.read_stream():
                    out.append((r.value, r.started_s, r.ended_s, r.saturated))
            out += [(r.value, r.started_s, r.ended_s, r.saturated) for r in det.stop_stream()]
    return det, out


@pytest.mark.parametrize("effects", list(EFFECTS))
def test_readings_computed_ahead_are_those_computed_alone(
    rigs: dict[str, Rig], effects: str
) -> None:
    alone, expected = read(rigs["arch"], EFFECTS[effects], lookahead=False)
    ahead, got = read(rigs["arch"], EFFECTS[effects], lookahead=True)
    assert len(got) == len(expected) > 100
    assert got == expected  # bit for bit, noise included
    assert alone.windows.hits == 0
    assert ahead.windows.hits >= 0.9 * sum(ahead.stream_nodes)
    assert ahead.stream_nodes == alone.stream_nodes


def test_a_motion_changed_after_its_windows_were_computed_ahead_reads_the_new_motion(
    rigs: dict[str, Rig],
) -> None:
    _, expected = read(rigs["arch"], EFFECTS["none"], lookahead=False, change_at=1.0)
    ahead, got = read(rigs["arch"], EFFECTS["none"], lookahead=True, change_at=1.0)
    assert got == expected
    # the windows computed ahead before the change were not used after it
    assert len(got) - ahead.windows.hits >= FIRST_AHEAD


def test_the_simulated_instruments_sweeps_read_their_windows_computed_ahead(
    rigs: dict[str, Rig],
) -> None:
    rig = rigs["arch"]
    instrument = SimulatedInstrument(scene(EFFECTS["shipped"]), rig)
    bus, det = instrument.bus, instrument.detector
    assert det.windows.lookahead
    with instrument.devices():
        bus.torque(True)
        bus.move_to(dict(zip(rig.axes, (0.6, 0.0, -0.2, 0.0), strict=True)))
        bus.wait_settled(10.0)
        bus.sweep({"detector_elevation": -1.0}, {"detector_elevation": 0.5})
        det.start_stream(100.0)
        readings, arrived = [], False
        while not arrived:
            arrived = bus.poll_positions().arrived
            readings += det.read_stream(timeout_s=0.01)
        readings += det.stop_stream()
    assert len(readings) > 100
    assert det.windows.hits >= 0.9 * len(readings)
