"""`SimMotorBus.follow`: ideal tracking on the virtual clock — the joints on the path
between set-points, its set-points and polls timed as the bus's wire would time them,
the position_error effect along it (ticks, backlash from the direction of each axis's
last motion, one repeatability draw per trajectory), a resumed bus moving exactly as an
uninterrupted one, and injected faults striking half-way through it."""

from __future__ import annotations

import math

import numpy as np
import pytest

from drivers.dynamixel.wire import BITS_PER_BYTE, setpoint_period, sync_write_bytes
from drivers.errors import MotionTimeout, MotorFault
from drivers.trajectory import SETTLE_TIMEOUT_S, Trajectory
from drivers.values import StampedPositions
from gonio.rig.model import Rig
from gonio.scene import FaultRule, PositionErrorSpec
from sim.clock import ManualClock
from sim.virtual.devices.motors import SimMotorBus
from sim.virtual.faults import FaultInjector
from sim.virtual.physics.streams import Streams

START = [0.6, -0.4, 0.8, 1.2]
END = [0.2, -1.0, 0.3, 0.4]
EFFECTS = PositionErrorSpec(ticks=True, backlash_deg=0.3, repeatability_deg=0.05)


def curve(rig: Rig, axes: tuple[str, ...] | None = None) -> Trajectory:
    """``axes`` (default all) from `START` to `END` on a cosine time law at half the rig's
    rates, the first one going out 0.3 rad and back instead (it turns)."""
    names = axes or rig.axes
    columns = [rig.axes.index(n) for n in names]
    a0, a1 = np.array(START)[columns], np.array(END)[columns]
    tau = np.linspace(0.0, 1.0, 2001)
    s = 0.5 * (1.0 - np.cos(math.pi * tau))
    shape = a0 + np.outer(s, a1 - a0)
    shape[:, 0] = a0[0] + 0.3 * np.sin(math.pi * s)
    d1 = np.max(np.abs(np.gradient(shape, tau, axis=0)), axis=0)
    d2 = np.max(np.abs(np.gradient(np.gradient(shape, tau, axis=0), tau, axis=0)), axis=0)
    duration = max(
        np.max(d1 / (0.5 * rig.velocity[columns])),
        math.sqrt(np.max(d2 / (0.5 * rig.acceleration[columns]))),
    )
    period = setpoint_period(len(rig.axes), rig.spec.bus.baud)
    t = np.minimum(np.arange(math.ceil(duration / period) + 1) * period / duration, 1.0)
    goals = np.column_stack([np.interp(t, tau, shape[:, j]) for j in range(len(names))])
    return Trajectory(tuple(names), period, goals)


def at_start(bus: SimMotorBus, trajectory: Trajectory) -> None:
    bus.move_to(dict(zip(trajectory.axes, trajectory.goals[0].tolist(), strict=True)))
    bus.wait_settled(60.0)


def make(rig: Rig, clock: ManualClock, rules: tuple[FaultRule, ...] = ()) -> SimMotorBus:
    streams = Streams(7)
    return SimMotorBus(
        rig, clock, position_error=EFFECTS, streams=streams, faults=FaultInjector(rules, streams)
    )


def test_the_joints_are_on_the_path_and_the_polls_read_its_ticks(rig: Rig) -> None:
    clock = ManualClock()
    trajectory = curve(rig)
    ticks = np.array([a.resolution_rad for a in rig.bus_axes()])
    with make(rig, clock) as bus:
        bus.begin_sample(3)
        at_start(bus, trajectory)
        truth: list[tuple[float, dict[str, float], dict[str, float]]] = []

        def on_poll(poll: StampedPositions) -> None:
            now = clock.now()
            truth.append((now, bus.true_positions(), bus.true_position_at(now)))

        followed = bus.follow(trajectory, on_poll)
        # set-points sent exactly when due, each poll after its set-point's wire time
        k = np.arange(len(trajectory))
        assert np.array_equal(followed.sent_s, followed.started_s + k * trajectory.period_s)
        write_s = sync_write_bytes(len(rig.axes)) * BITS_PER_BYTE / rig.spec.bus.baud
        for sent, poll in zip(followed.sent_s, followed.polls, strict=True):
            assert poll.request_s == pytest.approx(sent + write_s, abs=1e-12)
            assert poll.window_s == pytest.approx(bus.poll_s, abs=1e-12)
            read = np.array([poll.positions[n] for n in rig.axes])
            assert np.allclose(read / ticks, np.round(read / ticks), atol=1e-6, rtol=0)  # ticks
        # within one tick of the path (set-points on ticks, then the reading's tick)
        assert 0 < followed.tracking_rad <= np.max(ticks) + 1e-12
        # the joints: the path plus backlash and repeatability, the same by either call
        for now, by_call, at_time in truth:
            assert by_call == at_time
            here = np.array([by_call[n] for n in rig.axes])
            path = trajectory.at(now - followed.started_s)
            assert np.max(np.abs(here - path)) < np.max(ticks) + math.radians(0.15 + 4 * 0.05)
        assert bus.moves_of(3) == 2  # the move to set-point 0 and the trajectory
        end = trajectory.goals[-1]
        assert np.max(np.abs(np.array(list(bus.positions().values())) - end) / ticks) <= 0.5 + 1e-9
        assert followed.ended_s == clock.now() >= followed.started_s + trajectory.duration_s


