"""`simulate(plan, scene)`: a whole simulated run computed at once (vectorized); and
`simulate_standard`, readings of the reference standard (or dark readings) at a fixed
pose, as the engine's calibrations take them, with `expected_rate` their noise-free value.

The same run `SimulatedInstrument.run` measures target by target through the driver
protocols — the same motion (each target's move from the previous goal, trapezoidal
profiles, settle time), the same position errors, the same optics and the same random
streams per sample index — so the two agree to rounding, and a planning study can
simulate tens of thousands of targets in a fraction of a second.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from drivers.base import StageTarget
from gonio.rig import Rig
from gonio.scene import Scene
from gonio.types import FloatArray
from sim.virtual.devices.detector import sensor_of
from sim.virtual.devices.position_error import planned_poses
from sim.virtual.physics import lockin, sensor
from sim.virtual.physics.optics import SceneOptics
from sim.virtual.physics.streams import Streams
from sim.virtual.record import SimRun


class Targets(Protocol):
    """What a simulation needs of a plan (`gonio.planner` builds one): the rig, and per
    target the joint angles (rad, (N, A)), exposure (s) and number of exposures."""

    @property
    def rig(self) -> Rig: ...
    @property
    def angles(self) -> FloatArray: ...
    @property
    def exposure_s(self) -> FloatArray: ...
    @property
    def averages(self) -> np.ndarray: ...
    def __len__(self) -> int: ...


def simulate(plan: Targets, scene: Scene, *, seed: int | None = None) -> SimRun:
    """Measure every target of ``plan`` in the simulated ``scene`` (see the module)."""
    rig = plan.rig
    streams = Streams(scene.seed if seed is None else int(seed))
    n = len(plan)
    index = np.arange(n, dtype=np.int64)
    goal, true, previous = planned_poses(rig, plan.angles, scene, streams)

    # Virtual time: move, settle, then `averages` exposures (+ readout) per target, added
    # up in the order the instrument's clock adds them (so the times agree bit for bit).
    travel = rig.travel_time(previous, goal)
    readout = rig.spec.detector.readout_s
    reading = _reading_s(scene, plan.exposure_s)
    period = reading + readout
    busy = period * plan.averages
    settle = np.full(n, rig.spec.settle_s)
    clock = np.cumsum(np.stack([travel, settle, busy], axis=1).ravel()).reshape(n, 3)
    settled, end = clock[:, 1], clock[:, 2]

    chain = SceneOptics(scene, rig)
    wi, wo, geometric = chain.at_poses(true)
    sensor_spec, sensor_effects = sensor_of(scene)
    value = np.empty(n)
    std = np.empty(n)
    saturated = np.empty(n, dtype=np.bool_)
    for a in np.unique(plan.averages):  # one batch per number of averages
        rows = np.flatnonzero(plan.averages == a)
        t_mid = (
            settled[rows, None]
            + period[rows, None] * np.arange(a)[None, :]
            + 0.5 * reading[rows, None]
        )
        power = chain.power(geometric[rows], t_mid)
        counts, sat = _read(
            scene, chain, power, plan.exposure_s[rows], t_mid, streams, index[rows],
            sensor_spec, sensor_effects,
        )  # fmt: skip
        v, s, _, flag = sensor.summarize(counts, sat)
        value[rows], std[rows], saturated[rows] = v, s, flag
    return SimRun(
        index=index,
        commanded=np.asarray(plan.angles, dtype=np.float64),
        read_back=goal,
        true=true,
        wi=wi,
        wo=wo,
        exposure_s=plan.exposure_s,
        averages=plan.averages,
        settled_s=settled,
        end_s=end,
        value=value,
        std=std,
        saturated=saturated,
    )


def _reading_s(scene: Scene, exposure_s: FloatArray) -> FloatArray:
    """How long each reading takes before the readout (s): the exposure, or a lock-in's
    settle time when longer (`sim.virtual.physics.lockin.reading_s`)."""
    exposure = np.asarray(exposure_s, dtype=np.float64)
    if scene.detector.kind == "lockin":
        return lockin.reading_s(scene.detector, exposure)
    return exposure


def _read(
    scene: Scene,
    chain: SceneOptics,
    power: FloatArray,
    exposure_s: FloatArray,
    t_mid: FloatArray,
    streams: Streams,
    index: np.ndarray,
    spec: sensor.SensorSpec,
    effects: sensor.SensorEffects,
) -> tuple[FloatArray, np.ndarray]:
    """Readings (N, A) and their saturation of powers (W, (N, A)): the sensor's counts,
    or a lock-in's volts (`SimDetector.expose` reads the same)."""
    if scene.detector.kind == "lockin":
        signal = chain.electrons(power, np.ones(len(power)))
        value, overloaded, _ = lockin.read_out(
            signal, exposure_s, t_mid, scene.detector, scene.effects.names(), streams, index
        )
        return value, overloaded
    signal = chain.electrons(power, exposure_s)
    return sensor.read_out(signal, exposure_s, spec, effects, streams, index)


