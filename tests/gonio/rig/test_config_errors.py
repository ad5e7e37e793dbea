"""Bad rig files: each mistake is a `ConfigError` whose message is one line naming the
file, the field path and what is expected (with the line where pydantic or the YAML
parser reports the mistake; the chain checks made after validation, in `Rig`, name the
file and the field but no line)."""

from __future__ import annotations

import copy
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from gonio.config import ConfigError
from gonio.rig.model import Rig
from gonio.rig.solution import Reason
from tests.conftest import RIG_FILES
from tests.support.rigs import direction, uniform_directions

BASE = {name: yaml.safe_load(path.read_text()) for name, path in RIG_FILES.items()}


def write(tmp_path: Path, data: Any, name: str = "bad-rig.yaml") -> Path:
    path = tmp_path / name
    text = data if isinstance(data, str) else yaml.safe_dump(data, sort_keys=False)
    path.write_text(text, encoding="utf-8")
    return path


def error_of(path: Path) -> str:
    with pytest.raises(ConfigError) as info:
        Rig.from_yaml(path)
    message = str(info.value)
    assert all(line.startswith(f"{path}:") for line in message.splitlines())  # one a problem
    return message


def line_of_value(path: Path, *keys: str) -> int:
    """1-based line where the value of the nested key keys[-1] starts (each key searched
    after the previous one, as block-style YAML writes them): the key's line, or the
    next one for a block mapping or sequence (where `gonio.config` points)."""
    lines = path.read_text().splitlines()
    at = 0
    for key in keys:
        at = next(i for i in range(at, len(lines)) if lines[i].lstrip().startswith(f"{key}:"))
    return at + 1 + lines[at].rstrip().endswith(":")


def edit(rig: str, change: Callable[[dict[str, Any]], object]) -> dict[str, Any]:
    data = copy.deepcopy(BASE[rig])
    change(data)
    return data


def serial(**fields: object) -> Callable[[dict[str, Any]], object]:
    """A change: the detector's interface serial on a port, with ``fields``."""
    return lambda d: d["detector"].update(interface={"kind": "serial", "port": "/dev/x", **fields})


def switch(fields: dict[Any, object]) -> Callable[[dict[str, Any]], object]:
    """A change: a serial light switch, with ``fields``."""
    base = {"kind": "serial", "port": "/dev/y", "on_command": "L1", "off_command": "L0"}
    return lambda d: d["light"].update(switch={**base, **fields})


def point(d: dict[str, Any]) -> None:
    d["light"].update(kind="point", distance_mm=300)
    d["constraints"].pop("beam_diameter_mm")


def _chain(*changes: Callable[[dict[str, Any]], object]) -> Callable[[dict[str, Any]], object]:
    return lambda d: [change(d) for change in changes]


