"""The mirror scan of `gonio align`: a first-surface mirror seated as the sample is
measured through the device contract (move the motors, read the detector), so the same
code runs on the simulator, the rehearsal and the hardware; the detector's specular
peaks are located by cross scans and fitted (`gonio.rig.alignment_fit`).

The scan's planning is pure (`gonio.workflows.align_plan`: `nominal_poses`,
`cross_scan`, `fly_sweep`, `visiting_order`, re-exported here; a check's verdict is
`gonio.workflows.align_check`'s); this module is its device I/O: `measure_line` (stop
and go), `fly_cross` (flown, `gonio.workflows.align_fly`) and `scan`. A pose outside
the rig's limits or inside a keep-out box is never commanded: the rig's own pose check
(`Rig.pose_reasons`) drops a peak whose scan (a fly sweep's whole travel included)
would reach one.

Each peak is found by a coarse cross scan (detector elevation, then azimuth) about the
rig file's specular pose, then a fine one about the coarse peak; flown where the
detector streams (`scan_mode`; `run_scan` where `fly_allowed`), the fine one both
ways. Every reading (how it was taken, pose commanded and read back, value, window) is
kept in `Readings`, written beside the alignment file as a small SQLite table
(`write_readings`): the acquisition engine takes plans of direction pairs, not explicit
joint-space scans, so the scan is not a run.
"""

from __future__ import annotations

import dataclasses
import math
import sqlite3
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from drivers.devices import Devices
from drivers.stream import can_stream
from gonio.acquire import TargetReading, measure_target
from gonio.errors import GonioError
from gonio.rig import Rig, peak_at
from gonio.scene import Scene
from gonio.types import FloatArray
from gonio.workflows import align_fly, backends
from gonio.workflows.align_plan import (
    CHECK,
    FLY,
    MARGIN_TICKS,
    PEAK_SIGMA_DEG,
    SCANNED,
    STOP_AND_GO,
    FlySweep,
    ScanSettings,
    arc_factor,
    coarse_offsets,
    cross_scan,
    fine_offsets,
    fly_sweep,
    for_rig,
    nominal_poses,
    reachable,
    tick_rad,
    visiting_order,
)
from gonio.workflows.backends import BackendKind

#: The fine fly scan's stream rate (Hz) on the hardware path (the rehearsal, the
#: hardware), where the polls and the stamps are known to a millisecond or so (several
#: on a loaded host): a sweep moves its readings by v · δt, and at 25 Hz the fine sweep
#: moves 1.07°/s (0.001° a millisecond; rehearsed at real speed, one pose's peaks
#: within 0.004° where at 100 Hz they scattered by 0.013°). The simulated clock has no
#: such error: its fine scan streams at `ScanSettings.fine_rate_hz`.
HARDWARE_FINE_RATE_HZ = 25.0
#: The fastest rehearsal (``--speedup``) whose scans `run_scan` flies: real speed. A
#: poll's and a line's real delays count ``speedup`` times on the rehearsal's clock
#: (at 2, one pose's peaks scattered by 0.007°; at 4, sweeps lost their polls three
#: times in a row; at 10⁶ a stream does not stop within its timeout); a faster
#: rehearsal scans stop-and-go.
MAX_FLY_SPEEDUP = 1.0
#: How many times a fly sweep is measured at most: one whose readings leave a gap in
#: its scan (`align_fly.FlyLine.covers`: a host stalled past the polls' or the
#: stream's reading) is measured again.
SWEEP_ATTEMPTS = 3


@dataclass
class Readings:
    """Every reading of a scan, in order: the peak and the joint scanned, how it was
    taken (`STOP_AND_GO` or `FLY`), the commanded and read-back poses (rad; a fly
    reading's: the pose its sweep was sent to and the angles interpolated at its
    window's middle), the value and its window (s)."""

    axes: tuple[str, ...]
    peak: list[int] = field(default_factory=list)
    joint: list[str] = field(default_factory=list)
    mode: list[str] = field(default_factory=list)
    commanded: list[list[float]] = field(default_factory=list)
    read_back: list[list[float]] = field(default_factory=list)
    value: list[float] = field(default_factory=list)
    started_s: list[float] = field(default_factory=list)
    ended_s: list[float] = field(default_factory=list)
    saturated: list[bool] = field(default_factory=list)

    def add(
        self, peak: int, joint: str, mode: str, commanded: FloatArray, read_back: FloatArray,
        value: FloatArray, started_s: FloatArray, ended_s: FloatArray, saturated: np.ndarray,
    ) -> None:  # fmt: skip
        """Keep K readings: poses (K, A) rad, the rest (K,)."""
        k = len(value)
        self.peak += [peak] * k
        self.joint += [joint] * k
        self.mode += [mode] * k
        self.commanded += np.asarray(commanded, dtype=np.float64).reshape(k, -1).tolist()
        self.read_back += np.asarray(read_back, dtype=np.float64).reshape(k, -1).tolist()
        self.value += np.asarray(value, dtype=np.float64).tolist()
        self.started_s += np.asarray(started_s, dtype=np.float64).tolist()
        self.ended_s += np.asarray(ended_s, dtype=np.float64).tolist()
        self.saturated += [bool(x) for x in np.asarray(saturated).tolist()]


