"""`gonio.workflows.hardware`: a rig file's hardware backend — the real `DynamixelBus`,
`SerialDetector` and `SerialLightSwitch` built from the rig's sections — driven through
the per-target step against the emulator, the simulated photometer and the simulated
lamp, each on its own pseudo-terminal."""

from __future__ import annotations

import math
from collections.abc import Iterator
from pathlib import Path

import pytest
import yaml

from gonio.acquire.measure import measure_target
from gonio.config import ConfigError
from gonio.rig.model import Rig
from gonio.workflows.hardware import hardware_devices
from sim.clock import ScaledClock
from sim.peers.serial_light import SerialLamp
from sim.peers.serial_photometer import SerialPhotometer
from sim.rehearsal import emulated_bus
from tests.conftest import RIG_FILES

RATE = 2.0e4  # counts per second with the lamp on


@pytest.fixture
def bench(tmp_path: Path) -> Iterator[tuple[Rig, SerialLamp, SerialPhotometer]]:
    """The arch rig wired to an emulated bus, a photometer that sees the lamp, a lamp."""
    base = Rig.from_yaml(RIG_FILES["arch"])
    with SerialLamp() as lamp, emulated_bus(base, ScaledClock(50.0)) as emu:
        photometer = SerialPhotometer(lambda s: RATE * s if lamp.is_on else 0.0, dark=3.0)
        with photometer:
            data = yaml.safe_load(RIG_FILES["arch"].read_text(encoding="utf-8"))
            data["bus"] = {"port": emu.path, "baud": base.spec.bus.baud}
            data["detector"]["interface"] = {
                "kind": "serial",
                **_photometer_fields(photometer),
            }
            data["light"]["switch"] = {
                "kind": "serial",
                "port": lamp.path,
                "on_command": "ON",
                "off_command": "OFF",
                "ack": "^OK$",
                "query_command": "STATE?",
                "on_reply": "^ON$",
                "off_reply": "^OFF$",
                "timeout_s": 0.5,
            }
            path = tmp_path / "rig.yaml"
            path.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
            yield Rig.from_yaml(path), lamp, photometer
            assert photometer.error is None
        assert lamp.error is None and emu.error is None


def _photometer_fields(photometer: SerialPhotometer) -> dict[str, object]:
    config = photometer.config()
    endings = {"\n": "lf", "\r\n": "crlf", "\r": "cr"}
    return {
        "port": config.port,
        "baud": config.baud,
        "query": config.query,
        "set_exposure": config.set_exposure,
        "response": config.response,
        "line_ending": endings[config.line_ending],
        "timeout_s": config.timeout_s,
        "reset_banner": config.reset_banner,
        "init": list(config.init),
        "command_ack": config.command_ack,
        "error_reply": config.error_reply,
        "saturated_status": config.saturated_status,
    }


def test_the_rig_file_alone_drives_the_whole_hardware_path(
    bench: tuple[Rig, SerialLamp, SerialPhotometer],
) -> None:
    rig, lamp, photometer = bench
    pose = dict(zip(rig.axes, (math.radians(30.0), 0.0, math.radians(-45.0), 0.0), strict=True))
    with hardware_devices(rig) as devices:
        assert devices.light is not None and devices.simulation is None
        devices.light.on()
        lit = measure_target(devices, 0, pose, 0.01, 2, settle_s=0.0)
        devices.light.off()
        dark = measure_target(devices, 1, pose, 0.01, 1, settle_s=0.0)
        assert not lamp.is_on
    assert lit.reading.value == pytest.approx(RATE * 0.01 + 3.0)
    assert lit.reading.n == 2 and lit.reading.started_s < lit.reading.ended_s
    assert dark.reading.value == pytest.approx(3.0)  # the photometer's own dark counts
    for axis, angle in pose.items():  # read back from the emulated encoders
        assert lit.read_back[axis] == pytest.approx(angle, abs=2.5 * 2 * math.pi / 4096)
    assert "EXP 10" in photometer.commands
    # Every port was released: the same devices open again at once.
    with hardware_devices(rig) as again:
        assert again.light is not None and not again.light.is_on


def test_a_rig_with_a_simulated_detector_has_no_hardware_backend() -> None:
    with pytest.raises(ConfigError, match=r"detector\.interface: is 'simulated'"):
        hardware_devices(Rig.from_yaml(RIG_FILES["arch"]))
