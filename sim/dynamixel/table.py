"""The emulated X-series control table: the driver's table plus what only the emulator needs.

:mod:`drivers.dynamixel.control_table` lists the items the driver uses (addresses 0-146).
An emulated motor also has, as the ROBOTIS e-manual's X430 control tables give them
(XM430-W350, XM430-W210 and XL430-W250 pages, emanual.robotis.com/docs/en/dxl/x/):

* Startup Configuration (60, EEPROM, 1 byte, 0-3; firmware ≥ 45): bit 0 turns torque on
  at start-up, bit 1 restores the backed-up RAM items at start-up;
* Feedforward 2nd and 1st Gains (88 and 90, RAM, 2 bytes, 0-16,383, default 0);
* Backup Ready (147, RAM, read-only, 1 byte): 1 while a Control Table Backup exists;
* Indirect Address 1-28 at 168-222 (2 bytes each, RAM, range 64-661, default the address
  of Indirect Data *n*, 224-251) with Indirect Data 1-28 at 224-251 (1 byte each), and
  Indirect Address 29-56 at 578-632 (default 634-661) with Indirect Data 29-56 at
  634-661. The table ends at 661.

Indirect Data *n* stands for the byte whose address Indirect Address *n* holds, and
inherits its size, range and access (e-manual, "Indirect Address, Indirect Data"): an
item wider than one byte takes one slot per byte, and only RAM addresses (64-661) may be
mapped. How an emulated motor resolves the slots is in :mod:`sim.dynamixel.rules`.
"""

from __future__ import annotations

from drivers.dynamixel.control_table import ITEMS as DRIVER_ITEMS
from drivers.dynamixel.control_table import Area, Item

#: Indirect Address n at ADDRESS_BLOCKS[k][0] + 2(n - first), Indirect Data n at
#: DATA_BLOCKS[k][0] + (n - first): (first slot number, address of its Indirect Address,
#: address of its Indirect Data, slots in the block).
INDIRECT_BLOCKS: tuple[tuple[int, int, int, int], ...] = ((1, 168, 224, 28), (29, 578, 634, 28))
#: One past the last address of the emulated table.
EMULATED_TABLE_SIZE = 662
#: The addresses an Indirect Address may hold (the RAM area).
INDIRECT_TARGETS = range(64, EMULATED_TABLE_SIZE)


def _indirect_items() -> tuple[Item, ...]:
    items: list[Item] = []
    for first, address_at, data_at, count in INDIRECT_BLOCKS:
        for k in range(count):
            n, data = first + k, data_at + k
            items.append(
                Item(
                    f"indirect_address_{n}",
                    address_at + 2 * k,
                    2,
                    Area.RAM,
                    True,
                    default=data,
                    low=INDIRECT_TARGETS.start,
                    high=INDIRECT_TARGETS.stop - 1,
                )
            )
            items.append(Item(f"indirect_data_{n}", data, 1, Area.RAM, True, low=0, high=255))
    return tuple(items)


_EXTRA: tuple[Item, ...] = (
    Item("startup_configuration", 60, 1, Area.EEPROM, True, default=0, low=0, high=3),
    Item("feedforward_2nd_gain", 88, 2, Area.RAM, True, default=0, low=0, high=16383),
    Item("feedforward_1st_gain", 90, 2, Area.RAM, True, default=0, low=0, high=16383),
    Item("backup_ready", 147, 1, Area.RAM, False, default=0),
)

#: Every item of an emulated motor, in address order.
ITEMS: tuple[Item, ...] = tuple(
    sorted(DRIVER_ITEMS + _EXTRA + _indirect_items(), key=lambda it: it.address)
)
BY_NAME: dict[str, Item] = {it.name: it for it in ITEMS}

#: The item each address belongs to (None for reserved bytes).
ITEM_AT: tuple[Item | None, ...] = tuple(
    next((it for it in ITEMS if it.address <= a < it.address + it.size), None)
    for a in range(EMULATED_TABLE_SIZE)
)

#: Indirect Data address → address of its Indirect Address.
INDIRECT_SLOT: dict[int, int] = {
    data_at + k: address_at + 2 * k
    for _, address_at, data_at, count in INDIRECT_BLOCKS
    for k in range(count)
}


def touches_indirect_data(address: int, length: int) -> bool:
    """True if ``length`` bytes from ``address`` include an Indirect Data byte."""
    return any(
        address < data_at + count and data_at < address + length
        for _, _, data_at, count in INDIRECT_BLOCKS
    )


#: Startup Configuration bits (firmware ≥ 45).
STARTUP_TORQUE_ON = 0x01
STARTUP_RAM_RESTORE = 0x02

#: The RAM items a Control Table Backup keeps besides the whole EEPROM area (e-manual,
#: Protocol 2.0, "Control Table Backup"): velocity PI and position PID gains, the
#: feedforward gains, Profile Acceleration and Velocity, the Indirect Addresses.
BACKUP_RAM_ITEMS: tuple[Item, ...] = tuple(
    it
    for it in ITEMS
    if it.name
    in {
        "velocity_i_gain",
        "velocity_p_gain",
        "position_d_gain",
        "position_i_gain",
        "position_p_gain",
        "feedforward_2nd_gain",
        "feedforward_1st_gain",
        "profile_acceleration",
        "profile_velocity",
    }
    or it.name.startswith("indirect_address_")
)
