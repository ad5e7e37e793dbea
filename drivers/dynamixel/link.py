"""One serial port to a Dynamixel bus, through the unmodified ROBOTIS SDK.

`DynamixelLink` owns a port handler and a Protocol 2.0 packet handler (the SDK's
classes with the corrections of :mod:`drivers.dynamixel.sdk_boundary`: byte stuffing
on send, true reply lengths, a per-port latency timer) and turns their result codes
into exceptions: every transaction is retried a bounded number of times on
communication failures, then raises `CommError` naming the port, the motor and the
SDK's result; a status that is not the answer (another motor's, not as long as
requested, more bytes behind it: a late or stale reply) counts as a corrupt packet and
is retried; a status packet with the alert bit makes it read the motor's Hardware
Error Status and raise `MotorFault` with the named bits. The port is locked while open
(two programs on one bus would interleave packets) and always released: also after
Ctrl-C in the middle of a transaction, which would otherwise leave the SDK's
``is_using`` flag set and every later call failing with "port is in use".

Late replies: every attempt that did not end with its answer (a timeout, a bad reply,
Ctrl-C) leaves its replies owed, and the next attempt first syncs the bus
(`drivers.dynamixel.owed`), so a reply to an earlier request is never taken for the
answer to a later one; `late_counts` says how often.

Models: ``tables`` holds each motor's control table once it is known (`DynamixelBus`
sets it from the model number a PING returns); reads and writes then use that model's
items and ranges, and an item the model lacks is refused before anything is sent.

EEPROM: the link remembers each motor's Torque Enable as far as it knows it (written
with a status, read, or just rebooted = exact; sent by SYNC_WRITE = 1 presumed on, 0
unknown) and refuses, before sending, to write an EEPROM item to a motor whose torque
is known or presumed on (`DriverError`): turn torque off and read it back first.

Latency: the port's latency timer covers what the SDK's reply timeouts leave out
(`drivers.dynamixel.latency`).
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import itertools
import os
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import Any, TypeVar

import dynamixel_sdk as sdk
import serial

from drivers.devices import Resource
from drivers.dynamixel.control_table import FACTORY_BAUD, Area, Item, decode_hardware_error, item
from drivers.dynamixel.latency import assumed_adapter_ms, sdk_latency_timer
from drivers.dynamixel.models import Model
from drivers.dynamixel.owed import LateCounts, OwedReplies
from drivers.dynamixel.sdk_boundary import PING_PARAMS, PacketHandler, Port, SyncRead
from drivers.errors import CommError, DriverError, LimitError, MotorFault

#: Result codes worth another attempt (noise, a lost byte, a late reply).
RETRYABLE = frozenset(
    {sdk.COMM_RX_TIMEOUT, sdk.COMM_RX_CORRUPT, sdk.COMM_TX_FAIL, sdk.COMM_RX_FAIL}
)
ALERT = 0x80
#: The error numbers of a status packet, in words (Protocol 2.0).
STATUS_ERRORS = {
    1: "result fail (the motor could not carry out the instruction)",
    2: "instruction error (undefined instruction, or ACTION without REG_WRITE)",
    3: "CRC error (the packet was corrupted on the way)",
    4: "data range error (value outside the item's range)",
    5: "data length error (fewer bytes than the item needs)",
    6: "data limit error (value outside the motor's configured limit)",
    7: "access error (read-only item, an address the model lacks, or an EEPROM item "
    "written with torque on)",
}

T = TypeVar("T")


class DynamixelLink(Resource):
    """A Protocol 2.0 bus on ``port`` at ``baud``; a context manager.

    ``names`` maps motor IDs to axis names for error messages; ``retries`` is the number
    of extra attempts per transaction; ``latency_ms`` is the USB adapter's latency timer
    (default: read from sysfs, else 16 ms; 0 for a pty);
    ``raise_alerts=False`` lets a diagnostic tool read a faulted motor (the alert bit is
    then ignored; read Hardware Error Status to see it).
    """

    def __init__(
        self,
        port: str,
        baud: int = FACTORY_BAUD,
        *,
        retries: int = 3,
        latency_ms: float | None = None,
        names: Mapping[int, str] | None = None,
        raise_alerts: bool = True,
    ) -> None:
        if retries < 0:
            raise ValueError("retries must be ≥ 0")
        self.port_name = port
        self.baud = baud
        self.retries = retries
        self.latency_ms = latency_ms
        self.names = dict(names or {})
        self.raise_alerts = raise_alerts
        self._port: Any = None
        self._packets: Any = PacketHandler()
        #: Torque Enable per motor as far as the link knows (True also when presumed on
        #: after a SYNC_WRITE; absent when unknown).
        self._torque: dict[int, bool] = {}
        #: Each motor's control table, where its model is known (else the XM430-W350's).
        self.tables: dict[int, Model] = {}
        #: Replies the bus may still send (failed or interrupted attempts).
        self._owed = OwedReplies()

    # -- opening and releasing -----------------------------------------------------------
    @property
    def is_open(self) -> bool:
        return self._port is not None

    @property
    def latency_timer_ms(self) -> float:
        """The latency timer (ms) of this link's reply timeouts (SDK: 2 × it + 2 ms +
        the reply's wire time)."""
        return sdk_latency_timer(assumed_adapter_ms(self.port_name, self.latency_ms), self.baud)

    def open(self) -> None:
        """Open and lock the port at the configured baud; `CommError` if it cannot."""
        if self._port is not None:
            return
        handler = Port(self.port_name, self.latency_timer_ms)
        handler.baudrate = self.baud
        try:
            ok = handler.setBaudRate(self.baud)  # opens the port
        except (serial.SerialException, OSError) as exc:
            raise CommError(self._open_failure(exc), port=self.port_name) from None
        if not ok:
            raise CommError(
                f"{self.port_name}: baud rate {self.baud} is not one the Dynamixel SDK supports",
                port=self.port_name,
            )
        try:
            fcntl.flock(handler.ser.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            handler.closePort()
            raise CommError(
                f"{self.port_name} is busy: another program holds it open (close it first)",
                port=self.port_name,
            ) from None
        self._port = handler
        self._torque.clear()
        self._owed.clear()

    def _open_failure(self, exc: BaseException) -> str:
        code = getattr(exc, "errno", None)
        if code == errno.ENOENT or not os.path.exists(self.port_name):
            return f"{self.port_name} does not exist: is the USB adapter plugged in?"
        if code in (errno.EACCES, errno.EPERM):
            return f"no permission to open {self.port_name}: add your user to the 'dialout' group"
        if code == errno.EBUSY:
            return f"{self.port_name} is busy: another program holds it open"
        return f"cannot open {self.port_name}: {exc}"

    def close(self) -> None:
        """Release the port; safe to call twice and after an interrupted transaction."""
        handler, self._port = self._port, None
        if handler is None:
            return
        handler.is_using = False
        with contextlib.suppress(serial.SerialException, OSError):
            handler.closePort()

    @property
    def late_counts(self) -> LateCounts:
        """Syncs made, status packets they discarded, syncs that timed out (since the
        link was made)."""
        return self._owed.counts

    def reset(self) -> None:
        """Forget a transaction cut short (Ctrl-C): clear the SDK's busy flag and the
        input. A reply still on its way is owed: the next transaction syncs first."""
        port = self._port
        if port is None:
            return
        port.is_using = False
        with contextlib.suppress(serial.SerialException, OSError):
            port.clearPort()

    # -- transactions ----------------------------------------------------------------------
    def _handler(self) -> Any:
        if self._port is None:
            raise CommError(f"{self.port_name} is not open", port=self.port_name)
        return self._port

    def who(self, motor_id: int) -> str:
        name = self.names.get(motor_id)
        return f"motor {motor_id}" + (f" (axis {name!r})" if name else "")

    def _attempt(
        self,
        what: str,
        motor_id: int | None,
        call: Callable[[], tuple[T, int]],
        replies: Sequence[int] = (),
        via: int | None = None,
    ) -> T:
        """Run ``call`` (returning (value, SDK result)) with retries; CommError at the end.

        ``replies``: the parameter counts of the status packets it waits for (none: it
        waits for none, and a sync before it is left to the next that does); ``via``:
        the motor a sync before it reads (default ``motor_id``: the one it talks to).
        """
        handler = self._handler()
        result = sdk.COMM_SUCCESS
        sync_via = motor_id if via is None else via
        for _ in range(self.retries + 1):
            try:
                if replies and self._owed and sync_via is not None:
                    result = self._owed.sync(handler, self._packets, sync_via, self.baud)
                    if result != sdk.COMM_SUCCESS:
                        continue  # owed still: the next attempt syncs
                self._owed.owe(replies)  # until its answer is in
                value, result = call()
            except (serial.SerialException, OSError) as exc:
                raise CommError(
                    f"{self.port_name}: {what} failed: {exc}",
                    port=self.port_name,
                    motor_id=motor_id,
                ) from None
            finally:
                # An interrupted call would leave the SDK's busy flag set for good.
                handler.is_using = False
            if result == sdk.COMM_SUCCESS:
                if replies:
                    self._owed.clear()
                return value
            if result not in RETRYABLE:
                break
        target = f" to {self.who(motor_id)}" if motor_id is not None else ""
        raise CommError(
            f"{self.port_name}: {what}{target} failed after {self.retries + 1} attempts: "
            f"{self._packets.getTxRxResult(result)} (SDK result {result})",
            port=self.port_name,
            motor_id=motor_id,
            result=result,
        )

    def _check_status(
        self, motor_id: int, error: int, what: str, alerts: bool | None = None
    ) -> None:
        """Alert bit → MotorFault with the named hardware error (unless ``alerts`` is False,
        default: ``raise_alerts``); other errors → DriverError."""
        if error & ALERT and (self.raise_alerts if alerts is None else alerts):
            raise self.fault(motor_id)
        if error & 0x7F:
            reason = STATUS_ERRORS.get(error & 0x7F, f"error number {error & 0x7F}")
            raise DriverError(f"{self.who(motor_id)} refused {what}: {reason}")

    def fault(self, motor_id: int) -> MotorFault:
        """The `MotorFault` of a motor whose status carried the alert bit."""
        flags = self.hardware_error(motor_id)
        return MotorFault(
            f"{self.who(motor_id)} reports a hardware error: {', '.join(flags) or 'unknown'}"
            " (its torque is off if the error is in its Shutdown mask; a reboot —"
            " `DynamixelBus.reboot()` or `gonio motors reboot` — clears it once the cause"
            " is removed)",
            motor_id=motor_id,
            axis=self.names.get(motor_id),
            flags=flags,
        )

    def hardware_error(self, motor_id: int) -> tuple[str, ...]:
        """The named bits of a motor's Hardware Error Status (no alert check)."""
        reg = item("hardware_error_status")
        data, error = self._read_exact(motor_id, reg, f"reading {reg.name}")
        self._check_status(motor_id, error, f"reading {reg.name}", alerts=False)
        return decode_hardware_error(data[0])

    def _read_exact(self, motor_id: int, reg: Item, what: str) -> tuple[bytes, int]:
        """(data, status error) of a READ of ``reg``, with retries. A status without an
        error number whose data is not exactly ``reg.size`` bytes (a late reply to
        another instruction, a short packet) is a corrupt packet: retried, then
        `CommError`."""

        def call() -> tuple[tuple[bytes, int], int]:
            data, result, error = self._packets.readTxRx(
                self._handler(), motor_id, reg.address, reg.size
            )
            if result == sdk.COMM_SUCCESS and not error & 0x7F and len(data) != reg.size:
                result = sdk.COMM_RX_CORRUPT
            return (bytes(data), error), result

        return self._attempt(what, motor_id, call, (reg.size,))

    def ping(self, motor_id: int) -> int:
        """The model number of ``motor_id``; CommError if it does not answer."""
        model, error = self._attempt(
            "ping",
            motor_id,
            lambda: self._pair(self._packets.ping(self._handler(), motor_id)),
            (PING_PARAMS,),
        )
        self._check_status(motor_id, error, "a ping")
        return int(model)

    @staticmethod
    def _pair(triple: tuple[Any, int, int]) -> tuple[tuple[Any, int], int]:
        value, result, error = triple
        return (value, error), result

    def scan(self) -> dict[int, tuple[int, int]]:
        """Every motor answering a broadcast ping: {id: (model number, firmware)}."""
        handler = self._handler()
        try:
            self._owed.owe((PING_PARAMS,))  # a motor may answer past the SDK's wait
            found, result = self._packets.broadcastPing(handler)
        finally:
            handler.is_using = False
        if result not in (sdk.COMM_SUCCESS, sdk.COMM_RX_TIMEOUT):
            raise CommError(
                f"{self.port_name}: broadcast ping failed: {self._packets.getTxRxResult(result)}",
                port=self.port_name,
                result=result,
            )
        return {int(k): (int(v[0]), int(v[1])) for k, v in found.items()}

    def read(self, motor_id: int, name: str, *, alerts: bool | None = None) -> int:
        """The value of control-table item ``name`` of ``motor_id`` (signed where the item
        is). ``alerts=False`` reads a faulted motor without raising `MotorFault`."""
        reg = self.item(motor_id, name)
        data, error = self._read_exact(motor_id, reg, f"reading {name}")
        self._check_status(motor_id, error, f"reading {name}", alerts)
        value = reg.decode(data)
        if name == "torque_enable":
            self._torque[motor_id] = bool(value)
        return value

    def torque_known_on(self, motor_id: int) -> bool:
        """True when the link has turned (or seen) ``motor_id``'s torque on and has not
        seen it go off since (a SYNC_WRITE of 0 leaves it unknown: read it back)."""
        return self._torque.get(motor_id, False)

    def _check_eeprom(self, motor_id: int, reg: Item, value: int) -> None:
        if reg.area is Area.EEPROM and self.torque_known_on(motor_id):
            raise DriverError(
                f"{self.who(motor_id)}: refusing to write {reg.name} = {value} while its "
                "torque is on (EEPROM items are written only with torque off: turn torque "
                "off and read it back first); nothing was sent"
            )

    def write(self, motor_id: int, name: str, value: int) -> None:
        """Write ``value`` to item ``name``; refused before sending if out of its range, or
        if it is an EEPROM item and the motor's torque is known to be on."""
        reg = self._writable(motor_id, name, value)
        self._check_eeprom(motor_id, reg, value)
        payload = list(reg.encode(value))
        error = self._attempt(
            f"writing {name}",
            motor_id,
            lambda: self._swap(
                self._packets.writeTxRx(self._handler(), motor_id, reg.address, reg.size, payload)
            ),
            (0,),
        )
        if name == "torque_enable" and not error & 0x7F:
            self._torque[motor_id] = bool(value)
        self._check_status(motor_id, error, f"writing {name} = {value}")

    @staticmethod
    def _swap(pair: tuple[int, int]) -> tuple[int, int]:
        result, error = pair
        return error, result

    def item(self, motor_id: int, name: str) -> Item:
        """Item ``name`` of ``motor_id``'s model (`DriverError` if the model lacks it)."""
        table = self.tables.get(motor_id)
        if table is None:
            return item(name)
        if not table.has(name):
            raise DriverError(
                f"{self.who(motor_id)} is an {table.name}, which has no {name}; nothing was sent"
            )
        return table.item(name)

    def _writable(self, motor_id: int, name: str, value: int) -> Item:
        reg = self.item(motor_id, name)
        if not reg.writable:
            raise DriverError(f"{name} is read-only")
        if not reg.in_range(value):
            raise LimitError(f"{name} = {value} is outside the range the motors accept")
        return reg

    def sync_write(self, name: str, values: Mapping[int, int]) -> None:
        """One SYNC_WRITE of item ``name``: {motor id: value} (no status packets come back)."""
        self.sync_write_items((name,), {m: (v,) for m, v in values.items()})

    def sync_write_items(self, names: Sequence[str], values: Mapping[int, Sequence[int]]) -> None:
        """One SYNC_WRITE of the contiguous items ``names`` (in address order): {motor id:
        one value per item}. Every value is checked as `write` checks it (its item's
        range; an EEPROM item with torque on) before anything is sent."""
        if not values:
            return
        regs = [item(name) for name in names]
        for a, b in itertools.pairwise(regs):
            if b.address != a.address + a.size:
                raise ValueError(f"{a.name} and {b.name} are not contiguous")
        payload: dict[int, list[int]] = {}
        for motor_id, row in values.items():
            if len(row) != len(regs):
                raise ValueError(f"{len(row)} values for {len(regs)} items ({', '.join(names)})")
            payload[motor_id] = []
            for reg, value in zip(regs, row, strict=True):
                self._writable(motor_id, reg.name, value)
                self._check_eeprom(motor_id, reg, value)
                payload[motor_id] += reg.encode(value)
        size = sum(reg.size for reg in regs)
        group = sdk.GroupSyncWrite(self._handler(), self._packets, regs[0].address, size)
        for motor_id, data in payload.items():
            group.addParam(motor_id, data)
        if "torque_enable" in names:  # no status comes back: on is presumed, off unknown
            at = list(names).index("torque_enable")
            for motor_id, row in values.items():
                if row[at]:
                    self._torque[motor_id] = True
                else:
                    self._torque.pop(motor_id, None)
        what = f"sync-writing {', '.join(names)}"
        self._attempt(what, None, lambda: (None, group.txPacket()))

    def sync_read(
        self, ids: Iterable[int], first: str, last: str, *, alerts: bool = True
    ) -> dict[int, bytes]:
        """One SYNC_READ of the bytes from item ``first`` through item ``last``.

        Returns {motor id: raw bytes}; with ``alerts``, a reply with the alert bit raises
        `MotorFault` (other error bits always raise).
        """
        data, _, _ = self.sync_read_stamped(ids, first, last, time.monotonic, alerts=alerts)
        return data

    def sync_read_stamped(
        self,
        ids: Iterable[int],
        first: str,
        last: str,
        now: Callable[[], float],
        *,
        alerts: bool = True,
    ) -> tuple[dict[int, bytes], float, float]:
        """As `sync_read`, with the times (s, on ``now``) just before the successful
        attempt's instruction was sent and just after its last status arrived: the
        motors sampled the data in between. ({motor id: raw bytes}, request_s, reply_s)."""
        start, end = item(first), item(last)
        length = end.address + end.size - start.address
        ids = list(ids)
        group = SyncRead(self._handler(), self._packets, start.address, length)
        for motor_id in ids:
            group.addParam(motor_id)
        stamps = [0.0, 0.0]

        def call() -> tuple[None, int]:
            stamps[0] = now()
            result = group.read()
            stamps[1] = now()
            return None, result

        try:
            self._attempt(f"sync-reading {first}…{last}", None, call, (length,) * len(ids), ids[0])
        except CommError as exc:
            if group.failed is None:
                raise
            how = "no answer from" if exc.result == sdk.COMM_RX_TIMEOUT else "a bad reply from"
            raise CommError(
                f"{exc}; {how} {self.who(group.failed)}",
                port=self.port_name,
                motor_id=group.failed,
                result=exc.result,
            ) from None
        for motor_id in ids:
            error = group.errors[motor_id] if alerts else group.errors[motor_id] & ~ALERT
            self._check_status(motor_id, error, f"sync-reading {first}…{last}")
        data = {motor_id: bytes(group.data_dict[motor_id]) for motor_id in ids}
        return data, stamps[0], stamps[1]

    def reboot(self, motor_id: int) -> None:
        """Reboot a motor (clears its hardware error; torque comes back off). The status
        leaves before the motor restarts: `ping` it until it answers again."""
        error = self._attempt(
            "reboot",
            motor_id,
            lambda: self._swap(self._packets.reboot(self._handler(), motor_id)),
            (0,),
        )
        if error & 0x7F:
            self._check_status(motor_id, error & 0x7F, "a reboot")
        self._torque[motor_id] = False