def test_backlash_follows_the_direction_of_each_axis_along_the_path(rigs: dict[str, Rig]) -> None:
    rig = rigs["arch"]
    clock = ManualClock()
    spec = PositionErrorSpec(ticks=False, backlash_deg=0.4, repeatability_deg=0.0)
    trajectory = curve(rig)
    half = math.radians(0.2)
    with SimMotorBus(rig, clock, position_error=spec, streams=Streams(0)) as bus:
        at_start(bus, trajectory)
        errors: list[tuple[float, np.ndarray]] = []

        def on_poll(poll: StampedPositions) -> None:
            true = bus.true_positions()
            encoder = bus.positions()
            errors.append((clock.now(), np.array([true[n] - encoder[n] for n in rig.axes])))

        followed = bus.follow(trajectory, on_poll)
        velocity = trajectory.velocities()
        for now, error in errors[1:-1]:
            k = int((now - followed.started_s) // trajectory.period_s)
            moving = velocity[min(k, len(velocity) - 1)]
            # the joint lags half the backlash behind each axis's motion, the turning one too
            sure = np.abs(moving) > 1e-9
            assert np.allclose(error[sure], -half * np.sign(moving[sure]), atol=1e-12)
        # the first axis went out and came back: it ends lagging behind its return
        last = dict(zip(rig.axes, (np.array(list(bus.true_positions().values()))), strict=True))
        assert last[rig.axes[0]] - bus.positions()[rig.axes[0]] == pytest.approx(half)


def test_axes_not_named_hold_still(rigs: dict[str, Rig]) -> None:
    rig = rigs["arch"]
    clock = ManualClock()
    trajectory = curve(rig, rig.axes[:2])
    with make(rig, clock) as bus:
        at_start(bus, trajectory)
        before = bus.true_positions()
        followed = bus.follow(trajectory)
        for poll in followed.polls:
            for name in rig.axes[2:]:
                assert poll.positions[name] == bus.positions()[name]
        after = bus.true_positions()
        assert [after[n] for n in rig.axes[2:]] == [before[n] for n in rig.axes[2:]]


def test_a_resumed_bus_follows_exactly_as_an_uninterrupted_one(rigs: dict[str, Rig]) -> None:
    rig = rigs["arch"]
    trajectory = curve(rig)
    runs = []
    for resume in (False, True):
        clock = ManualClock()
        with make(rig, clock) as bus:
            bus.begin_sample(5)
            at_start(bus, trajectory)
            if resume:  # a new bus continues from the first one's snapshot
                state, moves, now = bus.snapshot(), bus.moves_of(5), clock.now()
                clock = ManualClock(now)
                bus = make(rig, clock)
                bus.open()
                bus.restore(state)
                bus.begin_sample(5)
                bus.set_moves(5, moves)
            followed = bus.follow(trajectory)
            runs.append(([p.positions for p in followed.polls], bus.true_positions()))
            bus.close()
    assert runs[0] == runs[1]


def test_an_injected_fault_strikes_half_way_and_holds_every_axis(rigs: dict[str, Rig]) -> None:
    rig = rigs["arch"]
    clock = ManualClock()
    trajectory = curve(rig)
    rule = FaultRule.model_validate({"kind": "motor_fault", "at": 1, "axis": rig.axes[1]})
    with make(rig, clock, (rule,)) as bus:
        at_start(bus, trajectory)
        bus.begin_sample(1)
        polls: list[StampedPositions] = []
        started = clock.now()
        with pytest.raises(MotorFault) as info:
            bus.follow(trajectory, polls.append)
        assert info.value.axis == rig.axes[1]
        half = started + 0.5 * trajectory.duration_s
        assert polls[-1].middle_s < half <= clock.now() < half + trajectory.period_s + bus.poll_s
        held = bus.true_positions()
        clock.advance(100.0)
        assert bus.true_positions() == held
        assert np.max(np.abs(np.array(list(held.values())) - trajectory.goals[-1])) > 0.1


def test_a_blocked_axis_times_out_after_the_last_set_point(rigs: dict[str, Rig]) -> None:
    rig = rigs["arch"]
    clock = ManualClock()
    trajectory = curve(rig)
    rule = FaultRule.model_validate({"kind": "motion_timeout", "at": 1})
    with make(rig, clock, (rule,)) as bus:
        at_start(bus, trajectory)
        bus.begin_sample(1)
        polls: list[StampedPositions] = []
        started = clock.now()
        with pytest.raises(MotionTimeout):
            bus.follow(trajectory, polls.append)
        assert len(polls) == len(trajectory)  # every set-point was sent, then it timed out
        assert clock.now() >= started + trajectory.duration_s + SETTLE_TIMEOUT_S
        held = bus.true_positions()
        clock.advance(100.0)
        assert bus.true_positions() == held
