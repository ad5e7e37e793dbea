"""Ctrl-C in a real process: a child polls the bus in a loop and gets SIGINT at a random
point of a transaction; the port must come back released and the motors holding."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from collections.abc import Callable
from pathlib import Path

import pytest

from drivers.dynamixel.control_table import RAD_PER_TICK
from drivers.dynamixel.link import DynamixelLink
from sim.peers.dynamixel.emulator import DxlEmulator

ROOT = Path(__file__).resolve().parents[2]
#: The child imports only the installed-or-on-PYTHONPATH packages (not the tests), and
#: runs in an empty directory: nothing depends on where pytest was started.
CHILD = textwrap.dedent(
    """
    import math, sys
    from drivers.dynamixel.axis import AxisConfig
    from drivers.dynamixel.bus import DynamixelBus
    axes = [
        AxisConfig(f"axis{i}", i, -1.0, 1.0, zero_offset_rad=-math.pi,
                   profile_velocity_rad_s=4.0, profile_acceleration_rad_s2=40.0)
        for i in (1, 2, 3)
    ]
    with DynamixelBus(sys.argv[1], axes, latency_ms=16) as bus:
        bus.move_to({"axis1": 0.5, "axis2": -0.5})
        print("ready", flush=True)
        while True:
            bus.positions()
    """
)


@pytest.mark.parametrize("delay_s", [0.05, 0.13, 0.21])
def test_sigint_in_a_child_process_leaves_the_port_free(
    emulator: Callable[..., DxlEmulator], delay_s: float, tmp_path: Path
) -> None:
    emu = emulator(ids=(1, 2, 3), clock=time.monotonic)
    path = os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))
    child = subprocess.Popen(
        [sys.executable, "-c", CHILD, emu.path],
        cwd=tmp_path,
        env={**os.environ, "PYTHONPATH": path},
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert child.stdout is not None
        assert child.stdout.readline().strip() == "ready"
        time.sleep(delay_s)
        child.send_signal(signal.SIGINT)
        _, stderr = child.communicate(timeout=20)
    finally:
        child.kill()
    assert "KeyboardInterrupt" in stderr
    assert "in use" not in stderr.lower()
    # The port is free at once, and the child told the motors to hold on its way out
    # (goal = where it was, torque on; a moving motor brakes and comes back to it).
    with DynamixelLink(emu.path, latency_ms=16) as link:
        deadline = time.monotonic() + 3.0
        while any(link.read(m, "moving") for m in emu.motors) and time.monotonic() < deadline:
            time.sleep(0.01)
        for motor_id in emu.motors:
            goal = link.read(motor_id, "goal_position")
            present = link.read(motor_id, "present_position")
            assert link.read(motor_id, "torque_enable") == 1
            assert abs(goal - 2048) <= round(0.5 / RAD_PER_TICK)
            assert abs(goal - present) <= 2, (motor_id, goal, present)
