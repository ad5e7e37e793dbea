"""In-process device servers lower the interpreter's switch interval while they run."""

from __future__ import annotations

import sys

import pytest

from sim.peers import responsive
from sim.peers.dynamixel.emulator import DxlEmulator
from sim.peers.serial_photometer.device import SerialPhotometer

#: The interval the interpreter keeps (it stores whole microseconds).
SERVING = pytest.approx(responsive.SERVING_SWITCH_INTERVAL_S, rel=1e-6)


def test_servers_lower_the_switch_interval_while_any_runs() -> None:
    before = sys.getswitchinterval()
    assert before > responsive.SERVING_SWITCH_INTERVAL_S
    bus, meter = DxlEmulator(ids=(1,)), SerialPhotometer()
    with bus:
        assert sys.getswitchinterval() == SERVING
        with meter:
            assert sys.getswitchinterval() == SERVING
        assert sys.getswitchinterval() == SERVING
    assert sys.getswitchinterval() == before
    bus.stop()  # a second stop does not restore twice
    assert sys.getswitchinterval() == before


def test_unbalanced_stops_leave_the_interval_alone() -> None:
    before = sys.getswitchinterval()
    responsive.serving_stopped()
    assert sys.getswitchinterval() == before
