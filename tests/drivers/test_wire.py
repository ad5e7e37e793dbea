"""The wire-time budget of a stop-and-go step (`drivers.dynamixel.wire.step_seconds`),
by hand."""

from __future__ import annotations

import numpy as np
import pytest

from drivers.dynamixel import wire


def test_a_step_is_the_goal_write_two_polls_and_half_a_poll_period_when_it_moves() -> None:
    baud = 57_600
    goals = (4 + 1 + 2 + 1 + 2 + 2 + 4 * (1 + 4) + 2) * 10 / baud  # 34 bytes, no reply
    poll = (18 + 4 * (11 + 14)) * 10 / baud + 4 * 500e-6  # 118 bytes, 4 return delays
    assert goals == pytest.approx(5.903e-3, abs=1e-6)
    assert poll == pytest.approx(22.486e-3, abs=1e-6)
    got = wire.step_seconds(4, baud, np.array([[0.0, 1.5], [0.01, 0.0]]))
    still = goals + 2 * poll
    moving = still + 0.5 * (poll + 0.002)
    np.testing.assert_allclose(got, [[still, moving], [moving, still]], rtol=1e-12)
    assert got.dtype == np.float64
    fast = wire.step_seconds(4, 1_000_000, 1.0, poll_interval_s=0.0, return_delay_s=0.0)
    assert float(fast) == pytest.approx((34 + 2.5 * 118) * 10 / 1e6, rel=1e-12)
