"""`gonio acquire PLAN --rehearse` end to end with each PyMeasure detector: the rig file
names the instrument's PyMeasure class, the rehearsal serves its emulated instrument on
a pty, pyvisa-py opens it (``ASRL/dev/pts/N::INSTR``) and the unmodified class drives
it, its readings the scene's through the simulated detector chain. A mistake in the
rig's section is one line naming the field, exit 2."""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest

from gonio.store import open_run
from tests.conftest import CONFIGS, CliResult

pytest.importorskip("pymeasure")

PLAN = CONFIGS / "plans" / "rehearsal.yaml"
LOCKIN = CONFIGS / "rigs" / "arch_lockin.yaml"
SCENE = CONFIGS / "scenes" / "matte.yaml"

#: The interface section of each instrument's rig (the rest is arch_lockin.yaml's).
INTERFACES = {
    "sr830": None,  # arch_lockin.yaml as shipped
    "sr860": (
        "    kind: pymeasure\n"
        "    instrument: pymeasure.instruments.srs.SR860\n"
        "    resource: USB0::0xB506::0x2000::003000::INSTR\n"
    ),
    "pm100usb": (
        "    kind: pymeasure\n"
        "    instrument: pymeasure.instruments.thorlabs.ThorlabsPM100USB\n"
        "    resource: USB0::0x1313::0x8072::P2000000::INSTR\n"
        "    settings: {wavelength: 633}\n"  # as the how-to shows it
        "    full_scale: 0.05\n"
    ),
    "keithley6517b": (
        "    kind: pymeasure\n"
        "    instrument: pymeasure.instruments.keithley.Keithley6517B\n"
        "    resource: GPIB0::27::INSTR\n"
    ),
    "keithley2000": (
        "    kind: pymeasure\n"
        "    instrument: pymeasure.instruments.keithley.Keithley2000\n"
        "    resource: GPIB0::16::INSTR\n"
    ),
}


def rig_with(tmp_path: Path, interface: str | None) -> Path:
    text = LOCKIN.read_text()
    if interface is not None:
        head, _, rest = text.partition("  interface:")
        _, _, tail = rest.partition("sample: {axes")
        text = f"{head}  interface:\n{interface}sample: {{axes{tail}"
    rig = tmp_path / "rig.yaml"
    rig.write_text(text)
    plan = tmp_path / "plan.yaml"
    plan.write_text(PLAN.read_text().replace("../rigs/arch_serial.yaml", str(rig)))
    return plan