def _refuse_saturated(saturated: np.ndarray, exposure_s: float) -> None:
    if np.any(saturated):
        raise GonioError(
            f"align: the mirror saturates the detector at {exposure_s:g} s; give a shorter "
            "--exposure"
        )


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
    got: list[TargetReading] = []
    for pose in poses:
        target = dict(zip(rig.axes, pose.tolist(), strict=True))
        got.append(
            measure_target(
                devices, len(readings.value) + len(got), target, exposure_s, 1,
                settle_s=rig.spec.settle_s,
            )
        )  # fmt: skip
    values = np.array([g.reading.value for g in got], dtype=np.float64)
    saturated = np.array([g.reading.saturated for g in got], dtype=np.bool_)
    readings.add(
        peak, joint, STOP_AND_GO, poses,
        np.array([[g.read_back[a] for a in rig.axes] for g in got], dtype=np.float64),
        values, np.array([g.reading.started_s for g in got], dtype=np.float64),
        np.array([g.reading.ended_s for g in got], dtype=np.float64), saturated,
    )  # fmt: skip
    _refuse_saturated(saturated, exposure_s)
    return values


def fly_cross(
    devices: Devices,
    rig: Rig,
    center: FloatArray,
    joint: str,
    settings: ScanSettings,
    readings: Readings,
    peak: int,
    fine: bool,
) -> tuple[FloatArray, float]:
    """A flown cross scan of ``joint`` about ``center`` (A,): one sweep (coarse), or one
    each way (``fine``: a timing latency shifts a one-way sweep's peak by velocity ×
    latency, and the two ways' mean cancels it); the angles (K, A) of every reading and
    the peak (rad, the mean of each way's), each reading kept in ``readings``."""
    j = rig.axes.index(joint)
    sweep = fly_sweep(rig, settings, joint, fine)
    half = math.radians(settings.fine_half_deg if fine else settings.coarse_half_deg)
    spacing = sweep.velocity / sweep.rate_hz
    angles, peaks = [], []
    for backward in (False, True) if fine else (False,):
        sweeps = align_fly.line_sweep(
            rig, center, j, half, sweep.velocity, sweep.rate_hz, settings.exposure_s,
            sweep.margin_rad, backward=backward,
        )  # fmt: skip
        for _ in range(SWEEP_ATTEMPTS):
            line = align_fly.fly_line(devices, rig, sweeps, len(readings.value))
            if line.covers(j, center[j] - half, center[j] + half, spacing):
                break
        else:
            raise GonioError(
                f"align: {SWEEP_ATTEMPTS} fly sweeps of {joint} in a row lost readings the "
                "scan needs (the polls or the stream stalled); try --stop-and-go"
            )
        target = np.repeat(line.target[None, :], len(line.values), axis=0)
        readings.add(
            peak, joint, FLY, target, line.angles, line.values, line.started_s, line.ended_s,
            line.saturated,
        )  # fmt: skip
        _refuse_saturated(line.saturated, settings.exposure_s)
        angles.append(line.angles)
        peaks.append(peak_at(line.angles[:, j], line.values))
    return np.concatenate(angles), float(np.mean(peaks))


def locate(
    devices: Devices,
    rig: Rig,
    center: FloatArray,
    settings: ScanSettings,
    readings: Readings,
    peak: int,
    mode: str = STOP_AND_GO,
) -> FloatArray:
    """The pose (A,) of the mirror's peak near ``center``, as the motors read it back:
    a coarse cross scan, then a fine one (elevation, then azimuth, each about the
    other's latest peak; each joint's widths and steps the settings' degrees of arc,
    `arc_factor`), the peak located in the read-back angles (a motor stands on
    its ticks, not where it was asked), the joints not scanned where they were read.
    Stop and go, the fine step is at least one tick of the scanned motor; flown
    (`fly_cross`), the readings are spaced as the stop-and-go steps would be."""
    found = np.asarray(center, dtype=np.float64).copy()
    ticks = tick_rad(rig)
    scanned = SCANNED[rig.spec.type]
    still = [i for i, name in enumerate(rig.axes) if name not in scanned]
    wide = {joint: settings.widened(arc_factor(rig, center, joint)) for joint in scanned}
    for fine in (False, True):
        for joint in scanned:
            j = rig.axes.index(joint)
            steps = fine_offsets(wide[joint]) if fine else coarse_offsets(wide[joint])
            if mode == FLY:
                read, found[j] = fly_cross(devices, rig, found, joint, wide[joint], readings,
                                           peak, fine)  # fmt: skip
            else:
                if len(steps) > 1 and steps[1] - steps[0] < ticks[j]:
                    half = steps[-1]
                    steps = np.arange(-half, half + 0.5 * ticks[j], ticks[j])
                start = len(readings.value)
                poses = cross_scan(rig, found, joint, steps)
                values = measure_line(
                    devices, rig, poses, settings.exposure_s, readings, peak, joint
                )
                read = np.asarray(readings.read_back[start:], dtype=np.float64)
                found[j] = peak_at(read[:, j], values)  # the scanned ones keep their estimates
            found[still] = np.median(read[:, still], axis=0)  # where the others stood
    return found


