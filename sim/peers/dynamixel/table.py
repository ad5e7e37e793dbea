"""An emulated motor's control table: its model's table (:mod:`drivers.dynamixel.models`)
with what the emulator derives from it.

Each model's items, ranges, defaults and Indirect blocks are the driver's data, taken
from the model's e-manual page; `Table` adds the lookups the write rules need: the item
at each address, the Indirect Address of each Indirect Data byte, the factory memory
image and the items a Control Table Backup keeps.

Indirect Data *n* stands for the byte whose address Indirect Address *n* holds, and
inherits its size, range and access (e-manual, "Indirect Address, Indirect Data"): an
item wider than one byte takes one slot per byte, and only RAM addresses (64 to the end
of the table) may be mapped. How an emulated motor resolves the slots is in
:mod:`sim.peers.dynamixel.rules`.
"""

from __future__ import annotations

from drivers.dynamixel import DEFAULT_MODEL, Item, Model, model

#: The RAM items a Control Table Backup keeps besides the whole EEPROM area (e-manual,
#: Protocol 2.0, "Control Table Backup"): velocity PI and position PID gains, the
#: feedforward gains, Profile Acceleration and Velocity, the Indirect Addresses.
_BACKUP_RAM_NAMES = frozenset(
    {
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
)


class Table:
    """The control table of ``spec`` (a model) as an emulated motor uses it."""

    def __init__(self, spec: Model) -> None:
        self.model = spec
        self.items: tuple[Item, ...] = spec.items
        self.by_name: dict[str, Item] = spec.by_name
        #: One past the last address.
        self.size: int = spec.table_end
        #: The item each address belongs to (None for reserved bytes).
        self.item_at: tuple[Item | None, ...] = spec.item_at
        #: Indirect Data address → address of its Indirect Address.
        self.indirect_slot: dict[int, int] = {
            data_at + k: address_at + 2 * k
            for _, address_at, data_at, count in spec.indirect
            for k in range(count)
        }
        #: The addresses an Indirect Address may hold (the RAM area).
        self.indirect_targets = range(64, self.size)
        self.backup_ram_items: tuple[Item, ...] = tuple(
            it
            for it in self.items
            if it.name in _BACKUP_RAM_NAMES or it.name.startswith("indirect_address_")
        )
        memory = bytearray(self.size)
        for it in self.items:
            memory[it.address : it.address + it.size] = it.encode(it.default)
        #: The memory image of a motor fresh from the factory.
        self.defaults = bytes(memory)

    def touches_indirect_data(self, address: int, length: int) -> bool:
        """True if ``length`` bytes from ``address`` include an Indirect Data byte."""
        return any(
            address < data_at + count and data_at < address + length
            for _, _, data_at, count in self.model.indirect
        )


_TABLES: dict[int, Table] = {}


def table_of(number: int) -> Table:
    """The emulated table of model ``number`` (an unknown number: the XM430-W350's)."""
    table = _TABLES.get(number)
    if table is None:
        table = _TABLES[number] = Table(model(number))
    return table


#: The default model's table (XM430-W350), as module names.
DEFAULT_TABLE = table_of(DEFAULT_MODEL.number)
ITEMS = DEFAULT_TABLE.items
BY_NAME = DEFAULT_TABLE.by_name
EMULATED_TABLE_SIZE = DEFAULT_TABLE.size
INDIRECT_SLOT = DEFAULT_TABLE.indirect_slot
BACKUP_RAM_ITEMS = DEFAULT_TABLE.backup_ram_items

#: Startup Configuration bits (firmware ≥ 45).
STARTUP_TORQUE_ON = 0x01
STARTUP_RAM_RESTORE = 0x02
