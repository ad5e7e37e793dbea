"""A byte-level Dynamixel Protocol 2.0 bus of X-series motors on a real pseudo-terminal.

`DxlEmulator` holds a `sim.peers.pty_host.PtyHost` (the slave end kept open, to read
the rate the host set with termios) and serves the master end from its thread: bytes are
split into packets by `PacketReader`, executed by
:func:`sim.peers.dynamixel.instructions.handle`, and the status packets are written back
by its `sim.peers.dynamixel.line.Line` after the time they would take on the wire (10
bits per byte at the bus rate) and each motor's Return Delay Time; its
`sim.peers.dynamixel.traffic.Traffic` counts what crossed. A motor whose Baud Rate
register differs from the host's tty rate neither hears nor answers. Faults can be
injected: lost, corrupt or misaddressed replies, noise, a silent bus, hardware alerts.

Run standalone: ``python -m sim.dynamixel.emulator --ids 1,2,3,4 [--baud 57600]``.
"""

from __future__ import annotations

import argparse
import os
import select
import signal
import sys
import threading
import time
from collections.abc import Iterable, Mapping, Sequence
from types import FrameType, TracebackType
from typing import Self

from drivers.dynamixel import BAUD_RATES, MODEL_NAMES, model_number
from sim.clock import ManualClock, ScaledClock, TimeSource
from sim.peers.dynamixel.faults import Fault, FaultBook
from sim.peers.dynamixel.instructions import Reply, Response, handle
from sim.peers.dynamixel.instructions import instruction_name as _name
from sim.peers.dynamixel.line import BITS_PER_BYTE, Line
from sim.peers.dynamixel.motor import EmulatedMotor
from sim.peers.dynamixel.protocol import (
    BROADCAST_ID,
    CorruptPacket,
    CRCError,
    Packet,
    PacketReader,
    StatusError,
)
from sim.peers.dynamixel.traffic import BusStats, Traffic
from sim.peers.dynamixel.tty import set_raw, tty_rate
from sim.peers.pty_host import PtyHost

__all__ = [
    "BITS_PER_BYTE",
    "BusStats",
    "DxlEmulator",
    "EmulatedMotor",
    "Fault",
    "ManualClock",
    "main",
]

# -- the emulator -------------------------------------------------------------------------


