"""`sim.rehearsal`: the rig file's hardware path on simulated peers, each on its own
pseudo-terminal, driven by the real drivers; a serial photometer whose counts are the
simulated detector's, bit for bit, at the pose the emulated motors are at."""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Any

import pytest
import yaml

from drivers.dynamixel.bus import DynamixelBus
from drivers.light.serial_switch import SerialLightSwitch
from drivers.serial_detector.detector import SerialDetector
from gonio.acquire.measure import measure_target
from gonio.config import ConfigError
from gonio.rig.model import Rig
from gonio.scene import Scene, load_scene
from gonio.workflows.rehearsal import rehearsal_devices
from sim.clock import ManualClock
from sim.virtual.devices.detector import SimDetector, SimLightSource
from sim.virtual.physics.streams import Streams
from tests.conftest import CONFIGS, RIG_FILES

pytestmark = pytest.mark.pty

SERIAL_RIG = CONFIGS / "rigs" / "arch_serial.yaml"
POSE = dict(
    zip(
        ("light_elevation", "detector_azimuth", "detector_elevation", "sample_rotation"),
        (math.radians(30.0), math.radians(10.0), math.radians(-45.0), 0.3),
        strict=True,
    )
)


@pytest.fixture(scope="module")
def scene() -> Scene:
    return load_scene(CONFIGS / "scenes" / "matte.yaml")


def _rig(tmp_path: Path, edit: dict[str, dict[str, Any]]) -> Rig:
    """arch_serial.yaml with ``edit`` merged into its sections."""
    data = yaml.safe_load(SERIAL_RIG.read_text(encoding="utf-8"))
    for section, fields in edit.items():
        target = data
        for key in section.split("."):
            target = target[key]
        target.update(fields)
    path = tmp_path / "rig.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    return Rig.from_yaml(path)


def test_a_serial_rig_rehearses_on_the_real_drivers_reading_the_scene(scene: Scene) -> None:
    rig = Rig.from_yaml(SERIAL_RIG)
    with rehearsal_devices(rig, scene, None, 1000.0) as (devices, _):
        assert isinstance(devices.bus, DynamixelBus)
        assert isinstance(devices.detector, SerialDetector)
        assert isinstance(devices.light, SerialLightSwitch)
        side = devices.simulation
        assert side is not None
        with devices:
            devices.light.on()
            lit = measure_target(devices, 7, POSE, 0.05, 2, settle_s=0.2)
            assert side.true_positions() == lit.read_back  # the emulated motors, at rest
            devices.light.off()
            dark = measure_target(devices, 8, POSE, 0.05, 1, settle_s=0.0).reading
            devices.light.on()
            side.show("reference")
            reference = measure_target(devices, 9, POSE, 0.05, 1, settle_s=0.0).reading
            side.show("sample")

    # The simulated detector at the read-back pose, with the same streams, reads the same
    # counts (matte has no drift, so the time of each exposure does not matter).
    light = SimLightSource()
    twin = SimDetector(
        scene, rig, lambda: lit.read_back, clock=ManualClock(), streams=Streams(scene.seed),
        light=light,
    )  # fmt: skip
    with twin, light:
        twin.begin_sample(7)
        assert lit.reading.raw == twin.measure(0.05, 2).raw
        light.off()
        twin.begin_sample(8)
        assert dark.value == twin.measure(0.05).value
        light.on()
        twin.show("reference")
        twin.begin_sample(9)
        assert reference.value == twin.measure(0.05).value
    assert dark.value < 0.01 * lit.reading.value < reference.value


def test_a_rig_with_a_simulated_detector_keeps_the_simulated_detector(scene: Scene) -> None:
    rig = Rig.from_yaml(RIG_FILES["arch"])
    with rehearsal_devices(rig, scene, None, 1000.0) as (devices, _):
        assert isinstance(devices.bus, DynamixelBus)
        assert isinstance(devices.detector, SimDetector)
        assert isinstance(devices.light, SimLightSource)
        with devices:
            measured = measure_target(devices, 0, POSE, 0.05, 1, settle_s=0.0)
    assert measured.reading.value > 0


def test_an_arduino_that_resets_on_open_prints_its_banner(tmp_path: Path, scene: Scene) -> None:
    """With a reset banner and a settle time the photometer reboots when the port opens,
    as an Uno does, and the driver is ready as soon as the banner arrives."""
    rig = _rig(tmp_path, {"detector.interface": {"settle_s": 3.0}})
    with rehearsal_devices(rig, scene, None, 1000.0) as (devices, _):
        started = time.monotonic()
        with devices:
            assert time.monotonic() - started < 1.0
            assert measure_target(devices, 0, POSE, 0.05, 1, settle_s=0.0).reading.value > 0


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (
            {"detector.interface": {"query": "READ?"}},
            "detector.interface.query: --rehearse: 'READ?' is not a command of the simulated "
            "photometer (MEAS, EXP, GAIN, ID?, STREAM, STOP)",
        ),
        (
            {"detector.interface": {"response": r"READING (?P<value>\S+) (?P<status>\w+)"}},
            "detector.interface.response: --rehearse: does not match the simulated "
            "photometer's answer 'VAL 1234.0 OK'",
        ),
        (
            {"light.switch": {"ack": "^DONE$"}},
            "light.switch.ack: --rehearse: '^DONE$' does not match the simulated lamp "
            "relay's answer 'OK'",
        ),
    ],
    ids=["query", "response", "lamp"],
)
def test_a_protocol_the_peers_do_not_speak_is_one_line(
    tmp_path: Path, scene: Scene, edit: dict[str, dict[str, Any]], message: str
) -> None:
    rig = _rig(tmp_path, edit)
    with pytest.raises(ConfigError) as info, rehearsal_devices(rig, scene, None, 1000.0):
        pass
    assert str(info.value) == f"{rig.source}: {message}"
