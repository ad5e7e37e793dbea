"""The mirror scan of `gonio align`: a first-surface mirror seated as the sample is
measured through the device contract (move the motors, read the detector), so the same
code runs on the simulator, the rehearsal and the hardware; the detector's specular
peaks are located by cross scans and fitted (`gonio.rig.alignment_fit`).

The scan's planning is pure (`nominal_poses`, `cross_scan`, `predicted_peaks`, the
verdict of a check); its device I/O is `measure_line` and `scan`. A pose outside the
rig's limits or inside a keep-out box is never commanded: the rig's own pose check
(`Rig.pose_reasons`) drops a peak whose scan would reach one.

Each peak is found by a coarse cross scan (detector elevation, then azimuth) about the
rig file's specular pose, then a fine one about the coarse peak. Every reading (pose
commanded and read back, value, time) is kept in `Readings`, written beside the
alignment file as a small SQLite table (`write_readings`): the acquisition engine takes
plans of direction pairs, not explicit joint-space scans, so the scan is not a run.
"""

from __future__ import annotations

import math
import sqlite3
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from drivers.devices import Devices
from gonio.acquire import measure_target
from gonio.errors import GonioError
from gonio.rig import Rig
from gonio.rig.alignment_fit import as_alignment, miss, peak_at, stated_covariance, vector
from gonio.types import FloatArray
from gonio.workflows import backends
from gonio.workflows.backends import BackendKind
from sim.scene import Scene


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


#: The settings of ``--check``: a few peaks, at one sample rotation more than the fit's.
CHECK = ScanSettings(
    incidences_deg=(30.0, 55.0), azimuths_deg=(60.0, 180.0), rotations_deg=(0.0, 180.0)
)
#: A peak's location error (°): the fine scan's step over the log-parabola's vertex.
PEAK_SIGMA_DEG = 0.005
#: The joints a cross scan moves.
SCANNED = ("detector_elevation", "detector_azimuth")


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


def reachable(rig: Rig, centers: FloatArray, settings: ScanSettings) -> np.ndarray:
    """Which peaks (M,) can be scanned: every pose of their coarse cross scans is inside
    the limits and outside the keep-out boxes (the fine scans lie within them)."""
    half = math.radians(settings.coarse_half_deg + settings.fine_half_deg)
    ok = np.ones(len(centers), dtype=np.bool_)
    for joint in SCANNED:
        for i, center in enumerate(centers):
            poses = cross_scan(rig, center, joint, np.linspace(-half, half, 41))
            ok[i] &= bool(np.all(rig.pose_reasons(poses)[1]))
    return ok


@dataclass
class Readings:
    """Every reading of a scan, in order: the peak and the joint scanned, the commanded
    and read-back poses (rad), the value and when its exposure ended (s)."""

    axes: tuple[str, ...]
    peak: list[int] = field(default_factory=list)
    joint: list[str] = field(default_factory=list)
    commanded: list[list[float]] = field(default_factory=list)
    read_back: list[list[float]] = field(default_factory=list)
    value: list[float] = field(default_factory=list)
    ended_s: list[float] = field(default_factory=list)
    saturated: list[bool] = field(default_factory=list)


def measure_line(
    devices: Devices,
    rig: Rig,
    poses: FloatArray,
    exposure_s: float,
    readings: Readings,
    peak: int,
    joint: str,
) -> FloatArray:
    """Move to each pose (K, A) in turn, settle, read the detector (stop and go, through
    the device contract); the values (K,), each reading kept in ``readings``."""
    if not np.all(rig.pose_reasons(poses)[1]):  # never command outside the rig's limits
        raise GonioError(f"align: a scan of {joint} leaves the rig's limits; nothing moved")
    values = np.empty(len(poses))
    for k, pose in enumerate(poses):
        target = dict(zip(rig.axes, pose.tolist(), strict=True))
        got = measure_target(
            devices, len(readings.value), target, exposure_s, 1, settle_s=rig.spec.settle_s
        )
        values[k] = got.reading.value
        readings.peak.append(peak)
        readings.joint.append(joint)
        readings.commanded.append(pose.tolist())
        readings.read_back.append([got.read_back[a] for a in rig.axes])
        readings.value.append(float(got.reading.value))
        readings.ended_s.append(float(got.reading.ended_s))
        readings.saturated.append(bool(got.reading.saturated))
    if any(readings.saturated[-len(poses) :]):
        raise GonioError(
            f"align: the mirror saturates the detector at {exposure_s:g} s; give a shorter "
            "--exposure"
        )
    return values


def locate(
    devices: Devices,
    rig: Rig,
    center: FloatArray,
    settings: ScanSettings,
    readings: Readings,
    peak: int,
) -> FloatArray:
    """The pose (A,) of the mirror's peak near ``center``, as the motors read it back:
    a coarse cross scan, then a fine one (elevation, then azimuth, each about the
    other's latest peak), the fine step at least one tick of the scanned motor; the
    peak located in the read-back angles (a motor stands on its ticks, not where it was
    asked), the joints not scanned where they were read."""
    found = np.asarray(center, dtype=np.float64).copy()
    ticks = tick_rad(rig)
    for steps in (coarse_offsets(settings), fine_offsets(settings)):
        for joint in SCANNED:
            j = rig.axes.index(joint)
            if len(steps) > 1 and steps[1] - steps[0] < ticks[j]:
                half = steps[-1]
                steps = np.arange(-half, half + 0.5 * ticks[j], ticks[j])
            start = len(readings.value)
            poses = cross_scan(rig, found, joint, steps)
            values = measure_line(devices, rig, poses, settings.exposure_s, readings, peak, joint)
            read = np.asarray(readings.read_back[start:], dtype=np.float64)
            still = [i for i, name in enumerate(rig.axes) if name not in SCANNED]
            found[still] = np.median(read[:, still], axis=0)  # where the others stood
            found[j] = peak_at(read[:, j], values)  # the scanned ones keep their estimates
    return found