class DxlEmulator:
    """N X-series motors answering Protocol 2.0 on a pseudo-terminal.

    ``ids`` are the motors' IDs (0-252), all of ``model`` (a model number or name, e.g.
    ``"XL430-W250"``; or {ID: model} for a bus of several models) with ``firmware``,
    listening at ``baud`` (a rate of every motor's model). ``clock`` drives the motion (default
    `time.monotonic`; a `ManualClock` in tests). ``wire_time`` and ``return_delay``
    make replies wait as on a real bus; ``record`` keeps a transcript.
    """

    def __init__(
        self,
        ids: Iterable[int] = (1,),
        model: int | str | Mapping[int, int | str] = 1020,
        baud: int = 57_600,
        clock: TimeSource | None = None,
        wire_time: bool = True,
        return_delay: bool = True,
        *,
        firmware: int = 46,
        record: bool = False,
    ) -> None:
        ids = tuple(ids)
        if not ids or len(set(ids)) != len(ids) or not all(0 <= i <= 252 for i in ids):
            raise ValueError(f"ids must be distinct integers 0-252, got {ids}")
        if baud not in BAUD_RATES.values():
            raise ValueError(f"{baud} baud is not an X-series rate: {sorted(BAUD_RATES.values())}")
        self.baud = baud
        self.clock: TimeSource = clock if clock is not None else time.monotonic
        self.wire_time = wire_time
        self.return_delay = return_delay
        self._lock = threading.RLock()
        models = model if isinstance(model, Mapping) else dict.fromkeys(ids, model)
        if set(models) != set(ids):
            raise ValueError(f"models {dict(models)} must name exactly the ids {ids}")
        self._motors = [
            EmulatedMotor(
                i,
                model=model_number(models[i]),
                firmware=firmware,
                baud=baud,
                clock=self.clock,
                lock=self._lock,
            )
            for i in ids
        ]
        self._faults = FaultBook()
        self._silent = False
        self._traffic = Traffic(self._lock, record)
        self._pty = PtyHost(
            self._serve, "dxl-emulator", configure=lambda fd: set_raw(fd, baud), join_s=2.0
        )
        self._stopping = self._pty.stopping
        self._line = Line(self._pty, self._lock, self._faults, self._traffic, baud, self.host_baud)
        #: The last exception raised while serving a packet (the thread keeps serving).
        self.error: BaseException | None = None

    # -- lifecycle ----------------------------------------------------------------------

    def start(self) -> str:
        """Open the pty, start serving, and return the slave's path (e.g. /dev/pts/5)."""
        return self._pty.start()

    def stop(self) -> None:
        """Stop serving and close the pty (idempotent; never blocks for long)."""
        self._pty.stop()

    def __enter__(self) -> Self:
        self.start()
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.stop()

    # -- inspection ---------------------------------------------------------------------

    @property
    def path(self) -> str:
        """The pty slave a client opens (after `start`)."""
        return self._pty.path

    @property
    def motors(self) -> dict[int, EmulatedMotor]:
        """The motors by their present ID."""
        with self._lock:
            return {m.id: m for m in self._motors}

    @property
    def stats(self) -> BusStats:
        """A snapshot of the traffic counters."""
        return self._traffic.snapshot()

    def totals(self) -> tuple[int, int]:
        """Bytes read from the host and bytes written to it since the emulator was made
        (running totals: `reset_stats` leaves them)."""
        return self._traffic.totals()

    def wait_served(self, heard: int, timeout: float) -> bool:
        """Wait until the emulator has read ``heard`` bytes from the host in all (the
        first of `totals`) and served every packet among them, their replies written to
        the pty (late ones included); False if ``timeout`` (s) passed first. A host
        that knows what it sent then knows every byte the bus will answer with."""
        return self._traffic.wait_served(heard, timeout)

    def reset_stats(self) -> None:
        self._traffic.reset_stats()

    @property
    def transcript(self) -> list[tuple[str, bytes]]:
        """``("rx", bytes)`` read from the host and ``("tx", bytes)`` written to it, in
        order (empty unless created with ``record=True``)."""
        return self._traffic.transcript()

    def goals_written(self) -> dict[int, list[int]]:
        """Every Goal Position value (ticks) the host has written to each motor, by ID,
        oldest first (`EmulatedMotor.goals_written`)."""
        with self._lock:
            return {m.id: m.goals_written for m in self._motors}

    def clear_goals(self) -> None:
        with self._lock:
            for motor in self._motors:
                motor.clear_goals()

    def host_baud(self) -> int | None:
        """The rate the host has set on the tty (bits/s)."""
        slave = self._pty.slave
        return tty_rate(slave) if slave is not None else None

    # -- faults -------------------------------------------------------------------------

    def inject(
        self,
        fault: Fault,
        motor_id: int | None = None,
        count: int | None = 1,
        *,
        delay_ms: float = 0.0,
    ) -> None:
        """Cause ``fault`` on motor ``motor_id`` (None: every motor).

        Reply faults affect that motor's next ``count`` status packets (None: all of them
        until `clear_faults`); `Fault.LATE` sends each ``delay_ms`` (ms) late, and the bus
        behind it waits (bytes keep their order). Hardware alerts latch until REBOOT.
        `Fault.SILENT` mutes the whole bus (nothing is heard or answered) until
        `clear_faults`.
        """
        with self._lock:
            if fault is Fault.SILENT:
                self._silent = True
                return
            targets = self._motors if motor_id is None else [self._motor(motor_id)]
            bit = fault.alert_bit
            if bit is not None:
                for motor in targets:
                    motor.raise_alert(bit)
                return
            for motor in targets:
                self._faults.add(motor, fault, count, delay_ms / 1000.0)

    def inject_rate(self, fault: Fault, rate: float, *, seed: int = 0) -> None:
        """Let reply ``fault`` strike every motor's status packets at random, each with
        probability ``rate`` (0 ends it; faults queued by `inject` come first), from a
        generator seeded with ``seed``: a lossy bus (`Fault.NO_REPLY`), a noisy one."""
        with self._lock:
            self._faults.strike(fault, rate, seed)

    def clear_faults(self, *, alerts: bool = False) -> None:
        """End reply faults (queued and at a rate) and `Fault.SILENT`; with ``alerts``,
        also clear every motor's Hardware Error Status (otherwise only REBOOT does, as on
        hardware)."""
        with self._lock:
            self._faults.clear()
            self._silent = False
            if alerts:
                for motor in self._motors:
                    motor.set("hardware_error_status", 0)

    def _motor(self, motor_id: int) -> EmulatedMotor:
        for motor in self._motors:
            if motor.id == motor_id:
                return motor
        raise KeyError(f"no motor with ID {motor_id} on the bus")

    # -- serving ------------------------------------------------------------------------

    def _serve(self) -> None:
        reader = PacketReader()
        master, wake = self._pty.master, self._pty.wake
        while not self._stopping.is_set():
            try:
                ready, _, _ = select.select([master, wake], [], [])
                if wake in ready:
                    return
                data = os.read(master, 4096)
            except (BlockingIOError, InterruptedError):
                continue
            except (OSError, ValueError):  # closed under us by stop(), or EIO
                if self._stopping.wait(0.01):
                    return
                continue
            arrived = time.perf_counter()
            with self._lock:
                self._traffic.heard(data)
                if self._silent:
                    reader.clear()
                    self._traffic.serving(False)
                    continue
                self._traffic.serving(True)
            try:
                reader.feed(data)
                more = True
                while more:
                    try:
                        more = self._next(reader, arrived)
                    except Exception as exc:  # keep serving; tests look at .error
                        self.error = exc
            finally:
                self._traffic.serving(False)

    def _next(self, reader: PacketReader, arrived: float) -> bool:
        """Serve the next complete packet in ``reader`` (False when there is none)."""
        try:
            packet = reader.next_packet()
        except CorruptPacket as exc:
            self._on_corrupt(exc, arrived)
            return True
        if packet is None:
            return False
        self._on_packet(packet, arrived)
        return True

    def _listening(self) -> list[EmulatedMotor]:
        host = self.host_baud()
        return [m for m in self._motors if m.protocol == 2 and (host is None or m.baud == host)]

    def _on_packet(self, packet: Packet, arrived: float) -> None:
        with self._lock:
            stats = self._traffic.stats
            stats.packets_in += 1
            if not packet.is_status:
                stats.instructions[_name(packet.instruction)] += 1
            responses = handle(packet, self._listening())
        size = 10 + len(packet.params)
        self._transmit(responses, arrived, size)

    def _on_corrupt(self, exc: CorruptPacket, arrived: float) -> None:
        """A host packet with a bad CRC, or with FF FF FD not followed by the stuffing FD:
        the addressed motor answers CRC error (3) and executes nothing."""
        packet_id = exc.packet_id
        with self._lock:
            stats = self._traffic.stats
            stats.packets_in += 1
            if isinstance(exc, CRCError):
                stats.crc_errors += 1
            else:
                stats.stuffing_errors += 1
            responses: list[Response] = [
                Reply(m, m.id, m.status_error(StatusError.CRC), b"", m.baud, m.return_delay)
                for m in self._listening()
                if packet_id != BROADCAST_ID and m.id == packet_id and m.status_return_level == 2
            ]
        self._transmit(responses, arrived, 10)

    def _transmit(self, responses: Sequence[Response], arrived: float, size_in: int) -> None:
        """Write ``responses`` to the host as the line would (`Line.transmit`)."""
        self._line.transmit(
            responses, arrived, size_in, wire_time=self.wire_time, return_delay=self.return_delay
        )


