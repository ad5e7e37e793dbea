"""An emulated motor's control-table memory: the bytes of its model's table (little
endian), its registers by name, reads with Indirect Data resolved, and the position
frame its registers define.

Position frame (e-manual): Present Position = s·shaft + Homing Offset, with s = −1 in
reverse Drive Mode (the offset's sign is not reversed); position mode ignores an offset
outside ±1,024. Positions are in ticks (`TICKS_PER_REV` a turn).
"""

from __future__ import annotations

from drivers.dynamixel import BAUD_RATES, DRIVE_MODE_REVERSE, TICKS_PER_REV
from sim.peers.dynamixel.motion import TICKS_PER_S_PER_VELOCITY_UNIT
from sim.peers.dynamixel.rules import MULTI_TURN, POSITION, resolve
from sim.peers.dynamixel.table import Table

#: Position mode ignores a Homing Offset outside ±1,024 (e-manual).
_POSITION_MODE_HOMING_LIMIT = 1024


def wrap32(value: int) -> int:
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


class Memory:
    """The memory ``image`` of a motor of ``table`` (its defaults at first); the image is
    changed in place, never replaced."""

    def __init__(self, table: Table) -> None:
        self.table = table
        self.image = bytearray(table.defaults)

    def raw(self, name: str) -> int:
        """Register ``name``'s value as stored."""
        it = self.table.by_name[name]
        return it.decode(bytes(self.image[it.address : it.address + it.size]))

    def put(self, name: str, value: int) -> None:
        """Store ``value`` in item ``name``; ValueError (nothing stored) if the register
        cannot hold it (e.g. 2³¹ in a signed 4-byte item)."""
        it = self.table.by_name[name]
        self.image[it.address : it.address + it.size] = it.encode(value)

    def read(self, address: int, length: int) -> bytes:
        """``length`` bytes from ``address`` (IndexError outside the table); an Indirect
        Data byte reads the byte its Indirect Address names (a reserved one reads 0)."""
        table, image = self.table, self.image
        if length < 1 or address < 0 or address + length > table.size:
            raise IndexError(f"read of {length} bytes at {address} is outside 0..{table.size}")
        if not table.touches_indirect_data(address, length):
            return bytes(image[address : address + length])
        out = bytearray()
        for a in range(address, address + length):
            target = resolve(table, image, a)
            known = 0 <= target < table.size and table.item_at[target] is not None
            out.append(image[target] if known else 0)
        return bytes(out)

    # -- the position frame ---------------------------------------------------------------

    def homing(self) -> int:
        """The Homing Offset in effect (ticks): 0 in position mode beyond ±1,024."""
        offset = self.raw("homing_offset")
        if self.raw("operating_mode") == POSITION and abs(offset) > _POSITION_MODE_HOMING_LIMIT:
            return 0
        return offset

    def sign(self) -> int:
        """−1 in reverse Drive Mode, else 1."""
        return -1 if self.raw("drive_mode") & DRIVE_MODE_REVERSE else 1

    def to_shaft(self, position: float) -> float:
        """The shaft angle (ticks) of Present Position ``position``."""
        return self.sign() * (position - self.homing())

    def from_shaft(self, shaft: float) -> float:
        """Present Position (ticks) of the shaft angle ``shaft``."""
        return self.sign() * shaft + self.homing()

    def one_turn(self, position: float) -> float:
        """``position`` (ticks) brought back within one turn past the Homing Offset."""
        homing = self.homing()
        return homing + (position - homing) % TICKS_PER_REV

    # -- the registers derived from the motion ------------------------------------------

    def show_motion(
        self,
        position: float,
        velocity: float,
        running: bool,
        endless: bool,
        kind: int,
        tick_ms: int,
    ) -> None:
        """Store the registers a drive's sample derives: Present Position and Velocity
        (``position`` ticks, ``velocity`` ticks/s), Moving, Moving Status (``running``,
        the profile ``kind``, in position), the trajectories (``endless``: a spin) and
        Realtime Tick (``tick_ms`` since boot, modulo 32,768)."""
        present = wrap32(round(position))
        speed = wrap32(round(velocity / TICKS_PER_S_PER_VELOCITY_UNIT))
        moving = running or abs(speed) > self.raw("moving_threshold")
        status = kind
        if running:
            status |= 0x02
        if (
            self.raw("operating_mode") in (POSITION, *MULTI_TURN)
            and self.raw("torque_enable")
            and not running
            and present == self.raw("goal_position")
        ):
            status |= 0x01
        self.put("present_position", present)
        self.put("present_velocity", speed)
        self.put("moving", int(moving))
        self.put("moving_status", status)
        self.put("velocity_trajectory", speed if running or endless else 0)
        self.put("position_trajectory", present)
        self.put("realtime_tick", tick_ms % 32768)