def simulate_standard(
    rig: Rig,
    scene: Scene,
    pose: FloatArray,
    started_s: FloatArray,
    exposure_s: float,
    averages: int,
    index: np.ndarray,
    *,
    light_on: bool = True,
    seed: int | None = None,
    target: StageTarget = "reference",
    optics: SceneOptics | None = None,
) -> sensor.Summary:
    """K readings of ``target`` at the true joint angles ``pose`` (rad, (A,)), each of
    ``averages`` exposures of ``exposure_s`` s, the first starting at ``started_s`` (s,
    (K,)), with the random streams of sample indices ``index`` (K,) from their first draw:
    what `sim.virtual.devices.detector.SimDetector.measure` reads there (light off: a dark
    reading), vectorized over K; ``optics``: the scene's `SceneOptics` on ``rig``, when
    the caller has it. The mean counts, spread, count and saturation of each."""
    started = np.asarray(started_s, dtype=np.float64).reshape(-1)
    k = len(started)
    chain = SceneOptics(scene, rig) if optics is None else optics
    _, _, geometric = chain.at_poses(np.asarray(pose, dtype=np.float64)[None, :], target)
    geometric = np.repeat(geometric, k)
    reading = float(_reading_s(scene, np.array([exposure_s]))[0])
    period = reading + rig.spec.detector.readout_s
    t_mid = started[:, None] + period * np.arange(averages)[None, :] + 0.5 * reading
    power = chain.power(geometric, t_mid, light_on=light_on)
    spec, effects = sensor_of(scene)
    streams = Streams(scene.seed if seed is None else int(seed))
    counts, sat = _read(
        scene, chain, power, np.full(k, exposure_s), t_mid, streams,
        np.asarray(index, dtype=np.int64), spec, effects,
    )  # fmt: skip
    return sensor.summarize(counts, sat)


def expected_rate(
    rig: Rig,
    scene: Scene,
    pose: FloatArray,
    t_s: FloatArray,
    target: StageTarget = "reference",
    optics: SceneOptics | None = None,
) -> FloatArray:
    """The noise-free signal rate (counts/s, dark excluded; a lock-in's level, V) of
    ``target`` at the true
    joint angles ``pose`` (rad, (A,)) at run times ``t_s`` (s): the source's drift at
    that instant, no rounding (the truth a calibration's rate estimates); ``optics`` as
    in `simulate_standard`."""
    t = np.asarray(t_s, dtype=np.float64)
    chain = SceneOptics(scene, rig) if optics is None else optics
    _, _, geometric = chain.at_poses(np.asarray(pose, dtype=np.float64)[None, :], target)
    power = chain.power(np.repeat(geometric, t.size), t.reshape(-1, 1))
    electrons = chain.electrons(power, np.ones(t.size))[:, 0]
    if scene.detector.kind == "lockin":
        return np.asarray(lockin.expected_v(scene.detector, electrons).reshape(t.shape))
    spec, _ = sensor_of(scene)
    return np.asarray((electrons / spec.gain_e_per_count).reshape(t.shape), dtype=np.float64)
