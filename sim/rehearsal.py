"""The simulated peers of `gonio acquire --rehearse`: the hardware path without
hardware. Each device the rig file wires to a port runs as a simulated peer on its own
pseudo-terminal, for the real driver built from the rig file exactly as for hardware
(only the port is the pty's; the wiring is `gonio.workflows.rehearsal`):

- the motors: the byte-level Dynamixel emulator, driven by `DynamixelBus` through the
  unmodified SDK;
- a ``serial`` detector: the simulated photometer (`sim.peers.serial_photometer`) driven by
  `SerialDetector`, its counts those of the scene through `SimDetector`'s radiometric
  chain and sensor at the pose the emulated motors are at; a ``simulated`` detector:
  `SimDetector` reading the bus's positions;
- a ``pymeasure`` detector: the emulated instrument of its PyMeasure class
  (`sim.peers.visa_instruments`), opened by PyVISA's pure-Python backend on its pty and driven
  by the unmodified class through `PyMeasureDetector`, its readings the scene's rate
  through the same chain;
- a ``serial`` light switch: the simulated lamp relay (`sim.peers.serial_light`) driven by
  `SerialLightSwitch`, whose state the detector sees; else a `SimLightSource`.

Time runs ``speedup`` times faster than real time (motion profiles, settle dwells and
exposures alike); waits for serial answers are real time, as they are the ports'. The
scene's injected faults are not applied (inject faults into the peers instead).
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from drivers.base import StageTarget
from drivers.dynamixel import AxisConfig
from gonio.config import ConfigError
from gonio.rig import PyMeasureInterfaceSpec, Rig, SerialSwitchSpec
from sim.clock import ScaledClock, TimeSource
from sim.peers import (
    EMULATORS,
    FULL_SCALE,
    SR830,
    EmulatedInstrument,
    SerialLamp,
    SerialPhotometer,
    mismatch,
)
from sim.peers.dynamixel.emulator import DxlEmulator
from sim.virtual import SimDetector

Pose = Callable[[], dict[str, float]]
PoseAt = Callable[[float], dict[str, float]]


def emulated_pose(emulator: DxlEmulator, axes: list[AxisConfig]) -> Pose:
    """The axis angles (rad) the emulated motors are at, from their Present Position
    registers, with no bus traffic."""

    def pose() -> dict[str, float]:
        motors = emulator.motors
        return {a.name: a.to_rad(motors[a.motor_id].get("present_position")) for a in axes}

    return pose


def emulated_trajectory(emulator: DxlEmulator, axes: list[AxisConfig]) -> PoseAt:
    """The axis angles (rad, unrounded) the emulated motors are at at a time on the
    emulator's clock, along their present motion profiles (`EmulatedMotor.position_at`:
    valid from each motor's last goal on): the truth of a sweep in time."""

    def pose_at(t: float) -> dict[str, float]:
        motors = emulator.motors
        return {a.name: a.to_rad(motors[a.motor_id].position_at(t)) for a in axes}  # type: ignore[arg-type]

    return pose_at


@dataclass(frozen=True)
class Peers:
    """The simulated devices at the far end of the ports (for tests and benchmarks)."""

    emulator: DxlEmulator
    photometer: SerialPhotometer | None  # a serial detector's
    lamp: SerialLamp | None  # a serial light switch's
    instrument: EmulatedInstrument | None = None  # a pymeasure detector's


class RehearsalSide:
    """The `drivers.base.Simulated` side of a rehearsal (or of real motors with a
    simulated detector: no peers): which sample's random streams the detector's physics
    uses and what is on the stage; the true joint angles are ``pose()``'s (the emulated
    motors'). A rehearsal resumes as hardware does, with no snapshot."""

    def __init__(
        self,
        physics: SimDetector,
        pose: Pose,
        peers: Peers | None = None,
        pose_at: PoseAt | None = None,
    ) -> None:
        self.physics = physics
        self.pose = pose
        self.peers = peers
        self._pose_at = pose_at

    def true_pose_at(self, t: float) -> dict[str, float]:
        """The joint angles (rad) the emulated motors were at at time ``t`` on the
        rehearsal's clock, along their present motion profiles (read-only; the truth a
        test compares a sweep's merged angles with). Without a trajectory: now's."""
        return self.pose() if self._pose_at is None else self._pose_at(t)

    def begin_sample(self, index: int) -> None:
        self.physics.begin_sample(index)

    def show(self, target: StageTarget) -> None:
        self.physics.show(target)

    def true_positions(self) -> dict[str, float]:
        return self.pose()

    def expect(self, goals: Any, index: Any) -> None:
        pass

    def snapshot(self) -> Any:
        return None

    def restore(self, state: Any) -> None:
        raise NotImplementedError("a rehearsal resumes as hardware does, without a snapshot")


def _where(rig: Rig) -> str:
    return str(rig.source) if rig.source else "rig"


def lamp_for(rig: Rig, switch: SerialSwitchSpec) -> SerialLamp:
    """The simulated relay answering the rig's switch commands (`ConfigError` if the
    rig expects answers it does not give)."""
    answers = (("ack", "OK"), ("on_reply", "ON"), ("off_reply", "OFF"))
    for field, answer in answers:
        pattern = getattr(switch, field)
        if pattern is not None and re.search(pattern, answer) is None:
            raise ConfigError(
                f"{_where(rig)}: light.switch.{field}: --rehearse: {pattern!r} does not "
                f"match the simulated lamp relay's answer {answer!r}"
            )
    query = switch.query_command or "STATE?"
    return SerialLamp(commands=(switch.on_command, switch.off_command, query))


