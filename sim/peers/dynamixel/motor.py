"""One emulated X-series motor: its control-table memory, the write rules, the backup.

The memory is its model's table (:mod:`sim.peers.dynamixel.table`, from
:mod:`drivers.dynamixel.models`: the XM430-W350's addresses 0-661 by default, an XL330's
0-227; little endian), with that model's defaults and ranges; writes go through
:mod:`sim.peers.dynamixel.rules` (Indirect Data resolved there) and a rejected write changes
nothing. Motion and heat are the motor's :mod:`sim.peers.dynamixel.drive` on its clock,
started from the registers written; derived registers (Present Position, Present
Velocity, Moving, Moving Status, trajectories, Realtime Tick, Present Temperature) are
computed whenever they are read.

Position frames (e-manual): Present Position = s·shaft + Homing Offset, with s = −1 in
reverse Drive Mode (the offset's sign is not reversed); position mode ignores an offset
outside ±1,024. Present Position is brought back within one turn when torque goes on
in position mode, when the mode changes to position mode, and on reboot.

Control Table Backup (instruction 0x20, firmware ≥ 45; e-manual, Protocol 2.0,
emanual.robotis.com/docs/en/dxl/protocol2/, "Control Table Backup (0x20)"): with
torque off, "store" keeps the EEPROM area and the RAM items of `BACKUP_RAM_ITEMS` (gains,
profile, Indirect Addresses) in a backup area that survives REBOOT and FACTORY_RESET
(*assumption* for the latter) and sets Backup Ready (147); "restore" writes the backed-up
EEPROM area back and reboots. At every boot (REBOOT, restore, factory reset) Startup
Configuration (60) bit 1 restores the backed-up RAM items and bit 0 turns torque on.
"""

from __future__ import annotations

import threading
import time
from collections import deque
from collections.abc import Callable

from drivers.dynamixel import (
    BAUD_RATES,
    DRIVE_MODE_REVERSE,
    EEPROM_END,
    HARDWARE_ERROR_BITS,
    OPERATING_MODES,
    TICKS_PER_REV,
)
from sim.clock import TimeSource
from sim.peers.dynamixel.drive import NOMINAL_TEMPERATURE, Drive, Heat
from sim.peers.dynamixel.motion import TICKS_PER_S_PER_VELOCITY_UNIT
from sim.peers.dynamixel.protocol import ALERT, StatusError
from sim.peers.dynamixel.rules import (
    MULTI_TURN,
    POSITION,
    check_write,
    check_writes,
    resolve,
    targets,
)
from sim.peers.dynamixel.table import (
    BY_NAME,
    STARTUP_RAM_RESTORE,
    STARTUP_TORQUE_ON,
    Table,
    table_of,
)

#: Drive Mode bit 2: time-based profile (Profile Velocity/Acceleration in ms).
DRIVE_MODE_TIME_BASED = 0x04
#: Drive Mode bit 3: writing a goal while torque is off turns torque on.
DRIVE_MODE_TORQUE_ON_BY_GOAL = 0x08

VELOCITY = OPERATING_MODES["velocity"]
#: Position mode ignores a Homing Offset outside ±1,024 (e-manual).
_POSITION_MODE_HOMING_LIMIT = 1024

#: Goal Position values a motor remembers (`EmulatedMotor.goals_written`); older ones
#: are dropped.
GOAL_LOG_SIZE = 100_000
_GOAL = BY_NAME["goal_position"]

#: Present Input Voltage (0.1 V) of a healthy motor (its temperature: `NOMINAL_TEMPERATURE`).
NOMINAL_VOLTAGE = 120
_OVERHEATING = next(bit for bit, name in HARDWARE_ERROR_BITS.items() if name == "overheating")

