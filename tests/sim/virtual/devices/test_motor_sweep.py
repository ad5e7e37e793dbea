"""`SimMotorBus` sweeps: a poll takes the rig bus's SYNC_READ time on the virtual clock
and reads the trapezoid at its middle, a sweep's profile times its move exactly, and
with the position_error effect the polls read encoder ticks."""

from __future__ import annotations

import numpy as np
import pytest

from drivers.dynamixel.wire import poll_seconds
from gonio.rig.model import Rig
from gonio.scene import PositionErrorSpec
from sim.clock import ManualClock
from sim.virtual.devices.motors import SimMotorBus, profile_duration, profile_position
from sim.virtual.physics.streams import Streams

TARGET = [0.6, -1.0, 0.8, 1.5]


def test_profile_duration_is_the_rigs_travel_time(rig: Rig) -> None:
    goal = np.array(TARGET)
    expected = float(rig.travel_time(rig.home, goal))
    got = profile_duration(rig.home, goal, rig.velocity, rig.acceleration)
    assert got == pytest.approx(expected, rel=1e-12)


def test_a_poll_takes_the_buses_sync_read_time_and_reads_the_profile_at_its_middle(
    rig: Rig,
) -> None:
    clock = ManualClock()
    with SimMotorBus(rig, clock, streams=Streams(0)) as bus:
        assert bus.poll_s == poll_seconds(len(rig.axes), rig.spec.bus.baud)
        speeds = {a: 0.5 * v for a, v in bus.velocity_limits().items()}
        target = dict(zip(rig.axes, TARGET, strict=True))
        assert bus.sweep(target, speeds) == speeds
        v = np.array([speeds[a] for a in rig.axes])
        duration = profile_duration(rig.home, np.array(TARGET), v, rig.acceleration)
        polls = []
        while not (polls and polls[-1].arrived):
            polls.append(bus.poll_positions())
        for poll in polls:
            assert poll.window_s == pytest.approx(bus.poll_s, abs=1e-12)
            expected = profile_position(
                rig.home, np.array(TARGET), v, rig.acceleration, poll.middle_s
            )
            assert list(poll.positions.values()) == pytest.approx(expected.tolist(), abs=1e-12)
        # arrived at the first poll ending after the profile's end
        assert polls[-1].reply_s >= duration > polls[-2].reply_s
        t = clock.now()
        bus.wait_settled(1.0)
        assert clock.now() == t


def test_polls_read_encoder_ticks_with_the_position_error_effect(rig: Rig) -> None:
    spec = PositionErrorSpec(ticks=True, backlash_deg=0.0, repeatability_deg=0.0)
    with SimMotorBus(rig, ManualClock(), position_error=spec, streams=Streams(0)) as bus:
        speeds = {a: 0.25 * v for a, v in bus.velocity_limits().items()}
        bus.sweep(dict(zip(rig.axes, TARGET, strict=True)), speeds)
        ticks = np.array([a.resolution_rad for a in rig.bus_axes()])
        zero = np.array([a.zero_offset_rad for a in rig.bus_axes()])
        for _ in range(20):
            here = np.array(list(bus.poll_positions().positions.values()))
            steps = (here - zero) / ticks
            assert steps == pytest.approx(np.round(steps), abs=1e-6)
