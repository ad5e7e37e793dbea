"""A sweep's merge against a known trapezoidal motion (no devices): readings are placed
only from polls whose linear interpolation the motion supports, exactly where both lie
in the constant-velocity part, within `RAMP_BIAS` of a period's travel where close polls
take in a ramp; where sparse polls take in a ramp, on the line at the commanded
velocity through the constant-velocity part's polls, else not at all."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from drivers.stream import StreamReading
from gonio.acquire.fly import merge, ramp_gap, stamp_slack
from gonio.acquire.fly.merge import RAMP_BIAS
from gonio.planner.model import Sweeps

V = math.radians(20.0)  # rad/s, the swept axis's constant velocity
A = math.radians(90.0)  # rad/s², its acceleration
RAMP_S = V / A  # s
RAMP = V * V / (2.0 * A)  # rad
CRUISE_S = 1.0  # s at constant velocity
PERIOD = 0.01  # s
HELD = 0.3  # rad, the other axis's


def truth(t: np.ndarray) -> np.ndarray:
    """(N, 2) angles at ``t`` (s): the swept axis from rest at 0 through a trapezoid, the
    other held."""
    t = np.asarray(t, dtype=np.float64)
    up = np.clip(t, 0.0, RAMP_S)
    cruise = np.clip(t - RAMP_S, 0.0, CRUISE_S)
    down = np.clip(t - RAMP_S - CRUISE_S, 0.0, RAMP_S)
    x = 0.5 * A * up**2 + V * cruise + V * down - 0.5 * A * down**2
    return np.stack([x, np.full_like(x, HELD)], axis=1)


def sweeps() -> Sweeps:
    streamed = round(CRUISE_S / PERIOD)
    entry, exit_ = RAMP, RAMP + V * CRUISE_S
    return Sweeps(
        start=[[0.0, HELD]], entry=[[entry, HELD]], exit=[[exit_, HELD]],
        stop=[[exit_ + RAMP, HELD]], velocity=[[V, 0.0]], first=[0], count=[streamed],
        cruise_at_s=[RAMP_S], streamed=[streamed], period_s=PERIOD, integration_s=PERIOD,
    )  # fmt: skip


def merged_against_truth(
    poll_at: np.ndarray, velocity: float | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """The matched slots and their angles' errors (K,) rad, polls at ``poll_at`` (s;
    each answered 1 ms after its request), the stream's phase 4 ms ahead of the cruise
    (its first window starts in the ramp); ``velocity``: the plan's (rad/s; the motion's
    `V` is the one commanded)."""
    request = np.asarray(poll_at, dtype=np.float64)
    reply = request + 1e-3
    positions = truth(0.5 * (request + reply))
    started = RAMP_S - 4e-3 + PERIOD * np.arange(round(CRUISE_S / PERIOD) + 1)
    ended = started + PERIOD
    plan = sweeps() if velocity is None else replace(sweeps(), velocity=[[velocity, 0.0]])
    m = merge(request, reply, positions, started, ended, plan, 0, velocity=np.array([V, 0.0]))
    middle = 0.5 * (started + ended)[m.index]
    return m.slot, np.abs(m.angles - truth(middle)).max(axis=1)


def test_sparse_polls_about_a_ramp_place_readings_on_the_commanded_line() -> None:
    # polls 400 ms apart, the first at rest and the last after the stop (the median gap
    # is the only gap: interpolating across either ramp errs by up to a degree); three
    # in the cruise place it on the line at the commanded velocity, the plan's 4 % off
    slots, error = merged_against_truth(np.arange(5) * 0.4, velocity=1.04 * V)
    # every window, the first too (it begins 4 ms in the ramp, its middle in the cruise)
    np.testing.assert_array_equal(slots, np.arange(round(CRUISE_S / PERIOD)))
    assert error.max() <= 1e-9


def test_two_polls_in_the_cruise_place_only_the_readings_between_them() -> None:
    slots, error = merged_against_truth(np.array([0.0, 0.5, 1.0, 1.6]))
    assert 45 <= len(slots) <= 51  # the half second between the polls at 0.5 and 1.0 s
    assert error.max() <= 1e-9


def test_close_polls_place_every_reading_even_at_a_ramp() -> None:
    # polls every 5 ms: a ramp's curvature across one gap is a·g²/8 = 5e-6 rad
    slots, error = merged_against_truth(np.arange(0.0, 2 * RAMP_S + CRUISE_S + 0.05, 5e-3))
    np.testing.assert_array_equal(slots, np.arange(round(CRUISE_S / PERIOD)))
    assert error.max() <= RAMP_BIAS * V * PERIOD


def test_the_ramp_gap_bounds_the_ramps_bend() -> None:
    g = ramp_gap(sweeps(), 0, 0)
    assert A * g * g / 8.0 == pytest.approx(RAMP_BIAS * V * PERIOD)
    # polls as sparse as lets a window's two polls (a period apart and up to two poll
    # gaps more) be no more than the ramp gap apart
    gap = 0.45 * (g - PERIOD)
    slots, error = merged_against_truth(np.arange(0.0, 2 * RAMP_S + CRUISE_S + 0.05, gap))
    assert slots[0] == 0 and slots[-1] == round(CRUISE_S / PERIOD) - 1  # both edges
    assert error.max() <= RAMP_BIAS * V * PERIOD


def test_the_stamp_slack_spans_what_a_host_late_for_every_line_cannot_know() -> None:
    """A host that reads every line of a stream 12 ms after its window ended (a loaded
    one) stamps each window from the fastest line, 12 ms late; with the start command's
    bound 2 ms before the truth, the slack spans the 14 ms the truth may lie in, so the
    timing σ it adds covers the bias. Without a stated bound, the slack is what the
    stamps left before the arrivals."""
    truth = 0.2 + 0.01 * np.arange(50)
    readings = [
        StreamReading(1.0, math.nan, t + 0.012 - 0.01, t + 0.012, received_s=t + 0.012,
                      earliest_end_s=t - 0.002)
        for t in truth.tolist()
    ]  # fmt: skip
    assert stamp_slack(readings) == pytest.approx(0.014)
    bias = max(r.ended_s - t for r, t in zip(readings, truth.tolist(), strict=True))
    assert bias <= stamp_slack(readings) + 1e-12
    unbounded = [replace(r, earliest_end_s=None, received_s=r.ended_s + 0.001) for r in readings]
    assert stamp_slack(unbounded) == pytest.approx(0.001)
