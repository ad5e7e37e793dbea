"""The backends of the contract suite, each behind a small harness that builds an
unopened device and looks at the device's own state (not through the driver under
test): `SimMotorBus` and `DynamixelBus` on the byte-level emulator over a pty (three motors of
three models);
`SimDetector` and `SerialDetector` on the simulated photometer over a pty;
`PyMeasureDetector` driving PyMeasure's SR830, SR860, ThorlabsPM100USB, Keithley6517B
and Keithley2000 classes over pyvisa-py on their emulated instruments' ptys;
`SimLightSource` and `SerialLightSwitch` on the simulated lamp over a pty."""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

import pytest

from drivers.base import Detector, LightSource, MotorBus
from drivers.dynamixel.axis import AxisConfig
from drivers.dynamixel.bus import DynamixelBus
from drivers.dynamixel.control_table import FACTORY_BAUD
from drivers.dynamixel.wire import setpoint_period
from drivers.light.serial_switch import SerialLightSwitch
from drivers.serial_detector.detector import SerialDetector
from gonio.rig.model import Rig
from gonio.scene import FaultRule, load_scene
from sim.clock import ManualClock, ScaledClock
from sim.peers.dynamixel.emulator import DxlEmulator
from sim.peers.dynamixel.faults import Fault
from sim.peers.serial_light import SerialLamp
from sim.peers.serial_photometer import STREAM_CONFIG, SerialPhotometer
from sim.peers.visa_instruments import EMULATORS, FULL_SCALE
from sim.virtual.devices.detector import SimDetector, SimLightSource
from sim.virtual.devices.motors import SimMotorBus
from sim.virtual.faults import FaultInjector
from sim.virtual.physics.streams import Streams
from tests.conftest import CONFIGS

#: The motor faults every bus must survive the same way.
MOTOR_FAULTS = ("motor_fault", "comm_error")
#: The models of the emulated bus's three motors (each axis names its motor's): an
#: XM430-W350, an XL430-W250 (no current registers, four modes) and an XL330-M288 (its
#: own ranges, a shorter table), so every contract test crosses three control tables.
EMULATED_MODELS = {1: 1020, 2: 1060, 3: 1200}
#: The tracking error (rad) `DynamixelBus.follow` keeps on the emulated X series: a
#: trajectory at half the configured velocity and acceleration (4 rad/s, 40 rad/s²).
EMULATOR_TRACKING_RAD = 0.015


# -- motor buses ---------------------------------------------------------------------


@dataclass
class MotorHarness:
    """``make(fault)`` builds an unopened bus; ``arm()``, called after a `move_to`, makes
    the next `wait_settled` meet ``fault`` mid-move; ``observe()`` reads where the motors
    really are (from the device, not the driver); ``advance(s)`` lets time pass."""

    name: str
    clock: ManualClock
    target: dict[str, float]
    make: Callable[[str | None], MotorBus]
    observe: Callable[[], dict[str, float]]
    faulted_axis: str
    arm: Callable[[], None] = lambda: None
    sync: Callable[[], None] = lambda: None  # wait until the motors have been told everything sent
    #: Each axis's configured acceleration (rad/s²), the set-point period (s) of a
    #: trajectory on this bus, and the tracking error (rad) the backend states for it.
    accelerations: dict[str, float] = field(default_factory=dict)
    period_s: float = 0.0
    tracking_bound: float = 0.0
    #: Changes whenever a goal reaches a motor (the device's own record).
    goals_sent: Callable[[], object] = lambda: None

    def advance(self, seconds: float) -> None:
        self.clock.advance(seconds)


