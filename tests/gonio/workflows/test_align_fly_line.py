"""The line a flown cross scan puts its readings on (`gonio.workflows.align_fly`): an
encoder's whole ticks polled at uneven times, as a loaded host polls them. Through the
polls themselves a least-squares line keeps a share of their rounding; at the velocity
the bus commanded, the line every poll allows lands within the polls' own bounds."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gonio.workflows import align_fly

TICK = 2.0 * math.pi / 4096.0  # rad
VELOCITY = math.radians(4.122)  # rad/s: a Dynamixel's register step times 3
TRUE_AT_ZERO = 0.37 * TICK  # the line's angle at t = 0 (rad)


def _polls(seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(request, reply, reading) of a loaded host's polls of a motor at ``VELOCITY``:
    clumps of quick polls between stalls, each sampled somewhere in its span and read
    to the nearest tick."""
    rng = np.random.default_rng(seed)
    gaps = np.where(rng.random(80) < 0.2, rng.uniform(0.01, 0.03, 80), rng.uniform(3e-4, 2e-3, 80))
    request = np.cumsum(gaps) - 0.08
    span = rng.uniform(2e-4, 1.5e-2, 80)
    sampled = request + rng.random(80) * span
    reading = np.rint((TRUE_AT_ZERO + VELOCITY * sampled) / TICK) * TICK
    return request, request + span, reading


@pytest.mark.parametrize("seed", range(12))
def test_the_line_at_the_commanded_velocity_is_within_what_the_polls_allow(seed: int) -> None:
    request, reply, x = _polls(seed)
    lo, hi = float(x.min()) - 1.0, float(x.max()) + 1.0
    line = align_fly.cruise_line(request, reply, x, lo, hi, TICK, VELOCITY)
    assert line is not None and line.slope == VELOCITY and not line.fitted
    assert line.placed(10.0)  # the velocity known: three polls place it, however close
    error = float(line.at(np.zeros(1))[0]) - TRUE_AT_ZERO
    # the truth is one of the angles every poll allows; the estimate their middle
    early = np.minimum(VELOCITY * request, VELOCITY * reply)
    late = np.maximum(VELOCITY * request, VELOCITY * reply)
    allowed = float(np.min(x + 0.5 * TICK - early) - np.max(x - 0.5 * TICK - late))
    assert allowed >= 0.0 and abs(error) <= 0.5 * allowed + 1e-12
    assert abs(error) <= 0.05 * TICK


def test_polled_ticks_bias_a_line_through_the_polls_not_the_line_the_polls_allow() -> None:
    """Over the twelve hosts, the least-squares line through the polls errs by more than
    a tenth of a tick at worst; the line every poll allows by less than half that."""
    through, allowed = [], []
    for seed in range(12):
        request, reply, x = _polls(seed)
        t = 0.5 * (request + reply)
        _, at_zero = np.polyfit(t, x, 1)
        through.append(abs(at_zero - TRUE_AT_ZERO))
        line = align_fly.cruise_line(request, reply, x, -1.0, 1.0, TICK, VELOCITY)
        assert line is not None
        allowed.append(abs(float(line.at(np.zeros(1))[0]) - TRUE_AT_ZERO))
    assert max(through) > 0.1 * TICK and max(allowed) < 0.05 * TICK


def test_without_the_velocity_the_line_goes_through_the_changes_of_reading() -> None:
    """Each change of reading lies between the two polls about it: the midway angle at
    the middle of their span; the least-squares line through those."""
    request = np.array([0.0, 0.01, 0.02, 0.03, 0.04])
    reply = request + 0.002
    x = np.array([0.0, 0.0, 1.0, 1.0, 2.0]) * TICK
    t, at, weight = align_fly.tick_changes(request, reply, x)
    assert t.tolist() == pytest.approx([0.016, 0.036])
    assert at.tolist() == pytest.approx([0.5 * TICK, 1.5 * TICK])
    assert weight.tolist() == pytest.approx([1 / 0.012, 1 / 0.012])
    assert not align_fly.on_grid(x + np.array([0, 0, 0.3, 0, 0]) * TICK, TICK)


def test_polls_off_the_commanded_velocity_fall_back_to_the_changes() -> None:
    """Readings no line at the commanded velocity explains (the motor slower than the
    register says): no interval is common to every poll, and the line goes through the
    changes of reading at its own slope."""
    request = np.linspace(0.0, 0.2, 60)
    reply = request + 5e-4
    x = np.rint(0.5 * VELOCITY * request / TICK) * TICK
    assert align_fly.consistent_intercept(request, reply, x, TICK, VELOCITY) is None
    line = align_fly.cruise_line(request, reply, x, -1.0, 1.0, TICK, VELOCITY)
    assert line is not None and line.slope == pytest.approx(0.5 * VELOCITY, rel=0.05)
    assert line.fitted and line.placed(0.3) and not line.placed(0.5)  # over half of it
