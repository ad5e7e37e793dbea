"""One emulated X-series motor: its control-table memory, the write rules, the backup.

The memory (:mod:`sim.peers.dynamixel.memory`) is its model's table
(:mod:`sim.peers.dynamixel.table`, from :mod:`drivers.dynamixel.models`: the
XM430-W350's addresses 0-661 by default, an XL330's 0-227; little endian), with that
model's defaults and ranges; writes go through
:mod:`sim.peers.dynamixel.rules` (Indirect Data resolved there) and a rejected write changes
nothing. Motion and heat are the motor's :mod:`sim.peers.dynamixel.drive` on its clock,
started from the registers written; derived registers (Present Position, Present
Velocity, Moving, Moving Status, trajectories, Realtime Tick, Present Temperature) are
computed whenever they are read.

Position frames: see :mod:`sim.peers.dynamixel.memory`. Present Position is brought back
within one turn when torque goes on in position mode, when the mode changes to position
mode, and on reboot.

The motor holds its Control Table Backup (:mod:`sim.peers.dynamixel.backup`). At every
boot (REBOOT, restore, factory reset) Startup Configuration (60) bit 1 restores the
backed-up RAM items and bit 0 turns torque on.
"""

from __future__ import annotations

import threading
import time
from collections import deque
from collections.abc import Callable

