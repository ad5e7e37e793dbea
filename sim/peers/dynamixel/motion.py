"""Closed-form motion profiles of an X-series motor (ticks and seconds).

A profile is a chain of constant-acceleration segments, so position and velocity at
any time are exact (no integration drift). Position moves follow the velocity-based
profile of the e-manual: with maximum velocity V (ticks/s) and acceleration A
(ticks/s²) a move of distance D from rest takes

* triangular (peak √(A·D) ≤ V):  T = 2·√(D/A), peak velocity √(A·D);
* trapezoidal (otherwise):       T = D/V + V/A, accelerating for t₁ = V/A;
* rectangular (A = ∞):           T = D/V;
* step (V = ∞ and A = ∞):        T = 0.

A new goal during a move keeps the present velocity ("velocity override"): the motor
first brakes if it moves away from the goal or cannot stop before it, then runs the
profile above starting from its present velocity. Jerk limiting is not modelled.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import IntEnum

from drivers.dynamixel import TICKS_PER_REV

#: One Profile/Present Velocity unit (0.229 rev/min) in ticks/s.
TICKS_PER_S_PER_VELOCITY_UNIT = 0.229 * TICKS_PER_REV / 60.0
#: One Profile Acceleration unit (214.577 rev/min²) in ticks/s².
TICKS_PER_S2_PER_ACCELERATION_UNIT = 214.577 * TICKS_PER_REV / 3600.0

INF = math.inf


class ProfileType(IntEnum):
    """Bits 4-5 of Moving Status: the kind of velocity profile of the last goal."""

    STEP = 0x00
    RECTANGULAR = 0x10
    TRIANGULAR = 0x20
    TRAPEZOIDAL = 0x30


@dataclass(frozen=True)
class Segment:
    """Constant acceleration from ``start`` (s, since the profile began) for ``duration`` s."""

    start: float
    duration: float
    position: float  # ticks at ``start``
    velocity: float  # ticks/s at ``start``
    acceleration: float  # ticks/s²

    def at(self, tau: float) -> tuple[float, float]:
        """Position (ticks) and velocity (ticks/s) ``tau`` seconds into the segment."""
        a = self.acceleration
        return (
            self.position + self.velocity * tau + 0.5 * a * tau * tau,
            self.velocity + a * tau,
        )


@dataclass(frozen=True)
class Trajectory:
    """Where the motor is at each time after the profile started.

    ``target`` is where a position profile ends at rest; an endless trajectory (velocity
    mode) keeps its last segment forever.
    """

    segments: tuple[Segment, ...]
    target: float
    kind: ProfileType = ProfileType.STEP
    endless: bool = False

    @property
    def duration(self) -> float:
        """Seconds until the motor is at rest on ``target`` (∞ for an endless one)."""
        if self.endless:
            return INF
        last = self.segments[-1] if self.segments else None
        return last.start + last.duration if last else 0.0

    def running(self, t: float) -> bool:
        """True while the profile is in progress ``t`` seconds after it started."""
        return t < self.duration

    def at(self, t: float) -> tuple[float, float]:
        """Position (ticks) and velocity (ticks/s) ``t`` seconds after the start."""
        if not self.segments:
            return self.target, 0.0
        if not self.endless and t >= self.duration:
            return self.target, 0.0
        t = max(t, 0.0)
        for index, seg in enumerate(self.segments):
            if t < seg.start + seg.duration or index == len(self.segments) - 1:
                position, velocity = seg.at(t - seg.start)
                if not self.endless and index == len(self.segments) - 1:
                    position = _not_past(position, seg.position, self.target)
                return position, velocity
        raise AssertionError("unreachable")  # pragma: no cover


def _not_past(position: float, start: float, target: float) -> float:
    """Clamp rounding so the last segment never passes its target."""
    if start <= target:
        return min(position, target)
    return max(position, target)


def at_rest(position: float) -> Trajectory:
    """A motor holding ``position`` (ticks)."""
    return Trajectory((), float(position))


def classify(distance: float, v_max: float, a_max: float) -> ProfileType:
    """The e-manual's profile type for a move of ``distance`` ticks from rest."""
    if math.isinf(a_max):
        return ProfileType.STEP if math.isinf(v_max) else ProfileType.RECTANGULAR
    if math.sqrt(a_max * abs(distance)) <= v_max:
        return ProfileType.TRIANGULAR
    return ProfileType.TRAPEZOIDAL


def travel_time(distance: float, v_max: float, a_max: float) -> float:
    """Seconds to move ``distance`` ticks from rest to rest (v_max, a_max may be ∞)."""
    d = abs(distance)
    if d == 0 or (math.isinf(v_max) and math.isinf(a_max)):
        return 0.0
    if math.isinf(a_max):
        return d / v_max
    if math.sqrt(a_max * d) <= v_max:
        return 2.0 * math.sqrt(d / a_max)
    return d / v_max + v_max / a_max


