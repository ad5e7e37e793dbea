"""`Goals`: where a `DynamixelBus` last told its axes to go (Goal Position, ticks) and the
reads that compare them with where the axes are: one SYNC_READ of Moving … Present
Position (`state`), a stamped poll of Present Position (`poll`), the wait until every
axis has settled on its goal (`wait_settled`) and the hold of the axes where they stand
(`hold`). The bus holds one and guards each call (an open port, a hold on a fault)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from drivers.base import Clock
from drivers.dynamixel.axis import AxisConfig
from drivers.dynamixel.control_table import item
from drivers.dynamixel.link import DynamixelLink
from drivers.errors import CommError, DriverError, MotionTimeout
from drivers.values import StampedPositions

_MOVING = item("moving")
_PRESENT = item("present_position")


class Goals:
    """The goals (ticks) last sent to ``axes`` over ``link``, by axis name (`ticks`)."""

    def __init__(self, link: DynamixelLink, axes: Mapping[str, AxisConfig]) -> None:
        self._link = link
        self._axes = axes
        #: The last Goal Position (ticks) each axis was sent, by name.
        self.ticks: dict[str, int] = {}

    def send(self, goals: Mapping[str, int]) -> None:
        """Goal Position ``goals`` (ticks, by axis) in one SYNC_WRITE."""
        self._link.sync_write(
            "goal_position", {self._axes[n].motor_id: t for n, t in goals.items()}
        )
        self.ticks.update(goals)

    def state(self) -> dict[str, tuple[bool, int]]:
        """{axis: (moving, present ticks)} from one SYNC_READ of Moving … Present Position."""
        ids = [a.motor_id for a in self._axes.values()]
        raw = self._link.sync_read(ids, _MOVING.name, _PRESENT.name)
        offset = _PRESENT.address - _MOVING.address
        out = {}
        for name, axis in self._axes.items():
            data = raw[axis.motor_id]
            out[name] = (
                bool(data[0]),
                _PRESENT.decode(data[offset : offset + _PRESENT.size]),
            )
        return out

    def poll(self, clock: Clock, settle_ticks: int) -> StampedPositions:
        """Axis angles (rad) from one SYNC_READ of Present Position, stamped on ``clock``
        just before the instruction is sent and just after the last status arrives;
        arrived when every axis is within ``settle_ticks`` of its goal."""
        ids = [a.motor_id for a in self._axes.values()]
        raw, request_s, reply_s = self._link.sync_read_stamped(
            ids, _PRESENT.name, _PRESENT.name, clock.now
        )
        ticks = {name: _PRESENT.decode(raw[axis.motor_id]) for name, axis in self._axes.items()}
        arrived = all(abs(t - self.ticks.get(name, t)) <= settle_ticks for name, t in ticks.items())
        return StampedPositions(
            {name: self._axes[name].to_rad(t) for name, t in ticks.items()},
            request_s,
            reply_s,
            arrived,
        )

    def wait_settled(
        self, timeout_s: float, clock: Clock, settle_ticks: int, poll_interval_s: float
    ) -> None:
        """Poll `state` every ``poll_interval_s`` (s on ``clock``) until no axis moves and
        each is within ``settle_ticks`` of its goal; `MotionTimeout` naming the laggards
        after ``timeout_s`` (s on ``clock``)."""
        # On the motion's clock, as the polls are paced: a rehearsal's scaled time, a
        # test's manual one (on the host's clock, a fast host polled a manual clock past
        # the motion's end before the timeout).
        deadline = clock.now() + timeout_s
        while True:
            state = self.state()
            pending = {
                name: (moving, ticks - self.ticks.get(name, ticks))
                for name, (moving, ticks) in state.items()
                if moving or abs(ticks - self.ticks.get(name, ticks)) > settle_ticks
            }
            if not pending:
                return
            if clock.now() >= deadline:
                detail = ", ".join(
                    f"{n} {'moving' if m else 'stopped'} {abs(d)} ticks from its goal"
                    for n, (m, d) in pending.items()
                )
                raise MotionTimeout(
                    f"axes did not settle within {timeout_s:g} s ({detail}); holding them"
                )
            clock.sleep(poll_interval_s)  # the motion's time: a rehearsal's scaled

    def hold(self, names: Sequence[str]) -> dict[str, int]:
        """Goal := present position (within limits) for ``names``, in one SYNC_WRITE; the
        goals (ticks). Positions are read without raising on alert bits, one axis at a
        time if the group read fails; `CommError` names any axis that could not be held
        once the others are."""
        axes = [self._axes[n] for n in names]
        present: dict[str, int] = {}
        missing: dict[str, DriverError] = {}
        try:
            raw = self._link.sync_read(
                [a.motor_id for a in axes], _PRESENT.name, _PRESENT.name, alerts=False
            )
            present = {a.name: _PRESENT.decode(raw[a.motor_id]) for a in axes}
        except DriverError:
            for axis in axes:  # hold whoever answers
                try:
                    present[axis.name] = self._link.read(axis.motor_id, _PRESENT.name, alerts=False)
                except DriverError as exc:
                    missing[axis.name] = exc
        goals = {name: self._axes[name].clamp_ticks(ticks) for name, ticks in present.items()}
        if goals:
            self.send(goals)
        if missing:
            first, cause = next(iter(missing.items()))
            raise CommError(
                f"could not hold {', '.join(missing)} (may still be moving; "
                f"{', '.join(goals) or 'no other axis'} held): {cause}",
                port=self._link.port_name,
                motor_id=self._axes[first].motor_id,
                result=cause.result if isinstance(cause, CommError) else None,
            )
        return goals