def _sim_motors(rig: Rig, clock: ManualClock) -> MotorHarness:
    # Every axis still moving half-way through the slowest axis's move (the sim's faults
    # strike then): light and detector elevations 51°, azimuth 60°, rotation 120°.
    degrees = {"light_elevation": 51.0, "detector_azimuth": 60.0, "detector_elevation": -51.0}
    target = {a: math.radians(degrees.get(a, 120.0)) for a in rig.axes}
    buses: list[SimMotorBus] = []
    faulted = rig.axes[2]

    def make(fault: str | None) -> MotorBus:
        rules: tuple[FaultRule, ...] = ()
        if fault is not None:
            axis = faulted if fault == "motor_fault" else None
            rules = (FaultRule.model_validate({"kind": fault, "at": 0, "axis": axis}),)
        streams = Streams(0)
        bus = SimMotorBus(rig, clock, streams=streams, faults=FaultInjector(rules, streams))
        buses.append(bus)
        return bus

    return MotorHarness(
        "sim", clock, target, make, lambda: buses[-1].true_positions(), faulted_axis=faulted,
        accelerations=dict(zip(rig.axes, rig.acceleration.tolist(), strict=True)),
        period_s=setpoint_period(len(rig.axes), rig.spec.bus.baud),
        tracking_bound=1e-9,  # ideal tracking, no encoder ticks without the position_error effect
        goals_sent=lambda: buses[-1].moves_of(0),
    )  # fmt: skip


def _dynamixel_motors(emulator: Callable[..., DxlEmulator], latency_ms: int) -> MotorHarness:
    config = [
        AxisConfig(
            name=f"axis{i}", motor_id=i, min_rad=-1.0, max_rad=1.0, zero_offset_rad=-math.pi,
            profile_velocity_rad_s=4.0, profile_acceleration_rad_s2=40.0,
            model=EMULATED_MODELS[i],
        )
        for i in (1, 2, 3)
    ]  # fmt: skip
    emu = emulator(ids=(1, 2, 3), model=EMULATED_MODELS)
    clock = emu.clock
    assert isinstance(clock, ManualClock)
    state: dict[str, Any] = {}

    def make(fault: str | None) -> MotorBus:
        state["fault"] = fault
        # A lost reply must surface as the injected fault; other cases keep the driver's
        # retries, so that a reply late on a loaded machine does not fail their set-up.
        retries = 0 if fault == "comm_error" else 3
        bus = DynamixelBus(emu.path, config, latency_ms=latency_ms, retries=retries, clock=clock)
        state["bus"] = bus
        return bus

    def arm() -> None:
        state["bus"].health()  # a read: the goals have been served
        clock.advance(0.1)  # mid-move
        if state["fault"] == "motor_fault":
            emu.inject(Fault.OVERLOAD, motor_id=3)
        elif state["fault"] == "comm_error":
            emu.inject(Fault.NO_REPLY, motor_id=1, count=1)  # the poll's reply is lost

    def observe() -> dict[str, float]:
        return {a.name: a.to_rad(emu.motors[a.motor_id].get("present_position")) for a in config}

    return MotorHarness(
        "dynamixel", clock, {"axis1": 0.8, "axis2": -0.8, "axis3": 0.5}, make, observe,
        faulted_axis="axis3", arm=arm, sync=lambda: state["bus"].health(),
        accelerations=dict.fromkeys(("axis1", "axis2", "axis3"), 40.0),
        period_s=setpoint_period(3, FACTORY_BAUD), tracking_bound=EMULATOR_TRACKING_RAD,
        goals_sent=lambda: [emu.motors[i].goals_written for i in (1, 2, 3)],
    )  # fmt: skip


@pytest.fixture(params=["sim", "dynamixel"])
def motors(
    request: pytest.FixtureRequest,
    rigs: dict[str, Rig],
    clock: ManualClock,
    emulator: Callable[..., DxlEmulator],
    latency_timer: int,
) -> MotorHarness:
    if request.param == "sim":
        return _sim_motors(rigs["arch"], clock)
    return _dynamixel_motors(emulator, latency_timer)


# -- detectors ---------------------------------------------------------------------------


@dataclass
class DetectorHarness:
    """``make(saturating)`` builds an unopened detector whose signal saturates a 1 s
    exposure or not; ``activity()`` changes whenever the detector exposes or talks;
    ``silence()`` (None: the backend cannot be silenced) makes the last one made stop
    streaming without a word."""

    name: str
    make: Callable[[bool], Detector]
    activity: Callable[[], object]
    clock_now: Callable[[], float]
    closers: list[Callable[[], None]] = field(default_factory=list)
    silence: Callable[[], None] | None = None


