"""The rehearsal backend of `gonio acquire --rehearse`: the real drivers, built from
the rig file as for hardware (`gonio.workflows.hardware`), wired to the simulated peers
of `sim.rehearsal` on pseudo-terminals.

Time runs ``speedup`` times faster than real time (motion profiles, settle dwells and
exposures alike); waits for serial answers are real time, as they are the ports'. The
scene's injected faults are not applied (inject faults into the peers instead).
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import ExitStack, contextmanager

from drivers.base import Detector, LightSource
from drivers.devices import Devices
from gonio.rig import PyMeasureInterfaceSpec, Rig, SerialSwitchSpec
from gonio.scene import Scene
from gonio.workflows.hardware import (
    dynamixel_bus,
    light_switch,
    pymeasure_detector,
    serial_detector,
)
from sim.clock import ScaledClock
from sim.rehearsal import (
    Peers,
    RehearsalSide,
    emulated_bus,
    emulated_pose,
    emulated_trajectory,
    instrument_for,
    lamp_for,
    photometer_for,
)
from sim.virtual import LightState, SimDetector, SimLightSource, Streams


@contextmanager
def rehearsal_devices(
    rig: Rig, scene: Scene, seed: int | None, speedup: float, *, wire_time: bool = False
) -> Iterator[tuple[Devices, ScaledClock]]:
    """The peers running (stopped on exit) and the unopened `Devices` driving them (their
    ``simulation`` is a `RehearsalSide`). ``wire_time``: the emulated bus answers when a
    real one would (`sim.rehearsal.emulated_bus`)."""
    clock = ScaledClock(speedup)
    streams = Streams(scene.seed if seed is None else seed)
    axes = rig.bus_axes()
    with ExitStack() as stack:
        emulator = stack.enter_context(emulated_bus(rig, clock, wire_time=wire_time))
        bus = dynamixel_bus(rig, port=emulator.path, clock=clock)
        switch = rig.spec.light.switch
        light: LightSource
        state: LightState
        lamp = photometer = instrument = None
        if isinstance(switch, SerialSwitchSpec):
            lamp = stack.enter_context(lamp_for(rig, switch))
            driver = light_switch(rig, clock, port=lamp.path)
            assert driver is not None  # the switch is serial
            light, state = driver, lamp
        else:
            light = state = SimLightSource()
        truth, truth_at = emulated_pose(emulator, axes), emulated_trajectory(emulator, axes)
        interface = rig.spec.detector.interface
        serial = interface.kind == "serial"
        physics = SimDetector(
            scene,
            rig,
            truth if interface.kind != "simulated" else bus.positions,
            clock=clock,
            streams=streams,
            light=state,
            pose_at=truth_at,
        )
        if isinstance(interface, PyMeasureInterfaceSpec):
            instrument = stack.enter_context(instrument_for(rig, interface, physics, clock))
            detector: Detector = pymeasure_detector(
                rig, clock, resource=f"ASRL{instrument.path}::INSTR", visa_library="@py"
            )
        elif serial:
            photometer = stack.enter_context(photometer_for(rig, physics, clock))
            detector = serial_detector(rig, clock, port=photometer.path)
        else:
            detector = physics
        side = RehearsalSide(
            physics, truth, Peers(emulator, photometer, lamp, instrument), pose_at=truth_at
        )
        yield Devices(bus, detector, clock, light, side), clock
