"""The transport every emulated instrument shares: a pseudo-terminal served by the
line server the simulated photometer also holds (`sim.peers.line_server`), ``;``-separated
commands, queries answered after the instrument's integration time, a refused command
left unanswered and recorded in the instrument's event status
(`sim.peers.visa_instruments.registers`), and the faults a test injects (silence, garbage,
slow answers, late ones)."""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field

from sim.peers.line_server import LineServer, ServedPeer
from sim.peers.visa_instruments.registers import EventStatus, Refused

#: The reading of one integration of t seconds, in the instrument's unit.
Signal = Callable[[float], float]


@dataclass
class _Faults:
    silent: bool = False
    garbage: int = 0
    slow_s: float = 0.0
    late: deque[float] = field(default_factory=deque)


class EmulatedInstrument(ServedPeer):
    """An instrument's command set on a pseudo-terminal (subclasses: the dialects).

    ``signal(t)`` is the reading of an integration of ``t`` s; ``speedup``: an
    integration of t s takes t / ``speedup`` real seconds (a rehearsal's scaled time);
    ``terminator``: what ends each answer. Subclasses implement `answer`.
    """

    identity = "gonio-sim instrument"
    #: What ends its answers by default.
    terminator = "\n"

    def __init__(
        self, signal: Signal, *, speedup: float = 1.0, terminator: str | None = None
    ) -> None:
        if not speedup > 0:
            raise ValueError(f"speedup must be > 0, got {speedup!r}")
        self._signal = signal
        self._speedup = float(speedup)
        self._terminator = terminator or self.terminator
        self._faults = _Faults()
        self._busy_until = 0.0
        self._commands: list[str] = []
        self.status = EventStatus()
        # The pty's slave end is not held: until a host opens it no process has it open
        # (``fuser``/``lsof`` name none), as a real instrument's port.
        super().__init__(
            LineServer(type(self).__name__, self._handle, self._reset_locked, hold_slave=False)
        )
        self._lock = self._server.lock

    # -- inspection and faults ------------------------------------------------------------

    @property
    def commands(self) -> list[str]:
        """Every command received so far (split at ``;``), in order."""
        with self._lock:
            return list(self._commands)

    def silent(self) -> None:
        """Answer nothing until `clear`."""
        with self._lock:
            self._faults.silent = True

    def garbage(self, count: int = 1) -> None:
        """Answer the next ``count`` queries with text that is not a number."""
        with self._lock:
            self._faults.garbage += count

    def slow(self, seconds: float) -> None:
        """Delay every answer by ``seconds`` more, until `clear`."""
        with self._lock:
            self._faults.slow_s = seconds

    def late(self, seconds: float, count: int = 1) -> None:
        """Send the next ``count`` answers ``seconds`` late; the instrument is busy
        meanwhile, so what it answers after them waits behind them (in order)."""
        if not seconds > 0 or count < 1:
            raise ValueError(f"a late answer needs seconds > 0 and count ≥ 1, got {seconds!r}")
        with self._lock:
            self._faults.late.extend([seconds] * count)

    def clear(self) -> None:
        with self._lock:
            self._faults = _Faults()

    # -- the dialect ------------------------------------------------------------------------

    def answer(self, command: str) -> tuple[str | None, float]:
        """(the answer or None for a command, the integration it takes in s); `Refused`
        for a command the instrument does not know or a value it does not take."""
        raise NotImplementedError

    @property
    def refusals(self) -> list[tuple[int, str]]:
        """The errors queued and not yet read (oldest first)."""
        with self._lock:
            return list(self.status.queue)

    def read_signal(self, integration_s: float) -> float:
        return float(self._signal(integration_s))

    # -- the transport ------------------------------------------------------------------------

    def _reset_locked(self, now: float, *, banner_now: bool = False) -> None:
        self._server.events.clear()

    def _handle(self, line: str, now: float) -> None:
        with self._lock:
            faults = self._faults
            parts = [p.strip() for p in line.split(";") if p.strip()]
            self._commands.extend(parts)
            if faults.silent:
                return
            start = max(now, self._busy_until)
            for part in parts:
                try:
                    reply, integration_s = self.answer(part)
                except Refused as refused:  # unanswered, remembered as the instrument does
                    reply, integration_s = None, 0.0
                    self.status.refuse(refused)
                except Exception as exc:  # a defect of the emulator: reported by .error
                    reply, integration_s = None, 0.0
                    self._server.error = exc
                if reply is None:
                    continue
                done = start + integration_s / self._speedup + faults.slow_s
                done += faults.late.popleft() if faults.late else 0.0
                if faults.garbage:
                    faults.garbage -= 1
                    reply = "#?garbage?#"
                self._busy_until = start = done
                self._server.schedule_locked(done, (reply + self._terminator).encode("ascii"))
        self._server.wakeup()
