"""What crossed an emulated Dynamixel bus: the traffic counters (`BusStats`), the
running totals of bytes each way, the transcript, and whether the serving thread is
still serving what it has read (`Traffic.wait_served`)."""

from __future__ import annotations

import dataclasses
import threading
from collections import Counter
from dataclasses import dataclass, field


@dataclass
class BusStats:
    """Traffic counters: packets and bytes each way, host packets with a bad CRC or with
    an unstuffed FF FF FD, and host packets per instruction name (e.g.
    ``instructions["SYNC_READ"]``)."""

    packets_in: int = 0
    packets_out: int = 0
    bytes_in: int = 0
    bytes_out: int = 0
    crc_errors: int = 0
    stuffing_errors: int = 0
    #: Late status packets (`Fault.LATE`) sent, and those of them the host's next
    #: packet had overtaken (it had given up waiting: the reply lands in a later
    #: transaction).
    late: int = 0
    overtaken: int = 0
    instructions: Counter[str] = field(default_factory=Counter)


class Traffic:
    """The bus's traffic, kept under the emulator's ``lock`` (every method takes it):
    ``stats`` (reset by `reset_stats`), the bytes heard from and said to the host since
    creation (`totals`), and the ``("rx" | "tx", bytes)`` transcript when ``record``."""

    def __init__(self, lock: threading.RLock, record: bool) -> None:
        self._lock = lock
        #: Notified each time the serving thread has served what it read (`wait_served`).
        self._served = threading.Condition(lock)
        self._heard = self._said = 0
        self._serving = False
        self.stats = BusStats()
        self._transcript: list[tuple[str, bytes]] | None = [] if record else None

    def heard(self, data: bytes) -> None:
        """Count (and record) ``data`` read from the host."""
        with self._lock:
            self.stats.bytes_in += len(data)
            self._heard += len(data)
            if self._transcript is not None:
                self._transcript.append(("rx", data))

    def said(self, raw: bytes) -> None:
        """Count (and record) one status packet ``raw`` written to the host."""
        with self._lock:
            self.stats.packets_out += 1
            self.stats.bytes_out += len(raw)
            self._said += len(raw)
            if self._transcript is not None:
                self._transcript.append(("tx", raw))

    def late(self, overtaken: bool) -> None:
        """Count a late reply about to leave, ``overtaken`` if the host has sent more since."""
        with self._lock:
            self.stats.late += 1
            self.stats.overtaken += overtaken

    def serving(self, busy: bool) -> None:
        """The serving thread starts (``busy``) or ends serving what it read; at the
        end, wake `wait_served`."""
        with self._lock:
            self._serving = busy
            if not busy:
                self._served.notify_all()

    def wait_served(self, heard: int, timeout: float) -> bool:
        """Wait until ``heard`` bytes in all have been read from the host and every packet
        among them served; False if ``timeout`` (s) passed first."""
        with self._served:
            return self._served.wait_for(
                lambda: self._heard >= heard and not self._serving, timeout
            )

    def snapshot(self) -> BusStats:
        """A copy of the counters."""
        with self._lock:
            return dataclasses.replace(self.stats, instructions=Counter(self.stats.instructions))

    def totals(self) -> tuple[int, int]:
        """Bytes read from the host and bytes written to it since creation."""
        with self._lock:
            return self._heard, self._said

    def reset_stats(self) -> None:
        with self._lock:
            self.stats = BusStats()

    def transcript(self) -> list[tuple[str, bytes]]:
        """The transcript so far (empty unless recording)."""
        with self._lock:
            return list(self._transcript or [])
