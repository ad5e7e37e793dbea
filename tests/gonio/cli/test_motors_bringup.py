"""`gonio motors move | home | torque | set-id` against the byte-level emulator on a real
pty, in-process: limits refused before any byte, a released arm not moved, every axis
to home, IDs changed only when free and with torque off, the port released after each
command (the next one opens it at once)."""

from __future__ import annotations

import io
import math
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
import yaml

from drivers.dynamixel.link import DynamixelLink
from gonio.rig.model import Rig
from sim.clock import ScaledClock
from sim.peers.dynamixel.emulator import DxlEmulator
from sim.rehearsal import emulated_bus
from tests.conftest import RIG_FILES, CliResult

pytestmark = pytest.mark.pty

Gonio = Callable[..., CliResult]
Emulator = Callable[..., DxlEmulator]


@pytest.fixture
def bench(tmp_path: Path) -> Iterator[tuple[Rig, Path, DxlEmulator]]:
    """The arch rig's four motors on an emulated bus (at home, torque off), and a copy
    of the rig file naming the emulator's pty as its port."""
    base = Rig.from_yaml(RIG_FILES["arch"])
    with emulated_bus(base, ScaledClock(50.0)) as emu:
        data = yaml.safe_load(RIG_FILES["arch"].read_text(encoding="utf-8"))
        data["bus"] = {"kind": "dynamixel", "port": emu.path, "baud": base.spec.bus.baud}
        path = tmp_path / "rig.yaml"
        path.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
        yield Rig.from_yaml(path), path, emu
        assert emu.error is None


def _released(emu: DxlEmulator, baud: int = 57_600) -> None:
    """The port can be opened (and locked) again at once."""
    with DynamixelLink(emu.path, baud, latency_ms=0):
        pass


#: Within the bus's settle tolerance (2 ticks of 0.088°) and the print's rounding.
SETTLED_DEG = 2 * 360 / 4096 + 0.005


def _assert_read_back(line: str, axis: str, motor: int, deg: float) -> None:
    head = f"axis {axis} (motor {motor}): at "
    tail = f"° (asked {deg:g}°)"
    assert line.strip().startswith(head) and line.strip().endswith(tail), line
    read = float(line.strip().removeprefix(head).removesuffix(tail))
    assert abs(read - deg) <= SETTLED_DEG, line


def _served(emu: DxlEmulator, baud: int = 57_600) -> None:
    """Every byte sent so far has been served: a ping's reply comes after them."""
    with DynamixelLink(emu.path, baud, latency_ms=0) as link:
        link.ping(1)


def _ticks(rig: Rig, axis: str, deg: float) -> int:
    config = next(a for a in rig.bus_axes() if a.name == axis)
    return config.to_ticks(math.radians(deg))


def test_a_move_beyond_the_limits_sends_no_byte(
    bench: tuple[Rig, Path, DxlEmulator], run_gonio: Gonio
) -> None:
    _, path, emu = bench
    assert run_gonio("motors", "torque", "on", "--rig", str(path)).returncode == 0
    _served(emu)  # the release's SYNC_WRITE (no reply) is in before the count starts
    emu.reset_stats()
    emu.clear_goals()
    for deg in ("86", "-5.5", "1e308"):
        r = run_gonio(
            "motors", "move", "--rig", str(path), "--axis", "light_elevation", "--deg", deg
        )
        assert r.returncode == 2, r
        assert r.stdout == ""
        assert len(r.stderr.splitlines()) == 1
        assert "is outside its limits [-5°, 85°]" in r.stderr and "nothing was sent" in r.stderr
    assert emu.stats.bytes_in == 0
    assert all(goals == [] for goals in emu.goals_written().values())
    for bad in ("nan", "inf"):
        r = run_gonio(
            "motors", "move", "--rig", str(path), "--axis", "light_elevation", "--deg", bad
        )
        assert r.returncode == 2 and "expected a finite angle in degrees" in r.stderr
    r = run_gonio("motors", "move", "--rig", str(path), "--axis", "nope", "--deg", "1")
    assert r.returncode == 2 and "no axis 'nope'; the axes are light_elevation" in r.stderr
    assert emu.stats.bytes_in == 0


def test_move_settles_and_prints_the_read_back_then_home_moves_every_axis(
    bench: tuple[Rig, Path, DxlEmulator], run_gonio: Gonio
) -> None:
    rig, path, emu = bench
    r = run_gonio("motors", "torque", "on", "--rig", str(path))
    assert r.returncode == 0, r.stderr
    assert r.stdout.splitlines()[0] == "axis light_elevation (motor 1): torque on, holding"
    _released(emu)
    moves = {"light_elevation": 30.0, "detector_elevation": -45.0, "sample_rotation": 120.0}
    for axis, deg in moves.items():
        emu.clear_goals()
        r = run_gonio("motors", "move", "--rig", str(path), "--axis", axis, "--deg", f"{deg:g}")
        assert r.returncode == 0, r.stderr
        motor = next(a.motor_id for a in rig.bus_axes() if a.name == axis)
        _assert_read_back(r.stdout, axis, motor, deg)
        _served(emu)
        assert _ticks(rig, axis, deg) in emu.goals_written()[motor]
    emu.clear_goals()
    r = run_gonio("motors", "home", "--rig", str(path))
    assert r.returncode == 0, r.stderr
    _served(emu)
    lines = r.stdout.splitlines()
    assert len(lines) == 4
    for axis, config, line in zip(rig.axes, rig.bus_axes(), lines, strict=True):
        home = math.degrees(float(rig.home[rig.axes.index(axis)]))
        _assert_read_back(line, axis, config.motor_id, home)
        assert emu.goals_written()[config.motor_id][-1] == _ticks(rig, axis, home)
        assert emu.motors[config.motor_id].get("present_position") == _ticks(rig, axis, home)
    _released(emu)