#: The light, detector and reference sections (id, rig, change, field, line keys, words).
INSTRUMENT_CASES: list[
    tuple[str, str, Callable[[dict[str, Any]], object], str, tuple[str, ...], str]
] = [
    (
        "unknown-light-kind",
        "arch",
        lambda d: d["light"].update(kind="laser"),
        "light.kind",
        ("light", "kind"),
        "Input should be 'collimated' or 'point' (got 'laser')",
    ),
    (
        "point-source-without-a-distance",
        "arch",
        _chain(point, lambda d: d["light"].pop("distance_mm")),
        "light.distance_mm",
        ("light",),
        "Field required for a point source (kind: point)",
    ),
    (
        "collimated-light-with-a-distance",
        "in_plane",
        lambda d: d["light"].update(distance_mm=300),
        "light.distance_mm",
        ("light", "distance_mm"),
        "a collimated beam has no distance; expected it with kind: point",
    ),
    (
        "point-source-with-a-beam",
        "arch",
        _chain(point, lambda d: d["constraints"].update(beam_diameter_mm=6)),
        "constraints.beam_diameter_mm",
        ("constraints", "beam_diameter_mm"),
        "a point source floods the sample and has no beam diameter",
    ),
    (
        "unknown-switch",
        "arch",
        lambda d: d["light"].update(switch="relay"),
        "light.switch",
        ("light", "switch"),
        "Input tag 'relay' found using 'kind' does not match any of the expected tags: "
        "'none', 'serial'",
    ),
    (
        "serial-switch-without-a-port",
        "arch",
        lambda d: d["light"].update(switch={"kind": "serial", "on_command": "L1"}),
        "light.switch.port",
        ("light", "switch"),
        "Field required",
    ),
    (
        "switch-with-yaml-boolean-keys",
        "arch",
        switch({True: "L1", False: "L0"}),  # what `on: L1` and `off: L0` read as
        "light.switch",
        ("light", "switch"),
        "YAML reads the keys on: and off: as true and false; expected on_command:",
    ),
    (
        "switch-command-of-two-lines",
        "arch",
        switch({"on_command": "L1\nL2"}),
        "light.switch.on_command",
        ("light", "switch", "on_command"),
        "expected one line of ASCII text, got 'L1\\nL2'",
    ),
    (
        "switch-ack-not-a-regex",
        "in_plane",
        switch({"ack": "(OK"}),
        "light.switch.ack",
        ("light", "switch", "ack"),
        "'(OK' is not a valid regular expression: missing ), unterminated subpattern",
    ),
    (
        "switch-query-without-replies",
        "arch",
        switch({"query_command": "L?", "off_reply": "^OFF"}),
        "light.switch.on_reply",
        ("light", "switch"),
        "expected a regex for the answer to query_command",
    ),
    (
        "switch-reply-without-a-query",
        "arch",
        switch({"on_reply": "^ON"}),
        "light.switch.query_command",
        ("light", "switch"),
        "expected the command that on_reply answers",
    ),
    (
        "detector-without-an-aperture",
        "arch",
        lambda d: d["detector"].pop("aperture_sr"),
        "detector.aperture_sr",
        ("detector",),
        "Field required",
    ),
    (
        "aperture-beyond-a-hemisphere",
        "in_plane",
        lambda d: d["detector"].update(aperture_sr=7),
        "detector.aperture_sr",
        ("detector", "aperture_sr"),
        "less than or equal to 6.28",
    ),
    (
        "exposure-range-inverted",
        "arch",
        lambda d: d["detector"].update(exposure_range_s=[1, 0.1]),
        "detector.exposure_range_s",
        ("detector", "exposure_range_s"),
        "expected [min, max] with 0 < min ≤ max, got [1.0, 0.1]",
    ),
    (
        "negative-readout",
        "arch",
        lambda d: d["detector"].update(readout_s=-0.1),
        "detector.readout_s",
        ("detector", "readout_s"),
        "greater than or equal to 0",
    ),
    (
        "zero-max-averages",
        "arch",
        lambda d: d["detector"].update(max_averages=0),
        "detector.max_averages",
        ("detector", "max_averages"),
        "greater than or equal to 1",
    ),
    (
        "unknown-interface",
        "arch",
        lambda d: d["detector"].update(interface="usb"),
        "detector.interface",
        ("detector", "interface"),
        "Input tag 'usb' found using 'kind' does not match any of the expected tags: "
        "'simulated', 'serial'",
    ),
    (
        "serial-detector-without-a-port",
        "arch",
        lambda d: d["detector"].update(interface="serial"),
        "detector.interface.port",
        ("detector", "interface"),
        "Field required",
    ),
    (
        "serial-query-with-an-unknown-field",
        "arch",
        serial(query="MEAS {gain}"),
        "detector.interface.query",
        ("detector", "interface", "query"),
        "'MEAS {gain}' uses ['gain']; allowed fields: {averages}, {exposure_ms}",
    ),
    (
        "serial-query-not-a-template",
        "arch",
        serial(query="MEAS {exposure_ms"),
        "detector.interface.query",
        ("detector", "interface", "query"),
        "'MEAS {exposure_ms' is not a valid template: ",
    ),
    (
        "serial-set-exposure-with-averages",
        "in_plane",
        serial(set_exposure="EXP {averages}"),
        "detector.interface.set_exposure",
        ("detector", "interface", "set_exposure"),
        "'EXP {averages}' uses ['averages']; allowed fields: {exposure_ms}",
    ),
    (
        "serial-init-command-with-a-field",
        "arch",
        serial(init=["MODE {x}"]),
        "detector.interface.init.0",
        ("detector", "interface", "init"),
        "'MODE {x}' uses ['x']; allowed fields: none",
    ),
    (
        "serial-response-without-a-value",
        "arch",
        serial(response=r"VAL (\d+)"),
        "detector.interface.response",
        ("detector", "interface", "response"),
        "needs a named group (?P<value>...)",
    ),
    (
        "serial-response-not-a-regex",
        "arch",
        serial(response="(?P<value>[0-9"),
        "detector.interface.response",
        ("detector", "interface", "response"),
        "is not a valid regular expression: unterminated character set",
    ),
    (
        "serial-banner-not-a-regex",
        "arch",
        serial(reset_banner="READY)"),
        "detector.interface.reset_banner",
        ("detector", "interface", "reset_banner"),
        "'READY)' is not a valid regular expression: unbalanced parenthesis",
    ),
    (
        "serial-saturated-status-without-a-group",
        "arch",
        serial(saturated_status="^SAT$"),
        "detector.interface.saturated_status",
        ("detector", "interface", "saturated_status"),
        "needs a named group (?P<status>...) in response",
    ),
    (
        "serial-device-averaging-without-the-field",
        "arch",
        serial(device_averaging=True),
        "detector.interface.device_averaging",
        ("detector", "interface", "device_averaging"),
        "needs an {averages} field in query",
    ),
    (
        "serial-unknown-line-ending",
        "arch",
        serial(line_ending="\t"),
        "detector.interface.line_ending",
        ("detector", "interface", "line_ending"),
        "Input should be 'lf', 'crlf' or 'cr' (got '\\t')",
    ),
    (
        "serial-zero-timeout",
        "arch",
        serial(timeout_s=0),
        "detector.interface.timeout_s",
        ("detector", "interface", "timeout_s"),
        "greater than 0",
    ),
    (
        "serial-short-max-line",
        "arch",
        serial(max_line_bytes=8),
        "detector.interface.max_line_bytes",
        ("detector", "interface", "max_line_bytes"),
        "greater than or equal to 16",
    ),
    (
        "serial-unknown-field",
        "arch",
        serial(parity="E"),
        "detector.interface.parity",
        ("detector", "interface", "parity"),
        "unknown field",
    ),
    (
        "reference-albedo-above-one",
        "arch",
        lambda d: d["reference"].update(albedo=1.2),
        "reference.albedo",
        ("reference", "albedo"),
        "less than or equal to 1",
    ),
    (
        "reference-at-grazing",
        "in_plane",
        lambda d: d["reference"].update(theta_o_deg=90),
        "reference.theta_o_deg",
        ("reference", "theta_o_deg"),
        "less than 90",
    ),
]

