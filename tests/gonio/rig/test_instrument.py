"""The rig file's instrument sections: the light's kind and switch, the detector's
limits and interface (a serial detector configured from YAML talks to the simulated
photometer), the reference standard. Their mistakes are in test_config_errors.py."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from drivers.serial_detector import SerialDetectorConfig, SerialStreamConfig
from drivers.serial_detector.detector import SerialDetector
from gonio.config import ConfigError
from gonio.rig.instrument import NoSwitchSpec, SerialInterfaceSpec, SerialSwitchSpec
from gonio.rig.model import Rig
from gonio.rig.solution import Reason
from sim.peers.serial_photometer import RESPONSE, STREAM_CONFIG, SerialPhotometer, default_config
from tests.conftest import ARCH_POINT_FILE, RIG_FILES
from tests.support.rigs import direction

ARCH_SERIAL_FILE = RIG_FILES["arch"].parent / "arch_serial.yaml"
ARCH_DATA = yaml.safe_load(RIG_FILES["arch"].read_text())

#: The simulated photometer's protocol as a user writes it in a rig file.
PHOTOMETER_INTERFACE = r"""
  interface:
    kind: serial
    port: {port}
    baud: 115200
    query: MEAS
    set_exposure: "EXP {{exposure_ms:d}}"
    response: 'VAL (?P<value>\S+) (?P<status>OK|SAT)(?: (?P<std>\S+))?'
    line_ending: lf
    timeout_s: 0.5
    retries: 2
    reset_banner: ^READY
    init: [GAIN 1]
    command_ack: ^OK$
    error_reply: ^ERR
    saturated_status: ^SAT$
"""


def rig_file(tmp_path: Path, interface: str) -> Path:
    """arch.yaml with its detector's ``interface:`` line replaced by ``interface``."""
    text = RIG_FILES["arch"].read_text()
    line = next(x for x in text.splitlines() if x.lstrip().startswith("interface:"))
    path = tmp_path / "serial-rig.yaml"
    path.write_text(text.replace(line + "\n", interface.lstrip("\n")), encoding="utf-8")
    return path


def test_a_serial_detector_configured_from_the_rig_file_measures(tmp_path: Path) -> None:
    with SerialPhotometer(20_000.0) as device:
        rig = Rig.from_yaml(rig_file(tmp_path, PHOTOMETER_INTERFACE.format(port=device.path)))
        config = rig.serial_detector_config()
        assert config == default_config(device.path)
        with SerialDetector(config) as detector:
            reading = detector.measure(0.05, averages=3)
    assert reading.value == pytest.approx(1000.0)  # 20 000 counts/s for 50 ms
    assert reading.n == 3 and not reading.saturated
    assert device.error is None


def test_every_driver_field_can_be_set_from_yaml() -> None:
    """The rig's serial section names every field of the driver's configuration, and
    a value given for each reaches the driver."""
    driver_fields = {f.name for f in dataclasses.fields(SerialDetectorConfig)}
    assert set(SerialInterfaceSpec.model_fields) - {"kind"} == driver_fields
    given: dict[str, Any] = {
        "port": "socket://localhost:7777",
        "baud": 9600,
        "query": "MEAS {exposure_ms:d} {averages:d}",
        "set_exposure": "EXP {exposure_us:d}",
        "response": RESPONSE,
        "line_ending": "\r\n",
        "timeout_s": 2.5,
        "retries": 5,
        "full_scale": 65535.0,
        "reset_banner": "^READY",
        "init": ("GAIN 2", "MODE FAST"),
        "settle_s": 3.0,
        "command_ack": "^OK$",
        "error_reply": "^ERR",
        "saturated_status": "^SAT$",
        "device_averaging": True,
        "max_line_bytes": 256,
        "stream": SerialStreamConfig(
            start="GO {period_us:d}",
            stop="HALT",
            line=r"(?P<value>\S+) (?P<device_t>\d+)",
            rate_hz=50.0,
            max_rate_hz=500.0,
            device_time_s=1e-6,
            latency_s=0.002,
            starts_on_command=True,
        ),
    }
    assert set(given) == driver_fields
    for f in dataclasses.fields(SerialDetectorConfig):  # none is the default: each is carried
        assert given[f.name] != f.default, f.name
    for f in dataclasses.fields(SerialStreamConfig):
        assert getattr(given["stream"], f.name) != f.default, f.name
    stream = dataclasses.asdict(given["stream"])
    spec = SerialInterfaceSpec.model_validate({"kind": "serial", **given, "stream": stream})
    assert spec.line_ending == "crlf"
    assert spec.config() == SerialDetectorConfig(**given)


def test_the_defaults_are_the_drivers() -> None:
    spec = SerialInterfaceSpec.model_validate({"kind": "serial", "port": "/dev/ttyACM0"})
    assert spec.config() == SerialDetectorConfig(port="/dev/ttyACM0")


def test_a_simulated_detector_has_no_serial_config(rigs: dict[str, Rig]) -> None:
    with pytest.raises(ConfigError) as info:
        rigs["arch"].serial_detector_config()
    assert str(info.value) == (
        f"{RIG_FILES['arch']}: detector.interface: is 'simulated'; expected 'serial' for a "
        "serial detector"
    )


