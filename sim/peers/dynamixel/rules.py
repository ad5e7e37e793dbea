"""The X-series control-table write rules, as pure functions of a memory image.

Following the ROBOTIS e-manual (Protocol 2.0 error numbers):

* a write must cover whole items (part of an item → Data Length error 5) and only
  defined addresses (a reserved gap or past the table → Access error 7);
* read-only items, and EEPROM items (address < 64) while Torque Enable = 1 or when
  addressed through the Secondary ID → Access error 7;
* a value outside the item's range (the model's: `sim.peers.dynamixel.table.Table`), or an
  Operating Mode the model does not have (0, 1, 3, 4, 5, 16; the XL430 1, 3, 4, 16)
  → Data Range error 4;
* Goal Position outside [Min, Max Position Limit] in position mode or outside
  ±1,048,575 in (current-based) extended position mode, |Goal Velocity| > Velocity
  Limit, |Goal Current| > Current Limit, |Goal PWM| > PWM Limit → Data Limit error 6
  (limits written in the same packet count);
* Torque Enable = 1 while a shutdown is latched → Result Fail 1.

Indirect Data (e-manual, "Indirect Address, Indirect Data"): a host access to an
Indirect Data byte reaches the address its Indirect Address holds (`resolve`), so the
target's size, range and access rules apply through it — a 4-byte item mapped to four
slots must be written in one packet through all four (Data Length error 5 otherwise),
a read-only target stays read-only (Access error 7). The mapping is read after the
packet's own direct bytes, so one packet may set the slots and write through them
(*assumption*). A slot mapped to an Indirect Data address (the default maps each slot
to itself) reaches that byte itself, with no further indirection (*assumption*).

Items are checked in the order the packet reaches them and the first error wins.
"""

from __future__ import annotations

from drivers.dynamixel import EXTENDED_POSITION_LIMIT, OPERATING_MODES, Area, Item
from sim.peers.dynamixel.protocol import StatusError
from sim.peers.dynamixel.table import Table

POSITION = OPERATING_MODES["position"]
MULTI_TURN = (OPERATING_MODES["extended_position"], OPERATING_MODES["current_based_position"])

_GOAL_LIMITS = {
    "goal_velocity": "velocity_limit",
    "goal_current": "current_limit",
    "goal_pwm": "pwm_limit",
}


def value_in(table: Table, memory: bytes | bytearray, name: str) -> int:
    """The value of item ``name`` in a memory image of ``table``."""
    it = table.by_name[name]
    return it.decode(bytes(memory[it.address : it.address + it.size]))


def resolve(table: Table, memory: bytes | bytearray, address: int) -> int:
    """The address a host access at ``address`` reaches: itself, or for an Indirect Data
    byte the address its Indirect Address holds."""
    slot = table.indirect_slot.get(address)
    if slot is None:
        return address
    return memory[slot] | (memory[slot + 1] << 8)


def targets(table: Table, memory: bytes | bytearray, address: int, data: bytes) -> dict[int, int]:
    """Where each byte of a WRITE of ``data`` at ``address`` lands: target address →
    byte, in packet order (Indirect Data resolved after the packet's direct bytes)."""
    if not table.touches_indirect_data(address, len(data)):
        return dict(zip(range(address, address + len(data)), data, strict=True))
    direct = bytearray(memory)
    for i, byte in enumerate(data):
        if address + i not in table.indirect_slot:
            direct[address + i] = byte
    out: dict[int, int] = {}
    for i, byte in enumerate(data):
        out[resolve(table, direct, address + i)] = byte
    return out


def items_written(table: Table, writes: dict[int, int]) -> tuple[list[Item], StatusError]:
    """The items a scattered write (target address → byte) covers, or the error it gets
    for its shape alone (nothing, outside the table, a reserved byte, part of an item)."""
    if not writes:
        return [], StatusError.DATA_LENGTH
    items: dict[int, Item] = {}
    for a in writes:
        it = table.item_at[a] if 0 <= a < table.size else None
        if it is None:
            return [], StatusError.ACCESS
        if it.address in items:
            continue
        for b in range(it.address, it.address + it.size):
            if b not in writes:
                return [], StatusError.DATA_LENGTH
        items[it.address] = it
    return list(items.values()), StatusError.NONE


def check_write(
    table: Table,
    memory: bytes | bytearray,
    address: int,
    data: bytes,
    *,
    shutdown: bool = False,
    via_secondary: bool = False,
) -> StatusError:
    """The error a WRITE of ``data`` at ``address`` gets against ``memory`` (NONE if none).

    ``shutdown`` says a hardware error in the Shutdown mask is latched.
    """
    if not data:
        return StatusError.DATA_LENGTH
    if address < 0 or address + len(data) > table.size:
        return StatusError.ACCESS
    return check_writes(
        table,
        memory,
        targets(table, memory, address, data),
        shutdown=shutdown,
        via_secondary=via_secondary,
    )


def check_writes(
    table: Table,
    memory: bytes | bytearray,
    writes: dict[int, int],
    *,
    shutdown: bool = False,
    via_secondary: bool = False,
) -> StatusError:
    """The error a scattered write (target address → byte, see `targets`) gets."""
    items, error = items_written(table, writes)
    if error:
        return error
    after = bytearray(memory)
    for a, byte in writes.items():
        after[a] = byte
    torque_on = value_in(table, memory, "torque_enable") == 1
    for it in items:
        error = _check_item(
            table, it, after, torque_on=torque_on, shutdown=shutdown, via_secondary=via_secondary
        )
        if error:
            return error
    return StatusError.NONE


def _check_item(
    table: Table,
    it: Item,
    after: bytearray,
    *,
    torque_on: bool,
    shutdown: bool,
    via_secondary: bool,
) -> StatusError:
    if not it.writable:
        return StatusError.ACCESS
    if it.area is Area.EEPROM and (torque_on or via_secondary):
        return StatusError.ACCESS
    new = value_in(table, after, it.name)
    if not it.in_range(new):
        return StatusError.DATA_RANGE
    if it.name == "operating_mode" and new not in table.model.modes:
        return StatusError.DATA_RANGE
    if it.name == "goal_position":
        mode = value_in(table, after, "operating_mode")
        if mode == POSITION:
            low = value_in(table, after, "min_position_limit")
            high = value_in(table, after, "max_position_limit")
            if not low <= new <= high:
                return StatusError.DATA_LIMIT
        elif mode in MULTI_TURN and abs(new) > EXTENDED_POSITION_LIMIT:
            return StatusError.DATA_LIMIT
    if it.name in _GOAL_LIMITS and abs(new) > value_in(table, after, _GOAL_LIMITS[it.name]):
        return StatusError.DATA_LIMIT
    if it.name == "torque_enable" and new == 1 and shutdown:
        return StatusError.RESULT_FAIL
    return StatusError.NONE