def tick_rad(rig: Rig) -> FloatArray:
    """Each joint's smallest step (rad, (A,)): a motor tick through its gear (the
    simulated motors quantize so too when a scene asks)."""
    by_name = {a.name: a.resolution_rad for a in rig.bus_axes()}
    return np.array([by_name[name] for name in rig.axes])


@dataclass(frozen=True)
class Scan:
    """A mirror scan: the peaks' poses (M, A), the readings, the instrument time (s)."""

    peaks: FloatArray
    readings: Readings
    seconds: float


def scan(devices: Devices, rig: Rig, settings: ScanSettings) -> Scan:
    """Locate the mirror's peaks at the reachable nominal poses of ``settings`` with the
    opened ``devices``; `GonioError` if none is reachable."""
    centers = nominal_poses(rig, settings)
    centers = centers[reachable(rig, centers, settings)]
    if not len(centers):
        raise GonioError("align: no mirror pose of the scan is within the rig's limits")
    readings = Readings(rig.axes)
    if devices.light is not None:
        devices.light.on()
    start = devices.clock.now()
    peaks = np.stack(
        [locate(devices, rig, c, settings, readings, i) for i, c in enumerate(centers)]
    )
    return Scan(peaks, readings, devices.clock.now() - start)


def run_scan(
    rig: Rig,
    scene: Scene | None,
    kind: BackendKind,
    settings: ScanSettings,
    *,
    seed: int | None = None,
    speedup: float = 50.0,
) -> Scan:
    """A mirror scan on the backend ``kind`` built from the rig file (the ``scene``
    where the detector is simulated), its devices opened and closed here."""
    backend = backends.build(kind, rig, scene, seed, time.time(), speedup=speedup)
    try:
        with backend.devices:
            return scan(backend.devices, rig, settings)
    finally:
        backend.close()


def write_readings(path: Path, readings: Readings) -> None:
    """The readings as a SQLite table ``reading`` (one row each; angles in rad, one
    column per axis commanded and read back) at ``path`` (a new file)."""
    axes = readings.axes
    columns = [f'"commanded_{a}" REAL, "read_{a}" REAL' for a in axes]
    with sqlite3.connect(path) as db:
        db.execute(
            "CREATE TABLE reading (i INTEGER PRIMARY KEY, peak INTEGER, joint TEXT, "
            f"{', '.join(columns)}, value REAL, ended_s REAL, saturated INTEGER)"
        )
        rows = [
            (i, readings.peak[i], readings.joint[i],
             *(v for pair in zip(readings.commanded[i], readings.read_back[i], strict=True)
               for v in pair),
             readings.value[i], readings.ended_s[i], int(readings.saturated[i]))
            for i in range(len(readings.value))
        ]  # fmt: skip
        marks = ", ".join("?" * (6 + 2 * len(axes)))
        db.executemany(f"INSERT INTO reading VALUES ({marks})", rows)
    db.close()


@dataclass(frozen=True)
class Verdict:
    """A check of an alignment: each peak's miss under it (rad, (M, 2)), its allowed
    bound (rad, (M, 2), three standard errors) and whether every miss is within."""

    misses_rad: FloatArray
    bounds_rad: FloatArray

    @property
    def holds(self) -> bool:
        return bool(np.all(np.abs(self.misses_rad) <= self.bounds_rad))

    def rows_deg(self) -> list[tuple[tuple[float, float], tuple[float, float]]]:
        """Each peak's |miss| and bound (°, two components each)."""
        misses, bounds = np.degrees(np.abs(self.misses_rad)), np.degrees(self.bounds_rad)
        return [
            ((m[0], m[1]), (b[0], b[1]))
            for m, b in zip(misses.tolist(), bounds.tolist(), strict=True)
        ]


def verdict(rig: Rig, peaks: FloatArray) -> Verdict:
    """Whether the peaks (M, A) agree with the rig's alignment: each miss within three
    times the peak's location error combined with the alignment's propagated error (the
    covariance its file states, `gonio.rig.alignment_fit.stated_covariance`, carried by
    central differences over each stated parameter's standard error)."""
    values, covariance = vector(rig, rig.alignment), stated_covariance(rig)
    misses = miss(rig, peaks, as_alignment(rig, values))
    errors = np.sqrt(np.diag(covariance))
    stated = np.flatnonzero(errors > 0)
    columns = []
    for i in stated:
        step = np.zeros_like(values)
        step[i] = errors[i]
        up = miss(rig, peaks, as_alignment(rig, values + step))
        down = miss(rig, peaks, as_alignment(rig, values - step))
        columns.append((up - down) / (2.0 * errors[i]))
    variance = np.full(misses.shape, math.radians(PEAK_SIGMA_DEG) ** 2)
    if columns:
        jac = np.stack(columns, axis=-1)  # (M, 2, S) per unit of each stated parameter
        block = covariance[np.ix_(stated, stated)]
        variance += np.einsum("mis,st,mit->mi", jac, block, jac)
    return Verdict(misses, 3.0 * np.sqrt(variance))


__all__ = [
    "CHECK", "PEAK_SIGMA_DEG", "Readings", "Scan", "ScanSettings", "Verdict", "cross_scan",
    "measure_line", "nominal_poses", "reachable", "run_scan", "scan",
    "verdict", "write_readings",
]  # fmt: skip