def _no_lockin(rig: Rig, physics: SimDetector, instrument: str) -> None:
    """`ConfigError` when the scene's detector is a lock-in and the rig's is not one."""
    if physics.lockin:
        raise ConfigError(
            f"{_where(rig)}: detector.interface: --rehearse: the scene's detector is a "
            f"lock-in (detector.kind: lockin) and the rig reads {instrument}; expected a "
            "lock-in (pymeasure.instruments.srs.SR830 or SR860), or a scene with kind: adc"
        )


def photometer_for(rig: Rig, physics: SimDetector, clock: ScaledClock) -> SerialPhotometer:
    """The simulated photometer the rig's serial interface can talk to, reading each
    exposure's counts from ``physics`` (`ConfigError` if the rig's protocol is not the
    photometer's: docs/reference/serial_detector.md)."""
    _no_lockin(rig, physics, "a serial photometer")
    config = rig.serial_detector_config()
    problem = mismatch(config)
    if problem is not None:
        field, reason = problem
        raise ConfigError(f"{_where(rig)}: detector.interface.{field}: --rehearse: {reason}")

    def signal(exposure_s: float) -> float:
        counts, _ = physics.expose(exposure_s, 1, clock.now())
        return float(counts[0, 0])

    def windows(starts: list[float], ends: list[float]) -> tuple[list[float], list[bool]]:
        """A stream's windows (`time.monotonic` s) on the rehearsal's clock, read in one
        call at the poses the motors' profiles had then (`SimDetector.window_counts`)."""
        started = np.array([clock.at(t) for t in starts])
        ended = np.array([clock.at(t) for t in ends])
        integration = float(np.median(ended - started))
        counts, saturated = physics.window_counts(started, ended, integration)
        return counts.tolist(), saturated.tolist()

    return SerialPhotometer(
        signal,
        full_scale=physics.sensor.max_count if physics.sensor_effects.saturation else None,
        reset_on_open=config.reset_banner is not None and config.settle_s > 0,
        speedup=clock.speedup,
        windows=windows if physics.pose_at is not None else None,
    )


#: The integration (s) at which the sensor's full scale is the instrument's full range.
REFERENCE_INTEGRATION_S = 0.01


def instrument_for(
    rig: Rig, interface: PyMeasureInterfaceSpec, physics: SimDetector, clock: ScaledClock
) -> EmulatedInstrument:
    """The emulated instrument of the rig's PyMeasure class, its reading the scene's
    rate through ``physics`` (an integration of t s: the counts of t s over t, scaled
    so that the sensor's full scale at `REFERENCE_INTEGRATION_S` is the instrument's
    full range); `ConfigError` for a class with no emulator or a terminator it does
    not use."""
    config = interface.config()
    emulator = EMULATORS.get(config.instrument)
    if emulator is None:
        known = ", ".join(sorted(EMULATORS))
        raise ConfigError(
            f"{_where(rig)}: detector.interface.instrument: --rehearse: no emulated "
            f"{config.instrument} (emulated: {known})"
        )
    if not issubclass(emulator, SR830):
        _no_lockin(rig, physics, config.instrument)
    terminator = emulator.terminator
    if (config.read_termination or "\n") != terminator:
        raise ConfigError(
            f"{_where(rig)}: detector.interface.read_termination: --rehearse: the emulated "
            f"instrument ends its answers with {terminator!r}; expected "
            f"read_termination: {terminator!r}"
        )
    per_rate = FULL_SCALE[config.instrument] * REFERENCE_INTEGRATION_S / physics.sensor.max_count

    def signal(integration_s: float) -> float:
        counts, _ = physics.expose(integration_s, 1, clock.now())
        if physics.lockin:  # the scene's lock-in reads volts already
            return float(counts[0, 0])
        return float(counts[0, 0]) / integration_s * per_rate

    if physics.lockin and issubclass(emulator, SR830):  # its phase: the simulated lock-in's
        return emulator(signal, speedup=clock.speedup, phase=lambda: physics.last_phase_deg or 0.0)
    return emulator(signal, speedup=clock.speedup)


def emulated_bus(rig: Rig, clock: TimeSource, *, wire_time: bool = False) -> DxlEmulator:
    """A (not yet started) byte-level emulator of the rig's motors (of the models and
    firmware the rig file expects), at home, in their operating modes, at the rig's bus
    rate; as fast as the host reads, or with
    ``wire_time`` as a real bus (bytes on the wire and the motors' return delays)."""
    axes = rig.bus_axes()
    emulator = DxlEmulator(
        ids=[a.motor_id for a in axes],
        baud=rig.spec.bus.baud,
        clock=clock,
        wire_time=wire_time,
        return_delay=wire_time,
    )
    for axis, home in zip(axes, rig.home, strict=True):
        motor = emulator.motors[axis.motor_id]
        motor.set("operating_mode", axis.operating_mode)
        motor.set("present_position", axis.to_ticks(float(home)))
        if axis.model is not None:  # the motors the rig file expects
            motor.set("model_number", axis.model)
        if axis.firmware is not None:
            motor.set("firmware_version", axis.firmware)
    return emulator
