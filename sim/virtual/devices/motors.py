"""`SimMotorBus`: the rig's axes as virtual motors on a virtual clock.

Implements `drivers.base.MotorBus` (every rule of the contract). Nothing sleeps:
`wait_settled` advances the clock to the end of the slowest axis's trapezoidal profile
(at the rates the rig's motors run, `Rig.motion_rates`: the rig file's, each rounded to a
register step on a Dynamixel rig; `gonio.rig.travel`), so a simulated run
reports the hours the real rig would take in the seconds it computes. The rig's settle
dwell is the caller's to wait, as on hardware. Faults are injected from the scene's
``faults:`` rules (`sim.virtual.faults`) for the sample named by `begin_sample`; their state and
the health they leave are `sim.virtual.devices.motor_faults.MotorFaults`.

Positions: each axis moves from where it is to its goal; a new goal starts a new
profile from the present position (at rest: blending is not modelled). With the
scene's ``position_error`` effect the motor goes to the goal rounded to its encoder
tick (4096 per motor revolution, through the gear), `positions` reads that tick back
(what the encoder sees), and the joint itself (`true_positions`, what the light and
the detector really see) is off by half the backlash against the direction of the last
move plus a Gaussian repeatability error drawn once per move from the sample's random
stream (`sim.virtual.physics.streams`, channel POSITION), so a resumed run moves exactly as an
uninterrupted one.

Sweeps: `sweep` runs the same trapezoidal profiles at the velocities and accelerations
it is given, for that move only. `poll_positions` takes the time of one poll on the
virtual clock (``poll_s``; default the SYNC_READ of Present Position on the rig's bus
at its baud, return delays included: `drivers.dynamixel.wire`) and reads the encoder
at the middle of it, so a loop of polls walks along the profile as a real bus does.

Trajectories: `follow` tracks a `drivers.trajectory.Trajectory` ideally: the joints are
on its path (the set-points, on encoder ticks with the position_error effect, joined by
straight lines; `sim.virtual.devices.motion.JointPath`) while it lasts, each set-point's
SYNC_WRITE takes its wire time on the clock and each poll ``poll_s``. A trajectory is
one move for the sample's random streams and faults: one repeatability draw per axis
that moves, backlash from the direction of each axis's last motion along the path, an
injected fault striking half-way through it.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping

import numpy as np

from drivers.devices import Resource
from drivers.dynamixel import BITS_PER_BYTE, poll_seconds, sync_write_bytes
from drivers.errors import (
    DeviceClosed,
    DriverError,
    LimitError,
    MotionTimeout,
    TorqueOff,
)
from drivers.sweep import sweep_profile
from drivers.trajectory import (
    SETTLE_TIMEOUT_S,
    Followed,
    Trajectory,
    check_trajectory,
    tracking_error,
)
from drivers.values import Health, Recovered, StampedPositions
from gonio.rig import Rig
from gonio.scene import FaultRule, PositionErrorSpec
from gonio.types import FloatArray
from sim.clock import ManualClock
from sim.virtual.devices.motion import JointPath, profile_duration, profile_position
from sim.virtual.devices.motor_faults import MotorFaults
from sim.virtual.devices.position_error import MotorState, PositionModel
from sim.virtual.faults import FaultInjector
from sim.virtual.physics import streams as streams_module

__all__ = ["MotorState", "PositionModel", "SimMotorBus", "profile_duration", "profile_position"]


class SimMotorBus(Resource):
    """Virtual motors for the axes of ``rig`` (see the module docstring)."""

    def __init__(
        self,
        rig: Rig,
        clock: ManualClock,
        *,
        position_error: PositionErrorSpec | None = None,
        streams: streams_module.Streams | None = None,
        faults: FaultInjector | None = None,
        poll_s: float | None = None,
    ) -> None:
        self.rig = rig
        self.clock = clock
        streams = streams or streams_module.Streams(0)
        self._names = rig.axes
        motor_ids = {a.name: a.motor_id for a in rig.bus_axes()}
        #: The injected faults and the health they leave (overheat, supply sag in force).
        self.faults = MotorFaults(faults or FaultInjector((), streams), self._names, motor_ids)
        self._index = {n: i for i, n in enumerate(self._names)}
        self._lo, self._hi = rig.limits[:, 0], rig.limits[:, 1]
        self._v, self._a = rig.velocity, rig.acceleration  # the limits of a sweep's rates
        self._run_v, self._run_a = rig.travel.velocity, rig.travel.acceleration  # a move's
        self._move_v, self._move_a = self._run_v, self._run_a  # the present move's profile
        if poll_s is None:
            poll_s = poll_seconds(len(self._names), rig.spec.bus.baud)
        #: Virtual seconds one `poll_positions` takes.
        self.poll_s = float(poll_s)
        self._travel = rig.travel.scalar()  # one move's time with Python floats: no numpy overhead
        self._model = (
            PositionModel(rig, position_error, streams) if position_error is not None else None
        )
        home = np.asarray(rig.home, dtype=np.float64)
        self._start = home.copy()  # where the present profile started
        self._goal = home.copy()  # where the motors are going (encoder ticks if quantized)
        self._t0 = self._end = clock.now()
        self._direction = np.zeros(len(home))  # sign of each axis's last move
        self._repeat = np.zeros(len(home))  # each axis's repeatability error
        self._error = np.zeros(len(home))  # joint − encoder
        self._path: JointPath | None = None  # the trajectory being followed, if any
        self._moves: dict[int, int] = {}  # moves made so far per sample index
        self._open = False
        self._torque = True
        self._sample = 0  # the sample the next move belongs to (streams, faults)

    # -- Resource / MotorBus ----------------------------------------------------------
    @property
    def axes(self) -> tuple[str, ...]:
        return self._names

    @property
    def is_open(self) -> bool:
        return self._open

    def limits(self) -> dict[str, tuple[float, float]]:
        return {n: (float(self._lo[i]), float(self._hi[i])) for n, i in self._index.items()}

    def open(self) -> None:
        self._open = True

    def close(self) -> None:
        if self._open:
            self._hold()
        self._open = False

    def _check_open(self) -> None:
        if not self._open:
            raise DeviceClosed("the simulated bus is not open (use it as a context manager)")

    def begin_sample(self, index: int) -> None:
        """The next moves belong to sample ``index``: its random stream draws their
        repeatability errors (a second move continues it) and its fault rules apply."""
        self._sample = int(index)

    def move_to(self, targets: Mapping[str, float]) -> None:
        """Start moving the named axes (rad); `LimitError` before anything moves if a
        target is outside its axis's limits or not finite, `TorqueOff` with torque off,
        `MotorFault` while an axis's fault is latched (until `reboot`)."""
        self._start_move(self._checked_goal(targets))

    def _checked_goal(self, targets: Mapping[str, float]) -> FloatArray:
        self._check_open()
        goal = self._present_encoder()
        for name, angle in targets.items():
            if name not in self._index:
                raise DriverError(f"unknown axis {name!r}; the axes are {', '.join(self._names)}")
            i = self._index[name]
            value = float(angle)
            if not (math.isfinite(value) and self._lo[i] <= value <= self._hi[i]):
                raise LimitError(
                    f"axis {name!r}: target {angle!r} rad is outside its limits "
                    f"[{self._lo[i]:.6f}, {self._hi[i]:.6f}] rad; nothing moved"
                )
            goal[i] = value
        if not self._torque:
            raise TorqueOff("torque is off: call torque(True) before moving; nothing moved")
        self.faults.check_clear()
        return goal

    def velocity_limits(self) -> dict[str, float]:
        """Each axis's maximum velocity in the rig file (rad/s)."""
        return {n: float(self._v[i]) for n, i in self._index.items()}

    def sweep(
        self,
        targets: Mapping[str, float],
        velocities: Mapping[str, float],
        accelerations: Mapping[str, float] | None = None,
    ) -> dict[str, float]:
        """`move_to` at ``velocities`` (rad/s) and ``accelerations`` (rad/s²; default the
        rig's) for this move only; returns the velocities commanded (those given).
        `LimitError` / `DriverError` / `TorqueOff` before anything moves."""
        self._check_open()
        for name in targets:
            if name not in self._index:
                raise DriverError(f"unknown axis {name!r}; the axes are {', '.join(self._names)}")
        top_a = {n: float(self._a[i]) for n, i in self._index.items()}
        rates = sweep_profile(targets, velocities, accelerations, self.velocity_limits(), top_a)
        goal = self._checked_goal(targets)
        v, a = self._v.copy(), self._a.copy()
        for name, (velocity, acceleration) in rates.items():
            v[self._index[name]], a[self._index[name]] = velocity, acceleration
        self._start_move(goal, v, a)
        return {name: velocity for name, (velocity, _) in rates.items()}

    def _start_move(
        self, goal: FloatArray, v: FloatArray | None = None, a: FloatArray | None = None
    ) -> None:
        here = self._present_encoder()
        if self._model is not None:
            goal = np.clip(self._model.quantize(goal), self._lo, self._hi)
        step = np.sign(goal - here)
        moved = step != 0
        self._direction = np.where(moved, step, self._direction)
        self._start, self._goal, self._t0 = here, goal, self.clock.now()
        if v is None or a is None:
            self._move_v, self._move_a = self._run_v, self._run_a
            self._end = self._t0 + self._travel(here.tolist(), goal.tolist())
        else:
            self._move_v, self._move_a = v, a
            self._end = self._t0 + profile_duration(here, goal, v, a)
        self._path = None
        self._count_move(moved)

    def _count_move(self, moved: np.ndarray) -> None:
        """One more move of the present sample from ``_t0``: arm its faults, and draw its
        repeatability error for the axes that ``moved`` (backlash from ``_direction``)."""
        k = self._moves.get(self._sample, 0)
        self._moves[self._sample] = k + 1
        self.faults.arm(self._sample, k, self._t0)
        if self._model is not None:
            axes = len(moved)
            draw = self._model.repeatability_draw(np.array([self._sample]), axes, start=k * axes)[0]
            self._repeat = np.where(moved, draw, self._repeat)
            self._error = self._model.backlash_error(self._direction) + self._repeat

    def _present_encoder(self) -> FloatArray:
        now = self.clock.now()
        if now >= self._end:  # at rest (the common case: read after settling)
            return self._goal.copy()
        if self._path is not None:
            return self._path.at(now)
        return profile_position(self._start, self._goal, self._move_v, self._move_a, now - self._t0)

    def _error_at(self, t: float) -> FloatArray:
        """Joint minus encoder (rad) at clock time ``t`` of the present motion."""
        if self._path is None or self._model is None or t >= self._end:
            return self._error
        backlash = self._model.backlash_error(self._path.direction_at(t))
        return np.asarray(backlash + self._repeat, dtype=np.float64)

    # -- trajectories -----------------------------------------------------------------
    def follow(
        self,
        trajectory: Trajectory,
        on_poll: Callable[[StampedPositions], None] | None = None,
    ) -> Followed:
        """Follow ``trajectory`` ideally: the joints on its path (set-points joined by
        straight lines, on encoder ticks with the position_error effect) from now on,
        each set-point's SYNC_WRITE taking its wire time and each poll ``poll_s``.

        `DriverError` (an unknown axis; the axes moving or not within one encoder tick
        of set-point 0), `LimitError`, `TorqueOff` or a latched `MotorFault` before
        anything moves. A fault (struck half-way, as in a move) or an exception of
        ``on_poll`` holds every axis before it propagates.
        """
        self._check_open()
        top_a = {n: float(self._a[i]) for n, i in self._index.items()}
        check_trajectory(trajectory, self.limits(), self.velocity_limits(), top_a)
        if not self._torque:
            raise TorqueOff("torque is off: call torque(True) before moving; nothing moved")
        self.faults.check_clear()
        goals = self._path_goals(trajectory)
        started = self.clock.now()
        period = trajectory.period_s
        path = JointPath(Trajectory(self._names, period, goals), started, self._direction)
        self._start, self._goal, self._t0, self._end = goals[0], goals[-1], started, path.end_s
        self._path = path
        self._direction = path.direction_at(path.end_s)
        self._count_move(path.moved)
        write_s = sync_write_bytes(len(trajectory.axes)) * BITS_PER_BYTE / self.rig.spec.bus.baud
        sent: list[float] = []
        polls: list[StampedPositions] = []
        try:
            for k in range(len(trajectory)):
                sent.append(self.clock.advance_to(max(started + k * period, self.clock.now())))
                self.clock.advance(write_s)
                polls.append(self.poll_positions())
                if on_poll is not None:
                    on_poll(polls[-1])
        except BaseException:
            self._hold()
            raise
        self.wait_settled(SETTLE_TIMEOUT_S)
        tracking = tracking_error(trajectory, started, polls)
        return Followed(started, tuple(sent), polls, tracking, self.clock.now())

    def _path_goals(self, trajectory: Trajectory) -> FloatArray:
        """(K, A) set-points of every axis (the others hold still), on encoder ticks with
        the position_error effect, starting where the axes are; `DriverError` unless they
        are at rest within one tick of set-point 0."""
        here = self._present_encoder()
        columns = [self._index[n] for n in trajectory.axes]
        tick = np.array([a.resolution_rad for a in self.rig.bus_axes()])[columns]
        off = np.abs(here[columns] - trajectory.goals[0]) > tick
        if self.clock.now() < self._end or off.any():
            where = ", ".join(f"{n} {x:.6f} rad" for n, x in zip(self._names, here, strict=True))
            raise DriverError(
                "follow: the axes must be at rest at the trajectory's set-point 0 (move_to "
                f"and wait_settled first); they are {'moving, ' if not off.any() else ''}"
                f"at {where}; nothing moved"
            )
        goals = np.repeat(here[None, :], len(trajectory), axis=0)
        goals[:, columns] = trajectory.goals
        if self._model is not None:
            goals = np.clip(self._model.quantize(goals), self._lo, self._hi)
        goals[0] = here
        return goals

    def wait_settled(self, timeout_s: float) -> None:
        """Advance the clock to the end of the motion (at once if that has passed); if
        that is more than ``timeout_s`` away, hold the axes where they are after
        ``timeout_s`` and raise `MotionTimeout`. An injected fault strikes half-way
        through the move: every axis is held, then the fault is raised."""
        self._check_open()
        if self.faults.pending is not None:
            self._strike(self.faults.pending, timeout_s)
        remaining = self._end - self.clock.now()
        if remaining > timeout_s:
            self.clock.advance(timeout_s)
            self._hold()
            raise MotionTimeout(
                f"axes did not settle within {timeout_s:g} s (the move needs "
                f"{remaining:.3f} s more); holding them"
            )
        if remaining > 0:
            self.clock.advance_to(self._end)

    def _strike(self, rule: FaultRule, timeout_s: float) -> None:
        """Raise the injected fault ``rule`` of the present move, holding every axis."""
        self.faults.disarm()
        now = self.clock.now()
        if rule.kind == "motion_timeout":
            self.clock.advance(timeout_s)
            self._hold()
            raise MotionTimeout(
                f"axes did not settle within {timeout_s:g} s (an axis is blocked: injected "
                f"at sample {self._sample}); holding them"
            )
        if self._end > now:
            self.clock.advance_to(now + 0.5 * (self._end - now))
        self._hold()
        raise self.faults.strike(rule, self._sample, self.clock.now())

    def positions(self) -> dict[str, float]:
        """The encoder's reading of each axis (rad)."""
        self._check_open()
        return dict(zip(self._names, self._present_encoder().tolist(), strict=True))

    def poll_positions(self) -> StampedPositions:
        """The encoder's reading of each axis (rad; its tick with the position_error
        effect) at the middle of a poll that takes ``poll_s`` on the clock, stamped at
        its start and end. An injected fault whose move has reached half-way strikes
        here as in `wait_settled`: every axis held, then the fault raised."""
        self._check_open()
        request_s = self.clock.now()
        self.clock.advance(0.5 * self.poll_s)
        rule = self.faults.pending
        halfway = self.clock.now() >= 0.5 * (self._t0 + self._end)
        if rule is not None and rule.kind != "motion_timeout" and halfway:
            self.faults.disarm()
            self.clock.advance(0.5 * self.poll_s)
            self._hold()
            raise self.faults.strike(rule, self._sample, self.clock.now())
        here = self._present_encoder()
        if self._model is not None:
            here = self._model.quantize(here)
        reply_s = self.clock.advance(0.5 * self.poll_s)
        return StampedPositions(
            dict(zip(self._names, here.tolist(), strict=True)),
            request_s,
            reply_s,
            arrived=reply_s >= self._end,
        )

    def true_positions(self) -> dict[str, float]:
        """Where the joints really are (rad): the encoder reading plus backlash and
        repeatability (equal to `positions` without the position_error effect)."""
        self._check_open()
        true = self._present_encoder() + self._error_at(self.clock.now())
        return dict(zip(self._names, true.tolist(), strict=True))

    def true_position_at(self, t: float) -> dict[str, float]:
        """Where the joints really are (rad) at clock time ``t`` (s) of the present move
        (at its start before it, at its goal after it): a stream window's pose."""
        if t >= self._end:
            here = self._goal
        elif self._path is not None:
            here = self._path.at(t)
        else:
            dt = max(t - self._t0, 0.0)
            here = profile_position(self._start, self._goal, self._move_v, self._move_a, dt)
        return dict(zip(self._names, (here + self._error_at(t)).tolist(), strict=True))

    def snapshot(self) -> MotorState:
        """The motors' state (at rest: call after `wait_settled`)."""
        return MotorState(
            tuple(self._present_encoder().tolist()),
            tuple(self._direction.tolist()),
            tuple(self._repeat.tolist()),
        )

    @property
    def present_sample(self) -> int:
        """The sample the moves belong to (`begin_sample`)."""
        return self._sample

    def moves_of(self, sample: int) -> int:
        """Moves made so far for ``sample``."""
        return self._moves.get(sample, 0)

    def set_moves(self, sample: int, moves: int) -> None:
        """Continue ``sample`` after ``moves`` moves (a resumed run)."""
        self._moves[sample] = moves

    def restore(self, state: MotorState) -> None:
        """Put the motors, at rest, in a `snapshot`'s state."""
        here = np.array(state.encoder, dtype=np.float64)
        self._start, self._goal, self._t0 = here, here.copy(), self.clock.now()
        self._end = self._t0
        self._path = None
        self._direction = np.array(state.direction, dtype=np.float64)
        self._repeat = np.array(state.repeatability, dtype=np.float64)
        backlash = self._model.backlash_error(self._direction) if self._model else 0.0
        self._error = backlash + self._repeat

    def stop(self) -> None:
        """Hold every axis where it is now (also a faulted axis's neighbours)."""
        self._check_open()
        self._hold()

    def _hold(self) -> None:
        here = self._present_encoder()
        if self._path is not None and self._model is not None:  # where a path left it
            self._direction = self._path.direction_at(self.clock.now())
            self._error = self._error_at(self.clock.now())
        self._start, self._goal, self._t0 = here, here, self.clock.now()
        self._end = self._t0
        self._path = None
        self.faults.disarm()

    def torque(self, on: bool) -> None:
        self._check_open()
        if not on:
            self._hold()
        self._torque = bool(on)

    def health(self) -> dict[str, Health]:
        """Temperatures (an injected overheat's axis: its temperature until it has cooled,
        else 35 °C), 12 V, the latched flags; the load is not modelled (None)."""
        self._check_open()
        return self.faults.health(self.clock.now())

    def reboot(self, axes: tuple[str, ...] | None = None) -> tuple[str, ...]:
        """Clear the latched faults (of ``axes``, or every faulted axis), holding; the
        axes rebooted."""
        self._check_open()
        names = tuple(self.faults.latched) if axes is None else tuple(axes)
        for name in names:
            if name not in self._index:
                raise DriverError(f"unknown axis {name!r}; the axes are {', '.join(self._names)}")
            self.faults.clear(name)
        self._hold()
        return names

    def recover(self, axis: str) -> Recovered:
        """Hold every axis, then reboot ``axis``'s motor: its latched fault clears, unless
        it is an overheating one and the axis is still hot (`MotorFault` again, as a
        real motor re-latches it). An injected ``shift_deg`` moves its encoder reading
        (not the joint) at the reboot. Where it was held and where it reads now (rad)."""
        self._check_open()
        if axis not in self._index:
            raise DriverError(f"unknown axis {axis!r}; the axes are {', '.join(self._names)}")
        self._hold()
        i = self._index[axis]
        held = float(self._goal[i])
        shift = self.faults.recover(axis, self.clock.now())
        if shift:  # the encoder jumps, the joint stays: true = encoder + error
            self._goal = self._goal.copy()
            self._goal[i] += shift
            self._start = self._goal.copy()
            self._error[i] -= shift
        return Recovered(axis, held, float(self._present_encoder()[i]))
