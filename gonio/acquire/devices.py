"""`Devices`: the instrument one run drives, through the `drivers.base` contract only.

A backend (hardware, rehearsal or simulation) is built by composition code (the CLI, or
`sim.devices.instrument`) and handed to the engine as a `Devices`: a motor bus, a
detector, an optional switchable light source, the clock they share and, for a
simulated backend, its `drivers.base.Simulated` side. `Devices` is a context manager
that opens them all and closes them all (in reverse order, also on an error), so the
motors hold and every port is released whatever happens.
"""

from __future__ import annotations

from contextlib import ExitStack
from dataclasses import dataclass, field
from types import TracebackType
from typing import Self

from drivers.base import Clock, Detector, LightSource, MotorBus, Simulated


@dataclass
class Devices:
    bus: MotorBus
    detector: Detector
    clock: Clock
    light: LightSource | None = None
    simulation: Simulated | None = None
    _stack: ExitStack = field(default_factory=ExitStack, repr=False)

    def __enter__(self) -> Self:
        with ExitStack() as stack:
            stack.enter_context(self.bus)
            stack.enter_context(self.detector)
            if self.light is not None:
                stack.enter_context(self.light)
            self._stack = stack.pop_all()
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self._stack.__exit__(exc_type, exc, tb)
