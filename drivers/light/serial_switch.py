"""`SerialLightSwitch`: a light source (lamp, shutter, relay) switched by line commands.

The host sends ``on`` or ``off`` (one line each); the device answers a line matching
``ack``, or a line matching ``error_reply`` (refused), and the switch is done only once
acknowledged (with ``ack`` None nothing is read: the switch is done once sent). ``is_on``
is the state last acknowledged; on open it is asked with ``query`` when the device has
one (the answer matches ``on_reply`` or ``off_reply``), else it is False until the
first switch, since nothing is assumed about a device just opened. After switching on the driver
waits ``warmup_s`` on its clock, for a lamp that needs time to stabilize (waits for an
answer are in real time: they are the port's). A missing or
refused acknowledgement is sent again up to ``retries`` more times, then raises
`LightError`; on a closed switch `on` and `off` raise `DeviceClosed`. ``close`` leaves
the light as it is and releases the port (idempotent).
"""

from __future__ import annotations

import contextlib
import re
import time
from typing import Any

import serial

from drivers.base import Clock, SystemClock
from drivers.devices import Resource
from drivers.errors import DeviceClosed, LightError
from drivers.light.config import SerialLightConfig

_POLL_S = 0.02  # the serial read timeout: how late a deadline may be noticed


class SerialLightSwitch(Resource):
    """A `drivers.base.LightSource` on a serial line (see the module docstring)."""

    def __init__(self, config: SerialLightConfig, *, clock: Clock | None = None) -> None:
        self.config = config
        self._clock: Clock = clock or SystemClock()
        self._ack = _compiled(config.ack)
        self._refused = _compiled(config.error_reply)
        self._on_reply = _compiled(config.on_reply)
        self._off_reply = _compiled(config.off_reply)
        self._serial: Any = None
        self._rx = bytearray()
        self._on = False

    @property
    def port(self) -> str:
        return self.config.port

    @property
    def is_open(self) -> bool:
        return self._serial is not None

    @property
    def is_on(self) -> bool:
        return self._on

    def open(self) -> None:
        if self._serial is not None:
            return
        try:
            self._serial = serial.serial_for_url(
                self.config.port,
                baudrate=self.config.baud,
                timeout=_POLL_S,
                write_timeout=self.config.timeout_s,
                exclusive=True,
            )
        except (OSError, ValueError, serial.SerialException) as exc:
            raise LightError(f"light switch {self.port}: cannot open the port: {exc}") from exc
        self._rx.clear()
        self._on = False
        if self.config.query is not None:
            try:
                self._on = self._ask_state()
            except BaseException:
                self.close()
                raise

    def _ask_state(self) -> bool:
        assert self.config.query is not None
        assert self._on_reply is not None and self._off_reply is not None
        answer = self._exchange(self.config.query, (self._on_reply, self._off_reply))
        if answer is not None and self._on_reply.search(answer):
            return True
        if answer is not None and self._off_reply.search(answer):
            return False
        problem = "no answer" if answer is None else f"the answer {answer[:80]!r}"
        raise LightError(
            f"light switch {self.port}: {self.config.query!r} did not say whether the light "
            f"is on ({problem})"
        )

    def close(self) -> None:
        port, self._serial = self._serial, None
        if port is None:
            return
        with contextlib.suppress(Exception):
            port.reset_output_buffer()
        with contextlib.suppress(Exception):
            port.close()

    def on(self) -> None:
        self._switch(True)
        self._clock.sleep(self.config.warmup_s)

    def off(self) -> None:
        self._switch(False)

    def _switch(self, on: bool) -> None:
        command = self.config.on if on else self.config.off
        if self._ack is None:  # a device that never answers: sent is switched
            self._exchange(command, ())
            self._on = on
            return
        problem = "no answer"
        for _ in range(self.config.retries + 1):
            answer = self._exchange(command, (self._ack,))
            if answer is not None and self._ack.search(answer):
                self._on = on
                return
            problem = "no answer" if answer is None else f"the answer {answer[:80]!r}"
        raise LightError(
            f"light switch {self.port}: {command!r} was not acknowledged after "
            f"{self.config.retries + 1} attempt(s) ({problem}); the light's state is unknown"
        )

    def _exchange(self, command: str, expected: tuple[re.Pattern[str], ...]) -> str | None:
        """Send ``command``; the first line matching one of ``expected`` or the refusal
        pattern, or None at the deadline (nothing is read when ``expected`` is empty)."""
        if self._serial is None:
            raise DeviceClosed(f"light switch {self.port} is not open")
        try:
            with contextlib.suppress(Exception):
                self._serial.reset_input_buffer()
            self._rx.clear()
            self._serial.write((command + self.config.line_ending).encode("ascii"))
            self._serial.flush()
            if not expected:
                return None
            patterns = (*expected, self._refused) if self._refused else expected
            return self._answer(patterns)
        except (OSError, serial.SerialException) as exc:
            self.close()
            raise LightError(f"light switch {self.port}: the port failed: {exc}") from exc

    def _answer(self, patterns: tuple[re.Pattern[str], ...]) -> str | None:
        deadline = time.monotonic() + self.config.timeout_s  # I/O waits in real time
        while time.monotonic() < deadline:
            self._rx += self._serial.read(256)
            while (end := _line_end(self._rx)) >= 0:
                text = self._rx[:end].decode("ascii", "replace").strip()
                del self._rx[: end + 1]
                if text and any(p.search(text) for p in patterns):
                    return text
        return None


def _compiled(pattern: str | None) -> re.Pattern[str] | None:
    return None if pattern is None else re.compile(pattern)


def _line_end(buffer: bytearray) -> int:
    ends = [i for i in (buffer.find(b"\n"), buffer.find(b"\r")) if i >= 0]
    return min(ends) if ends else -1
