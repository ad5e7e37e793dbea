"""Sweeps on the rehearsal path in real time: `DynamixelBus` polls the byte-level emulator
over a pty while its motors really move (wire time and return delays on), and every
polled position is within one encoder tick plus v · (reply − request) of the emulator's
own trajectory; a sweep's profile lasts for its move; a retried poll is stamped by the
attempt that answered; a rehearsal's bus stamps its polls on the run's (sped-up) clock."""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable

from drivers.dynamixel.axis import AxisConfig
from drivers.dynamixel.bus import DynamixelBus
from drivers.dynamixel.owed import SYNC_FIRST_LENGTH
from drivers.dynamixel.sdk_boundary import STATUS_OVERHEAD
from drivers.dynamixel.wire import poll_bytes, sync_read_bytes
from gonio.rig.model import Rig
from gonio.scene import load_scene
from gonio.workflows.rehearsal import rehearsal_devices
from sim.peers.dynamixel.emulator import DxlEmulator, Fault
from sim.rehearsal import RehearsalSide
from tests.conftest import CONFIGS

AXES = [
    AxisConfig(
        f"axis{i}", i, -1.0, 1.0, zero_offset_rad=-math.pi,
        profile_velocity_rad_s=4.0, profile_acceleration_rad_s2=40.0,
    )
    for i in (1, 2, 3)
]  # fmt: skip
TICK = 2 * math.pi / 4096
#: How long each axis's sweep lasts (s): polled every 50 ms, a loaded host sees 20
#: positions on the way.
SWEEP_S = 1.0


def test_polls_in_real_time_follow_the_emulated_trajectory(
    emulator: Callable[..., DxlEmulator],
) -> None:
    baud = 1_000_000
    emu = emulator(
        ids=(1, 2, 3), baud=baud, clock=time.monotonic, wire_time=True, return_delay=True
    )
    target = {"axis1": 0.4, "axis2": -0.4, "axis3": 0.2}
    with DynamixelBus(emu.path, AXES, baud=baud, latency_ms=16.0) as bus:
        start = bus.positions()
        # each sweep lasts about SWEEP_S, long enough for a host that polls a few times
        # slower (loaded, or sharing its cores) to see each one mid-way
        speeds = bus.sweep(target, {a: abs(goal) / SWEEP_S for a, goal in target.items()})
        emu.reset_stats()
        before = dataclasses.replace(bus.late_counts)
        polls, truths = [], []
        deadline = time.monotonic() + 5.0
        while time.monotonic() < deadline:
            poll = bus.poll_positions()
            # the trajectory the motors run, where it was at the middle of the poll
            truths.append({
                a.name: a.to_rad(round(emu.motors[a.motor_id].position_at(poll.middle_s)))
                for a in AXES
            })  # fmt: skip
            polls.append(poll)
            if poll.arrived:
                break
        stats = emu.stats
    assert polls[-1].arrived
    # one SYNC_READ per poll, and one more after each sync (a READ from address 0) the
    # link made when a loaded machine held a reply past its timeout; on the wire, 4
    # bytes of Present Position per motor in each SYNC_READ's replies and the sync's
    # answer, nothing else
    syncs = bus.late_counts.syncs - before.syncs
    failed = bus.late_counts.failed - before.failed
    reads = stats.instructions["SYNC_READ"]
    assert stats.instructions["READ"] == syncs
    assert reads == len(polls) + syncs - failed
    sync_answer = STATUS_OVERHEAD + SYNC_FIRST_LENGTH
    assert stats.bytes_out == reads * (poll_bytes(3) - sync_read_bytes(3)) + syncs * sync_answer
    for poll, truth in zip(polls, truths, strict=True):
        assert poll.request_s < poll.reply_s
        for axis, value in poll.positions.items():
            bound = TICK + speeds.get(axis, 0.0) * poll.window_s + 1e-9
            assert abs(value - truth[axis]) <= bound, (axis, value, truth[axis], poll)
    for axis, goal in target.items():
        path = [p.positions[axis] for p in polls]
        between = [v for v in path if abs(v - start[axis]) > TICK and abs(v - goal) > TICK]
        assert len(between) >= 10, f"{axis}: {len(between)} intermediate positions"


