"""The X-series control-table write rules, as pure functions of a memory image.

Following the ROBOTIS e-manual (Protocol 2.0 error numbers):

* a write must cover whole items (part of an item → Data Length error 5) and only
  defined addresses (a reserved gap or past the table → Access error 7);
* read-only items, and EEPROM items (address < 64) while Torque Enable = 1 or when
  addressed through the Secondary ID → Access error 7;
* a value outside the item's range, or an Operating Mode other than 0, 1, 3, 4, 5, 16
  → Data Range error 4;
* Goal Position outside [Min, Max Position Limit] in position mode or outside
  ±1,048,575 in (current-based) extended position mode, |Goal Velocity| > Velocity
  Limit, |Goal Current| > Current Limit, |Goal PWM| > PWM Limit → Data Limit error 6
  (limits written in the same packet count);
* Torque Enable = 1 while a shutdown is latched → Result Fail 1.

Items are checked in address order and the first error wins.
"""

from __future__ import annotations

from drivers.dynamixel.control_table import (
    BY_NAME,
    EXTENDED_POSITION_LIMIT,
    ITEMS,
    OPERATING_MODES,
    TABLE_SIZE,
    Area,
    Item,
)
from sim.dynamixel.protocol import StatusError

POSITION = OPERATING_MODES["position"]
MULTI_TURN = (OPERATING_MODES["extended_position"], OPERATING_MODES["current_based_position"])

#: The item each address belongs to (None for reserved bytes).
ITEM_AT: tuple[Item | None, ...] = tuple(
    next((it for it in ITEMS if it.address <= a < it.address + it.size), None)
    for a in range(TABLE_SIZE)
)

_GOAL_LIMITS = {
    "goal_velocity": "velocity_limit",
    "goal_current": "current_limit",
    "goal_pwm": "pwm_limit",
}


def value_in(memory: bytes | bytearray, name: str) -> int:
    """The value of item ``name`` in a memory image."""
    it = BY_NAME[name]
    return it.decode(bytes(memory[it.address : it.address + it.size]))


def items_written(address: int, length: int) -> tuple[list[Item], StatusError]:
    """The items a write of ``length`` bytes at ``address`` covers, or the error it gets
    for its shape alone (empty, outside the table, a reserved byte, part of an item)."""
    end = address + length
    if length < 1:
        return [], StatusError.DATA_LENGTH
    if address < 0 or end > TABLE_SIZE:
        return [], StatusError.ACCESS
    items: list[Item] = []
    a = address
    while a < end:
        it = ITEM_AT[a]
        if it is None:
            return [], StatusError.ACCESS
        if it.address < address or it.address + it.size > end:
            return [], StatusError.DATA_LENGTH
        items.append(it)
        a = it.address + it.size
    return items, StatusError.NONE


def check_write(
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
    items, error = items_written(address, len(data))
    if error:
        return error
    after = bytearray(memory)
    after[address : address + len(data)] = data
    torque_on = value_in(memory, "torque_enable") == 1
    for it in items:
        error = _check_item(
            it, after, torque_on=torque_on, shutdown=shutdown, via_secondary=via_secondary
        )
        if error:
            return error
    return StatusError.NONE


def _check_item(
    it: Item, after: bytearray, *, torque_on: bool, shutdown: bool, via_secondary: bool
) -> StatusError:
    if not it.writable:
        return StatusError.ACCESS
    if it.area is Area.EEPROM and (torque_on or via_secondary):
        return StatusError.ACCESS
    new = value_in(after, it.name)
    if not it.in_range(new):
        return StatusError.DATA_RANGE
    if it.name == "operating_mode" and new not in OPERATING_MODES.values():
        return StatusError.DATA_RANGE
    if it.name == "goal_position":
        mode = value_in(after, "operating_mode")
        if mode == POSITION:
            low, high = value_in(after, "min_position_limit"), value_in(after, "max_position_limit")
            if not low <= new <= high:
                return StatusError.DATA_LIMIT
        elif mode in MULTI_TURN and abs(new) > EXTENDED_POSITION_LIMIT:
            return StatusError.DATA_LIMIT
    if it.name in _GOAL_LIMITS and abs(new) > value_in(after, _GOAL_LIMITS[it.name]):
        return StatusError.DATA_LIMIT
    if it.name == "torque_enable" and new == 1 and shutdown:
        return StatusError.RESULT_FAIL
    return StatusError.NONE
