"""The mirror scan's plan, pure (no device I/O): where `gonio align` seeks the
mirror's specular peaks (`ScanSettings`, `nominal_poses`, the incidences a rig reaches,
`for_rig`), the poses of a cross scan about one (`cross_scan`, in rad), how a flown one
sweeps (`fly_sweep`), which peaks can be scanned without a pose outside the rig's limits
or inside a keep-out box (`reachable`, through `Rig.pose_reasons`) and the order they are
visited in (`visiting_order`). `gonio.workflows.align` measures the plan.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from gonio.rig import Rig
from gonio.types import FloatArray
from gonio.workflows import align_fly


@dataclass(frozen=True)
class ScanSettings:
    """Where the mirror's peaks are sought (°) and how finely."""

    incidences_deg: tuple[float, ...] = (20.0, 65.0)
    azimuths_deg: tuple[float, ...] = (0.0, 120.0, 240.0)
    rotations_deg: tuple[float, ...] = (0.0, 120.0, 240.0)
    #: The coarse cross scan: half its width and its step (°).
    coarse_half_deg: float = 4.0
    coarse_step_deg: float = 0.4
    #: The fine cross scan: half its width (°) and its number of points.
    fine_half_deg: float = 0.3
    fine_points: int = 15
    exposure_s: float = 1e-3
    #: A fly scan's stream rate (readings a second) and how far its ramps may run
    #: beyond a scan (°; `gonio.workflows.align_fly`); the fine scan's rate (Hz): its
    #: sweeps are that much slower, so that a timing error δt of the polls or the
    #: stamps moves its readings by v · δt only.
    stream_rate_hz: float = 100.0
    fly_overshoot_deg: float = 0.5
    fine_rate_hz: float = 100.0

    def widened(self, factor: float) -> ScanSettings:
        """These settings with the scans' widths and steps times ``factor``."""
        return dataclasses.replace(
            self,
            coarse_half_deg=self.coarse_half_deg * factor,
            coarse_step_deg=self.coarse_step_deg * factor,
            fine_half_deg=self.fine_half_deg * factor,
        )


#: The settings of ``--check``: a few peaks, at one sample rotation more than the fit's.
CHECK = ScanSettings(
    incidences_deg=(30.0, 55.0), azimuths_deg=(60.0, 180.0), rotations_deg=(0.0, 180.0)
)
#: A peak's location error (°): the fine scan's step over the log-parabola's vertex.
PEAK_SIGMA_DEG = 0.005
#: The joints a cross scan moves, per rig type: the detector across the peak in the
#: plane of incidence, then out of it (the in-plane rig's detector moves in the plane
#: only; tilting the sample moves the reflection out of it).
SCANNED = {
    "arch": ("detector_elevation", "detector_azimuth"),
    "in_plane": ("detector_arm", "sample_tilt"),
}
#: How the readings are taken: stopping at each angle, or streamed while sweeping.
STOP_AND_GO, FLY = "stop_and_go", "fly"
#: The incidences `for_rig` probes: every this many degrees.
PROBE_STEP_DEG = 5.0
#: The widest a scan of a joint is made per degree of arc it sweeps the detector over
#: (`arc_factor`: the azimuth at θo ≥ 10°), and the step of its central difference (rad).
MAX_ARC_FACTOR = 1.0 / math.sin(math.radians(10.0))
ARC_STEP = 1e-6
#: Encoder ticks a fly sweep's stop lies at least past its readings (its ramp, else
#: constant velocity): a bus counts a move arrived within a few ticks of its goal, and
#: the sweep stops polling then.
MARGIN_TICKS = 3


def nominal_poses(rig: Rig, settings: ScanSettings) -> FloatArray:
    """The rig file's specular poses of a mirror (M, A), at every incidence, azimuth and
    stage rotation of ``settings``, those the rig can reach."""
    theta = np.radians(settings.incidences_deg)[:, None]
    phi = np.radians(settings.azimuths_deg)[None, :]
    wi = np.stack(np.broadcast_arrays(
        np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)
    ), axis=-1).reshape(-1, 3)  # fmt: skip
    poses = []
    for rotation in np.radians(settings.rotations_deg):
        c, s = math.cos(rotation), math.sin(rotation)
        turn = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        solution = rig.solve(wi @ turn.T, (wi * (-1.0, -1.0, 1.0)) @ turn.T)
        poses.append(solution.angles[solution.ok])
    return np.concatenate(poses).reshape(-1, len(rig.axes))


