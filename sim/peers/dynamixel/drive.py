"""The physical side of one emulated X-series motor: its motion on the motor's clock
and its heat.

`Drive` holds the present trajectory (from :mod:`sim.peers.dynamixel.motion`), when it
started, the last `PAST_TRAJECTORIES` ones and the Moving Status profile type; it starts
moves, spins and holds from the register values the control table gives it (ticks, the
e-manual's velocity and acceleration units). `Heat` is the temperature of a heated
motor cooling exponentially toward `NOMINAL_TEMPERATURE`. Neither knows the control
table: :mod:`sim.peers.dynamixel.motor` reads the registers and writes the derived ones back.
"""

from __future__ import annotations

import math
from collections import deque
from typing import NamedTuple

from sim.peers.dynamixel.motion import (
    INF,
    TICKS_PER_S2_PER_ACCELERATION_UNIT,
    TICKS_PER_S_PER_VELOCITY_UNIT,
    ProfileType,
    Trajectory,
    at_rest,
    move,
    move_timed,
    spin,
)

#: Trajectories (moves and holds) a motor remembers for `Drive.position_at`: a streamed
#: trajectory writes a goal every period, so ten seconds of set-points at 100 Hz.
PAST_TRAJECTORIES = 1024

#: Present Temperature (°C) of a motor that is not heated.
NOMINAL_TEMPERATURE = 30


class Sample(NamedTuple):
    """Where the drive is at one instant: position (ticks), velocity (ticks/s), whether a
    finite move is still running and whether the trajectory is endless (a spin)."""

    position: float
    velocity: float
    running: bool
    endless: bool


class Drive:
    """One motor's trajectories on its clock, starting at rest at ``position`` (ticks)
    at ``now`` (s). Positions are Present Position ticks (before rounding)."""

    def __init__(self, position: float, now: float) -> None:
        #: When the present trajectory started (s on the motor's clock).
        self.t0 = now
        #: The present trajectory.
        self.trajectory: Trajectory = at_rest(position)
        #: The trajectories before the present one (start time, trajectory), newest last.
        self.past: deque[tuple[float, Trajectory]] = deque(maxlen=PAST_TRAJECTORIES)
        #: The profile type Moving Status reports (that of the last move or spin).
        self.kind = ProfileType.STEP

    def at(self, now: float) -> tuple[float, float]:
        """Position (ticks) and velocity (ticks/s) at ``now`` (s)."""
        return self.trajectory.at(now - self.t0)

    def position(self, now: float) -> float:
        """Position (ticks) at ``now`` (s)."""
        return self.trajectory.at(now - self.t0)[0]

    def running(self, now: float) -> bool:
        """True while the present trajectory is still changing at ``now`` (s)."""
        return self.trajectory.running(now - self.t0)

    def position_at(self, t: float) -> float:
        """Position (ticks) at ``t`` (s) along the present trajectory or, before it, the
        last `PAST_TRAJECTORIES` ones."""
        if t < self.t0:
            for t0, traj in reversed(self.past):
                if t >= t0:
                    return traj.at(t - t0)[0]
        return self.position(t)

    def place(self, position: float, now: float) -> None:
        """Put the motor at rest at ``position`` (ticks) from ``now`` (s), forgetting the
        present trajectory (a backdoor or a reset, not a motion)."""
        self.t0 = now
        self.trajectory = at_rest(position)

    def hold(self, position: float, now: float) -> None:
        """Hold ``position`` (ticks) from ``now`` (s); the present trajectory goes to the past."""
        self.past.append((self.t0, self.trajectory))
        self.t0, self.trajectory = now, at_rest(position)

    def reset_kind(self) -> None:
        """Moving Status reports a step profile again (boot)."""
        self.kind = ProfileType.STEP

    def move(
        self,
        now: float,
        goal: int,
        profile_velocity: int,
        profile_acceleration: int,
        velocity_limit: int,
        time_based: bool,
    ) -> None:
        """Start a move at ``now`` (s) to ``goal`` (ticks) under the profile registers
        (velocity-based units, or ms when ``time_based``)."""
        position, velocity = self.at(now)
        pv, pa, limit = profile_velocity, profile_acceleration, velocity_limit
        if time_based and pv:
            traj = move_timed(position, goal, pv / 1000.0, pa / 1000.0)
        else:
            # Profile Velocity 0: as fast as the Velocity Limit allows (0 too: a step).
            v = min(pv, limit) if pv and limit else (pv or limit)
            v_max = v * TICKS_PER_S_PER_VELOCITY_UNIT if v else INF
            a_max = pa * TICKS_PER_S2_PER_ACCELERATION_UNIT if pa and not time_based else INF
            traj = move(position, velocity, goal, v_max, a_max, None if pv else ProfileType.STEP)
        self.past.append((self.t0, self.trajectory))
        self.t0, self.trajectory, self.kind = now, traj, traj.kind

    def spin(self, now: float, goal_velocity: int, profile_acceleration: int) -> None:
        """Start spinning at ``now`` (s) toward ``goal_velocity`` (velocity units) under
        Profile Acceleration (0: at once)."""
        position, velocity = self.at(now)
        pa = profile_acceleration
        a_max = pa * TICKS_PER_S2_PER_ACCELERATION_UNIT if pa else INF
        goal = goal_velocity * TICKS_PER_S_PER_VELOCITY_UNIT
        self.t0, self.trajectory = now, spin(position, velocity, goal, a_max)
        self.kind = self.trajectory.kind

    def sample(self, now: float) -> Sample:
        """The drive at ``now`` (s); a finished move becomes a hold at its target."""
        elapsed = now - self.t0
        traj = self.trajectory
        position, velocity = traj.at(elapsed)
        running = traj.running(elapsed) and not traj.endless
        if not running and not traj.endless and traj.segments:
            self.hold(traj.target, now)
        return Sample(position, velocity, running, traj.endless)


class Heat:
    """A motor's temperature after `set`: cooling toward `NOMINAL_TEMPERATURE`."""

    def __init__(self) -> None:
        self._state: tuple[float, float, float] | None = None  # since (s), °C then, τ (s)

    def set(self, now: float, celsius: float, time_constant_s: float) -> None:
        """The motor is at ``celsius`` (°C) at ``now`` and cools with ``time_constant_s`` (s)."""
        self._state = (now, float(celsius), float(time_constant_s))

    def temperature(self, now: float) -> int | None:
        """Present Temperature (°C, 0-255) at ``now`` (s), or None if never heated."""
        if self._state is None:
            return None
        since, celsius, tau = self._state
        excess = (celsius - NOMINAL_TEMPERATURE) * math.exp(-(now - since) / tau)
        return min(max(round(NOMINAL_TEMPERATURE + excess), 0), 255)
