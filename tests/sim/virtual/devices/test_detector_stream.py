"""`SimDetector`'s stream: windows in virtual time, each read at the pose of its
middle through the instrument's ``pose_at`` callable."""

from __future__ import annotations

import functools
import math

import pytest

from drivers.errors import DetectorError, StreamNotSupported
from drivers.stream import can_stream
from gonio.rig.model import Rig
from gonio.scene import Scene, load_scene
from sim.clock import ManualClock
from sim.virtual.devices.detector import SimDetector, SimLightSource
from sim.virtual.physics.streams import Streams
from tests.conftest import CONFIGS

MATTE = load_scene(CONFIGS / "scenes" / "matte.yaml")


def exact(scene: Scene) -> Scene:
    return Scene.model_validate({**scene.model_dump(), "effects": []})


def pose_of(rig: Rig, theta_o_deg: float) -> dict[str, float]:
    angles = (math.radians(30.0), 0.0, math.radians(-theta_o_deg), 0.0)
    return dict(zip(rig.axes, angles, strict=True))


def test_each_window_is_read_at_the_pose_of_its_middle(rigs: dict[str, Rig]) -> None:
    rig, clock = rigs["arch"], ManualClock(10.0)
    asked: list[float] = []

    def pose_at(t: float) -> dict[str, float]:  # the detector sweeps 100°/s from 10°
        asked.append(t)
        return pose_of(rig, 10.0 + 100.0 * (t - 10.0))

    scene, light = exact(MATTE), SimLightSource()
    with SimDetector(
        scene, rig, lambda: pose_of(rig, 0.0), clock=clock, streams=Streams(0), light=light,
        pose_at=pose_at,
    ) as det:  # fmt: skip
        assert can_stream(det)
        det.start_stream(100.0, 0.004)
        assert det.read_stream() == []  # no window has ended yet
        readings = det.read_stream(1.0)  # virtual time passes to the first window's end
        assert clock.now() == pytest.approx(10.01) and len(readings) == 1
        clock.advance(0.1)
        readings += det.read_stream()
        readings += det.stop_stream()
        assert det.stop_stream() == []
    assert len(readings) == 11
    assert [r.ended_s for r in readings] == pytest.approx([10.0 + 0.01 * k for k in range(1, 12)])
    assert asked == pytest.approx([r.middle_s for r in readings])
    # each value is the one a still measurement at that pose gives
    for r in readings[::5]:
        pose = pose_of(rig, 10.0 + 100.0 * (r.middle_s - 10.0))
        with SimDetector(
            scene, rig, functools.partial(dict, pose), clock=clock, streams=Streams(0),
            light=light,
        ) as still:  # fmt: skip
            assert r.value == pytest.approx(still.measure(0.004).value, rel=1e-12)


def test_a_window_fits_the_period_less_the_readout(rigs: dict[str, Rig]) -> None:
    rig = rigs["arch"]
    pose = pose_of(rig, 20.0)
    with SimDetector(MATTE, rig, lambda: pose, clock=ManualClock(), streams=Streams(0)) as det:
        for rate, integration in ((100.0, 0.02), (0.0, None), (-1.0, None), (math.inf, None)):
            with pytest.raises(DetectorError):
                det.start_stream(rate, integration)
        det.start_stream(100.0)
        readings = det.read_stream(0.5)
        assert readings[0].ended_s - readings[0].started_s == pytest.approx(0.01 - det.readout_s)
        with pytest.raises(DetectorError):
            det.measure(0.01)
        det.stop_stream()
        det.measure(0.01)


def test_a_lock_in_does_not_stream(rigs: dict[str, Rig]) -> None:
    scene, rig = load_scene(CONFIGS / "scenes" / "matte_lockin.yaml"), rigs["arch"]
    with SimDetector(scene, rig, lambda: pose_of(rig, 20.0), clock=ManualClock(),
                     streams=Streams(0)) as det:  # fmt: skip
        assert not can_stream(det)
        with pytest.raises(StreamNotSupported):
            det.start_stream(100.0)
