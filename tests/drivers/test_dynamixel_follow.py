"""`DynamixelBus.follow` on the byte-level emulator over a pty, and what it writes: one
SYNC_WRITE of Profile Acceleration, Profile Velocity and Goal Position (108-119) per
set-point, values checked before any byte, goals that are always set-points of the
trajectory (never past an axis's turn, never outside the limits), profile velocities
never 0 ("unlimited" on the X series), the configured profile back on the next move."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pytest

from drivers.dynamixel.axis import AxisConfig
from drivers.dynamixel.bus import DynamixelBus
from drivers.dynamixel.follow import SetpointPlan
from drivers.dynamixel.link import DynamixelLink
from drivers.errors import LimitError
from drivers.trajectory import Trajectory
from sim.clock import ManualClock
from sim.peers.dynamixel.emulator import DxlEmulator
from tests.support.dynamixel import axes

Emulator = Callable[..., DxlEmulator]
SYNC_WRITE = 0x83


def curve(config: list[AxisConfig], period: float = 0.02) -> Trajectory:
    """Axis 1 from −0.5 out to 0.3 and back to 0.1 rad, axis 2 from 0.2 to −0.6 rad, on
    cosine time laws at most half the configured rates."""
    t = np.arange(0.0, 1.6 + period / 2, period) / 1.6
    s = 0.5 * (1.0 - np.cos(math.pi * t))
    first = -0.5 + 0.8 * np.sin(math.pi * s) + 0.6 * s
    second = 0.2 - 0.8 * s
    return Trajectory(tuple(a.name for a in config[:2]), period, np.column_stack([first, second]))


def test_one_sync_write_carries_the_three_items_of_every_motor(emulator: Emulator) -> None:
    emu = emulator(ids=(1, 2), record=True)
    with DynamixelLink(emu.path) as link:
        link.sync_write_items(
            ("profile_acceleration", "profile_velocity", "goal_position"),
            {1: (7, 300, 2100), 2: (9, 5, 20)},
        )
        link.read(1, "goal_position")  # the write has been served
    packets = [data for way, data in emu.transcript if way == "rx" and data[7] == SYNC_WRITE]
    assert len(packets) == 1
    body = packets[0][8:-2]
    assert int.from_bytes(body[0:2], "little") == 108  # Profile Acceleration first
    assert int.from_bytes(body[2:4], "little") == 12  # through Goal Position
    assert body[4] == 1 and body[17] == 2
    for motor_id, values in ((1, (7, 300, 2100)), (2, (9, 5, 20))):
        m = emu.motors[motor_id]
        assert (m.get("profile_acceleration"), m.get("profile_velocity")) == values[:2]
        assert m.goals_written[-1] == values[2]


def test_a_value_outside_its_item_is_refused_before_any_byte(emulator: Emulator) -> None:
    emu = emulator(ids=(1, 2))
    names = ("profile_acceleration", "profile_velocity", "goal_position")
    with DynamixelLink(emu.path) as link:
        before = emu.stats.packets_in
        with pytest.raises(LimitError, match="profile_velocity"):
            link.sync_write_items(names, {1: (7, 300, 2100), 2: (9, 40_000, 0)})
        with pytest.raises(ValueError, match="not contiguous"):
            link.sync_write_items(("profile_acceleration", "goal_position"), {1: (1, 2)})
        with pytest.raises(ValueError, match="2 values for 3 items"):
            link.sync_write_items(names, {1: (1, 2)})
        assert emu.stats.packets_in == before


def test_every_goal_is_a_set_point_short_of_the_next_turn() -> None:
    config = axes(2)
    trajectory = curve(config)
    plan = SetpointPlan.of(trajectory, {a.name: a for a in config})
    registers = plan.registers
    assert registers.shape == (len(trajectory), 2, 3)
    top = np.array([a.profile_registers() for a in config])
    assert np.all(registers[:, :, 1] >= 1) and np.all(registers[:, :, 1] <= top[:, 0])
    assert np.all(registers[:, :, 0] >= 1) and np.all(registers[:, :, 0] <= top[:, 1])
    for j, axis in enumerate(config):
        ticks = {axis.to_ticks(float(x)) for x in trajectory.goals[:, j]}
        assert set(registers[:, j, 2].tolist()) <= ticks
    # axis 1 turns once: its goals lead the path up to the turn, never beyond it
    first = trajectory.goals[:, 0]
    turn = int(np.argmax(first))
    goals = np.array([config[0].to_rad(int(t)) for t in registers[:, 0, 2]])
    assert np.all(goals[:turn] <= first[turn] + 1e-9)
    assert np.all(goals[:turn] >= first[:turn] - 1e-9)  # ahead of the path, going up
    assert np.all(goals[turn:] <= first[turn:] + 1e-9)  # ahead of the path, coming down
    assert goals[-1] == pytest.approx(first[-1], abs=config[0].resolution_rad)


def test_after_a_trajectory_the_next_move_runs_the_configured_profile(
    emulator: Emulator, latency_timer: int
) -> None:
    config = axes(2)
    emu = emulator(ids=(1, 2))
    clock = emu.clock
    assert isinstance(clock, ManualClock)
    trajectory = curve(config)
    with DynamixelBus(emu.path, config, latency_ms=latency_timer, clock=clock) as bus:
        bus.move_to(dict(zip(trajectory.axes, trajectory.goals[0].tolist(), strict=True)))
        bus.wait_settled(10.0)
        emu.motors[1].clear_goals()
        followed = bus.follow(trajectory)
        assert followed.tracking_rad < 0.015
        written = emu.motors[1].goals_written
        assert len(written) == len(trajectory)  # one goal per set-point
        profiles = [emu.motors[m].get("profile_velocity") for m in (1, 2)]
        bus.move_to({"axis1": 0.0})
        bus.health()  # a read: the writes have been served
        configured = [a.profile_registers() for a in config]
        assert [emu.motors[m].get("profile_velocity") for m in (1, 2)] == [c[0] for c in configured]
        assert profiles != [c[0] for c in configured]  # the trajectory's were its own
