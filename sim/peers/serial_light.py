"""A simulated serial light switch (lamp relay or shutter) on a pseudo-terminal, the
peer of `drivers.light.serial_switch.SerialLightSwitch`.

Protocol (lines end in CR LF on the way out; any line ending is accepted in):

- ``ON`` / ``OFF`` → ``OK`` once switched (after ``reply_delay_s``);
- ``STATE?`` → ``ON`` or ``OFF``;
- anything else → ``ERR unknown command: …``.

The three commands can be renamed (``commands``: a rig's ``light.switch`` section, as a
rehearsal wires it); the answers stay ``OK``, ``ON``, ``OFF`` and ``ERR …``.

Faults for tests: `silent` (ignore everything), `refuse` (answer the next switches with
``ERR lamp failure``), `clear`. ``is_on`` can drive a simulated detector's signal, so a
rehearsal's dark reading really is dark.
"""

from __future__ import annotations

from drivers.light import SerialLightConfig
from sim.peers.line_server import LineServer, ServedPeer


class SerialLamp(ServedPeer):
    """A lamp behind a serial relay, off at power-up."""

    def __init__(
        self,
        *,
        reply_delay_s: float = 0.0,
        commands: tuple[str, str, str] = ("ON", "OFF", "STATE?"),
    ) -> None:
        if reply_delay_s < 0:
            raise ValueError("reply_delay_s must be ≥ 0")
        self._words = tuple(c.strip().upper() for c in commands)  # on, off, query
        if len(self._words) != 3 or len(set(self._words)) != 3 or not all(self._words):
            raise ValueError(f"expected three distinct commands (on, off, query), got {commands}")
        self._reply_delay_s = reply_delay_s
        self._on = False
        self._silent = False
        self._refuse = 0
        self._commands: list[str] = []
        super().__init__(LineServer("lamp", self._handle, self._reset_locked))
        self._lock = self._server.lock

    # -- configuration -------------------------------------------------------------

    def config(self, **overrides: object) -> SerialLightConfig:
        """The driver configuration that speaks this protocol."""
        fields: dict[str, object] = {
            "port": self.path,
            "timeout_s": 0.5,
            "query": "STATE?",
            "on_reply": "^ON$",
            "off_reply": "^OFF$",
            **overrides,
        }
        return SerialLightConfig(**fields)  # type: ignore[arg-type]

    @property
    def is_on(self) -> bool:
        with self._lock:
            return self._on

    @property
    def commands(self) -> list[str]:
        with self._lock:
            return list(self._commands)

    def silent(self) -> None:
        with self._lock:
            self._silent = True

    def refuse(self, count: int = 1) -> None:
        with self._lock:
            self._refuse += count

    def clear(self) -> None:
        with self._lock:
            self._silent, self._refuse = False, 0

    def _reset_locked(self, now: float, *, banner_now: bool = False) -> None:
        self._server.events.clear()

    def _handle(self, line: str, now: float) -> None:
        with self._lock:
            self._commands.append(line)
            if self._silent:
                return
            word = line.strip().upper()
            on, off, query = self._words
            if word in (on, off):
                if self._refuse:
                    self._refuse -= 1
                    answer = "ERR lamp failure"
                else:
                    self._on = word == on
                    answer = "OK"
            elif word == query:
                answer = "ON" if self._on else "OFF"
            else:
                answer = f"ERR unknown command: {line}"
            reply = (answer + "\r\n").encode("ascii", "replace")
            self._server.schedule_locked(now + self._reply_delay_s, reply)