@dataclass(frozen=True)
class Scan:
    """A mirror scan: the peaks' poses (M, A), the readings, the instrument time (s),
    how the readings were taken (`STOP_AND_GO` or `FLY`)."""

    peaks: FloatArray
    readings: Readings
    seconds: float
    mode: str = STOP_AND_GO


def scan_mode(devices: Devices, stop_and_go: bool = False) -> str:
    """`FLY` where the bus sweeps and the detector streams, unless ``stop_and_go``;
    else `STOP_AND_GO`."""
    return STOP_AND_GO if stop_and_go or not can_stream(devices.detector) else FLY


def scan(devices: Devices, rig: Rig, settings: ScanSettings, *, stop_and_go: bool = False) -> Scan:
    """Locate the mirror's peaks at the reachable nominal poses of ``settings`` (its
    incidences those the rig reaches, `for_rig`) with the opened ``devices``, flown where
    the detector streams unless ``stop_and_go``; `GonioError` if none is reachable."""
    mode = scan_mode(devices, stop_and_go)
    settings = for_rig(rig, settings, mode)
    centers = nominal_poses(rig, settings)
    centers = centers[reachable(rig, centers, settings, mode)]
    if not len(centers):
        raise GonioError("align: no mirror pose of the scan is within the rig's limits")
    centers = centers[visiting_order(centers)]
    readings = Readings(rig.axes)
    if devices.light is not None:
        devices.light.on()
    start = devices.clock.now()
    peaks = np.stack(
        [locate(devices, rig, c, settings, readings, i, mode) for i, c in enumerate(centers)]
    )
    return Scan(peaks, readings, devices.clock.now() - start, mode)


def fly_allowed(kind: BackendKind, speedup: float) -> bool:
    """Whether `run_scan` may fly on the backend ``kind``: the simulated one and the
    hardware, and a rehearsal no faster than `MAX_FLY_SPEEDUP`."""
    return kind != "rehearsal" or speedup <= MAX_FLY_SPEEDUP


def run_scan(
    rig: Rig,
    scene: Scene | None,
    kind: BackendKind,
    settings: ScanSettings,
    *,
    seed: int | None = None,
    speedup: float = 50.0,
    stop_and_go: bool = False,
) -> Scan:
    """A mirror scan on the backend ``kind`` built from the rig file (the ``scene``
    where the detector is simulated), its devices opened and closed here; flown where
    the detector streams (`fly_allowed`), unless ``stop_and_go``; the fine scan on the
    hardware path at `HARDWARE_FINE_RATE_HZ` at most."""
    stop_and_go |= not fly_allowed(kind, speedup)
    if kind != "simulated":
        rate = min(settings.fine_rate_hz, HARDWARE_FINE_RATE_HZ)
        settings = dataclasses.replace(settings, fine_rate_hz=rate)
    backend = backends.build(kind, rig, scene, seed, time.time(), speedup=speedup)
    try:
        with backend.devices:
            return scan(backend.devices, rig, settings, stop_and_go=stop_and_go)
    finally:
        backend.close()


def write_readings(path: Path, readings: Readings) -> None:
    """The readings as a SQLite table ``reading`` (one row each; how it was taken;
    angles in rad, one column per axis commanded and read back; its window, s) at
    ``path`` (a new file)."""
    axes = readings.axes
    columns = [f'"commanded_{a}" REAL, "read_{a}" REAL' for a in axes]
    with sqlite3.connect(path) as db:
        db.execute(
            "CREATE TABLE reading (i INTEGER PRIMARY KEY, peak INTEGER, joint TEXT, mode TEXT, "
            f"{', '.join(columns)}, value REAL, started_s REAL, ended_s REAL, saturated INTEGER)"
        )
        rows = [
            (i, readings.peak[i], readings.joint[i], readings.mode[i],
             *(v for pair in zip(readings.commanded[i], readings.read_back[i], strict=True)
               for v in pair),
             readings.value[i], readings.started_s[i], readings.ended_s[i],
             int(readings.saturated[i]))
            for i in range(len(readings.value))
        ]  # fmt: skip
        marks = ", ".join("?" * (8 + 2 * len(axes)))
        db.executemany(f"INSERT INTO reading VALUES ({marks})", rows)
    db.close()


__all__ = [
    "CHECK", "FLY", "HARDWARE_FINE_RATE_HZ", "MARGIN_TICKS", "MAX_FLY_SPEEDUP", "PEAK_SIGMA_DEG",
    "STOP_AND_GO", "SWEEP_ATTEMPTS", "FlySweep", "Readings", "Scan", "ScanSettings",
    "arc_factor", "cross_scan", "fly_allowed", "fly_cross", "fly_sweep", "for_rig",
    "measure_line", "nominal_poses", "reachable", "run_scan", "scan", "scan_mode",
    "visiting_order", "write_readings",
]  # fmt: skip