class _Builder:
    """Appends constant-acceleration segments and tracks the state at their end."""

    def __init__(self, position: float, velocity: float) -> None:
        self.t = 0.0
        self.p = float(position)
        self.v = float(velocity)
        self.segments: list[Segment] = []

    def push(self, duration: float, acceleration: float, *, velocity: float | None = None) -> None:
        if velocity is not None:
            self.v = velocity
        if duration <= 0:
            return
        seg = Segment(self.t, duration, self.p, self.v, acceleration)
        self.segments.append(seg)
        self.p, self.v = seg.at(duration)
        self.t += duration


def move(
    position: float,
    velocity: float,
    goal: float,
    v_max: float,
    a_max: float,
    kind: ProfileType | None = None,
) -> Trajectory:
    """A position profile from (``position``, ``velocity``) to rest at ``goal``.

    ``v_max`` (ticks/s) and ``a_max`` (ticks/s²) are > 0 and may be ∞. ``kind`` overrides
    the reported profile type (the default classifies the move as if from rest).
    """
    if not (v_max > 0 and a_max > 0):
        raise ValueError(f"v_max and a_max must be > 0, got {v_max}, {a_max}")
    kind = kind if kind is not None else classify(goal - position, v_max, a_max)
    b = _Builder(position, velocity)
    if math.isinf(a_max):
        if not math.isinf(v_max) and goal != position:
            direction = math.copysign(1.0, goal - position)
            b.push(abs(goal - position) / v_max, 0.0, velocity=direction * v_max)
        return Trajectory(tuple(b.segments), float(goal), kind)

    d = goal - b.p
    # Moving away from the goal, or too fast to stop before it: brake to rest first.
    if b.v != 0 and (d == 0 or b.v * d < 0 or b.v * b.v / (2 * a_max) > abs(d)):
        b.push(abs(b.v) / a_max, -math.copysign(a_max, b.v))
        b.v = 0.0
        d = goal - b.p
    if d != 0:
        s = math.copysign(1.0, d)
        u = b.v * s  # speed toward the goal, ≥ 0 here
        if u > v_max:
            b.push((u - v_max) / a_max, -s * a_max)
            u = v_max
            b.v = s * v_max
        remaining = abs(goal - b.p)
        peak = math.sqrt(a_max * remaining + 0.5 * u * u)
        if peak <= v_max:
            b.push((peak - u) / a_max, s * a_max)
            b.push(peak / a_max, -s * a_max, velocity=s * peak)
        else:
            cruise = remaining - (v_max * v_max - u * u) / (2 * a_max) - v_max * v_max / (2 * a_max)
            b.push((v_max - u) / a_max, s * a_max)
            b.push(max(cruise, 0.0) / v_max, 0.0, velocity=s * v_max)
            b.push(v_max / a_max, -s * a_max, velocity=s * v_max)
    return Trajectory(tuple(b.segments), float(goal), kind)


def move_timed(position: float, goal: float, total_s: float, accel_s: float) -> Trajectory:
    """A time-based profile (Drive Mode bit 2): ``total_s`` for the whole move, of which
    ``accel_s`` (clamped to half of it) accelerating and as much decelerating.

    Starts from rest at ``position``; ``total_s`` = 0 is a step.
    """
    distance = goal - position
    if total_s <= 0 or distance == 0:
        return Trajectory((), float(goal), ProfileType.STEP)
    accel_s = min(max(accel_s, 0.0), total_s / 2)
    b = _Builder(position, 0.0)
    if accel_s == 0:
        b.push(total_s, 0.0, velocity=distance / total_s)
        return Trajectory(tuple(b.segments), float(goal), ProfileType.RECTANGULAR)
    peak = distance / (total_s - accel_s)
    a = peak / accel_s
    b.push(accel_s, a)
    b.push(total_s - 2 * accel_s, 0.0, velocity=peak)
    b.push(accel_s, -a, velocity=peak)
    kind = ProfileType.TRAPEZOIDAL if total_s > 2 * accel_s else ProfileType.TRIANGULAR
    return Trajectory(tuple(b.segments), float(goal), kind)


def spin(position: float, velocity: float, goal_velocity: float, a_max: float) -> Trajectory:
    """Velocity mode: ramp from ``velocity`` to ``goal_velocity`` (ticks/s) at ``a_max``
    (ticks/s², may be ∞), then turn at that velocity forever."""
    b = _Builder(position, velocity)
    if not math.isinf(a_max):
        change = goal_velocity - b.v
        b.push(abs(change) / a_max, math.copysign(a_max, change))
    b.segments.append(Segment(b.t, INF, b.p, float(goal_velocity), 0.0))
    kind = ProfileType.STEP if math.isinf(a_max) else ProfileType.TRAPEZOIDAL
    return Trajectory(tuple(b.segments), math.nan, kind, endless=True)
