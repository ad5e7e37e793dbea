"""`SimDetector` and `SimLightSource`: a detector that measures the scene's material
through the real radiometric chain, at the pose the motors are really in.

Implements `drivers.base.Detector` (and `LightSource`), every rule of the contract.
Each `measure` reads the pose (joint angles) from a callable — `SimMotorBus.true_positions`
in a simulated run, the read-back positions of a real `DynamixelBus` in a rehearsal —
turns it into the sample frame's (ωi, ωo) with the rig's forward kinematics, computes
the power reaching the detector (`sim.virtual.physics.optics`), the expected electrons of each
exposure, and reads them out through the sensor (`sim.virtual.physics.sensor`) with the random
streams of the sample named by `begin_sample` (a second measurement of the same sample
continues its streams), so any sample can be recomputed alone. Time passes on the
``clock`` (`drivers.base.Clock`): virtual in a simulation, scaled real time in a
rehearsal. Injected ``detector_error`` and ``saturated`` faults (`sim.virtual.faults`) apply to
the first measurement of their samples.

Streaming (`drivers.stream.StreamingDetector`): windows of the integration end every
period from ``start_stream``'s time on the clock; ``read_stream`` returns those ended by
now (letting virtual time pass up to its timeout for the next one). Each window is read
out as one exposure at the pose ``pose_at(t)`` gives for the window's middle time ``t``
(the instrument's callable; without one, the pose of the moment of reading). With the
scene's ``motion_blur`` effect a window is instead the mean over Gauss–Legendre nodes in
time of the power at the poses ``pose_at(t_k)`` (`blur_nodes`: as many as its smear
needs); with ``timestamp_jitter`` the stamps it reports are the true window shifted by
a latency and a Gaussian jitter from the sample's ``TIMING`` stream (the true windows
kept in ``stream_truth``). A lock-in does not stream. The windows' optics are
`sim.virtual.devices.windows.WindowOptics`'s, computed ahead in one pass where ``pose_at``
gives the poses to come (``lookahead``).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping
from typing import Protocol

import numpy as np

from drivers.base import Clock, StageTarget
from drivers.devices import Resource
from drivers.errors import DetectorError, DeviceClosed, StreamNotSupported
from drivers.pymeasure import PyMeasureDetectorConfig
from drivers.stream import StreamReading
from drivers.values import Reading
from gonio.rig import PyMeasureInterfaceSpec, Rig
from gonio.scene import STREAM_GAP, STREAM_GAP_FROM, Scene
from sim.virtual.devices.windows import WindowOptics
from sim.virtual.faults import FaultInjector
from sim.virtual.physics import lockin, sensor
from sim.virtual.physics.optics import SceneOptics
from sim.virtual.physics.streams import TIMING, Streams

DETECTOR_KINDS = frozenset({"detector_error", "saturated"})
#: The injected faults a stream meets.
STREAM_KINDS = frozenset({"stream_gap"})


class LightState(Protocol):
    """Whether the light reaches the sample: a `SimLightSource`, or a rehearsal's
    simulated lamp relay (`sim.peers.serial_light.SerialLamp`)."""

    @property
    def is_on(self) -> bool: ...


class SimLightSource(Resource):
    """A switchable source (on at start); off, the detector sees only its own dark
    signal. ``is_on`` can be read when closed; switching needs it open."""

    def __init__(self) -> None:
        self._on = True
        self._open = False

    @property
    def is_open(self) -> bool:
        return self._open

    @property
    def is_on(self) -> bool:
        return self._on

    def open(self) -> None:
        self._open = True

    def close(self) -> None:
        self._open = False

    def _check_open(self) -> None:
        if not self._open:
            raise DeviceClosed("the simulated light source is not open")

    def on(self) -> None:
        self._check_open()
        self._on = True

    def off(self) -> None:
        self._check_open()
        self._on = False


def sensor_of(scene: Scene) -> tuple[sensor.SensorSpec, sensor.SensorEffects]:
    """The scene's sensor and the sensor effects it lists (a lock-in's: a placeholder
    well of one electron, never read out)."""
    d, e = scene.detector, scene.effects
    spec = sensor.SensorSpec(
        full_well_e=1.0 if d.full_well_e is None else d.full_well_e,
        adc_bits=d.adc_bits,
        read_noise_e=d.read_noise_e,
        dark_current_e_s=d.dark_current_e_s,
    )
    return spec, sensor.SensorEffects.from_names(e.names())


class SimDetector(Resource):
    """A simulated detector looking at the scene from the pose ``pose()`` returns."""

    def __init__(
        self,
        scene: Scene,
        rig: Rig,
        pose: Callable[[], Mapping[str, float]],
        *,
        clock: Clock,
        streams: Streams,
        light: LightState | None = None,
        faults: FaultInjector | None = None,
        pose_at: Callable[[float], Mapping[str, float]] | None = None,
        lookahead: bool = False,
    ) -> None:
        self.scene = scene
        self.rig = rig
        self.chain = SceneOptics(scene, rig)
        self.sensor, self.sensor_effects = sensor_of(scene)
        self._pose = pose
        self._clock = clock
        self.streams = streams
        self._faults = faults or FaultInjector((), streams)
        self.light: LightState = light or SimLightSource()
        self.readout_s = rig.spec.detector.readout_s
        self._target: StageTarget = "sample"  # what is on the stage
        self._sample = 0  # whose random streams the next measurement uses
        self._open = False
        self._draws: dict[int, int] = {}  # draws used so far per sample index
        self._streams_started: dict[int, int] = {}  # streams started per sample index
        self._gap = (0, 0)  # the present stream's lost windows [from, to) (stream_gap)
        self._prepared: dict[tuple[float, ...], float] = {}
        #: Measurements that found their pose prepared.
        self.prepared_hits = 0
        #: A lock-in's readings (``detector.kind: lockin``): volts, no dark signal, a phase.
        self.lockin = scene.detector.kind == "lockin"
        self._phase: np.ndarray | None = None  # the last lock-in readings' phases (°)
        self._stream: tuple[float, float, float] | None = None  # (t0, period, integration)
        self._windows = 0  # windows of the running stream read so far
        #: The true windows (started, ended) on the clock of the running (or last)
        #: stream's readings, before ``timestamp_jitter`` offsets their stamps.
        self.stream_truth: list[tuple[float, float]] = []
        #: Time nodes of each window read so far of the running (or last) stream.
        self.stream_nodes: list[int] = []
        #: The windows' optics (``lookahead``: ``pose_at`` gives the poses to come).
        self.windows = WindowOptics(self.chain, rig.axes, pose, pose_at, lookahead=lookahead)
        self._ahead_until = 0  # windows of the running stream computed ahead

    @property
    def pose_at(self) -> Callable[[float], Mapping[str, float]] | None:
        """The pose (joint angles) at a time on the clock, for a stream's windows."""
        return self.windows.pose_at

    # -- Resource / Detector -------------------------------------------------------
    @property
    def is_open(self) -> bool:
        return self._open

    @property
    def exposure_range_s(self) -> tuple[float, float]:
        return self.rig.spec.detector.exposure_range_s

    @property
    def dark_subtracted(self) -> bool:
        """A lock-in's readings carry no dark signal (`drivers.base.dark_subtracted`)."""
        return self.lockin

    @property
    def unit(self) -> str:
        """V for a lock-in, else counts."""
        return "V" if self.lockin else "counts"

    @property
    def phase_tolerance_deg(self) -> float | None:
        """A lock-in's: the rig's PyMeasure section's (when it names one), else 5°."""
        if not self.lockin:
            return None
        interface = self.rig.spec.detector.interface
        if isinstance(interface, PyMeasureInterfaceSpec):
            return interface.config().phase_tolerance_deg
        return PyMeasureDetectorConfig.phase_tolerance_deg

    @property
    def can_stream(self) -> bool:
        """Whether it streams (`drivers.stream.can_stream`): yes, unless a lock-in."""
        return bool(self.scene.detector.streams)

    def open(self) -> None:
        self._open = True

    def close(self) -> None:
        self._open = False
        self._stream = None

    # -- streaming -------------------------------------------------------------------
    def start_stream(self, rate_hz: float, integration_s: float | None = None) -> None:
        """Windows of ``integration_s`` (default: the period less the readout dead
        time) ending every ``1 / rate_hz`` s from now on the clock."""
        if not self._open:
            raise DeviceClosed("the simulated detector is not open (use it as a context manager)")
        if not self.can_stream:
            raise StreamNotSupported("the simulated lock-in cannot stream readings")
        if self._stream is not None:
            raise DetectorError("a stream is already running (stop_stream first)")
        if not (isinstance(rate_hz, int | float) and 0 < rate_hz < np.inf):
            raise DetectorError(f"stream rate_hz must be a positive number, got {rate_hz!r}")
        period = 1.0 / float(rate_hz)
        room = period - self.readout_s
        integration = room if integration_s is None else integration_s
        if not (isinstance(integration, int | float) and 0 < integration <= room * (1 + 1e-9)):
            raise DetectorError(
                f"stream integration_s must be in (0, {room:.6g}] s (the period at {rate_hz:g} "
                f"Hz less the readout {self.readout_s:g} s), got {integration_s!r}"
            )
        lo, hi = self.exposure_range_s
        if not lo <= integration <= hi:
            raise DetectorError(
                f"stream integration {integration!r} s is outside the detector's range "
                f"[{lo:g}, {hi:g}] s"
            )
        self._stream = (self._clock.now(), period, float(integration))
        self._windows = 0
        attempt = self._streams_started.get(self._sample, 0)
        self._streams_started[self._sample] = attempt + 1
        gap = self._faults.fired(self._sample, attempt, STREAM_KINDS) if self._faults else None
        self._gap = (STREAM_GAP_FROM, STREAM_GAP_FROM + STREAM_GAP) if gap else (0, 0)
        self.stream_truth, self.stream_nodes = [], []
        self.windows.forget()
        self._ahead_until = 0

    def read_stream(self, timeout_s: float = 0.0) -> list[StreamReading]:
        """The windows ended since the last call; with none, let up to ``timeout_s``
        pass on the clock for the next."""
        if self._stream is None:
            raise DetectorError("no stream is running (start_stream first)")
        t0, period, _ = self._stream
        readings = self._ended_windows()
        if not readings and timeout_s > 0:
            wait = t0 + (self._windows + 1) * period - self._clock.now()
            self._clock.sleep(min(max(wait, 0.0), timeout_s))
            readings = self._ended_windows()
        return readings

    def stop_stream(self) -> list[StreamReading]:
        """Stop (idempotent): the windows ended by now."""
        if self._stream is None or not self._open:
            self._stream = None
            return []
        readings = self._ended_windows()
        self._stream = None
        return readings

    def _ended_windows(self) -> list[StreamReading]:
        assert self._stream is not None
        t0, period, integration = self._stream
        done = int(np.floor((self._clock.now() - t0) / period + 1e-9))
        k = np.arange(self._windows, max(done, self._windows))
        if not len(k):
            return []
        self._windows = done
        if self.windows.lookahead and done > self._ahead_until:
            first = max(self._ahead_until, self._windows)
            ahead = np.arange(first, first + self.windows.ahead_count(done - first))
            ends = t0 + (ahead + 1) * period
            self.windows.ahead(ends - integration, ends, self._target)
            self._ahead_until = first + len(ahead)
        ended = t0 + (k + 1) * period
        started = ended - integration
        start = self._draws.get(self._sample, 0)
        counts, saturated = self._stream_counts(started, ended, integration)
        self.stream_truth += list(zip(started.tolist(), ended.tolist(), strict=True))
        shift = self._stamp_shift(len(k), start)
        lost = (k >= self._gap[0]) & (k < self._gap[1])
        return [
            StreamReading(value=c, std=np.nan, started_s=a, ended_s=b, saturated=sat)
            for c, sat, a, b, gone in zip(
                counts.tolist(),
                saturated.tolist(),
                (started + shift).tolist(),
                (ended + shift).tolist(),
                lost.tolist(),
                strict=True,
            )
            if not gone
        ]

    def _stamp_shift(self, n: int, start: int) -> np.ndarray | float:
        """What ``timestamp_jitter`` adds to the stamps of ``n`` windows whose first is
        draw ``start`` of the sample (s): latency + σ·z, z from the ``TIMING`` stream."""
        spec = self.scene.effects.timestamp_jitter
        if spec is None:
            return 0.0
        index = np.array([self._sample], dtype=np.int64)
        z = self.streams.normal(index, TIMING, n, start=start)[0]
        return np.asarray(spec.latency_s + spec.sigma_s * z, dtype=np.float64)

    def window_counts(
        self, started: np.ndarray, ended: np.ndarray, integration: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """Counts and saturated flags (N,) of exposures of ``integration`` s over the
        windows [started, ended] (clock times, s), as a stream's (`pose_at`, the
        ``motion_blur`` nodes), continuing the present sample's random streams: for a
        peer that streams these physics (a rehearsal's photometer)."""
        return self._stream_counts(
            np.asarray(started, dtype=np.float64), np.asarray(ended, dtype=np.float64), integration
        )

    def _stream_counts(
        self, started: np.ndarray, ended: np.ndarray, integration: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """Counts and saturated flags (N,) of one exposure per window, continuing the
        present sample's random streams: at the pose of each window's middle time, or
        with ``motion_blur`` the mean power over the window's time nodes."""
        middle = 0.5 * (started + ended)
        times, weights, owner, nodes = self.windows.time_nodes(started, ended)
        self.stream_nodes += nodes.tolist()
        geometric = self.windows.power(self.windows.poses(times), self._target)
        at_nodes = self.chain.power(geometric, times[:, None], light_on=self.light.is_on)[:, 0]
        if len(times) == len(middle):
            power = at_nodes[None, :]
        else:  # the weighted mean over each window's nodes
            mean = np.bincount(owner, weights * at_nodes, minlength=len(middle))
            power = np.asarray(mean, dtype=np.float64)[None, :]
        index = np.array([self._sample], dtype=np.int64)
        start = self._draws.get(self._sample, 0)
        self._draws[self._sample] = start + len(middle)
        signal = self.chain.electrons(power, np.array([integration]))
        counts, saturated = sensor.read_out(
            signal, np.array([integration]), self.sensor, self.sensor_effects, self.streams,
            index, start=start,
        )  # fmt: skip
        return counts[0], saturated[0]

    # -- what only a simulation has ------------------------------------------------
    def begin_sample(self, index: int) -> None:
        """The next measurements use sample ``index``'s random streams and faults."""
        self._sample = int(index)

    def draws_of(self, sample: int) -> int:
        """Exposures read so far for ``sample``."""
        return self._draws.get(sample, 0)

    def set_draws(self, sample: int, draws: int) -> None:
        """Continue ``sample`` after ``draws`` exposures (a resumed run)."""
        self._draws[sample] = draws

    def show(self, target: StageTarget) -> None:
        """Put the sample or the reference standard on the stage."""
        if target not in ("sample", "reference"):
            raise ValueError(f"expected 'sample' or 'reference', got {target!r}")
        self._target = target

    def prepare(self, poses: np.ndarray) -> None:
        """Compute, in one vectorized pass, the sample's geometric power at joint poses
        (N, A) the run expects to measure at; `measure` then looks a pose up instead of
        evaluating the chain for it alone. Only an exactly equal pose is a hit: anything
        else is computed as usual, so the readings do not depend on this."""
        poses = np.asarray(poses, dtype=np.float64).reshape(-1, len(self.rig.axes))
        _, _, power = self.chain.at_poses(poses, "sample")
        self._prepared = dict(zip(map(tuple, poses.tolist()), power.tolist(), strict=True))

    def _pose_angles(self) -> tuple[float, ...]:
        pose = self._pose()
        try:
            return tuple(float(pose[name]) for name in self.rig.axes)
        except KeyError as exc:
            raise DetectorError(f"the pose has no angle for axis {exc.args[0]!r}") from None

    def _geometric_power(self) -> np.ndarray:
        angles = self._pose_angles()
        if self._target == "sample" and angles in self._prepared:
            self.prepared_hits += 1
            return np.array([self._prepared[angles]])
        return self.chain.at_poses(np.array([angles], dtype=np.float64), self._target)[2]

    def measure(self, exposure_s: float, averages: int = 1) -> Reading:
        """Expose ``averages`` times for ``exposure_s`` s each; the mean in counts."""
        if not self._open:
            raise DeviceClosed("the simulated detector is not open (use it as a context manager)")
        lo, hi = self.exposure_range_s
        if not lo <= exposure_s <= hi:
            raise DetectorError(
                f"exposure {exposure_s!r} s is outside the detector's range [{lo:g}, {hi:g}] s"
            )
        if int(averages) != averages or averages < 1:
            raise DetectorError(f"averages must be a positive integer, got {averages!r}")
        if self._stream is not None:
            raise DetectorError("measure() during a stream (stop_stream first)")
        averages = int(averages)
        start = self._draws.get(self._sample, 0)
        # The attempt at this sample: each earlier one (failed or not) used `averages` draws.
        attempt = start // averages if start % averages == 0 else -1
        fault = self._faults.fired(self._sample, attempt, DETECTOR_KINDS) if self._faults else None
        if fault is not None and fault.kind == "detector_error":
            self._draws[self._sample] = start + averages
            raise DetectorError(f"the detector did not answer (injected at sample {self._sample})")
        started = self._clock.now()
        counts, saturated = self.expose(exposure_s, averages, started)
        if fault is not None:  # saturated: the sensor's top code (a lock-in's overload), flagged
            top = self.scene.detector.sensitivity_v if self.lockin else None
            counts = np.full_like(counts, 1.1 * top if top else float(self.sensor.max_count))
            saturated = np.ones_like(saturated)
        self._clock.sleep((self.reading_s(exposure_s) + self.readout_s) * averages)
        reading = sensor.readings(counts, saturated, started, self._clock.now())[0]
        phase = self.last_phase_deg
        return reading if phase is None else dataclasses.replace(reading, phase_deg=phase)

    @property
    def last_phase_deg(self) -> float | None:
        """A lock-in's last reading's phase (°, the mean over its averages), else None."""
        if self._phase is None:
            return None
        rad = np.radians(self._phase[0])
        return float(np.degrees(np.arctan2(np.sin(rad).sum(), np.cos(rad).sum())))

    def reading_s(self, exposure_s: float) -> float:
        """How long one reading of ``exposure_s`` s takes before the readout (s): the
        exposure, or a lock-in's settle time when longer (`sim.virtual.physics.lockin`)."""
        if not self.lockin:
            return exposure_s
        return float(lockin.reading_s(self.scene.detector, np.array([exposure_s]))[0])

    def expose(
        self, exposure_s: float, averages: int, started_s: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """The physics of one reading, with no checks and no waiting: counts and
        saturated flags, each (1, averages), of ``averages`` exposures of ``exposure_s``
        s (> 0) each, the first starting at ``started_s`` (s on the clock), at the pose
        ``pose()`` gives now, continuing the present sample's random streams. A
        rehearsal's serial photometer reads its signal here."""
        geometric = self._geometric_power()
        busy = self.reading_s(exposure_s)
        period = busy + self.readout_s
        t_mid = np.asarray(
            started_s + period * np.arange(averages)[None, :] + 0.5 * busy,
            dtype=np.float64,
        )
        power = self.chain.power(geometric, t_mid, light_on=self.light.is_on)
        index = np.array([self._sample], dtype=np.int64)
        start = self._draws.get(self._sample, 0)
        self._draws[self._sample] = start + averages
        if self.lockin:  # the open chopper's signal rate (e/s), read by the lock-in
            signal = self.chain.electrons(power, np.ones(1))
            value, overloaded, self._phase = lockin.read_out(
                signal, np.array([exposure_s]), t_mid, self.scene.detector,
                self.scene.effects.names(), self.streams, index, start=start,
            )  # fmt: skip
            return value, overloaded
        signal = self.chain.electrons(power, np.array([exposure_s]))
        return sensor.read_out(
            signal, np.array([exposure_s]), self.sensor, self.sensor_effects, self.streams,
            index, start=start,
        )  # fmt: skip
