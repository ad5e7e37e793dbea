"""A mirror scan's cross scans flown (`gonio align` where the detector streams): the
scanned joint sweeps at constant velocity across the peak while the detector streams
readings, instead of stopping at each angle.

One cross scan is one sweep of a fly plan (`gonio.planner.model.Sweeps`, one row): the
planning is pure (`fly_velocity`, `overshoot`, `line_sweep`), the device I/O is the fly
acquisition's own (`gonio.acquire.fly.run_sweep`: settle once at the start, start the
stream, sweep, poll the positions and read the stream until arrived, stop the stream) and
so is the merge (`gonio.acquire.fly.derive`: each reading inside the constant-velocity
part gets the joint angles interpolated from the stamped polls at its window's middle).

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
from gonio.acquire.fly import Derived, derive, run_sweep
from gonio.errors import GonioError
from gonio.planner.blur import blur_budget_of_width
from gonio.planner.model import Sweeps
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
    """A flown cross scan's matched readings: the joint angles at each window's middle
    (K, A) rad, the values, saturated flags and windows (K,) (the clock's s), the pose
    the sweep was sent to (A,)."""

    angles: FloatArray
    values: FloatArray
    saturated: np.ndarray
    started_s: FloatArray
    ended_s: FloatArray
    target: FloatArray


def fly_line(devices: Devices, rig: Rig, sweeps: Sweeps, sample: int) -> FlyLine:
    """Fly the one sweep of ``sweeps`` on the opened ``devices`` (``sample``: the
    simulated backend's random streams) and merge its readings; `GonioError` before
    anything moves when its travel leaves the rig's limits or enters a keep-out box."""
    j = int(np.argmax(np.abs(sweeps.velocity[0])))
    lo, hi = float(sweeps.start[0, j]), float(sweeps.stop[0, j])
    grid = np.linspace(lo, hi, max(2, math.ceil(abs(hi - lo) / CHECK_STEP) + 1))
    travel = np.repeat(sweeps.start[:1], len(grid), axis=0)
    travel[:, j] = grid
    if not np.all(rig.pose_reasons(travel)[1]):  # never command outside the rig's limits
        raise GonioError(f"align: a sweep of {rig.axes[j]} leaves the rig's limits; nothing moved")
    if devices.simulation is not None:
        devices.simulation.begin_sample(sample)
    raw = run_sweep(
        devices, rig.axes, sweeps, 0, settle_s=rig.spec.settle_s, timeout_s=SWEEP_TIMEOUT_S
    )
    arrival = sweeps.cruise_at_s[0] + sweeps.period_s * np.arange(int(sweeps.count[0]))
    derived = derive(raw, rig.axes, sweeps, arrival, 0)
    matched = derived.matched
    angles = matched.angles.copy()
    middle = 0.5 * (derived.started + derived.ended)[matched.index]
    angles[:, j] = cruise_line(derived, sweeps, j, middle, angles[:, j])
    kept = [raw.readings[i] for i in matched.index.tolist()]
    return FlyLine(
        angles=angles,
        values=np.array([r.value for r in kept], dtype=np.float64),
        saturated=np.array([r.saturated for r in kept], dtype=np.bool_),
        started_s=np.array([r.started_s for r in kept], dtype=np.float64),
        ended_s=np.array([r.ended_s for r in kept], dtype=np.float64),
        target=np.asarray(sweeps.stop[0], dtype=np.float64),
    )


def cruise_line(
    derived: Derived, sweeps: Sweeps, j: int, times: FloatArray, interpolated: FloatArray
) -> FloatArray:
    """The swept joint ``j``'s angle (rad) at ``times`` (s) on the least-squares line
    through the polls of the constant-velocity part (position on their mid-times): an
    encoder reads its ticks, and interpolating two polls keeps their rounding (up to
    half a tick) where the line through a sweep's many averages it out. Where fewer than
    three polls cruised, the ``interpolated`` angles as they are."""
    t = 0.5 * (derived.request + derived.reply)
    x = derived.positions[:, j]
    lo, hi = sorted((float(sweeps.entry[0, j]), float(sweeps.exit[0, j])))
    cruising = (x >= lo) & (x <= hi)
    if np.count_nonzero(cruising) < 3 or np.ptp(t[cruising]) <= 0:
        return interpolated
    t0 = float(np.mean(t[cruising]))
    slope, intercept = np.polyfit(t[cruising] - t0, x[cruising], 1)
    return np.asarray(intercept + slope * (times - t0), dtype=np.float64)


__all__ = [
    "FlyLine", "cruise_line", "fly_line", "fly_rate", "line_sweep", "overshoot", "peak_width_rad",
]  # fmt: skip
