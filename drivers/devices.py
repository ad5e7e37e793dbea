"""The lifecycle shared by the backends and the instrument one run drives: `Resource`
(a device as a context manager) and `Devices` (one run's bus, detector, light and clock,
opened and closed together). The rules: `drivers.base`.
"""

from __future__ import annotations

from contextlib import ExitStack
from dataclasses import dataclass, field
from types import TracebackType
from typing import Self

from drivers.base import Clock, Detector, LightSource, MotorBus, Simulated


class Resource:
    """Mixin: a context manager that calls ``open()`` on entry and ``close()`` on exit
    (also on an exception or Ctrl-C). Subclasses implement both; ``close`` must be safe
    to call twice and must release the device whatever state it is in."""

    def open(self) -> None:
        raise NotImplementedError

    def close(self) -> None:
        raise NotImplementedError

    def __enter__(self) -> Self:
        self.open()
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()


@dataclass
class Devices(Resource):
    """The instrument one run drives: a motor bus, a detector, an optional switchable
    light source, the clock they share and, for a simulated backend, its `Simulated`
    side. A context manager that opens them all and closes them all (in reverse order,
    also on an error), so the motors hold and every port is released whatever happens.
    Backends are built by composition code (`gonio.workflows`) and handed to the
    acquisition engine as `Devices`."""

    bus: MotorBus
    detector: Detector
    clock: Clock
    light: LightSource | None = None
    simulation: Simulated | None = None
    _stack: ExitStack = field(default_factory=ExitStack, repr=False)

    def open(self) -> None:
        """Open the bus, the detector and the light; if one fails, close those opened."""
        with ExitStack() as stack:
            stack.enter_context(self.bus)
            stack.enter_context(self.detector)
            if self.light is not None:
                stack.enter_context(self.light)
            self._stack = stack.pop_all()

    def close(self) -> None:
        """Close them in reverse order (safe to call twice)."""
        self._stack.close()
