"""Bus hygiene at the start of a hardware run and in its dry run (`gonio.workflows.hygiene`):
the arch rig on the byte-level emulator's pty (the detector stays simulated). A motor
that is not what the rig file expects refuses the run before anything moves, one line
naming the motor and the fix, exit 2, no run file; the dry run shows each check."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from gonio.config import ConfigError
from gonio.rig.model import Rig
from sim.clock import ManualClock
from sim.peers.dynamixel.emulator import DxlEmulator
from sim.rehearsal import emulated_bus
from tests.conftest import CliResult
from tests.support.acquire import ARCH, RunFiles

Emulator = Callable[..., DxlEmulator]
Gonio = Callable[..., CliResult]


def hardware_rig(tmp_path: Path, port: str, model: str = "XM430-W350") -> Path:
    """The arch rig on a Dynamixel bus at ``port``, motor 3 expected to be ``model``
    at firmware 46."""
    text = ARCH.read_text().replace(
        "  port: /dev/ttyUSB0\n", f"  kind: dynamixel\n  port: {port}\n"
    )
    text = text.replace(
        "    motor_id: 3\n", f"    motor_id: 3\n    motor_model: {model}\n    motor_firmware: 46\n"
    )
    assert "kind: dynamixel" in text and "motor_model" in text
    rig = tmp_path / "hardware.yaml"
    rig.write_text(text)
    return rig


def test_a_motor_of_the_wrong_model_refuses_the_run_in_one_line(
    tmp_path: Path, emulator: Emulator, run_files: Callable[..., RunFiles], run_gonio: Gonio
) -> None:
    emu = emulator(ids=(1, 2, 3, 4))
    files = run_files(5, rig=hardware_rig(tmp_path, emu.path, model="XL430-W250"))
    path = tmp_path / "run.sqlite"
    for extra in ((), ("--dry-run",)):
        result = run_gonio(*files.cli(path), *extra)
        assert result.returncode == 2, result
        (line,) = result.stderr.splitlines()
        assert line.startswith("gonio: error: motor 3 (axis 'detector_elevation') is XM430-W350")
        assert "expects XL430-W250" in line and "axes.detector_elevation.motor_model" in line
    assert not path.exists()
    assert "SYNC_WRITE" not in emu.stats.instructions  # nothing moved
    assert not any(emu.goals_written().values())


def test_the_dry_run_shows_the_bus_checks(
    tmp_path: Path, emulator: Emulator, run_files: Callable[..., RunFiles], run_gonio: Gonio
) -> None:
    emu = emulator(ids=(1, 2, 3, 4))
    files = run_files(5, rig=hardware_rig(tmp_path, emu.path))
    result = run_gonio(*files.cli(tmp_path / "run.sqlite"), "--dry-run")
    assert result.returncode == 0, result
    out = result.stdout.splitlines()
    assert f"  ok: {emu.path}: readable and writable" in out
    assert f"  n/a: {emu.path}: latency timer does not apply (not a USB-serial adapter)" in out
    assert any(
        line.startswith("  ok: motor 3 (axis 'detector_elevation'): XM430-W350, firmware 46")
        for line in out
    )


def test_the_rig_file_names_motors_the_driver_knows_or_model_numbers(tmp_path: Path) -> None:
    rig = Rig.from_yaml(hardware_rig(tmp_path, "/dev/ttyUSB0", model="XL430-W250"))
    assert [(a.model, a.firmware) for a in rig.bus_axes()][2] == (1060, 46)
    for bad in ("XM999-W270", "70000"):
        with pytest.raises(ConfigError, match=r"axes\.detector_elevation\.motor_model: expected"):
            Rig.from_yaml(hardware_rig(tmp_path, "/dev/ttyUSB0", model=bad))


def test_a_rehearsal_emulates_the_motors_the_rig_file_expects(tmp_path: Path) -> None:
    rig = Rig.from_yaml(hardware_rig(tmp_path, "/dev/ttyUSB0", model="XL430-W250"))
    motors = emulated_bus(rig, ManualClock()).motors  # not started: no pty
    assert (motors[3].get("model_number"), motors[3].get("firmware_version")) == (1060, 46)
    assert motors[1].get("model_number") == 1020  # no expectation: the default XM430-W350