# -- command line -------------------------------------------------------------------------


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(2, f"{self.prog}: error: {message}\n")


def _ids(text: str) -> tuple[int, ...]:
    ids: list[int] = []
    try:
        for part in text.split(","):
            low, _, high = part.strip().partition("-")
            ids.extend(range(int(low), int(high or low) + 1))
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"not a list of IDs: {text!r} (e.g. 1,2,3 or 1-4)"
        ) from None
    if not ids or len(set(ids)) != len(ids) or not all(0 <= i <= 252 for i in ids):
        raise argparse.ArgumentTypeError(f"IDs must be distinct and within 0-252: {text!r}")
    return tuple(ids)


def _model(text: str) -> int:
    try:
        return model_number(int(text) if text.strip().isdigit() else text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def _positive(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not value > 0:
        raise argparse.ArgumentTypeError(f"must be a number > 0: {text!r}")
    return value


def main(argv: Sequence[str] | None = None) -> int:
    """Serve a bus until Ctrl-C (or SIGTERM); exit status 0, or 2 for bad arguments."""
    rates = sorted(BAUD_RATES.values())
    parser = _Parser(prog="python -m sim.dynamixel.emulator", description=__doc__.splitlines()[0])
    parser.add_argument("--ids", type=_ids, default=(1,), help="motor IDs, e.g. 1,2,3,4 or 1-4")
    parser.add_argument(
        "--baud", type=int, default=57_600, choices=rates, metavar="RATE", help=f"bits/s: {rates}"
    )
    parser.add_argument(
        "--model",
        type=_model,
        default=1020,
        help=f"model name or number (default 1020, XM430-W350): {', '.join(MODEL_NAMES.values())}",
    )
    parser.add_argument("--firmware", type=int, default=46, help="firmware version")
    parser.add_argument("--speedup", type=_positive, default=1.0, help="motion clock speed-up")
    parser.add_argument("--no-wire-time", action="store_true", help="answer without wire delays")
    args = parser.parse_args(argv)
    if not 0 <= args.model <= 0xFFFF or not 0 <= args.firmware <= 0xFF:
        parser.error("--model must be within 0-65535 and --firmware within 0-255")

    def terminate(signum: int, frame: FrameType | None) -> None:
        raise KeyboardInterrupt

    signal.signal(signal.SIGTERM, terminate)
    emulator = DxlEmulator(
        args.ids,
        model=args.model,
        baud=args.baud,
        clock=ScaledClock(args.speedup) if args.speedup != 1.0 else None,
        wire_time=not args.no_wire_time,
        firmware=args.firmware,
    )
    try:
        path = emulator.start()
        count = len(args.ids)
        print(f"serving {count} motors on {path} at {args.baud} baud; Ctrl-C to stop", flush=True)
        threading.Event().wait()
    except KeyboardInterrupt:
        pass
    finally:
        emulator.stop()
    return 0


if __name__ == "__main__":
    # Started with `&` from a non-interactive shell, the process inherits SIGINT ignored
    # and Python then installs no KeyboardInterrupt handler: restore it, so Ctrl-C (or
    # `kill -INT`) stops the emulator as its banner promises.
    signal.signal(signal.SIGINT, signal.default_int_handler)
    sys.exit(main())