def _sim_detector(rig: Rig, clock: ManualClock) -> DetectorHarness:
    scenes = CONFIGS / "scenes"
    # The mirror geometry on the arch rig: light 30° one side, detector 30° the other.
    pose = dict(zip(rig.axes, (math.radians(30.0), 0.0, math.radians(-30.0), 0.0), strict=True))

    def make(saturating: bool) -> Detector:
        scene = load_scene(scenes / ("glossy_metal.yaml" if saturating else "matte.yaml"))
        return SimDetector(
            scene, rig, lambda: pose, clock=clock, streams=Streams(1), light=SimLightSource()
        )

    return DetectorHarness("sim", make, clock.now, clock.now)


def _serial_detector() -> Iterator[DetectorHarness]:
    devices: list[SerialPhotometer] = []

    def make(saturating: bool) -> Detector:
        device = SerialPhotometer(2e6 if saturating else 2e4, full_scale=65535.0)
        device.start()
        devices.append(device)
        config = device.config(stream=STREAM_CONFIG)
        return SerialDetector(config, exposure_range_s=(1e-3, 10.0))

    def activity() -> object:
        return [len(d.commands) for d in devices]

    yield DetectorHarness(
        "serial", make, activity, time.monotonic, silence=lambda: devices[-1].silent()
    )
    for device in devices:
        device.stop()
        assert device.error is None


#: The PyMeasure classes the contract runs on, by a short name.
INSTRUMENTS = {
    "sr830": "pymeasure.instruments.srs.SR830",
    "sr860": "pymeasure.instruments.srs.SR860",
    "pm100usb": "pymeasure.instruments.thorlabs.ThorlabsPM100USB",
    "keithley6517b": "pymeasure.instruments.keithley.Keithley6517B",
    "keithley2000": "pymeasure.instruments.keithley.Keithley2000",
}


def _pymeasure_detector(name: str) -> Iterator[DetectorHarness]:
    # The optional extra: skipped, not failed, where it is not installed.
    pytest.importorskip("pymeasure")
    from drivers.pymeasure.detector import PyMeasureDetector
    from gonio.rig.lab_instrument import PyMeasureInterfaceSpec

    speedup = 100.0
    clock = ScaledClock(speedup)
    cls = INSTRUMENTS[name]
    emulator, top = EMULATORS[cls], FULL_SCALE[cls]
    devices = []

    def make(saturating: bool) -> Detector:
        # A saturating signal is far beyond the largest range; else a tenth of the default.
        value = 1e6 * top if saturating else 0.1 * top
        device = emulator(lambda t: value, speedup=speedup)
        device.start()
        devices.append(device)
        spec = PyMeasureInterfaceSpec.model_validate({
            "kind": "pymeasure", "instrument": cls, "resource": f"ASRL{device.path}::INSTR",
            "visa_library": "@py", "read_termination": emulator.terminator, "timeout_s": 0.5,
            # the power meter clips at its sensor's range: that is its full scale
            **({"full_scale": top} if name == "pm100usb" else {}),
        })  # fmt: skip
        return PyMeasureDetector(spec.config(), clock=clock, exposure_range_s=(1e-3, 10.0))

    def activity() -> object:
        return [len(d.commands) for d in devices]

    yield DetectorHarness(name, make, activity, clock.now)
    for device in devices:
        device.stop()
        assert device.error is None


@pytest.fixture(params=["sim", "serial", *INSTRUMENTS])
def detectors(
    request: pytest.FixtureRequest, rigs: dict[str, Rig], clock: ManualClock
) -> Iterator[DetectorHarness]:
    if request.param == "sim":
        yield _sim_detector(rigs["arch"], clock)
    elif request.param == "serial":
        yield from _serial_detector()
    else:
        yield from _pymeasure_detector(request.param)


# -- light sources -----------------------------------------------------------------------


@dataclass
class LightHarness:
    """``make()`` builds an unopened light source; ``device_on()`` reads the device's own
    state (the lamp behind the relay)."""

    name: str
    make: Callable[[], LightSource]
    device_on: Callable[[], bool]


@pytest.fixture(params=["sim", "serial"])
def lights(request: pytest.FixtureRequest) -> Iterator[LightHarness]:
    if request.param == "sim":
        made: list[SimLightSource] = []

        def make_sim() -> LightSource:
            made.append(SimLightSource())
            return made[-1]

        yield LightHarness("sim", make_sim, lambda: made[-1].is_on)
        return
    with SerialLamp() as lamp:
        yield LightHarness("serial", lambda: SerialLightSwitch(lamp.config()), lambda: lamp.is_on)
        assert lamp.error is None