#: CONTROL_TABLE_BACKUP (0x20): its parameters are an option then the magic "CTRL";
#: the instruction exists from firmware 45 on (X430/X540 series).
BACKUP_MAGIC = b"CTRL"
BACKUP_STORE = 0x01
BACKUP_RESTORE = 0x02
BACKUP_FIRMWARE = 45


def _wrap32(value: int) -> int:
    """``value`` as a signed 32-bit register would hold it."""
    return ((value + (1 << 31)) % (1 << 32)) - (1 << 31)


def baud_code(bps: int, table: Table | None = None) -> int:
    """The Baud Rate register value for ``bps`` (ValueError if the X-series, or the
    model of ``table``, has none)."""
    top = table.by_name["baud_rate"].high if table is not None else None
    codes = {code: rate for code, rate in BAUD_RATES.items() if top is None or code <= top}
    for code, rate in codes.items():
        if rate == bps:
            return code
    raise ValueError(f"{bps} baud is not a rate of this model; use one of {sorted(codes.values())}")


class EmulatedMotor:
    """An X-series motor's memory and motion, driven by a clock (seconds).

    ``model`` is its model number (`drivers.dynamixel.models.MODELS`; an unknown one
    gets the XM430-W350's table) and chooses its control table. ``position`` is where
    the motor starts (ticks, Present Position). Every public method holds ``lock`` (one
    lock shared by an emulator's motors; by default a private RLock), so a bus thread
    and a test can use the motor at the same time.
    """

    def __init__(
        self,
        motor_id: int = 1,
        *,
        model: int = 1020,
        firmware: int = 46,
        baud: int = 57_600,
        position: int = 2048,
        clock: TimeSource = time.monotonic,
        lock: threading.RLock | None = None,
    ) -> None:
        self._clock = clock
        self._lock = lock if lock is not None else threading.RLock()
        self._table = table_of(model)
        self._mem = bytearray(self._table.defaults)
        now = clock()
        self._boot = now
        self._drive = Drive(position, now)
        self._registered: tuple[int, bytes] | None = None
        self._goals: deque[int] = deque(maxlen=GOAL_LOG_SIZE)
        self._backup: bytes | None = None  # a copy of the memory when the backup was stored
        self._heat = Heat()
        self._put("model_number", model)
        self._put("firmware_version", firmware)
        self._put("id", motor_id)
        self._put("baud_rate", baud_code(baud, self._table))
        self._reset_ram(position)

    # -- identity and bus settings (plain register reads) -------------------------------

    @property
    def id(self) -> int:
        return self._raw("id")

    @property
    def secondary_id(self) -> int | None:
        """The Secondary (shadow) ID, or None when disabled (≥ 253)."""
        value = self._raw("secondary_id")
        return value if value <= 252 else None

    @property
    def model(self) -> int:
        return self._raw("model_number")

    @property
    def table(self) -> Table:
        """The motor's control table (its model's)."""
        return self._table

    @property
    def firmware(self) -> int:
        return self._raw("firmware_version")

    @property
    def baud(self) -> int:
        """The rate the motor listens and speaks at (bits/s)."""
        return BAUD_RATES[self._raw("baud_rate")]

    @property
    def protocol(self) -> int:
        return self._raw("protocol_type")

    @property
    def status_return_level(self) -> int:
        return self._raw("status_return_level")

    @property
    def return_delay(self) -> float:
        """Return Delay Time in seconds (register × 2 µs)."""
        return self._raw("return_delay_time") * 2e-6

    @property
    def hardware_error(self) -> int:
        """Hardware Error Status (bit numbers as in `HARDWARE_ERROR_BITS`)."""
        return self._raw("hardware_error_status")

    @property
    def in_shutdown(self) -> bool:
        """True when a latched hardware error is in the Shutdown mask (REBOOT clears it)."""
        return bool(self.hardware_error & self._raw("shutdown"))

    def status_error(self, error: int = StatusError.NONE) -> int:
        """The ERROR byte of a status packet: ``error`` plus ALERT if a hardware error is set."""
        return int(error) | (ALERT if self.hardware_error else 0)

    @property
    def shaft_position(self) -> float:
        """The physical shaft angle (ticks, counter-clockwise seen from the front), which
        Homing Offset and the reverse bit of Drive Mode map to Present Position."""
        with self._lock:
            return self._to_shaft(self._drive.position(self._clock()))

    def position_at(self, t: float) -> float:
        """Present Position (ticks, before rounding to the register) at time ``t`` on the
        motor's clock, along its present trajectory (valid from the last goal, torque
        change or stop on) or, before it, along the last
        `sim.peers.dynamixel.drive.PAST_TRAJECTORIES` moves and holds: the truth a test compares
        polled positions with."""
        with self._lock:
            return self._drive.position_at(t)

    # -- host-facing access ---------------------------------------------------------------

    def read(self, address: int, length: int) -> bytes:
        """``length`` bytes from ``address`` (IndexError outside the table); an Indirect
        Data byte reads the byte its Indirect Address names (a reserved one reads 0)."""
        table = self._table
        if length < 1 or address < 0 or address + length > table.size:
            raise IndexError(f"read of {length} bytes at {address} is outside 0..{table.size}")
        with self._lock:
            self._refresh()
            if not table.touches_indirect_data(address, length):
                return bytes(self._mem[address : address + length])
            out = bytearray()
            for a in range(address, address + length):
                target = resolve(table, self._mem, a)
                known = 0 <= target < table.size and table.item_at[target] is not None
                out.append(self._mem[target] if known else 0)
            return bytes(out)

    def write(self, address: int, data: bytes, *, via_secondary: bool = False) -> StatusError:
        """Apply a WRITE of ``data`` at ``address`` under the control-table rules (a
        Goal Position in it, directly or through Indirect Data, is logged first, whether
        the rules accept it or not)."""
        with self._lock:
            inside = address >= 0 and address + len(data) <= self._table.size
            writes = targets(self._table, self._mem, address, bytes(data)) if inside else {}
            sent = writes or dict(zip(range(address, address + len(data)), data, strict=True))
            goal = range(_GOAL.address, _GOAL.address + _GOAL.size)
            if all(a in sent for a in goal):
                self._goals.append(_GOAL.decode(bytes(sent[a] for a in goal)))
            if writes:
                error = check_writes(
                    self._table,
                    self._mem,
                    writes,
                    shutdown=self.in_shutdown,
                    via_secondary=via_secondary,
                )
            else:  # a shape error: empty or outside the table
                error = self.check_write(address, data, via_secondary=via_secondary)
            if error:
                return error
            self._apply(writes)
            return StatusError.NONE

    def check_write(self, address: int, data: bytes, *, via_secondary: bool = False) -> StatusError:
        """The error a WRITE would get, without applying it."""
        with self._lock:
            return check_write(
                self._table,
                self._mem,
                address,
                data,
                shutdown=self.in_shutdown,
                via_secondary=via_secondary,
            )

    @property
    def goals_written(self) -> list[int]:
        """Every Goal Position value (ticks) the host has written, oldest first (WRITE,
        SYNC_WRITE, BULK_WRITE, ACTION; refused ones too; the last `GOAL_LOG_SIZE`)."""
        with self._lock:
            return list(self._goals)

    def clear_goals(self) -> None:
        """Forget the Goal Position values written so far."""
        with self._lock:
            self._goals.clear()

    def get(self, name: str) -> int:
        """A register's value by control-table name (derived registers are up to date)."""
        with self._lock:
            self._refresh()
            return self._raw(name)

    def set(self, name: str, value: int) -> None:
        """Backdoor: store ``value`` in a register with no rules and no side effects.

        Setting ``present_position`` places the motor there at rest. Other derived
        registers are recomputed on the next read, so setting them has no lasting effect.
        """
        with self._lock:
            if name == "present_position":
                self._drive.place(value, self._clock())
            self._put(name, value)

    # -- instructions other than READ / WRITE ---------------------------------------------

    def reg_write(self, address: int, data: bytes) -> StatusError:
        """REG_WRITE: check now, apply on ACTION (Registered Instruction = 1 meanwhile)."""
        with self._lock:
            error = self.check_write(address, data)
            if not error:
                self._registered = (address, bytes(data))
                self._put("registered_instruction", 1)
            return error

    def action(self) -> StatusError:
        """ACTION: apply the registered write (Instruction error if there is none)."""
        with self._lock:
            if self._registered is None:
                return StatusError.INSTRUCTION
            address, data = self._registered
            self._registered = None
            self._put("registered_instruction", 0)
            return self.write(address, data)

    def reboot(self) -> None:
        """REBOOT: EEPROM kept, RAM to defaults (torque off, errors cleared), Present
        Position back within one turn (the multi-turn count is lost), tick restarts."""
        with self._lock:
            now = self._clock()
            position = self._drive.position(now)
            self._boot = now
            self._registered = None
            self._reset_ram(self._one_turn(position))
            self._cool(now)  # still above its Temperature Limit: Overheating again

    def factory_reset(self, option: int) -> StatusError:
        """FACTORY_RESET: 0xFF everything, 0x01 all but ID, 0x02 all but ID and baud rate;
        then reboot. Another option → Data Range error."""
        if option not in (0xFF, 0x01, 0x02):
            return StatusError.DATA_RANGE
        with self._lock:
            shaft = self.shaft_position
            keep_id, keep_baud = self.id, self._raw("baud_rate")
            model, firmware = self.model, self.firmware
            self._mem[:] = self._table.defaults
            self._put("model_number", model)
            self._put("firmware_version", firmware)
            if option in (0x01, 0x02):
                self._put("id", keep_id)
            if option == 0x02:
                self._put("baud_rate", keep_baud)
            self._drive.place(self._from_shaft(shaft), self._clock())
            self.reboot()
        return StatusError.NONE

    def clear_multi_turn(self) -> StatusError:
        """CLEAR (option 1): Present Position back within one turn; Result Fail if moving."""
        with self._lock:
            now = self._clock()
            if self._drive.running(now):
                return StatusError.RESULT_FAIL
            self._hold(self._one_turn(self._drive.position(now)), now)
            return StatusError.NONE

    def heat(self, celsius: float, time_constant_s: float) -> None:
        """The motor is at ``celsius`` (°C) now and cools toward its nominal 30 °C with
        ``time_constant_s`` (s) on its clock (Present Temperature follows). Above its
        Temperature Limit it latches Overheating, now and on a REBOOT while still
        above, as a real motor does."""
        if not time_constant_s > 0:
            raise ValueError(f"the time constant must be > 0 s, got {time_constant_s}")
        with self._lock:
            now = self._clock()
            self._heat.set(now, celsius, time_constant_s)
            self._cool(now)

    def raise_alert(self, bit: int) -> None:
        """Latch hardware error ``bit``; if it is in the Shutdown mask, torque goes off."""
        with self._lock:
            self._put("hardware_error_status", self.hardware_error | (1 << bit))
            if self.in_shutdown:
                self._torque_off()

    @property
    def backup_ready(self) -> bool:
        """True once a Control Table Backup has been stored (Backup Ready, 147)."""
        with self._lock:
            return self._backup is not None

    def check_backup(self, params: bytes) -> StatusError:
        """The error CONTROL_TABLE_BACKUP with ``params`` gets: Instruction error below
        firmware 45 (*assumption*: an older motor does not know it), Data Length unless
        five parameters, Data Range for another option or magic (*assumption*, as CLEAR),
        Result Fail with torque on (e-manual) or a restore with no backup (*assumption*)."""
        with self._lock:
            if self.firmware < BACKUP_FIRMWARE:
                return StatusError.INSTRUCTION
            if len(params) != 1 + len(BACKUP_MAGIC):
                return StatusError.DATA_LENGTH
            option, magic = params[0], bytes(params[1:])
            if option not in (BACKUP_STORE, BACKUP_RESTORE) or magic != BACKUP_MAGIC:
                return StatusError.DATA_RANGE
            if self._raw("torque_enable") or (option == BACKUP_RESTORE and not self._backup):
                return StatusError.RESULT_FAIL
            return StatusError.NONE

    def store_backup(self) -> None:
        """Keep the EEPROM area and the backed-up RAM items; Backup Ready = 1."""
        with self._lock:
            self._refresh()
            self._backup = bytes(self._mem)
            self._put("backup_ready", 1)

    def restore_backup(self) -> None:
        """Write the backed-up EEPROM area back (identity registers excepted), then reboot."""
        with self._lock:
            if self._backup is None:
                return
            shaft = self.shaft_position
            model, firmware = self.model, self.firmware
            self._mem[:EEPROM_END] = self._backup[:EEPROM_END]
            self._put("model_number", model)
            self._put("firmware_version", firmware)
            self._drive.place(self._from_shaft(shaft), self._clock())
            self.reboot()

    # -- internals ------------------------------------------------------------------------

    def _raw(self, name: str) -> int:
        it = self._table.by_name[name]
        return it.decode(bytes(self._mem[it.address : it.address + it.size]))

    def _put(self, name: str, value: int) -> None:
        """Store ``value`` in item ``name``; ValueError (nothing stored) if the register
        cannot hold it (e.g. 2³¹ in a signed 4-byte item)."""
        it = self._table.by_name[name]
        self._mem[it.address : it.address + it.size] = it.encode(value)

    def _reset_ram(self, position: float) -> None:
        """Boot: RAM to defaults, then Startup Configuration (RAM restore, torque on)."""
        self._mem[EEPROM_END:] = self._table.defaults[EEPROM_END:]
        self._put("goal_pwm", self._raw("pwm_limit"))
        if self._table.model.has("goal_current"):
            self._put("goal_current", self._raw("current_limit"))
        self._put("present_input_voltage", NOMINAL_VOLTAGE)
        self._put("present_temperature", NOMINAL_TEMPERATURE)
        self._put("backup_ready", int(self._backup is not None))
        startup = self._raw("startup_configuration")
        if startup & STARTUP_RAM_RESTORE and self._backup is not None:
            for it in self._table.backup_ram_items:
                end = it.address + it.size
                self._mem[it.address : end] = self._backup[it.address : end]
        self._drive.reset_kind()
        now = self._clock()
        self._hold(position, now)
        self._put("goal_position", _wrap32(round(position)))
        if startup & STARTUP_TORQUE_ON:
            self._put("torque_enable", 1)
            self._torque_on(now)

    def _apply(self, writes: dict[int, int]) -> None:
        """Store a checked scattered write (target address → byte) and its side effects."""
        now = self._clock()
        position = self._drive.position(now)
        before = {name: self._raw(name) for name in _WATCHED}
        shaft = self._to_shaft(position)
        for a, byte in writes.items():
            self._mem[a] = byte
        touched = {it.name for a in writes if (it := self._table.item_at[a]) is not None}
        changed = {name for name in _WATCHED if self._raw(name) != before[name]}

        if changed & {"homing_offset", "drive_mode", "operating_mode"}:
            self._hold(self._from_shaft(shaft), now)
        if "operating_mode" in changed:
            self._put("profile_velocity", 0)
            self._put("profile_acceleration", 0)
            self._put("goal_pwm", self._raw("pwm_limit"))
            if self._raw("operating_mode") == POSITION:
                self._hold(self._one_turn(self._position(now)), now)
        if "torque_enable" in changed:
            if self._raw("torque_enable"):
                self._torque_on(now)
            else:
                self._torque_off()
        mode = self._raw("operating_mode")
        if "goal_position" in touched and mode in (POSITION, *MULTI_TURN):
            self._goal_update(now, self._start_move)
        if "goal_velocity" in touched and mode == VELOCITY:
            self._goal_update(now, self._start_spin)

    def _goal_update(self, now: float, start: Callable[[float], None]) -> None:
        if not self._raw("torque_enable"):
            if not self._raw("drive_mode") & DRIVE_MODE_TORQUE_ON_BY_GOAL or self.in_shutdown:
                return  # accepted, not executed
            self._put("torque_enable", 1)
        start(now)

    def _start_move(self, now: float) -> None:
        self._drive.move(
            now,
            self._raw("goal_position"),
            self._raw("profile_velocity"),
            self._raw("profile_acceleration"),
            self._raw("velocity_limit"),
            bool(self._raw("drive_mode") & DRIVE_MODE_TIME_BASED),
        )

    def _start_spin(self, now: float) -> None:
        self._drive.spin(now, self._raw("goal_velocity"), self._raw("profile_acceleration"))

    def _torque_on(self, now: float) -> None:
        """Torque on: position mode wraps to one turn; the goal becomes the present position."""
        position = self._position(now)
        if self._raw("operating_mode") == POSITION:
            position = self._one_turn(position)
        self._hold(position, now)
        self._put("goal_position", _wrap32(round(position)))

    def _torque_off(self) -> None:
        now = self._clock()
        self._put("torque_enable", 0)
        self._hold(self._position(now), now)

    def _position(self, now: float) -> float:
        return self._drive.position(now)

    def _hold(self, position: float, now: float) -> None:
        self._drive.hold(position, now)

    def _homing(self) -> int:
        offset = self._raw("homing_offset")
        if self._raw("operating_mode") == POSITION and abs(offset) > _POSITION_MODE_HOMING_LIMIT:
            return 0
        return offset

    def _sign(self) -> int:
        return -1 if self._raw("drive_mode") & DRIVE_MODE_REVERSE else 1

    def _to_shaft(self, position: float) -> float:
        return self._sign() * (position - self._homing())

    def _from_shaft(self, shaft: float) -> float:
        return self._sign() * shaft + self._homing()

    def _one_turn(self, position: float) -> float:
        homing = self._homing()
        return homing + (position - homing) % TICKS_PER_REV

    def _cool(self, now: float) -> None:
        """Present Temperature on the way down from `heat`; Overheating above the limit."""
        temperature = self._heat.temperature(now)
        if temperature is None:
            return
        self._put("present_temperature", temperature)
        if self._raw("present_temperature") > self._raw("temperature_limit"):
            self.raise_alert(_OVERHEATING)

    def _refresh(self) -> None:
        now = self._clock()
        self._cool(now)
        position, velocity, running, endless = self._drive.sample(now)
        present = _wrap32(round(position))
        speed = _wrap32(round(velocity / TICKS_PER_S_PER_VELOCITY_UNIT))
        moving = running or abs(speed) > self._raw("moving_threshold")
        status = int(self._drive.kind)
        if running:
            status |= 0x02
        mode = self._raw("operating_mode")
        torque = self._raw("torque_enable")
        if (
            mode in (POSITION, *MULTI_TURN)
            and torque
            and not running
            and present == self._raw("goal_position")
        ):
            status |= 0x01
        self._put("present_position", present)
        self._put("present_velocity", speed)
        self._put("moving", int(moving))
        self._put("moving_status", status)
        self._put("velocity_trajectory", speed if running or endless else 0)
        self._put("position_trajectory", present)
        self._put("realtime_tick", int((now - self._boot) * 1000) % 32768)


#: Registers whose change has side effects beyond the stored bytes.
_WATCHED = ("homing_offset", "drive_mode", "operating_mode", "torque_enable")