# (id, rig, change, field path, line keys or None, expected words)
CASES: list[tuple[str, str, Callable[[dict[str, Any]], object], str, tuple[str, ...], str]] = [
    (
        "unknown-type",
        "arch",
        lambda d: d.update(type="delta"),
        "type",
        ("type",),
        "Input should be 'arch' or 'in_plane' (got 'delta')",
    ),
    (
        "inverted-limits",
        "arch",
        lambda d: d["axes"]["light_elevation"].update(min_deg=90, max_deg=10),
        "axes.light_elevation.max_deg",
        ("axes", "light_elevation", "max_deg"),
        "expected more than min_deg (90.0), got 10.0",
    ),
    (
        "equal-limits",
        "in_plane",
        lambda d: d["axes"]["sample_tilt"].update(min_deg=10, max_deg=10),
        "axes.sample_tilt.max_deg",
        ("axes", "sample_tilt", "max_deg"),
        "expected more than min_deg (10.0), got 10.0",
    ),
    (
        "negative-velocity",
        "arch",
        lambda d: d["axes"]["detector_azimuth"].update(max_velocity_deg_s=-40),
        "axes.detector_azimuth.max_velocity_deg_s",
        ("axes", "detector_azimuth", "max_velocity_deg_s"),
        "greater than or equal to 0.001 (got -40)",
    ),
    (
        "velocity-whose-moves-never-end",
        "arch",
        lambda d: d["axes"]["detector_azimuth"].update(max_velocity_deg_s=1e-300),
        "axes.detector_azimuth.max_velocity_deg_s",
        ("axes", "detector_azimuth", "max_velocity_deg_s"),
        "greater than or equal to 0.001 (got 1e-300)",
    ),
    (
        "joint-limit-beyond-any-motor",
        "arch",
        lambda d: d["axes"]["sample_rotation"].update(min_deg=-1e300),
        "axes.sample_rotation.min_deg",
        ("axes", "sample_rotation", "min_deg"),
        "greater than or equal to -921600 (got -1e+300)",
    ),
    (
        "a-baud-rate-the-motors-do-not-know",
        "arch",
        lambda d: d.setdefault("bus", {}).update(baud=12345),
        "bus.baud",
        ("bus", "baud"),
        "expected one of 9600, 57600, 115200",
    ),
    (
        "a-sample-a-kilometre-wide",
        "arch",
        lambda d: d["constraints"].update(sample_diameter_mm=1e6),
        "constraints.sample_diameter_mm",
        ("constraints", "sample_diameter_mm"),
        "less than or equal to 10000 (got 1000000.0)",
    ),
    (
        "zero-acceleration",
        "in_plane",
        lambda d: d["axes"]["light_arm"].update(max_acceleration_deg_s2=0),
        "axes.light_arm.max_acceleration_deg_s2",
        ("axes", "light_arm", "max_acceleration_deg_s2"),
        "greater than or equal to 0.001 (got 0)",
    ),
    (
        "missing-field",
        "arch",
        lambda d: d["constraints"].pop("sample_diameter_mm"),
        "constraints.sample_diameter_mm",
        ("constraints",),
        "Field required",
    ),
    (
        "collimated-light-without-a-beam",
        "arch",
        lambda d: d["constraints"].pop("beam_diameter_mm"),
        "constraints.beam_diameter_mm",
        ("constraints",),
        "Field required for a collimated light (light.kind: collimated)",
    ),
    (
        "missing-chain",
        "in_plane",
        lambda d: d.pop("detector"),
        "detector",
        (),
        "Field required",
    ),
    (
        "unknown-field",
        "arch",
        lambda d: d["axes"]["light_elevation"].update(speed=3),
        "axes.light_elevation.speed",
        ("axes", "light_elevation", "speed"),
        "unknown field",
    ),
    (
        "unknown-top-level-field",
        "in_plane",
        lambda d: d.update(colour="red"),
        "colour",
        ("colour",),
        "unknown field",
    ),
    (
        "zero-axis-vector",
        "arch",
        lambda d: d["axes"]["sample_rotation"].update(axis=[0, 0, 0]),
        "axes.sample_rotation.axis",
        ("axes", "sample_rotation", "axis"),
        "must not be the zero vector",
    ),
    (
        "theta-max-past-the-horizon",
        "arch",
        lambda d: d["constraints"].update(theta_max_deg=95),
        "constraints.theta_max_deg",
        ("constraints", "theta_max_deg"),
        "less than or equal to 90",
    ),
    (
        "motor-id-out-of-range",
        "in_plane",
        lambda d: d["axes"]["sample_rotation"].update(motor_id=253),
        "axes.sample_rotation.motor_id",
        ("axes", "sample_rotation", "motor_id"),
        "less than or equal to 252",
    ),
    (
        "chain-names-an-unknown-axis",
        "arch",
        lambda d: d["light"].update(axes=["light_arm"]),
        "light.axes.0",
        ("light", "axes"),
        "'light_arm' is not one of the axes",
    ),
    (
        "axes-of-the-other-type",
        "arch",
        lambda d: d.update(type="in_plane"),
        "axes",
        ("axes",),
        "a 'in_plane' rig has the axes light_arm, detector_arm, sample_tilt, sample_rotation",
    ),
    (
        "shared-motor-id",
        "arch",
        lambda d: d["axes"]["detector_azimuth"].update(motor_id=1),
        "axes.detector_azimuth.motor_id",
        ("axes", "detector_azimuth", "motor_id"),
        "motor ID 1 is already used by light_elevation",
    ),
    *INSTRUMENT_CASES,
    (
        "collision-names-an-unknown-axis",
        "in_plane",
        lambda d: d["constraints"]["collisions"][0]["ranges_deg"].update(arm=[0, 1]),
        "constraints.collisions.0.ranges_deg.arm",
        ("constraints", "collisions", "ranges_deg", "arm"),
        "names unknown axis 'arm'",
    ),
]