def test_torque_off_then_a_move_is_refused(
    bench: tuple[Rig, Path, DxlEmulator], run_gonio: Gonio
) -> None:
    rig, path, emu = bench
    assert run_gonio("motors", "torque", "on", "--rig", str(path)).returncode == 0
    r = run_gonio("motors", "torque", "off", "--rig", str(path))
    assert r.returncode == 0, r.stderr
    assert r.stdout.splitlines() == [
        f"axis {a.name} (motor {a.motor_id}): torque off" for a in rig.bus_axes()
    ]
    assert all(m.get("torque_enable") == 0 for m in emu.motors.values())
    _served(emu)
    emu.clear_goals()
    r = run_gonio("motors", "move", "--rig", str(path), "--axis", "light_elevation", "--deg", "10")
    assert r.returncode == 2
    assert r.stderr.startswith("gonio: error: torque is off on light_elevation (motor 1), ")
    assert "nothing was moved" in r.stderr and len(r.stderr.splitlines()) == 1
    _served(emu)
    assert all(goals == [] for goals in emu.goals_written().values())
    assert all(m.get("torque_enable") == 0 for m in emu.motors.values())
    _released(emu)


def test_a_fault_during_a_move_is_one_line_and_the_port_is_released(
    bench: tuple[Rig, Path, DxlEmulator], run_gonio: Gonio
) -> None:
    from sim.peers.dynamixel.faults import Fault

    _, path, emu = bench
    assert run_gonio("motors", "torque", "on", "--rig", str(path)).returncode == 0
    emu.inject(Fault.OVERLOAD, motor_id=3)
    r = run_gonio("motors", "move", "--rig", str(path), "--axis", "light_elevation", "--deg", "20")
    assert r.returncode == 2
    assert "motor 3 (axis 'detector_elevation') reports a hardware error" in r.stderr
    assert "Traceback" not in r.stderr
    _released(emu)


def test_set_id_changes_the_id_and_refuses_a_taken_one(
    emulator: Emulator, run_gonio: Gonio, monkeypatch: pytest.MonkeyPatch
) -> None:
    emu = emulator(ids=(1, 2))
    r = run_gonio("motors", "set-id", "--port", emu.path, "--from", "1", "--to", "2", "--yes")
    assert r.returncode == 2
    assert r.stderr == (
        f"gonio: error: ID 2 is already taken on {emu.path} (a XM430-W350); choose a free "
        "ID (gonio motors scan lists them); nothing was written\n"
    )
    assert sorted(emu.motors) == [1, 2]
    _released(emu)
    for bad in ("253", "-1", "x"):
        r = run_gonio("motors", "set-id", "--port", emu.path, "--from", "1", "--to", bad)
        assert r.returncode == 2 and "a motor ID is a whole number in 0…252" in r.stderr
    # Asked, answered no: nothing written.
    monkeypatch.setattr("sys.stdin", io.StringIO("n\n"))
    r = run_gonio("motors", "set-id", "--port", emu.path, "--from", "1", "--to", "7")
    assert r.returncode == 1
    assert r.stdout == (
        f"change the ID of motor 1 (XM430-W350) on {emu.path} to 7? [y/N] \nnothing changed\n"
    )
    assert sorted(emu.motors) == [1, 2]
    # Answered yes: changed, and verified by a ping of the new ID.
    monkeypatch.setattr("sys.stdin", io.StringIO("y\n"))
    r = run_gonio("motors", "set-id", "--port", emu.path, "--from", "1", "--to", "7")
    assert r.returncode == 0, r.stderr
    assert r.stdout.splitlines()[-1] == "motor 1 is now ID 7 (XM430-W350)"
    assert sorted(emu.motors) == [2, 7]
    _released(emu)
    # Torque on: the EEPROM is not written.
    emu.motors[2].set("torque_enable", 1)
    r = run_gonio("motors", "set-id", "--port", emu.path, "--from", "2", "--to", "9", "--yes")
    assert r.returncode == 2
    assert "motor 2 has its torque on" in r.stderr and "nothing was written" in r.stderr
    assert sorted(emu.motors) == [2, 7]
    # No motor at the old ID.
    r = run_gonio("motors", "set-id", "--port", emu.path, "--from", "5", "--to", "9", "--yes")
    assert r.returncode == 2 and "no motor answers as ID 5" in r.stderr
    _released(emu)