@pytest.mark.parametrize("instrument", list(INTERFACES))
def test_a_rehearsal_drives_the_pymeasure_class_on_the_emulated_instrument(
    instrument: str, run_gonio: Callable[..., CliResult], tmp_path: Path
) -> None:
    plan = rig_with(tmp_path, INTERFACES[instrument])
    out = tmp_path / "run.sqlite"
    result = run_gonio(
        "acquire", str(plan), "--scene", str(SCENE), "--rehearse", "--speedup", "1000",
        "-o", str(out), "-q",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    run = open_run(out)
    assert run.complete and len(run) == 30 and run.meta["backend"] == "rehearsal"
    reference = run.of_kind("calibration")[0].data["reference"]
    assert reference["value"] > 0 and not reference["saturated"]
    # The auto-ranging meters start on their top range: their changes are range events.
    changes = [e.data for e in run.of_kind("range")]
    assert bool(changes) is instrument.startswith("keithley")
    assert all(c["new"] != c["old"] and c["unit"] in ("A", "V") for c in changes)


def test_a_mistake_in_the_section_is_one_line_naming_the_field(
    run_gonio: Callable[..., CliResult], tmp_path: Path
) -> None:
    plan = rig_with(
        tmp_path,
        "    kind: pymeasure\n"
        "    instrument: pymeasure.instruments.srs.SR830\n"
        "    resource: GPIB0::8::INSTR\n"
        "    exposure: {kind: averaging}\n",
    )
    result = run_gonio("acquire", str(plan), "--scene", str(SCENE), "--rehearse", "--dry-run")
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "detector.interface.exposure.property" in lines[0], lines


def test_an_instrument_with_no_preset_needs_its_reading(
    run_gonio: Callable[..., CliResult], tmp_path: Path
) -> None:
    plan = rig_with(
        tmp_path,
        "    kind: pymeasure\n"
        "    instrument: mylab.instruments.Photometer\n"
        "    resource: GPIB0::8::INSTR\n",
    )
    result = run_gonio("acquire", str(plan), "--scene", str(SCENE), "--rehearse", "--dry-run")
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "detector.interface.reading" in lines[0], lines


def test_reading_and_planning_a_pymeasure_rig_needs_neither_pymeasure_nor_pyvisa() -> None:
    """Without the ``instruments`` extra the rig file still reads (its property names
    are checked against the class only where PyMeasure is installed)."""
    code = (
        "import sys\nsys.modules['pymeasure'] = sys.modules['pyvisa'] = None\n"
        "from gonio.rig.model import Rig\n"
        "from gonio.workflows import backends, hardware, rehearsal\n"
        f"print(Rig.from_yaml({str(LOCKIN)!r}).spec.detector.interface.instrument)"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=60, check=True
    )
    assert out.stdout.strip() == "pymeasure.instruments.srs.SR830"


def test_a_lockin_rig_needs_no_lamp_switch_and_its_phase_drift_is_journaled(
    run_gonio: Callable[..., CliResult], tmp_path: Path
) -> None:
    """The SR830 rig with no lamp switch and the plan's dark readings on: the lock-in
    subtracts the dark, so the run takes none and says why; the simulated lock-in's
    phase drifts (through the emulated SR830's θ), and the samples beyond the tolerance
    are events, counted by gonio info, not faults."""
    plan = rig_with(tmp_path, None)
    rig = tmp_path / "rig.yaml"
    text = rig.read_text()
    start = text.index("  switch:                    # a relay board")
    rig.write_text(text[:start] + "  switch: none" + text[text.index("\ndetector:", start) :])
    scene = tmp_path / "lockin.yaml"
    text = (CONFIGS / "scenes" / "matte_lockin.yaml").read_text()
    scene.write_text(text.replace("  duty: 0.5", "  duty: 0.5\n  phase_drift_deg_per_hour: 900"))
    out = tmp_path / "run.sqlite"
    dry = run_gonio("acquire", str(plan), "--scene", str(scene), "--rehearse", "--dry-run")
    assert dry.returncode == 0 and " V at its shortest exposure" in dry.stdout, dry.stderr
    result = run_gonio(
        "acquire", str(plan), "--scene", str(scene), "--rehearse", "--speedup", "1000",
        "-o", str(out), "-q",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    run = open_run(out)
    assert run.complete and len(run) == 30
    calibrations = [e.data for e in run.of_kind("calibration")]
    assert all(c["dark"] is None and c["dark_reason"] == "detector" for c in calibrations)
    assert all(c["unit"] == "V" and "phase_deg" in c["reference"] for c in calibrations)
    drifts = run.of_kind("phase")
    assert drifts and not run.of_kind("fault")
    assert all(abs(e.data["drift_deg"]) > e.data["tolerance_deg"] == 5.0 for e in drifts)
    info = run_gonio("info", str(out))
    assert "no dark reading: the detector subtracts it (lock-in)" in info.stdout
    assert f"phase drifts{len(drifts):>22}" in info.stdout


def test_a_lockin_scene_on_a_meter_is_one_line(
    run_gonio: Callable[..., CliResult], tmp_path: Path
) -> None:
    plan = rig_with(tmp_path, INTERFACES["keithley2000"])
    scene = CONFIGS / "scenes" / "matte_lockin.yaml"
    result = run_gonio("acquire", str(plan), "--scene", str(scene), "--rehearse", "-o",
                       str(tmp_path / "run.sqlite"), "-q")  # fmt: skip
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "detector.interface" in lines[0] and "lock-in" in lines[0]
