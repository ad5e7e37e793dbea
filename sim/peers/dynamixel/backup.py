"""An emulated motor's Control Table Backup (instruction 0x20, firmware ≥ 45; e-manual,
Protocol 2.0, emanual.robotis.com/docs/en/dxl/protocol2/, "Control Table Backup
(0x20)"): with torque off, "store" keeps the EEPROM area and the RAM items of
`BACKUP_RAM_ITEMS` (gains, profile, Indirect Addresses) in a backup area that survives
REBOOT and FACTORY_RESET (*assumption* for the latter) and sets Backup Ready (147);
"restore" writes the backed-up EEPROM area back and reboots. At every boot Startup
Configuration (60) bit 1 restores the backed-up RAM items.
"""

from __future__ import annotations

from drivers.dynamixel import EEPROM_END
from sim.peers.dynamixel.protocol import StatusError
from sim.peers.dynamixel.table import Table

#: CONTROL_TABLE_BACKUP (0x20): its parameters are an option then the magic "CTRL";
#: the instruction exists from firmware 45 on (X430/X540 series).
BACKUP_MAGIC = b"CTRL"
BACKUP_STORE = 0x01
BACKUP_RESTORE = 0x02
BACKUP_FIRMWARE = 45


class Backup:
    """A motor's backup area: a copy of its memory image when it was stored (None: never)."""

    def __init__(self, table: Table) -> None:
        self._table = table
        self._image: bytes | None = None

    @property
    def ready(self) -> bool:
        """True once a backup has been stored (Backup Ready)."""
        return self._image is not None

    def check(self, params: bytes, firmware: int, torque_on: bool) -> StatusError:
        """The error CONTROL_TABLE_BACKUP with ``params`` gets: Instruction error below
        firmware 45 (*assumption*: an older motor does not know it), Data Length unless
        five parameters, Data Range for another option or magic (*assumption*, as CLEAR),
        Result Fail with torque on (e-manual) or a restore with no backup (*assumption*)."""
        if firmware < BACKUP_FIRMWARE:
            return StatusError.INSTRUCTION
        if len(params) != 1 + len(BACKUP_MAGIC):
            return StatusError.DATA_LENGTH
        option, magic = params[0], bytes(params[1:])
        if option not in (BACKUP_STORE, BACKUP_RESTORE) or magic != BACKUP_MAGIC:
            return StatusError.DATA_RANGE
        if torque_on or (option == BACKUP_RESTORE and not self._image):
            return StatusError.RESULT_FAIL
        return StatusError.NONE

    def store(self, memory: bytearray) -> None:
        """Keep a copy of ``memory`` (its EEPROM area and backed-up RAM items count)."""
        self._image = bytes(memory)

    def restore_eeprom(self, memory: bytearray) -> bool:
        """Write the backed-up EEPROM area into ``memory``; False (nothing written) if
        there is no backup."""
        if self._image is None:
            return False
        memory[:EEPROM_END] = self._image[:EEPROM_END]
        return True

    def restore_ram(self, memory: bytearray) -> None:
        """Write the backed-up RAM items into ``memory`` (a boot with Startup
        Configuration's RAM restore bit; nothing without a backup)."""
        if self._image is None:
            return
        for it in self._table.backup_ram_items:
            end = it.address + it.size
            memory[it.address : end] = self._image[it.address : end]