def test_a_sweep_writes_its_profile_and_the_next_move_restores_the_configured_one(
    emulator: Callable[..., DxlEmulator], latency_timer: int
) -> None:
    emu = emulator(ids=(1, 2, 3))
    with DynamixelBus(emu.path, AXES, latency_ms=latency_timer) as bus:
        configured = {a.motor_id: a.profile_registers() for a in AXES}
        bus.health()  # a read: opening's writes have been served
        emu.reset_stats()
        speeds = bus.sweep({"axis1": 0.5, "axis2": -0.5}, {"axis1": 1.0, "axis2": 0.5})
        bus.health()  # a read: everything sent before has been served
        assert emu.stats.instructions["SYNC_WRITE"] == 3  # acceleration, velocity, goals
        for name, motor_id in (("axis1", 1), ("axis2", 2)):
            register = emu.motors[motor_id].get("profile_velocity")
            assert register == round(speeds[name] / (0.229 * 2 * math.pi / 60))
            assert register != configured[motor_id][0]
        assert emu.motors[3].get("profile_velocity") == configured[3][0]  # not swept
        bus.move_to({"axis1": 0.0})
        bus.health()
        for motor_id, (velocity, acceleration) in configured.items():
            assert emu.motors[motor_id].get("profile_velocity") == velocity
            assert emu.motors[motor_id].get("profile_acceleration") == acceleration
        emu.reset_stats()
        bus.move_to({"axis1": 0.1})  # restored once: a plain move is one SYNC_WRITE again
        bus.health()
        assert emu.stats.instructions["SYNC_WRITE"] == 1


def test_a_retried_poll_is_stamped_by_the_attempt_that_answered(
    emulator: Callable[..., DxlEmulator], latency_timer: int
) -> None:
    emu = emulator(ids=(1, 2, 3), clock=time.monotonic)
    with DynamixelBus(emu.path, AXES, latency_ms=latency_timer, retries=1) as bus:
        emu.inject(Fault.NO_REPLY, motor_id=3, count=1)  # the last: nothing comes after
        before = time.monotonic()
        poll = bus.poll_positions()
        # the first attempt waited out its timeout (2 × latency timer + 2 ms) first
        assert poll.request_s - before >= 2 * latency_timer / 1000
        assert poll.request_s < poll.reply_s
        assert emu.stats.instructions["SYNC_READ"] >= 2


def test_a_rehearsal_stamps_its_polls_on_the_runs_clock() -> None:
    """`gonio acquire --rehearse`'s devices: the real bus polls the emulator, whose motion
    runs on the rehearsal's sped-up clock, and stamps each poll on that same clock."""
    rig = Rig.from_yaml(CONFIGS / "rigs" / "arch_serial.yaml")
    scene = load_scene(CONFIGS / "scenes" / "matte.yaml")
    with rehearsal_devices(rig, scene, None, 5.0, wire_time=True) as (devices, clock):
        side = devices.simulation
        assert isinstance(side, RehearsalSide) and side.peers is not None
        motors = side.peers.emulator.motors
        axes = {a.name: a for a in rig.bus_axes()}
        with devices:
            bus = devices.bus
            start = bus.positions()
            axis = rig.axes[0]
            goal = start[axis] + 0.3
            speeds = bus.sweep({axis: goal}, {axis: 0.1 * bus.velocity_limits()[axis]})
            polls = [bus.poll_positions()]
            truth = []
            while True:
                poll = polls[-1]
                a = axes[axis]
                truth.append(a.to_rad(round(motors[a.motor_id].position_at(poll.middle_s))))
                if poll.arrived:
                    break
                polls.append(bus.poll_positions())
            assert abs(polls[-1].reply_s - clock.now()) < 1.0  # the run's clock, not the host's
    between = [p for p in polls if start[axis] + 0.01 < p.positions[axis] < goal - 0.01]
    assert len(between) >= 5
    for poll, true in zip(polls, truth, strict=True):
        bound = axes[axis].resolution_rad + speeds[axis] * poll.window_s + 1e-9
        assert abs(poll.positions[axis] - true) <= bound
