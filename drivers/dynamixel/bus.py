"""`DynamixelBus`: the rig's motor axes as a `drivers.base.MotorBus` on Dynamixel X-series.

Goal positions of all axes go out in one SYNC_WRITE; Moving and Present Position come
back in one SYNC_READ, whose status packets also carry each motor's alert bit. Safety:

- a target outside its axis's limits raises `LimitError` before a byte is sent, and
  goals are also clamped to the motor's own position limits (written to its EEPROM in
  position mode), so the motor refuses what the software would;
- torque is only enabled after each goal is set to the present position (no jump);
- `stop` holds every axis that answers at its present position clamped to its limits,
  reading positions *without* raising on alert bits: one faulted motor never keeps the
  others moving;
- leaving the context (normally, on an exception — a `MotorFault` of one axis included
  — or on Ctrl-C in the middle of a transaction) makes every axis hold where it is and
  releases the port; the exception that left the block is the one raised;
- any fault while axes may move (`MotorFault`, `MotionTimeout`, `CommError` from
  `move_to`, `wait_settled` or `positions`) holds every answering axis before it
  propagates, so code that catches it inside the ``with`` block leaves no arm running;
- with torque off `move_to` raises `TorqueOff`; on a closed bus every call but `close`
  raises `DeviceClosed` (the contract in `drivers.base`);
- `reboot` clears faulted motors and brings them back holding, configured as `open`
  configured them; `recover` does so for one axis while the others hold, and says
  where it was held before and where it reads after.

Sweeps (measuring while moving): `sweep` writes the axes' Profile Acceleration and
Profile Velocity for that move, then the goals (three SYNC_WRITEs; the limits and the
rates are checked before the first byte); the next `move_to` writes the configured
profiles back first. `poll_positions` is one SYNC_READ of Present Position (4 bytes per
motor), stamped on the bus's clock just before the instruction leaves and just after
the last status arrives.

Models and configuration: `open` identifies each motor by its model and writes what its
axis needs (`drivers.dynamixel.setup`); a motor that is not the model its axis names
stops `open` with one line saying so, before anything is written.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from types import TracebackType

from drivers.base import Clock, SystemClock
from drivers.devices import Resource
from drivers.dynamixel.axis import AxisConfig
from drivers.dynamixel.condition import Condition, ConditionContext
from drivers.dynamixel.control_table import FACTORY_BAUD, RAD_S_PER_VELOCITY_UNIT
from drivers.dynamixel.follow import SetpointPlan, SetpointStream
from drivers.dynamixel.goals import Goals
from drivers.dynamixel.link import DynamixelLink
from drivers.dynamixel.owed import LateCounts
from drivers.dynamixel.setup import MotorSetup, axis_named
from drivers.dynamixel.wire import SETTLE_POLL_INTERVAL_S
from drivers.errors import MOTION_FAULTS, DeviceClosed, DriverError, TorqueOff
from drivers.sweep import sweep_profile
from drivers.trajectory import SETTLE_TIMEOUT_S, Followed, Trajectory
from drivers.values import Health, Recovered, StampedPositions


class DynamixelBus(Resource):
    """A `MotorBus` of ``axes`` on the Dynamixel bus at ``port``.

    ``baud`` is the motors' rate (factory default 57 600; see docs/reference/hardware.md to move
    to 1 Mbps); ``retries`` extra attempts per transaction; ``settle_ticks`` how close
    (in motor ticks) an axis must be to its goal to count as settled; ``configure``
    writes operating mode, drive mode, position limits and profiles on open;
    ``reboot_timeout_s`` how long `reboot` waits for a motor to answer again;
    ``clock`` stamps `poll_positions` and paces `wait_settled`'s polls (default the
    host's monotonic clock; a rehearsal passes its run's scaled clock, the motion's).

    It holds the configuration it gives its motors (`drivers.dynamixel.setup`), its
    axes' goals and the reads that compare the axes with them (`drivers.dynamixel.goals`),
    its set-point stream (`drivers.dynamixel.follow`) and its condition and recovery
    (`drivers.dynamixel.condition`).
    """

    def __init__(
        self,
        port: str,
        axes: Sequence[AxisConfig],
        *,
        baud: int = FACTORY_BAUD,
        retries: int = 3,
        latency_ms: float | None = None,
        settle_ticks: int = 2,
        poll_interval_s: float = SETTLE_POLL_INTERVAL_S,
        configure: bool = True,
        reboot_timeout_s: float = 2.0,
        clock: Clock | None = None,
    ) -> None:
        if not axes:
            raise ValueError("a bus needs at least one axis")
        names = [a.name for a in axes]
        ids = [a.motor_id for a in axes]
        if len(set(names)) != len(names) or len(set(ids)) != len(ids):
            raise ValueError(f"axis names and motor IDs must be unique: {names}, {ids}")
        self._axes = {a.name: a for a in axes}
        self._link = DynamixelLink(
            port,
            baud,
            retries=retries,
            latency_ms=latency_ms,
            names=dict(zip(ids, names, strict=True)),
        )
        self._stream = SetpointStream(self._link)
        self.settle_ticks = settle_ticks
        self.poll_interval_s = poll_interval_s
        self.configure = configure
        self.reboot_timeout_s = reboot_timeout_s
        self.clock: Clock = clock if clock is not None else SystemClock()
        self.models: dict[str, str] = {}
        self._goals = Goals(self._link, self._axes)
        self._torque_on = False
        #: Motors running a sweep's profile: the next `move_to` restores the configured one.
        self._swept: set[int] = set()
        self._setup = MotorSetup(self._link, self._axes)
        self._condition = Condition(
            ConditionContext(self._link, self._axes, hold=self._goals.hold, restore=self._restore)
        )

    # -- lifecycle ---------------------------------------------------------------------
    @property
    def axes(self) -> tuple[str, ...]:
        return tuple(self._axes)

    @property
    def port(self) -> str:
        return self._link.port_name

    @property
    def is_open(self) -> bool:
        return bool(self._link.is_open)

    @property
    def late_counts(self) -> LateCounts:
        """The link's syncs after replies a timeout gave up on (`DynamixelLink.late_counts`)."""
        return self._link.late_counts

    def limits(self) -> dict[str, tuple[float, float]]:
        """Each axis's configured range (rad)."""
        return {n: (a.min_rad, a.max_rad) for n, a in self._axes.items()}

    def _check_open(self) -> None:
        if not self._link.is_open:
            raise DeviceClosed(
                f"the Dynamixel bus on {self.port} is not open (use it as a context manager)"
            )

    def open(self) -> None:
        """Open the port, check every motor answers and is healthy, configure, hold.
        Does nothing if the bus is already open."""
        if self._link.is_open:
            return
        self._link.open()
        self._swept.clear()
        try:
            for axis in self._axes.values():
                self.models[axis.name] = self._setup.identify(axis)
                flags = self._link.hardware_error(axis.motor_id)
                if flags:
                    raise self._link.fault(axis.motor_id)
            if self.configure:
                self._setup.configure()
            self.torque(True)
        except BaseException:
            self._link.reset()
            self._link.close()
            raise

    def close(self) -> None:
        """Hold every axis that answers where it is and release the port (always). If an
        axis could not be told to hold, raise that error once the port is released."""
        problem = self._release()
        if problem is not None:
            raise problem

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        """Hold and release; the exception leaving the block (if any) is the one that
        propagates, with a failure to hold added to it as a note."""
        problem = self._release()
        if problem is None:
            return
        if exc is None:
            raise problem
        exc.add_note(f"and on release: {problem}")

    def _release(self) -> DriverError | None:
        if not self._link.is_open:
            return None
        try:
            self._link.reset()
            self.stop()
        except DriverError as exc:
            return exc
        finally:
            self._link.close()
            self._torque_on = False
        return None

    @contextmanager
    def _holding_on_fault(
        self, caught: type[BaseException] | tuple[type[BaseException], ...] = MOTION_FAULTS
    ) -> Iterator[None]:
        """Hold every answering axis before a motion fault (or what is ``caught``)
        propagates (the contract); after Ctrl-C, a reply still on its way is let in first."""
        try:
            yield
        except caught as exc:
            if not isinstance(exc, DriverError):
                self._link.reset()
            try:
                self.stop()
            except DriverError as problem:
                exc.add_note(f"and holding the axes: {problem}")
            raise

    def _restore(self, motor_ids: Sequence[int]) -> None:
        """The configuration `open` gave ``motor_ids`` written again (with ``configure``
        off only the profile): they no longer run a sweep's profile."""
        if self.configure:
            self._setup.configure(motor_ids)
        else:
            self._setup.write_profiles(motor_ids)
        self._swept.difference_update(motor_ids)

    # -- motion ------------------------------------------------------------------------
    def move_to(self, targets: Mapping[str, float]) -> None:
        """Command axis angles (rad) in one SYNC_WRITE; returns at once. `LimitError`
        (a target outside its limits or not finite) and `TorqueOff` send nothing. After
        a sweep, the configured profiles are written back first."""
        self._check_open()
        goals = self._goal_ticks(targets)
        if not self._torque_on:
            raise TorqueOff("torque is off: call torque(True) before moving; nothing was sent")
        with self._holding_on_fault():
            if self._swept:
                self._setup.write_profiles(sorted(self._swept))
                self._swept.clear()
            self._goals.send(goals)

    def _goal_ticks(self, targets: Mapping[str, float]) -> dict[str, int]:
        """Goal registers of ``targets`` (rad); `LimitError` / `DriverError` first."""
        return {
            name: axis_named(self._axes, name).goal_ticks(angle) for name, angle in targets.items()
        }

    def velocity_limits(self) -> dict[str, float]:
        """Each axis's configured profile velocity (rad/s): the fastest a sweep may ask."""
        return {n: a.profile_velocity_rad_s for n, a in self._axes.items()}

    def sweep(
        self,
        targets: Mapping[str, float],
        velocities: Mapping[str, float],
        accelerations: Mapping[str, float] | None = None,
    ) -> dict[str, float]:
        """Move the named axes to ``targets`` (rad) at ``velocities`` (rad/s) with
        ``accelerations`` (rad/s²; default the configured ones), for this move only.

        Writes Profile Acceleration, Profile Velocity, then Goal Position (one
        SYNC_WRITE each) and returns at once with the velocities the registers hold
        (rad/s; one step is 0.229 rev/min of the motor). `LimitError` (a target outside
        its limits, a rate not in (0, configured] or below one register step),
        `DriverError` (an unknown axis) and `TorqueOff` send nothing.
        """
        self._check_open()
        goals = self._goal_ticks(targets)
        rates = sweep_profile(
            targets,
            velocities,
            accelerations,
            self.velocity_limits(),
            {n: a.profile_acceleration_rad_s2 for n, a in self._axes.items()},
        )
        registers: dict[int, tuple[int, int]] = {}
        commanded: dict[str, float] = {}
        for name, (velocity, acceleration) in rates.items():
            axis = self._axes[name]
            registers[axis.motor_id] = axis.rate_registers(velocity, acceleration)
            commanded[name] = (
                registers[axis.motor_id][0] * RAD_S_PER_VELOCITY_UNIT / axis.gear_ratio
            )
        if not self._torque_on:
            raise TorqueOff("torque is off: call torque(True) before moving; nothing was sent")
        with self._holding_on_fault():
            self._swept.update(registers)
            link = self._link
            link.sync_write("profile_acceleration", {m: r[1] for m, r in registers.items()})
            link.sync_write("profile_velocity", {m: r[0] for m, r in registers.items()})
            self._goals.send(goals)
        return commanded

    def follow(
        self,
        trajectory: Trajectory,
        on_poll: Callable[[StampedPositions], None] | None = None,
    ) -> Followed:
        """Stream ``trajectory`` (`drivers.dynamixel.follow`): per period one SYNC_WRITE of
        each axis's Profile Acceleration, Profile Velocity and a look-ahead Goal Position,
        then one `poll_positions` and ``on_poll``; then `wait_settled`. `LimitError`,
        `TorqueOff` and `DriverError` (an unknown axis; the axes not at rest within
        ``settle_ticks`` of set-point 0) send nothing; a fault, an exception of
        ``on_poll`` or Ctrl-C holds every answering axis before it propagates."""
        self._check_open()
        plan = SetpointPlan.of(trajectory, self._axes)
        if not self._torque_on:
            raise TorqueOff("torque is off: call torque(True) before moving; nothing was sent")
        with self._holding_on_fault():
            plan.check_start(self._goals.state(), self.settle_ticks)
        with self._holding_on_fault(BaseException):
            self._swept.update(plan.motor_ids)
            self._goals.ticks.update(plan.last_goals())
            followed = self._stream.run(plan, self.clock, self.poll_positions, on_poll)
            self._goals.wait_settled(
                SETTLE_TIMEOUT_S, self.clock, self.settle_ticks, self.poll_interval_s
            )
        return dataclasses.replace(followed, ended_s=self.clock.now())

    def positions(self) -> dict[str, float]:
        """Axis angles (rad) read back from the motors."""
        self._check_open()
        with self._holding_on_fault():
            state = self._goals.state()
        return {name: self._axes[name].to_rad(ticks) for name, (_, ticks) in state.items()}

    def poll_positions(self) -> StampedPositions:
        """Axis angles (rad) from one SYNC_READ of Present Position, stamped on the bus's
        clock just before the instruction is sent and just after the last status arrives
        (the successful attempt's, after a retry). Safe while moving; `MotorFault` and
        `CommError` hold every answering axis before they propagate."""
        self._check_open()
        with self._holding_on_fault():
            return self._goals.poll(self.clock, self.settle_ticks)

    def wait_settled(self, timeout_s: float) -> None:
        """Return once no axis is moving and each is within ``settle_ticks`` of its goal
        (the rig's settle dwell is the caller's: `drivers.base`).

        On timeout, on a motor's fault and on a failed poll, every answering axis is
        told to hold before `MotionTimeout` (naming the laggards), `MotorFault` or
        `CommError` propagates.
        """
        self._check_open()
        with self._holding_on_fault():
            self._goals.wait_settled(timeout_s, self.clock, self.settle_ticks, self.poll_interval_s)

    def stop(self) -> None:
        """Hold every axis that answers at its present position (clamped to its limits).

        Positions are read without raising on alert bits, so a faulted motor does not
        keep the others moving; if the group read fails (a motor does not answer), the
        axes are read one by one and the ones that answer are held. Then `CommError`
        names any axis that could not be held. Never raises `MotorFault`.
        """
        self._check_open()
        self._goals.hold(list(self._axes))

    def torque(self, on: bool) -> None:
        """Enable (after setting each goal to the present position) or disable torque."""
        self._check_open()
        ids = [a.motor_id for a in self._axes.values()]
        if on:
            self.stop()
        self._torque_on = False  # until the motors have been told
        self._link.sync_write("torque_enable", dict.fromkeys(ids, 1 if on else 0))
        self._torque_on = bool(on)

    # -- condition and recovery (`drivers.dynamixel.condition`) ---------------------------
    def reboot(self, axes: Iterable[str] | None = None) -> tuple[str, ...]:
        """Reboot the motors reporting a hardware error (or those of ``axes``), wait for
        them to answer again, restore the configuration `open` gave them (operating
        mode, drive mode and position limits where they differ, the profile; with
        ``configure`` off only the profile) and leave them holding where they are with
        torque on. Returns the axes rebooted.

        A motor whose error is still there after the reboot raises `MotorFault` (remove
        the cause first: load, heat, supply). In extended position mode a reboot loses
        the multi-turn count (the motor comes back within one turn), so re-home such an
        axis before trusting its angle.
        """
        self._check_open()
        return self._condition.reboot(
            axes, timeout_s=self.reboot_timeout_s, poll_s=self.poll_interval_s
        )

    def recover(self, axis: str) -> Recovered:
        """Hold every axis where it is, reboot ``axis``'s motor back into its configuration
        (`reboot`) and read its position again: the position (rad) it was told to hold
        just before the reboot and the one it reads after. `MotorFault` if its error
        is still there after the reboot, `CommError` if it does not answer again."""
        self._check_open()
        return self._condition.recover(
            axis, timeout_s=self.reboot_timeout_s, poll_s=self.poll_interval_s
        )

    def health(self) -> dict[str, Health]:
        """Temperature (°C), input voltage (V), hardware error flags and load (signed %:
        Present Current over the model's largest Current Limit; an XL430's Present
        Load) per axis; a motor's alert does not raise."""
        self._check_open()
        return self._condition.health()

    def check(self) -> None:
        """Raise `MotorFault` for the first axis reporting a hardware error."""
        self._check_open()
        self._condition.check()
