"""`gonio motors scan | status | reboot` against the emulator, in-process (`gonio_cli`)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from sim.peers.dynamixel.emulator import DxlEmulator
from sim.peers.dynamixel.faults import Fault
from tests.conftest import CONFIGS, CliResult

Emulator = Callable[..., DxlEmulator]
Gonio = Callable[..., CliResult]


def test_scan_finds_the_motors_at_their_rate(emulator: Emulator, run_gonio: Gonio) -> None:
    emu = emulator(ids=(1, 3, 4), baud=1_000_000)
    r = run_gonio("motors", "scan", "--port", emu.path)
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert f"{emu.path} at 57600 baud: 0 motor(s)" in lines
    assert f"{emu.path} at 1000000 baud: 3 motor(s)" in lines
    assert any(line.split()[:3] == ["3", "XM430-W350", "1020"] for line in lines)


def test_scan_of_an_empty_bus_says_what_to_check(emulator: Emulator, run_gonio: Gonio) -> None:
    emu = emulator(ids=(1,), baud=115_200)
    r = run_gonio("motors", "scan", "--port", emu.path, "--baud", "57600")
    assert r.returncode == 1
    assert "no motor answered: check power" in r.stdout


def test_status_shows_positions_temperatures_voltages_and_errors(
    emulator: Emulator, run_gonio: Gonio
) -> None:
    emu = emulator(ids=(1, 2))
    emu.motors[2].set("present_position", -1024)
    emu.inject(Fault.OVERHEATING, motor_id=2)
    r = run_gonio("motors", "status", "--port", emu.path, "--ids", "1-2,5")
    assert r.returncode == 1  # motor 5 is missing
    rows = {line.split()[0]: line for line in r.stdout.splitlines()[1:]}
    assert rows["1"].split()[2:4] == ["2048", "180.00"]
    assert "12.0" in rows["1"]
    assert rows["1"].endswith("none")
    assert rows["2"].split()[2:4] == ["-1024", "-90.00"]
    assert rows["2"].endswith("overheating")
    assert rows["5"].endswith("no answer")


def test_reboot_clears_a_hardware_error(emulator: Emulator, run_gonio: Gonio) -> None:
    emu = emulator(ids=(1,))
    emu.inject(Fault.OVERLOAD, motor_id=1)
    r = run_gonio("motors", "reboot", "--port", emu.path, "--ids", "1")
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == "motor 1 rebooted"
    assert emu.motors[1].hardware_error == 0


def test_errors_are_one_line_without_traceback(emulator: Emulator, run_gonio: Gonio) -> None:
    emu = emulator(ids=(1,))
    cases = [
        (("motors", "scan", "--port", "/dev/does-not-exist"), "does not exist"),
        (
            ("motors", "status", "--port", emu.path, "--ids", "1", "--baud", "12"),
            "baud must be one of",
        ),
        (("motors", "status", "--port", emu.path, "--ids", "300"), "motor IDs must be in 0…252"),
        (("motors", "reboot", "--port", emu.path, "--ids", "9"), "motor 9"),
    ]
    for args, message in cases:
        r = run_gonio(*args)
        assert r.returncode == 2, (args, r.stdout, r.stderr)
        assert "Traceback" not in r.stderr
        assert message in r.stderr


def test_status_with_a_rig_file_names_axes_and_joint_angles(
    emulator: Emulator, tmp_path: Path, run_gonio: Gonio
) -> None:
    """--rig supplies the IDs (and the rate); each row gains its axis and joint angle:
    light_elevation has its zero at −180°, so tick 2048 (180° of motor) is joint 0°."""
    import yaml

    emu = emulator(ids=(1, 2, 3, 4))
    emu.motors[3].set("present_position", 3072)  # 270° of motor: joint +90°, past 85°
    rig = yaml.safe_load((CONFIGS / "rigs" / "arch.yaml").read_text())
    rig["bus"] = {"port": emu.path, "baud": 57_600}
    path = tmp_path / "rig.yaml"
    path.write_text(yaml.safe_dump(rig), encoding="utf-8")
    r = run_gonio("motors", "status", "--rig", str(path))
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert lines[0].split()[-3:] == ["axis", "joint", "(deg)"]
    rows = {line.split()[0]: line for line in lines[1:]}
    assert set(rows) == {"1", "2", "3", "4"}
    assert rows["1"].split()[-2:] == ["light_elevation", "0.00"]
    assert rows["3"].split()[-4:] == ["detector_elevation", "90.00", "OUTSIDE", "LIMITS"]
    # Flags override the rig: only motor 2.
    r = run_gonio("motors", "status", "--rig", str(path), "--ids", "2")
    assert [line.split()[0] for line in r.stdout.splitlines()[1:]] == ["2"]


def test_status_needs_a_port_and_ids_or_a_rig(run_gonio: Gonio) -> None:
    r = run_gonio("motors", "status", "--port", "/dev/ttyUSB9")
    assert r.returncode == 2
    assert r.stderr.strip() == (
        "gonio: error: motors status: give --port and --ids, or --rig RIG.yaml"
    )
    r = run_gonio("motors", "status", "--rig", "/nowhere/rig.yaml")
    assert r.returncode == 2
    assert "/nowhere/rig.yaml: cannot read the file" in r.stderr


def test_scan_checks_the_bus_and_with_a_rig_each_axis(
    emulator: Emulator, tmp_path: Path, run_gonio: Gonio
) -> None:
    """scan: the port's checks first, then every motor found suits the driver; with
    --rig, every axis's motor is the one the rig file expects (at the rig's rate). A
    mismatch is one line naming the motor and the fix, and exit 2."""
    import yaml

    emu = emulator(ids=(1, 2, 3, 4, 9), baud=1_000_000)  # a broadcast ping's wait is shorter
    emu.motors[9].set("status_return_level", 1)
    r = run_gonio("motors", "scan", "--port", emu.path, "--baud", "1000000")
    assert r.returncode == 2, r.stderr
    lines = r.stdout.splitlines()
    assert lines[:2] == [
        f"ok: {emu.path}: readable and writable",
        f"n/a: {emu.path}: latency timer does not apply (not a USB-serial adapter)",
    ]
    (problem,) = [line for line in lines if "problem:" in line]
    assert "motor 9 has Status Return Level 1" in problem
    assert f"gonio motors reboot --port {emu.path} --ids 9" in problem

    emu.motors[9].set("status_return_level", 2)
    emu.motors[2].set("firmware_version", 45)
    rig = yaml.safe_load((CONFIGS / "rigs" / "arch.yaml").read_text())
    rig["bus"] = {"kind": "dynamixel", "port": emu.path, "baud": 1_000_000}
    for spec in rig["axes"].values():
        spec |= {"motor_model": "XM430-W350", "motor_firmware": 46}
    path = tmp_path / "rig.yaml"
    path.write_text(yaml.safe_dump(rig), encoding="utf-8")
    r = run_gonio("motors", "scan", "--rig", str(path))
    assert r.returncode == 2, r.stderr
    assert f"{emu.path} at 1000000 baud: 5 motor(s)" in r.stdout
    problems = [line.strip() for line in r.stdout.splitlines() if "problem:" in line]
    assert problems == [
        "problem: motor 2 (axis 'detector_azimuth') runs firmware 45; the rig file expects "
        "46: update it (ROBOTIS Dynamixel Wizard, firmware update) or correct "
        "axes.detector_azimuth.motor_firmware"
    ]
    assert "ok: motor 9: XM430-W350, firmware 46" in r.stdout  # not in the rig: any model