def test_the_shipped_rigs_instrument_sections(arch_point: Rig, rigs: dict[str, Rig]) -> None:
    for rig in (*rigs.values(), arch_point):
        d = rig.spec.detector
        assert (d.aperture_sr, d.exposure_range_s, d.readout_s, d.max_averages) == (
            1e-5,
            (1e-4, 60.0),
            0.0,
            64,
        )
        assert d.interface.kind == "simulated"
        assert rig.spec.light.switch == NoSwitchSpec(kind="none")
        assert (rig.spec.reference.albedo, rig.spec.constraints.detector_fov_mm) == (0.99, 25)
    assert [r.source_kind for r in rigs.values()] == ["collimated", "collimated"]
    assert arch_point.source_kind == "point"
    assert arch_point.spec.light.distance_mm == 300
    assert arch_point.spec.constraints.beam_diameter_mm is None


def test_the_point_rig_is_the_arch_rig_with_a_lamp() -> None:
    """arch_point.yaml repeats arch.yaml but for its name, its light and its beam."""
    point = yaml.safe_load(ARCH_POINT_FILE.read_text())
    arch = dict(ARCH_DATA)
    for data in (point, arch):
        data.pop("name")
        data["light"] = {k: v for k, v in data["light"].items() if k not in ("kind", "distance_mm")}
        data["constraints"] = {
            k: v for k, v in data["constraints"].items() if k != "beam_diameter_mm"
        }
    assert point == arch


def test_the_serial_rig_is_the_arch_rig_wired_to_hardware() -> None:
    """arch_serial.yaml repeats arch.yaml but for its name, its bus, its lamp relay, its
    photometer (the simulated photometer's protocol) and its shortest exposure (whole
    milliseconds)."""
    serial = Rig.from_yaml(ARCH_SERIAL_FILE)
    spec = serial.spec
    assert spec.bus.kind == "dynamixel" and isinstance(spec.light.switch, SerialSwitchSpec)
    stream = dataclasses.replace(STREAM_CONFIG, max_rate_hz=400.0)
    assert serial.serial_detector_config() == default_config(
        "/dev/ttyACM0", timeout_s=0.5, stream=stream
    )
    assert spec.detector.exposure_range_s == (1e-3, 60.0)
    data = yaml.safe_load(ARCH_SERIAL_FILE.read_text())
    arch = dict(ARCH_DATA)
    for d in (data, arch):
        d.pop("name"), d.pop("bus")
        d["light"] = {k: v for k, v in d["light"].items() if k != "switch"}
        d["detector"] = {
            k: v for k, v in d["detector"].items() if k not in ("interface", "exposure_range_s")
        }
    assert data == arch


def test_a_point_source_refuses_no_footprint(arch_point: Rig, rigs: dict[str, Rig]) -> None:
    """A grazing light: the collimated beam's ellipse leaves the sample; a point source
    floods the sample anyway. A grazing view runs past the sample's edge: the collimated
    rig accepts it (the detector sees only unlit holder beyond the lit ellipse), the
    point source, which lights the holder too, refuses it."""
    wi, wo = direction(79.0, 0.0)[None], direction(10.0, 180.0)[None]
    assert rigs["arch"].solve(wi, wo).reasons[0] == Reason.FOOTPRINT
    assert arch_point.solve(wi, wo).reasons[0] == Reason.OK
    wi, wo = direction(10.0, 0.0)[None], direction(40.0, 180.0)[None]  # 25/cos 40° > 30 mm
    assert rigs["arch"].solve(wi, wo).reasons[0] == Reason.OK
    assert arch_point.solve(wi, wo).reasons[0] == Reason.VIEW_OFF_SAMPLE


def test_a_serial_light_switch() -> None:
    spec = SerialSwitchSpec.model_validate(
        {
            "kind": "serial",
            "port": "/dev/ttyUSB1",
            "line_ending": "\r",
            "on_command": "LAMP ON",
            "off_command": "LAMP OFF",
            "ack": "^OK",
            "query_command": "LAMP?",
            "on_reply": "^ON$",
            "off_reply": "^OFF$",
            "warmup_s": 30,
        }
    )
    assert (spec.baud, spec.line_ending, spec.line_ending_chars) == (9600, "cr", "\r")
    assert (spec.timeout_s, spec.warmup_s) == (1.0, 30.0)


@pytest.mark.parametrize(("theta_i", "theta_o"), [(0.0, 45.0), (8.0, 30.0)])
def test_reference_directions(tmp_path: Path, theta_i: float, theta_o: float) -> None:
    data = {**ARCH_DATA, "reference": {"theta_i_deg": theta_i, "theta_o_deg": theta_o}}
    path = tmp_path / "rig.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    rig = Rig.from_yaml(path)
    wi, wo = rig.reference_directions()
    assert rig.spec.reference.albedo == 0.99  # the default
    np.testing.assert_allclose(wi, direction(theta_i, 0.0), atol=1e-15)
    np.testing.assert_allclose(wo, direction(theta_o, 180.0), atol=1e-15)
    assert math.isclose(float(wi @ wo), math.cos(math.radians(theta_i + theta_o)))