@pytest.mark.parametrize(
    ("rig", "change", "field", "line_keys", "expected"),
    [c[1:] for c in CASES],
    ids=[c[0] for c in CASES],
)
def test_invalid_field(
    tmp_path: Path,
    rig: str,
    change: Callable[[dict[str, Any]], object],
    field: str,
    line_keys: tuple[str, ...],
    expected: str,
) -> None:
    path = write(tmp_path, edit(rig, change))
    message = error_of(path)
    line = line_of_value(path, *line_keys) if line_keys else 1
    assert message.startswith(f"{path}:{line}: {field}: "), message
    assert expected in message


@pytest.mark.parametrize(
    ("rig", "change", "field", "expected"),
    [
        (
            "arch",
            lambda d: d["axes"]["light_elevation"].update(axis=[1, 0, 0]),
            "light.axes",
            "a arch rig needs light_elevation about (0, 1, 0)",
        ),
        (
            "arch",
            lambda d: d["axes"]["light_elevation"].update(axis=[0, -1, 0]),
            "light.axes",
            "light_elevation about (0, 1, 0)",
        ),
        (
            "arch",
            lambda d: d["detector"].update(axes=["detector_elevation", "detector_azimuth"]),
            "detector.axes",
            "detector_azimuth about (0, 0, 1), detector_elevation about (0, 1, 0)",
        ),
        (
            "in_plane",
            lambda d: d["axes"]["sample_tilt"].update(axis=[0, 1, 0]),
            "sample.axes",
            "a in_plane rig needs sample_tilt about (1, 0, 0), sample_rotation about (0, 0, 1)",
        ),
        (
            "in_plane",
            lambda d: d["detector"].update(pointing=[1, 0, 0]),
            "detector.pointing",
            "points along (0, 0, 1)",
        ),
    ],
    ids=[
        "arch-light-about-x",
        "arch-light-reversed",
        "arch-detector-chain-order",
        "in_plane-tilt-about-y",
        "in_plane-detector-pointing",
    ],
)
def test_chain_that_does_not_fit_the_type(
    tmp_path: Path, rig: str, change: Callable[[dict[str, Any]], object], field: str, expected: str
) -> None:
    path = write(tmp_path, edit(rig, change))
    message = error_of(path)
    assert message.startswith(f"{path}: {field}: "), message
    assert expected in message