def for_rig(rig: Rig, settings: ScanSettings, mode: str = STOP_AND_GO) -> ScanSettings:
    """``settings`` with incidences the rig reaches: as given where at least two of them
    are, or all (every azimuth and stage rotation of theirs scannable, `reachable`), else the
    lowest, the middle and the highest of the incidences every `PROBE_STEP_DEG` it
    reaches so (a point source's rig reaches no incidence beyond its detector's view of
    the spot): peaks over the widest range of incidences it offers."""

    def reached(theta: float) -> bool:
        one = dataclasses.replace(settings, incidences_deg=(theta,))
        centers = nominal_poses(rig, one)
        expected = len(settings.azimuths_deg) * len(settings.rotations_deg)
        return len(centers) == expected and bool(np.all(reachable(rig, centers, one, mode)))

    given = [t for t in settings.incidences_deg if reached(t)]
    if len(given) >= 2 or len(given) == len(settings.incidences_deg):
        return settings
    probed = [t for t in np.arange(PROBE_STEP_DEG, 90.0, PROBE_STEP_DEG) if reached(float(t))]
    if len(probed) < 2:
        return settings  # the scan refuses, or fits what it reaches
    chosen = sorted({probed[0], probed[len(probed) // 2], probed[-1]})
    return dataclasses.replace(settings, incidences_deg=tuple(float(t) for t in chosen))


def offsets(half_deg: float, points: int) -> FloatArray:
    """``points`` evenly spaced offsets over ±``half_deg`` (rad)."""
    return np.radians(np.linspace(-half_deg, half_deg, points))


def coarse_offsets(settings: ScanSettings) -> FloatArray:
    n = 2 * round(settings.coarse_half_deg / settings.coarse_step_deg) + 1
    return offsets(settings.coarse_half_deg, n)


def fine_offsets(settings: ScanSettings) -> FloatArray:
    return offsets(settings.fine_half_deg, settings.fine_points)


def cross_scan(rig: Rig, center: FloatArray, joint: str, steps: FloatArray) -> FloatArray:
    """The poses (K, A) of a scan of ``joint`` by ``steps`` (rad) about ``center`` (A,)."""
    poses = np.repeat(np.asarray(center, dtype=np.float64)[None, :], len(steps), axis=0)
    poses[:, rig.axes.index(joint)] += steps
    return poses


@dataclass(frozen=True)
class FlySweep:
    """How a flown cross scan sweeps: its velocity (rad/s), stream rate (Hz), the
    constant-velocity travel past its readings (rad, `MARGIN_TICKS`) and how far beyond
    the scan its travel reaches (rad, ramps included)."""

    velocity: float
    rate_hz: float
    margin_rad: float
    beyond_rad: float


def arc_factor(rig: Rig, center: FloatArray, joint: str) -> float:
    """How many radians of ``joint`` move the detector's direction by one radian of arc
    at the pose ``center`` (A,): 1 for the elevation, 1/sin θo for the azimuth (a scan
    of it crosses the peak that much slower), at most `MAX_ARC_FACTOR`."""
    step = np.zeros(len(rig.axes))
    step[rig.axes.index(joint)] = ARC_STEP
    center = np.asarray(center, dtype=np.float64)
    moved = rig.forward(center + step)[1] - rig.forward(center - step)[1]
    rate = float(np.linalg.norm(moved)) / (2.0 * ARC_STEP)
    return min(MAX_ARC_FACTOR, 1.0 / max(rate, 1.0 / MAX_ARC_FACTOR))


def fly_sweep(rig: Rig, settings: ScanSettings, joint: str, fine: bool) -> FlySweep:
    """How a flown coarse or ``fine`` cross scan of ``joint`` sweeps
    (`gonio.workflows.align_fly`): its readings spaced as the stop-and-go scan's steps."""
    j = rig.axes.index(joint)
    steps = fine_offsets(settings) if fine else coarse_offsets(settings)
    velocity, rate = align_fly.fly_rate(
        rig, j, float(steps[1] - steps[0]),
        settings.fine_rate_hz if fine else settings.stream_rate_hz, settings.exposure_s,
        math.radians(settings.fly_overshoot_deg),
    )  # fmt: skip
    ramp = align_fly.overshoot(rig, j, velocity, rate, 0.0, 0.0)  # the ramp alone
    margin = max(0.0, MARGIN_TICKS * float(tick_rad(rig)[j]) - ramp)
    beyond = align_fly.overshoot(rig, j, velocity, rate, settings.exposure_s, margin)
    return FlySweep(velocity, rate, margin, beyond)


def reachable(
    rig: Rig, centers: FloatArray, settings: ScanSettings, mode: str = STOP_AND_GO
) -> np.ndarray:
    """Which peaks (M,) can be scanned: every pose of their coarse cross scans, widened
    by the fine scan's half width and, flown, by the sweeps' travel beyond the scans
    (ramps included), is inside the limits and outside the keep-out boxes."""
    ok = np.ones(len(centers), dtype=np.bool_)
    for joint in SCANNED[rig.spec.type]:
        for i, center in enumerate(centers):
            wide = settings.widened(arc_factor(rig, center, joint))
            half = math.radians(wide.coarse_half_deg + wide.fine_half_deg)
            points = 41
            if mode == FLY:
                coarse, fine = (fly_sweep(rig, wide, joint, f).beyond_rad for f in (False, True))
                half = max(half + fine, math.radians(wide.coarse_half_deg) + coarse)
                points = max(points, math.ceil(2.0 * half / align_fly.CHECK_STEP) + 1)
            poses = cross_scan(rig, center, joint, np.linspace(-half, half, points))
            ok[i] &= bool(np.all(rig.pose_reasons(poses)[1]))
    return ok


def tick_rad(rig: Rig) -> FloatArray:
    """Each joint's smallest step (rad, (A,)): a motor tick through its gear (the
    simulated motors quantize so too when a scene asks)."""
    by_name = {a.name: a.resolution_rad for a in rig.bus_axes()}
    return np.array([by_name[name] for name in rig.axes])


def visiting_order(centers: FloatArray) -> np.ndarray:
    """The order (M,) in which to visit the peaks ``centers`` (M, A): equal poses one
    after another (the settings' azimuths and stage rotations reach some poses more
    than once: measured again, not travelled to again), else as given."""
    key = np.round(np.asarray(centers, dtype=np.float64), 9) + 0.0  # -0.0 as 0.0
    _, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    return np.argsort(first[np.ravel(inverse)], kind="stable")
