"""A mirror scan's cross scans flown (`gonio align` where the detector streams): the
scanned joint sweeps at constant velocity across the peak while the detector streams
readings, instead of stopping at each angle.

One cross scan is one sweep of a fly plan (`gonio.planner.model.Sweeps`, one row): the
planning is pure (`fly_velocity`, `overshoot`, `line_sweep`), the device I/O is the fly
acquisition's own (`gonio.acquire.fly.run_sweep`: settle once at the start, start the
stream, sweep, poll the positions and read the stream until arrived, stop the stream).
Each reading whose window lies inside the constant-velocity part gets the swept joint's
angle at its window's middle on the line the polls allow at the velocity the bus
commanded (`cruise_line`: an encoder's whole ticks polled at uneven times, located to a
fraction of a tick), the other joints' interpolated from the polls; no reading needs
polls about it, so a host that stalls between polls loses none (`fly_line`).

The readings are spaced as the stop-and-go scan spaces its steps. The velocity is the
slowest of: the joint's configured velocity; the blur budget of the narrowest peak the
detector can see over the integration (`gonio.planner.blur.blur_budget_of_width` of the
aperture's angular diameter, a perfect mirror's peak); the one whose deceleration ramp
stops within ``fly_overshoot_deg`` beyond the scan (v = √(2 a d)). The stream's rate is
the velocity over the spacing, in whole Hz, at most ``stream_rate_hz`` (the velocity
slowed to it where that caps it). A sweep's whole travel, ramps included, is checked
against the rig's limits and keep-out boxes before anything moves.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from drivers.devices import Devices
from gonio.acquire import poll_arrays, run_sweep
from gonio.errors import GonioError
from gonio.planner import Sweeps, blur_budget_of_width
from gonio.rig import Rig
from gonio.types import FloatArray

#: How long one sweep (its move to the start included) may take before the bus gives up (s).
SWEEP_TIMEOUT_S = 60.0
#: The grid step (rad) on which a sweep's travel is checked against the rig's limits.
CHECK_STEP = math.radians(0.05)


def peak_width_rad(rig: Rig) -> float:
    """The narrowest mirror peak the detector can see (rad): its aperture's angular
    diameter, 2 √(Ω / π) (a flat mirror and a collimated beam give no wider one)."""
    return 2.0 * math.sqrt(rig.spec.detector.aperture_sr / math.pi)


def fly_rate(
    rig: Rig, j: int, spacing_rad: float, max_rate_hz: float, integration_s: float,
    overshoot_rad: float,
) -> tuple[float, float]:  # fmt: skip
    """(velocity rad/s, stream rate Hz) of a sweep of joint ``j`` reading every
    ``spacing_rad``, each reading integrating ``integration_s``, its ramps stopping
    within ``overshoot_rad`` beyond the scan, at no more than ``max_rate_hz`` (a whole
    number of Hz): the fastest velocity the module docstring allows, then the rate that
    spaces the readings so, and the velocity slowed to it where the rate is capped."""
    budget = math.radians(blur_budget_of_width(math.degrees(peak_width_rad(rig))))
    velocity = min(
        float(rig.velocity[j]),
        budget / integration_s,
        math.sqrt(2.0 * float(rig.acceleration[j]) * overshoot_rad),
    )
    rate = float(max(1, math.floor(min(max_rate_hz, velocity / spacing_rad) + 1e-9)))
    return rate * spacing_rad, rate


def overshoot(
    rig: Rig, j: int, velocity: float, rate_hz: float, integration_s: float, margin_rad: float
) -> float:
    """How far (rad) a sweep of joint ``j`` at ``velocity`` runs beyond the readings'
    middles at each end: its constant-velocity slack (`line_sweep`) and its ramp."""
    return _slack(velocity, rate_hz, integration_s, margin_rad) + float(_ramp(rig, j, velocity))


def _slack(velocity: float, rate_hz: float, integration_s: float, margin_rad: float) -> float:
    """The constant-velocity travel (rad) beyond the readings' middles at each end: half
    a window, one period (the stream's phase is the device's) and ``margin_rad``."""
    return velocity * (0.5 * integration_s + 1.0 / rate_hz) + margin_rad


def _ramp(rig: Rig, j: int, velocity: float) -> float:
    """The distance (rad) joint ``j`` ramps over to ``velocity`` (or from it to rest)."""
    v = np.zeros(len(rig.axes))
    v[j] = velocity
    return float(rig.travel.ramp(v)[1][j])


def line_sweep(
    rig: Rig, center: FloatArray, j: int, half_rad: float, velocity: float, rate_hz: float,
    integration_s: float, margin_rad: float, *, backward: bool = False,
) -> Sweeps:  # fmt: skip
    """One sweep (a one-row `Sweeps`) of joint ``j`` at ``velocity`` (rad/s) about
    ``center`` (A,) whose readings' middles cover ±``half_rad`` (``backward``: from + to
    −), the stream at ``rate_hz`` integrating ``integration_s``, at constant velocity
    ``margin_rad`` further at each end (a bus counts a move arrived within a few ticks of
    its goal: the readings end before that), every slot a target."""
    period = 1.0 / rate_hz
    reach = half_rad + _slack(velocity, rate_hz, integration_s, margin_rad)
    n = math.floor((2.0 * reach - velocity * integration_s) / (velocity * period) + 1e-9) + 1
    ramp = _ramp(rig, j, velocity)
    offsets = np.array([-reach - ramp, -reach, reach, reach + ramp])
    poses = np.repeat(np.asarray(center, dtype=np.float64)[None, :], 4, axis=0)
    poses[:, j] += (-1.0 if backward else 1.0) * offsets
    v = np.zeros(len(rig.axes))
    v[j] = -velocity if backward else velocity
    return Sweeps(
        start=poses[:1], entry=poses[1:2], exit=poses[2:3], stop=poses[3:],
        velocity=v[None, :], first=np.zeros(1, np.int64), count=np.full(1, n),
        cruise_at_s=np.zeros(1), streamed=np.full(1, n), period_s=period,
        integration_s=integration_s,
    )  # fmt: skip


@dataclass(frozen=True)
class FlyLine:
    """A flown cross scan's readings inside its constant-velocity part: the joint angles
    at each window's middle (K, A) rad, the values, saturated flags and windows (K,)
    (the clock's s), the pose the sweep was sent to (A,)."""

    angles: FloatArray
    values: FloatArray
    saturated: np.ndarray
    started_s: FloatArray
    ended_s: FloatArray
    target: FloatArray

    def covers(self, j: int, lo: float, hi: float, spacing: float) -> bool:
        """Whether joint ``j``'s angles of the readings cover [``lo``, ``hi``] (rad) with
        no gap wider than 1.5 ``spacing`` (rad) and reach within one of each end: no
        reading the scan needs was lost."""
        x = np.sort(self.angles[:, j])
        x = x[(x >= lo - spacing) & (x <= hi + spacing)]
        if len(x) < 2:
            return False
        gaps_ok = bool(np.all(np.diff(x) <= 1.5 * spacing))
        return gaps_ok and x[0] <= lo + spacing and x[-1] >= hi - spacing


@dataclass(frozen=True)
class CruiseLine:
    """The swept joint's angle on a sweep's constant-velocity part: ``intercept`` (rad)
    at ``t0`` (s, the clock's) plus ``slope`` (rad/s) per second; from ``points`` points
    spanning ``span_s`` (s); ``fitted``: the slope too (else the velocity commanded)."""

    t0: float
    slope: float
    intercept: float
    points: int
    span_s: float
    fitted: bool = True

    def placed(self, cruise_s: float) -> bool:
        """Whether the line places the readings of a constant-velocity part ``cruise_s``
        (s) long: three points at least, over half of it where the slope was fitted."""
        return self.points >= 3 and (not self.fitted or self.span_s >= 0.5 * cruise_s)

    def at(self, times: FloatArray) -> FloatArray:
        """The angle (rad) at ``times`` (s)."""
        return np.asarray(self.intercept + self.slope * (times - self.t0), dtype=np.float64)


def fly_line(devices: Devices, rig: Rig, sweeps: Sweeps, sample: int) -> FlyLine:
    """Fly the one sweep of ``sweeps`` on the opened ``devices`` (``sample``: the
    simulated backend's random streams) and place its readings; `GonioError` before
    anything moves when its travel leaves the rig's limits or enters a keep-out box.

    The swept joint's angle at each window's middle is on the line through the polls of
    the constant-velocity part (`cruise_line`), the other joints' interpolated from the
    polls; only the windows that lie wholly inside that part (on the line) are kept. No
    reading needs polls about it: a host that stalls between two polls loses none,
    while the polls determine the line (else none is kept: `CruiseLine.placed`)."""
    j = int(np.argmax(np.abs(sweeps.velocity[0])))
    first, last = float(sweeps.start[0, j]), float(sweeps.stop[0, j])
    grid = np.linspace(first, last, max(2, math.ceil(abs(last - first) / CHECK_STEP) + 1))
    travel = np.repeat(sweeps.start[:1], len(grid), axis=0)
    travel[:, j] = grid
    if not np.all(rig.pose_reasons(travel)[1]):  # never command outside the rig's limits
        raise GonioError(f"align: a sweep of {rig.axes[j]} leaves the rig's limits; nothing moved")
    if devices.simulation is not None:
        devices.simulation.begin_sample(sample)
    raw = run_sweep(
        devices, rig.axes, sweeps, 0, settle_s=rig.spec.settle_s, timeout_s=SWEEP_TIMEOUT_S
    )
    request, reply, positions = poll_arrays(raw.polls, rig.axes)
    started = np.array([r.started_s for r in raw.readings], dtype=np.float64)
    ended = np.array([r.ended_s for r in raw.readings], dtype=np.float64)
    lo, hi = sorted((float(sweeps.entry[0, j]), float(sweeps.exit[0, j])))
    tick = {a.name: a.resolution_rad for a in rig.bus_axes()}.get(rig.axes[j], 0.0)
    commanded = (raw.velocities or {}).get(rig.axes[j])
    velocity = None if commanded is None else math.copysign(commanded, sweeps.velocity[0, j])
    line = cruise_line(request, reply, positions[:, j], lo, hi, tick, velocity)
    cruise_s = (hi - lo) / abs(float(sweeps.velocity[0, j]))
    if line is None or not line.placed(cruise_s):
        keep = np.zeros(len(ended), dtype=np.bool_)
    else:
        a, b = line.at(started), line.at(ended)
        keep = (np.minimum(a, b) >= lo) & (np.maximum(a, b) <= hi)
    middle = 0.5 * (started + ended)[keep]
    t = 0.5 * (request + reply)
    order = np.argsort(t, kind="stable")
    angles = np.stack(
        [np.interp(middle, t[order], positions[order, i]) for i in range(len(rig.axes))], axis=1
    ).reshape(len(middle), len(rig.axes))
    if line is not None:
        angles[:, j] = line.at(middle)
    kept = [r for r, k in zip(raw.readings, keep.tolist(), strict=True) if k]
    return FlyLine(
        angles=angles,
        values=np.array([r.value for r in kept], dtype=np.float64),
        saturated=np.array([r.saturated for r in kept], dtype=np.bool_),
        started_s=started[keep],
        ended_s=ended[keep],
        target=np.asarray(sweeps.stop[0], dtype=np.float64),
    )


def cruise_line(
    request: FloatArray, reply: FloatArray, x: FloatArray, lo: float, hi: float,
    tick_rad: float = 0.0, velocity: float | None = None,
) -> CruiseLine | None:  # fmt: skip
    """The line through a sweep's polls (request, reply (P,) s; the swept joint's angles
    ``x`` (P,) rad) of its constant-velocity part (``x`` within [``lo``, ``hi``], a tick
    in from each end): an encoder reads whole ticks (``tick_rad``), and interpolating two
    polls keeps their rounding (up to half a tick) where a line through the sweep's
    polls averages it out. Where the polls read a grid of ticks: with the ``velocity``
    commanded (rad/s), the line at it through the middle of the angles every poll allows
    (`consistent_intercept`), else the least-squares line through the changes of reading
    (`tick_changes`); else the least-squares line through the polls (on their
    mid-times). None with fewer than two points."""
    edge = tick_rad if tick_rad > 0 else 0.0
    cruising = (x >= lo + edge) & (x <= hi - edge)
    request, reply, x = request[cruising], reply[cruising], x[cruising]
    order = np.argsort(0.5 * (request + reply), kind="stable")
    request, reply, x = request[order], reply[order], x[order]
    t, weight = 0.5 * (request + reply), np.ones(len(x))
    if tick_rad > 0 and len(x) and on_grid(x, tick_rad):
        if velocity is not None and len(x) >= 3:
            t0 = float(np.mean(t))
            b = consistent_intercept(request - t0, reply - t0, x, tick_rad, velocity)
            if b is not None:
                return CruiseLine(t0, velocity, b, len(x), float(np.ptp(t)), fitted=False)
        t, x, weight = tick_changes(request, reply, x)
    if len(t) < 2 or np.ptp(t) <= 0:
        return None
    t0 = float(np.mean(t))
    slope, intercept = np.polyfit(t - t0, x, 1, w=weight)
    return CruiseLine(t0, float(slope), float(intercept), len(t), float(np.ptp(t)))


def consistent_intercept(
    request: FloatArray, reply: FloatArray, x: FloatArray, tick_rad: float, velocity: float
) -> float | None:
    """The angle (rad) at time 0 of a line at ``velocity`` (rad/s) that reads ``x``
    (P,) rad, each rounded to the nearest tick (``tick_rad``), at some instant of each
    poll's span (request, reply (P,) s): the middle of the angles every poll allows;
    None when none is (the motion was not at that velocity)."""
    early = np.minimum(velocity * request, velocity * reply)
    late = np.maximum(velocity * request, velocity * reply)
    low = float(np.max(x - 0.5 * tick_rad - late))
    high = float(np.min(x + 0.5 * tick_rad - early))
    return 0.5 * (low + high) if low <= high else None


def on_grid(x: FloatArray, tick_rad: float) -> bool:
    """Whether the positions ``x`` (rad) all stand on one grid of ``tick_rad``."""
    steps = (x - x[0]) / tick_rad
    return bool(np.all(np.abs(steps - np.rint(steps)) < 1e-6))


def tick_changes(
    request: FloatArray, reply: FloatArray, x: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Where a ticking encoder's reading changes between consecutive polls (request,
    reply (P,) s, in time order; readings ``x`` (P,) rad): the midway angle between the
    two readings at the middle of the span from the earlier poll's request to the later
    one's reply (the change happened in it), and a weight 1 / that span (s⁻¹; a stalled
    poll loop brackets a change loosely)."""
    change = np.flatnonzero(x[1:] != x[:-1])
    span = np.maximum(reply[change + 1] - request[change], 1e-9)
    middle = 0.5 * (request[change] + reply[change + 1])
    return middle, 0.5 * (x[change] + x[change + 1]), 1.0 / span


__all__ = [
    "CruiseLine", "FlyLine", "consistent_intercept", "cruise_line", "fly_line", "fly_rate",
    "line_sweep", "on_grid", "overshoot", "peak_width_rad", "tick_changes",
]  # fmt: skip