def test_motor_range_that_does_not_fit_position_mode(tmp_path: Path) -> None:
    """-5…85° of light elevation with the motor's zero at 0°: negative ticks."""
    path = write(
        tmp_path, edit("arch", lambda d: d["axes"]["light_elevation"].pop("zero_offset_deg"))
    )
    message = error_of(path)
    assert message.startswith(f"{path}: axes.light_elevation: "), message
    assert "outside 0…4095 in position mode" in message


def test_not_yaml(tmp_path: Path) -> None:
    path = write(tmp_path, "name: arch\ntype: [arch\naxes: {}\n")
    message = error_of(path)
    assert re.match(rf"{re.escape(str(path))}:\d+: not valid YAML: ", message), message


@pytest.mark.parametrize(("text", "kind"), [("- arch\n- in_plane\n", "list"), ("", "empty")])
def test_not_a_mapping(tmp_path: Path, text: str, kind: str) -> None:
    path = write(tmp_path, text)
    message = error_of(path)
    assert message == f"{path}: expected a mapping of fields at the top level, got {kind}"


def test_missing_file(tmp_path: Path) -> None:
    message = error_of(tmp_path / "nowhere.yaml")
    assert "cannot read the file" in message


@pytest.mark.parametrize(
    ("change", "reason"),
    [
        (lambda d: d["constraints"].update(beam_diameter_mm=40), Reason.FOOTPRINT),
        (
            lambda d: d["constraints"].update(theta_max_deg=3, min_separation_deg=10),
            Reason.THETA_MAX,  # the first check that fails is the one counted
        ),
    ],
    ids=["beam-wider-than-the-sample", "cap-narrower-than-the-blind-spot"],
)
def test_rig_with_nothing_reachable(
    tmp_path: Path, change: Callable[[dict[str, Any]], object], reason: Reason
) -> None:
    """A rig whose constraints leave nothing measurable is refused when it is loaded,
    with one line naming the file, the constraints and the reasons counted."""
    path = write(tmp_path, edit("arch", change))
    message = error_of(path)
    assert message.startswith(f"{path}: constraints: leave no direction pair measurable"), message
    assert reason.label.replace("_", " ") in message


def test_rig_with_a_sliver_reachable_loads(tmp_path: Path) -> None:
    """A narrow cap that still leaves pairs measurable loads, and refuses most pairs."""
    rig = Rig.from_yaml(
        write(tmp_path, edit("arch", lambda d: d["constraints"].update(theta_max_deg=20)))
    )
    rng = np.random.default_rng(0)
    wi = np.concatenate([uniform_directions(rng, 5000, np.pi / 2), direction(0.0, 0.0)[None]])
    wo = np.concatenate([uniform_directions(rng, 5000, np.pi / 2), direction(15.0, 0.0)[None]])
    ok, reasons = rig.reachable(wi, wo)
    assert ok[-1]
    assert 0 < ok.mean() < 0.05
    assert np.mean(reasons == Reason.THETA_MAX) > 0.9