from drivers.dynamixel import (
    BAUD_RATES,
    EEPROM_END,
    HARDWARE_ERROR_BITS,
    OPERATING_MODES,
)
from sim.clock import TimeSource
from sim.peers.dynamixel.backup import Backup
from sim.peers.dynamixel.drive import NOMINAL_TEMPERATURE, Drive, Heat
from sim.peers.dynamixel.memory import Memory, baud_code, wrap32
from sim.peers.dynamixel.protocol import ALERT, StatusError
from sim.peers.dynamixel.rules import (
    MULTI_TURN,
    POSITION,
    check_write,
    check_writes,
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

#: Goal Position values a motor remembers (`EmulatedMotor.goals_written`); older ones
#: are dropped.
GOAL_LOG_SIZE = 100_000
_GOAL = BY_NAME["goal_position"]

#: Present Input Voltage (0.1 V) of a healthy motor (its temperature: `NOMINAL_TEMPERATURE`).
NOMINAL_VOLTAGE = 120
_OVERHEATING = next(bit for bit, name in HARDWARE_ERROR_BITS.items() if name == "overheating")


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
        self._mem = Memory(self._table)
        self._image = self._mem.image  # the bytes, changed in place, never replaced
        now = clock()
        self._boot = now
        self._drive = Drive(position, now)
        self._registered: tuple[int, bytes] | None = None
        self._goals: deque[int] = deque(maxlen=GOAL_LOG_SIZE)
        self._backup = Backup(self._table)
        self._heat = Heat()
        self._mem.put("model_number", model)
        self._mem.put("firmware_version", firmware)
        self._mem.put("id", motor_id)
        self._mem.put("baud_rate", baud_code(baud, self._table))
        self._reset_ram(position)

    # -- identity and bus settings (plain register reads) -------------------------------

    @property
    def id(self) -> int:
        return self._mem.raw("id")

    @property
    def secondary_id(self) -> int | None:
        """The Secondary (shadow) ID, or None when disabled (≥ 253)."""
        value = self._mem.raw("secondary_id")
        return value if value <= 252 else None

    @property
    def model(self) -> int:
        return self._mem.raw("model_number")

    @property
    def table(self) -> Table:
        """The motor's control table (its model's)."""
        return self._table

    @property
    def firmware(self) -> int:
        return self._mem.raw("firmware_version")

    @property
    def baud(self) -> int:
        """The rate the motor listens and speaks at (bits/s)."""
        return BAUD_RATES[self._mem.raw("baud_rate")]

    @property
    def protocol(self) -> int:
        return self._mem.raw("protocol_type")

    @property
    def status_return_level(self) -> int:
        return self._mem.raw("status_return_level")

    @property
    def return_delay(self) -> float:
        """Return Delay Time in seconds (register × 2 µs)."""
        return self._mem.raw("return_delay_time") * 2e-6

    @property
    def hardware_error(self) -> int:
        """Hardware Error Status (bit numbers as in `HARDWARE_ERROR_BITS`)."""
        return self._mem.raw("hardware_error_status")

    @property
    def in_shutdown(self) -> bool:
        """True when a latched hardware error is in the Shutdown mask (REBOOT clears it)."""
        return bool(self.hardware_error & self._mem.raw("shutdown"))

    def status_error(self, error: int = StatusError.NONE) -> int:
        """The ERROR byte of a status packet: ``error`` plus ALERT if a hardware error is set."""
        return int(error) | (ALERT if self.hardware_error else 0)

    @property
    def shaft_position(self) -> float:
        """The physical shaft angle (ticks, counter-clockwise seen from the front), which
        Homing Offset and the reverse bit of Drive Mode map to Present Position."""
        with self._lock:
            return self._mem.to_shaft(self._drive.position(self._clock()))

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
        with self._lock:
            self._refresh()
            return self._mem.read(address, length)

    def write(self, address: int, data: bytes, *, via_secondary: bool = False) -> StatusError:
        """Apply a WRITE of ``data`` at ``address`` under the control-table rules (a
        Goal Position in it, directly or through Indirect Data, is logged first, whether
        the rules accept it or not)."""
        with self._lock:
            inside = address >= 0 and address + len(data) <= self._table.size
            writes = targets(self._table, self._image, address, bytes(data)) if inside else {}
            sent = writes or dict(zip(range(address, address + len(data)), data, strict=True))
            goal = range(_GOAL.address, _GOAL.address + _GOAL.size)
            if all(a in sent for a in goal):
                self._goals.append(_GOAL.decode(bytes(sent[a] for a in goal)))
            if writes:
                error = check_writes(
                    self._table,
                    self._image,
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
                self._image,
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
            return self._mem.raw(name)

    def set(self, name: str, value: int) -> None:
        """Backdoor: store ``value`` in a register with no rules and no side effects.

        Setting ``present_position`` places the motor there at rest. Other derived
        registers are recomputed on the next read, so setting them has no lasting effect.
        """
        with self._lock:
            if name == "present_position":
                self._drive.place(value, self._clock())
            self._mem.put(name, value)

    # -- instructions other than READ / WRITE ---------------------------------------------

    def reg_write(self, address: int, data: bytes) -> StatusError:
        """REG_WRITE: check now, apply on ACTION (Registered Instruction = 1 meanwhile)."""
        with self._lock:
            error = self.check_write(address, data)
            if not error:
                self._registered = (address, bytes(data))
                self._mem.put("registered_instruction", 1)
            return error

    def action(self) -> StatusError:
        """ACTION: apply the registered write (Instruction error if there is none)."""
        with self._lock:
            if self._registered is None:
                return StatusError.INSTRUCTION
            address, data = self._registered
            self._registered = None
            self._mem.put("registered_instruction", 0)
            return self.write(address, data)

    def reboot(self) -> None:
        """REBOOT: EEPROM kept, RAM to defaults (torque off, errors cleared), Present
        Position back within one turn (the multi-turn count is lost), tick restarts."""
        with self._lock:
            now = self._clock()
            position = self._drive.position(now)
            self._boot = now
            self._registered = None
            self._reset_ram(self._mem.one_turn(position))
            self._cool(now)  # still above its Temperature Limit: Overheating again

    def factory_reset(self, option: int) -> StatusError:
        """FACTORY_RESET: 0xFF everything, 0x01 all but ID, 0x02 all but ID and baud rate;
        then reboot. Another option → Data Range error."""
        if option not in (0xFF, 0x01, 0x02):
            return StatusError.DATA_RANGE
        with self._lock:
            shaft = self.shaft_position
            keep_id, keep_baud = self.id, self._mem.raw("baud_rate")
            model, firmware = self.model, self.firmware
            self._image[:] = self._table.defaults
            self._mem.put("model_number", model)
            self._mem.put("firmware_version", firmware)
            if option in (0x01, 0x02):
                self._mem.put("id", keep_id)
            if option == 0x02:
                self._mem.put("baud_rate", keep_baud)
            self._drive.place(self._mem.from_shaft(shaft), self._clock())
            self.reboot()
        return StatusError.NONE

    def clear_multi_turn(self) -> StatusError:
        """CLEAR (option 1): Present Position back within one turn; Result Fail if moving."""
        with self._lock:
            now = self._clock()
            if self._drive.running(now):
                return StatusError.RESULT_FAIL
            self._drive.hold(self._mem.one_turn(self._drive.position(now)), now)
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
            self._mem.put("hardware_error_status", self.hardware_error | (1 << bit))
            if self.in_shutdown:
                self._torque_off()

    @property
    def backup_ready(self) -> bool:
        """True once a Control Table Backup has been stored (Backup Ready, 147)."""
        with self._lock:
            return self._backup.ready

    def check_backup(self, params: bytes) -> StatusError:
        """The error CONTROL_TABLE_BACKUP with ``params`` gets: Instruction error below
        firmware 45 (*assumption*: an older motor does not know it), Data Length unless
        five parameters, Data Range for another option or magic (*assumption*, as CLEAR),
        Result Fail with torque on (e-manual) or a restore with no backup (*assumption*)."""
        with self._lock:
            return self._backup.check(params, self.firmware, bool(self._mem.raw("torque_enable")))

    def store_backup(self) -> None:
        """Keep the EEPROM area and the backed-up RAM items; Backup Ready = 1."""
        with self._lock:
            self._refresh()
            self._backup.store(self._image)
            self._mem.put("backup_ready", 1)

    def restore_backup(self) -> None:
        """Write the backed-up EEPROM area back (identity registers excepted), then reboot."""
        with self._lock:
            shaft = self.shaft_position
            model, firmware = self.model, self.firmware
            if not self._backup.restore_eeprom(self._image):
                return
            self._mem.put("model_number", model)
            self._mem.put("firmware_version", firmware)
            self._drive.place(self._mem.from_shaft(shaft), self._clock())
            self.reboot()

    # -- internals ------------------------------------------------------------------------

    def _reset_ram(self, position: float) -> None:
        """Boot: RAM to defaults, then Startup Configuration (RAM restore, torque on)."""
        self._image[EEPROM_END:] = self._table.defaults[EEPROM_END:]
        self._mem.put("goal_pwm", self._mem.raw("pwm_limit"))
        if self._table.model.has("goal_current"):
            self._mem.put("goal_current", self._mem.raw("current_limit"))
        self._mem.put("present_input_voltage", NOMINAL_VOLTAGE)
        self._mem.put("present_temperature", NOMINAL_TEMPERATURE)
        self._mem.put("backup_ready", int(self._backup.ready))
        startup = self._mem.raw("startup_configuration")
        if startup & STARTUP_RAM_RESTORE:
            self._backup.restore_ram(self._image)
        self._drive.reset_kind()
        now = self._clock()
        self._drive.hold(position, now)
        self._mem.put("goal_position", wrap32(round(position)))
        if startup & STARTUP_TORQUE_ON:
            self._mem.put("torque_enable", 1)
            self._torque_on(now)

    def _apply(self, writes: dict[int, int]) -> None:
        """Store a checked scattered write (target address → byte) and its side effects."""
        now = self._clock()
        position = self._drive.position(now)
        before = {name: self._mem.raw(name) for name in _WATCHED}
        shaft = self._mem.to_shaft(position)
        for a, byte in writes.items():
            self._image[a] = byte
        touched = {it.name for a in writes if (it := self._table.item_at[a]) is not None}
        changed = {name for name in _WATCHED if self._mem.raw(name) != before[name]}

        if changed & {"homing_offset", "drive_mode", "operating_mode"}:
            self._drive.hold(self._mem.from_shaft(shaft), now)
        if "operating_mode" in changed:
            self._mem.put("profile_velocity", 0)
            self._mem.put("profile_acceleration", 0)
            self._mem.put("goal_pwm", self._mem.raw("pwm_limit"))
            if self._mem.raw("operating_mode") == POSITION:
                self._drive.hold(self._mem.one_turn(self._drive.position(now)), now)
        if "torque_enable" in changed:
            if self._mem.raw("torque_enable"):
                self._torque_on(now)
            else:
                self._torque_off()
        mode = self._mem.raw("operating_mode")
        if "goal_position" in touched and mode in (POSITION, *MULTI_TURN):
            self._goal_update(now, self._start_move)
        if "goal_velocity" in touched and mode == VELOCITY:
            self._goal_update(now, self._start_spin)

    def _goal_update(self, now: float, start: Callable[[float], None]) -> None:
        if not self._mem.raw("torque_enable"):
            if not self._mem.raw("drive_mode") & DRIVE_MODE_TORQUE_ON_BY_GOAL or self.in_shutdown:
                return  # accepted, not executed
            self._mem.put("torque_enable", 1)
        start(now)

    def _start_move(self, now: float) -> None:
        self._drive.move(
            now,
            self._mem.raw("goal_position"),
            self._mem.raw("profile_velocity"),
            self._mem.raw("profile_acceleration"),
            self._mem.raw("velocity_limit"),
            bool(self._mem.raw("drive_mode") & DRIVE_MODE_TIME_BASED),
        )

    def _start_spin(self, now: float) -> None:
        self._drive.spin(now, self._mem.raw("goal_velocity"), self._mem.raw("profile_acceleration"))

    def _torque_on(self, now: float) -> None:
        """Torque on: position mode wraps to one turn; the goal becomes the present position."""
        position = self._drive.position(now)
        if self._mem.raw("operating_mode") == POSITION:
            position = self._mem.one_turn(position)
        self._drive.hold(position, now)
        self._mem.put("goal_position", wrap32(round(position)))

    def _torque_off(self) -> None:
        now = self._clock()
        self._mem.put("torque_enable", 0)
        self._drive.hold(self._drive.position(now), now)

    def _cool(self, now: float) -> None:
        """Present Temperature on the way down from `heat`; Overheating above the limit."""
        temperature = self._heat.temperature(now)
        if temperature is None:
            return
        self._mem.put("present_temperature", temperature)
        if self._mem.raw("present_temperature") > self._mem.raw("temperature_limit"):
            self.raise_alert(_OVERHEATING)

    def _refresh(self) -> None:
        now = self._clock()
        self._cool(now)
        position, velocity, running, endless = self._drive.sample(now)
        kind, tick_ms = int(self._drive.kind), int((now - self._boot) * 1000)
        self._mem.show_motion(position, velocity, running, endless, kind, tick_ms)


#: Registers whose change has side effects beyond the stored bytes.
_WATCHED = ("homing_offset", "drive_mode", "operating_mode", "torque_enable")
