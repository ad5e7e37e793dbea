"""The rig file's ``detector.interface: {kind: pymeasure, ...}``: presets filled in,
overrides taken, and each mistake one line naming the file and the field: a number
beyond what an instrument takes, and (PyMeasure being installed) a property the
instrument class does not declare, with the nearest it does."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
import yaml

from drivers.pymeasure import PRESETS, SETTLE_TAU
from gonio.config import ConfigError
from gonio.rig.lab_instrument import PyMeasureInterfaceSpec
from gonio.rig.model import Rig
from tests.conftest import RIG_FILES
from tests.support.process import refused

RIGS = RIG_FILES["arch"].parent
LOCKIN = yaml.safe_load((RIGS / "arch_lockin.yaml").read_text())
SR830 = "pymeasure.instruments.srs.SR830"


def test_the_lockin_rig_is_the_serial_rig_with_an_sr830() -> None:
    serial = yaml.safe_load((RIGS / "arch_serial.yaml").read_text())
    lockin = dict(LOCKIN)
    for d in (serial, lockin):
        d.pop("name")
        d["detector"] = {k: v for k, v in d["detector"].items() if k != "interface"}
    assert lockin == serial
    config = Rig.from_yaml(RIGS / "arch_lockin.yaml").spec.detector.interface
    assert isinstance(config, PyMeasureInterfaceSpec)
    driver = config.config()
    assert driver.instrument == SR830 and driver.read_termination == "\r"
    assert driver.exposure.settle_tau == SETTLE_TAU[24] and driver.dark_subtracted


@pytest.mark.parametrize("instrument", sorted(PRESETS))
def test_a_preset_needs_only_the_class_and_the_resource(instrument: str) -> None:
    spec = PyMeasureInterfaceSpec.model_validate(
        {"kind": "pymeasure", "instrument": instrument, "resource": "GPIB0::1::INSTR"}
    )
    assert spec.config().reading == PRESETS[instrument]["reading"]


def test_fields_override_the_preset() -> None:
    spec = PyMeasureInterfaceSpec.model_validate(
        {
            "kind": "pymeasure",
            "instrument": SR830,
            "resource": "GPIB0::8::INSTR",
            "reading": "x",
            "settings": {"filter_slope": 12, "sensitivity": 0.01},
            "exposure": {"kind": "time_constant", "property": "time_constant", "settle_tau": 7},
            "dark_subtracted": False,
        }
    )
    config = spec.config()
    assert config.reading == "x" and not config.dark_subtracted
    assert config.settings == (("filter_slope", 12), ("sensitivity", 0.01))
    assert config.exposure.settle_tau == 7 and config.overload_property == "lia_status"


@pytest.mark.parametrize(
    ("fields", "field", "says"),
    [
        ({"instrument": "SR830"}, "instrument", "not a dotted class name"),
        ({"resource": " "}, "resource", "expected a VISA resource"),
        ({"exposure": {"kind": "averaging"}}, "exposure.property", "expected"),
        (
            {"exposure": {"kind": "averaging", "command": "COUN {n}"}},
            "exposure.command",
            "not a template of {count}",
        ),
        (
            {
                "ranging": "auto",
                "range_property": None,
                "instrument": "a.B",
                "reading": "v",
                "exposure": {"kind": "wait"},
            },
            "range_property",
            "expected with ranging: auto",
        ),
        (
            {"overload_mask": 4, "instrument": "a.B", "reading": "v", "exposure": {"kind": "wait"}},
            "overload_property",
            "expected with overload_mask",
        ),
        ({"instrument": "mylab.Photometer"}, "reading", "no preset"),
        ({"reading": "not a name"}, "reading", "not a property name"),
        ({"timeout_s": 0}, "timeout_s", "greater than 0"),
        ({"timeout_s": "1e300"}, "timeout_s", "expected at most 1e+09 s (got '1e300')"),
        ({"timeout_s": 1e300}, "timeout_s", "expected at most 1e+09 s"),
        ({"timeout_s": 7200}, "timeout_s", "less than or equal to 3600"),
        ({"settings": {"filter_slpe": 24}}, "settings.filter_slpe", "did you mean 'filter_slope'"),
        ({"settings": {"sensitivity": "1e300"}}, "settings.sensitivity", "from 1e-15 to 1e+09"),
        ({"settings": {"sensitivity": -1e-300}}, "settings.sensitivity", "from 1e-15 to 1e+09"),
        ({"reading": "magnitud"}, "reading", "SR830 has no property 'magnitud'; did you mean"),
        ({"range_property": "sensitivty"}, "range_property", "did you mean 'sensitivity'"),
        ({"baud_rate": 10**9}, "baud_rate", "less than or equal to 12000000"),
        ({"baud_rate": 0}, "baud_rate", "greater than or equal to 50"),
        ({"full_scale": 1e300}, "full_scale", "less than or equal to 1000000000"),
        ({"overload_mask": 2**40}, "overload_mask", "less than or equal to 4294967295"),
        (
            {
                "exposure": {
                    "kind": "time_constant",
                    "property": "time_constant",
                    "settle_tau": 1e300,
                }
            },
            "exposure.settle_tau",
            "less than or equal to 100",
        ),
        (
            {"exposure": {"kind": "time_constant", "property": "time_constnt"}},
            "exposure.property",
            "did you mean 'time_constant'",
        ),
        (
            {"exposure": {"kind": "time_constant", "property": "time_constant", "values": [1e300]}},
            "exposure.values.0",
            "less than or equal to 1000000000",
        ),
        (
            {"exposure": {"kind": "averaging", "command": "C {count}", "max_count": 10**12}},
            "exposure.max_count",
            "less than or equal to 10000000",
        ),
        (
            {"exposure": {"kind": "nplc", "property": "x", "line_hz": 1e300}},
            "exposure.line_hz",
            "less than or equal to 400",
        ),
        (
            {"exposure": {"kind": "nplc", "property": "x", "nplc_range": [0.01, 1e300]}},
            "exposure.nplc_range.1",
            "less than or equal to 1000",
        ),
        ({"frobnicate": 1}, "frobnicate", "unknown field"),
    ],
)
def test_a_mistake_is_one_line_naming_the_field(
    tmp_path: Path, fields: dict[str, Any], field: str, says: str
) -> None:
    data = yaml.safe_load((RIGS / "arch_lockin.yaml").read_text())
    interface = {"kind": "pymeasure", "instrument": SR830, "resource": "GPIB0::8::INSTR"}
    interface.update({k: v for k, v in fields.items() if v is not None})
    data["detector"]["interface"] = interface
    path = tmp_path / "rig.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    with pytest.raises(ConfigError) as info:
        Rig.from_yaml(path)
    message = str(info.value)
    assert "\n" not in message and message.startswith(f"{path}:")
    assert f"detector.interface.{field}" in message and says in message, message


def test_a_misspelled_setting_stops_gonio_plan_in_one_line(tmp_path: Path) -> None:
    rig = tmp_path / "rig.yaml"
    text = (RIGS / "arch_lockin.yaml").read_text()
    rig.write_text(text.replace("{filter_slope: 24}", "{filter_slpe: 24}"))
    line = refused(
        tmp_path,
        "plan",
        "configs/plans/quick.yaml",
        "--rig",
        str(rig),
        "-o",
        str(tmp_path / "plan.csv"),
    )
    assert line == (
        f"gonio: error: {rig}:72: detector.interface.settings.filter_slpe: SR830 has no "
        "property 'filter_slpe'; did you mean 'filter_slope'?"
    )
