"""One target, measured through the `drivers.base` contract: move (a pose outside the
axis limits is refused by the bus before anything is sent: the contract), wait until the
motion stopped, wait the rig's settle dwell, read the positions back, measure.

The settle dwell is waited here, on the devices' clock, exactly once per target: the
planner's predicted time (`gonio.planner.builder`) counts it the same way (travel + settle
+ exposure × averages, and the bus's part of the step on a Dynamixel rig). A simulated
backend is told which sample comes next (its random streams and injected faults)
through `drivers.base.Simulated`, when it offers it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from drivers.devices import Devices
from drivers.values import Reading

#: How long one move may take before `wait_settled` gives up (s).
MOVE_TIMEOUT_S = 600.0


@dataclass(frozen=True)
class TargetReading:
    """What one target gave: the read-back joint angles (rad), the true ones when the
    backend is simulated (else None), the time the exposures could start (s, after the
    settle dwell) and the reading."""

    read_back: dict[str, float]
    true: dict[str, float] | None
    settled_s: float
    reading: Reading


def measure_target(
    devices: Devices,
    index: int,
    pose: Mapping[str, float],
    exposure_s: float,
    averages: int,
    *,
    settle_s: float,
    timeout_s: float = MOVE_TIMEOUT_S,
) -> TargetReading:
    """Move to ``pose`` (rad per axis), settle, measure sample ``index``."""
    simulation = devices.simulation
    if simulation is not None:
        simulation.begin_sample(index)
    bus = devices.bus
    bus.move_to(pose)
    bus.wait_settled(timeout_s)
    devices.clock.sleep(settle_s)
    settled = devices.clock.now()
    read_back = bus.positions()
    true = simulation.true_positions() if simulation is not None else None
    return TargetReading(read_back, true, settled, devices.detector.measure(exposure_s, averages))


def reading_fields(reading: Reading, asked_s: float, offset_s: float) -> dict[str, Any]:
    """What the journal keeps of a reading: its spread (None where the device gave none),
    the exposure the device integrated (``asked_s`` unless it says otherwise) and its
    start and end in run time (clock + ``offset_s``)."""
    return {
        "std": reading.std if math.isfinite(reading.std) else None,
        "exposure_s": asked_s if reading.exposure_s is None else reading.exposure_s,
        "started_s": reading.started_s + offset_s,
        "ended_s": reading.ended_s + offset_s,
    }
