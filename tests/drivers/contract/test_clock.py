"""The `drivers.base.Clock` contract on the real clock and the simulator's clocks."""

from __future__ import annotations

import time

import pytest

from drivers.base import Clock, SystemClock
from sim.clock import ManualClock, ScaledClock

CLOCKS = {
    "system": SystemClock,
    "manual": ManualClock,
    "scaled": lambda: ScaledClock(100.0),
}


@pytest.fixture(params=list(CLOCKS))
def a_clock(request: pytest.FixtureRequest) -> Clock:
    clock: Clock = CLOCKS[request.param]()
    return clock


def test_sleep_lets_that_much_time_pass_and_time_never_goes_back(a_clock: Clock) -> None:
    t0 = a_clock.now()
    a_clock.sleep(0.01)
    t1 = a_clock.now()
    assert t1 - t0 >= 0.01 - 1e-12
    a_clock.sleep(0.0)
    assert a_clock.now() >= t1
    with pytest.raises(ValueError, match=r"negative|backwards"):
        a_clock.sleep(-1.0)


def test_the_virtual_clock_moves_exactly_and_only_when_told() -> None:
    clock = ManualClock(5.0)
    time.sleep(0.01)
    assert clock.now() == 5.0
    clock.sleep(0.25)
    assert clock.now() == 5.25
    assert clock.advance_to(7.0) == 7.0 == clock()
