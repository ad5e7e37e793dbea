"""The X-series control table (Protocol 2.0) as data, and the units of its registers.

Addresses, sizes, ranges and defaults are the XM430-W350's (ROBOTIS e-manual,
emanual.robotis.com/docs/en/dxl/x/xm430-w350/): the base every model's table in
:mod:`drivers.dynamixel.models` changes where that model differs. The addresses of the
items the driver reads and writes are the same on every X-series model. EEPROM items
can be written only with Torque Enable off; writing them with torque on is an Access
error.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum


class Area(Enum):
    EEPROM = "EEPROM"
    RAM = "RAM"


@dataclass(frozen=True)
class Item:
    """One register: where it is, how wide, how to read it and what it accepts."""

    name: str
    address: int
    size: int  # bytes, 1, 2 or 4, little endian
    area: Area
    writable: bool
    signed: bool = False
    unit: str = ""
    default: int = 0
    low: int | None = None  # accepted range when written (None: the size's full range)
    high: int | None = None
    allowed: frozenset[int] | None = None  # the only values accepted, where the range has gaps

    def encode(self, value: int) -> bytes:
        """``value`` as the register's little-endian bytes (two's complement if signed);
        ValueError if the register cannot hold it: a signed 4-byte item takes
        −2³¹ … 2³¹−1 (not the unsigned 2³¹ … 2³²−1 that would read back negative), an
        unsigned one 0 … 2³²−1."""
        try:
            return int(value).to_bytes(self.size, "little", signed=self.signed)
        except OverflowError:
            kind = "signed" if self.signed else "unsigned"
            raise ValueError(
                f"{self.name} = {value} does not fit in {self.size} {kind} bytes"
            ) from None

    def decode(self, raw: bytes | int) -> int:
        """The register's value from its bytes, or from the SDK's unsigned integer."""
        if isinstance(raw, int):
            raw = (raw & ((1 << (8 * self.size)) - 1)).to_bytes(self.size, "little")
        return int.from_bytes(raw, "little", signed=self.signed)

    def in_range(self, value: int) -> bool:
        if self.allowed is not None:
            return value in self.allowed
        bits = 8 * self.size
        low = self.low if self.low is not None else (-(1 << (bits - 1)) if self.signed else 0)
        high = (
            self.high
            if self.high is not None
            else ((1 << (bits - 1)) - 1 if self.signed else (1 << bits) - 1)
        )
        return low <= value <= high


E, R = Area.EEPROM, Area.RAM

ITEMS: tuple[Item, ...] = (
    Item("model_number", 0, 2, E, False, default=1020),
    Item("model_information", 2, 4, E, False),
    Item("firmware_version", 6, 1, E, False),
    Item("id", 7, 1, E, True, default=1, low=0, high=252),
    Item("baud_rate", 8, 1, E, True, default=1, low=0, high=7),
    Item("return_delay_time", 9, 1, E, True, unit="2 µs", default=250, low=0, high=254),
    # Drive Mode bits: 0 reverse, 2 time-based profile, 3 torque on by goal update.
    Item(
        "drive_mode",
        10,
        1,
        E,
        True,
        default=0,
        allowed=frozenset(range(16)) - {2, 3, 6, 7, 10, 11, 14, 15},
    ),
    Item("operating_mode", 11, 1, E, True, default=3, allowed=frozenset({0, 1, 3, 4, 5, 16})),
    Item("secondary_id", 12, 1, E, True, default=255, low=0, high=255),
    Item("protocol_type", 13, 1, E, True, default=2, low=1, high=2),
    Item("homing_offset", 20, 4, E, True, signed=True, unit="tick", low=-1_044_479, high=1_044_479),
    Item("moving_threshold", 24, 4, E, True, unit="0.229 rev/min", default=10, low=0, high=1023),
    Item("temperature_limit", 31, 1, E, True, unit="°C", default=80, low=0, high=100),
    Item("max_voltage_limit", 32, 2, E, True, unit="0.1 V", default=160, low=60, high=160),
    Item("min_voltage_limit", 34, 2, E, True, unit="0.1 V", default=95, low=60, high=160),
    Item("pwm_limit", 36, 2, E, True, default=885, low=0, high=885),
    Item("current_limit", 38, 2, E, True, unit="2.69 mA", default=1193, low=0, high=1193),
    # 200 on the XM430-W350's present page (an older page, of a firmware with
    # Acceleration Limit at 40, gave 350).
    Item("velocity_limit", 44, 4, E, True, unit="0.229 rev/min", default=200, low=0, high=1023),
    Item("max_position_limit", 48, 4, E, True, unit="tick", default=4095, low=0, high=4095),
    Item("min_position_limit", 52, 4, E, True, unit="tick", default=0, low=0, high=4095),
    Item("shutdown", 63, 1, E, True, default=52, low=0, high=255),
    Item("torque_enable", 64, 1, R, True, default=0, low=0, high=1),
    Item("led", 65, 1, R, True, default=0, low=0, high=1),
    Item("status_return_level", 68, 1, R, True, default=2, low=0, high=2),
    Item("registered_instruction", 69, 1, R, False),
    Item("hardware_error_status", 70, 1, R, False),
    Item("velocity_i_gain", 76, 2, R, True, default=1920, low=0, high=16383),
    Item("velocity_p_gain", 78, 2, R, True, default=100, low=0, high=16383),
    Item("position_d_gain", 80, 2, R, True, default=0, low=0, high=16383),
    Item("position_i_gain", 82, 2, R, True, default=0, low=0, high=16383),
    Item("position_p_gain", 84, 2, R, True, default=800, low=0, high=16383),
    Item("bus_watchdog", 98, 1, R, True, default=0, low=0, high=127),
    Item("goal_pwm", 100, 2, R, True, signed=True, low=-885, high=885),
    Item("goal_current", 102, 2, R, True, signed=True, unit="2.69 mA", low=-1193, high=1193),
    Item("goal_velocity", 104, 4, R, True, signed=True, unit="0.229 rev/min", low=-1023, high=1023),
    Item("profile_acceleration", 108, 4, R, True, unit="214.577 rev/min²", low=0, high=32767),
    Item("profile_velocity", 112, 4, R, True, unit="0.229 rev/min", low=0, high=32767),
    Item("goal_position", 116, 4, R, True, signed=True, unit="tick"),
    Item("realtime_tick", 120, 2, R, False, unit="ms"),
    Item("moving", 122, 1, R, False),
    Item("moving_status", 123, 1, R, False),
    Item("present_pwm", 124, 2, R, False, signed=True),
    Item("present_current", 126, 2, R, False, signed=True, unit="2.69 mA"),
    Item("present_velocity", 128, 4, R, False, signed=True, unit="0.229 rev/min"),
    Item("present_position", 132, 4, R, False, signed=True, unit="tick"),
    Item("velocity_trajectory", 136, 4, R, False, signed=True, unit="0.229 rev/min"),
    Item("position_trajectory", 140, 4, R, False, signed=True, unit="tick"),
    Item("present_input_voltage", 144, 2, R, False, unit="0.1 V"),
    Item("present_temperature", 146, 1, R, False, unit="°C"),
)

BY_NAME: dict[str, Item] = {item.name: item for item in ITEMS}
BY_ADDRESS: dict[int, Item] = {item.address: item for item in ITEMS}
#: One past the last address of the table (the RAM area ends here).
TABLE_SIZE = 147
#: EEPROM ends before Torque Enable.
EEPROM_END = 64


def item(name: str) -> Item:
    """The register called ``name`` (a KeyError names the known ones)."""
    try:
        return BY_NAME[name]
    except KeyError:
        raise KeyError(f"no control-table item {name!r}; known: {', '.join(BY_NAME)}") from None


# -- values with meaning ----------------------------------------------------------------

#: Baud Rate register value → bits per second.
BAUD_RATES: dict[int, int] = {
    0: 9_600,
    1: 57_600,
    2: 115_200,
    3: 1_000_000,
    4: 2_000_000,
    5: 3_000_000,
    6: 4_000_000,
    7: 4_500_000,
}
#: The X series' factory baud rate (Baud Rate register 1), bits per second.
FACTORY_BAUD = BAUD_RATES[1]

#: Operating Mode register values.
OPERATING_MODES: dict[str, int] = {
    "current": 0,
    "velocity": 1,
    "position": 3,
    "extended_position": 4,
    "current_based_position": 5,
    "pwm": 16,
}

#: Hardware Error Status bit → name (bit 1 is unused).
HARDWARE_ERROR_BITS: dict[int, str] = {
    0: "input_voltage",
    2: "overheating",
    3: "motor_encoder",
    4: "electrical_shock",
    5: "overload",
}

#: Drive Mode bit 0: reverse the direction of rotation.
DRIVE_MODE_REVERSE = 0x01

#: Extended position mode range of Goal Position (ticks, ±256 revolutions).
EXTENDED_POSITION_LIMIT = 1_048_575

TICKS_PER_REV = 4096
RAD_PER_TICK = 2.0 * math.pi / TICKS_PER_REV
#: Profile Velocity unit: 0.229 rev/min, in rad/s.
RAD_S_PER_VELOCITY_UNIT = 0.229 * 2.0 * math.pi / 60.0
#: Profile Acceleration unit: 214.577 rev/min², in rad/s².
RAD_S2_PER_ACCELERATION_UNIT = 214.577 * 2.0 * math.pi / 3600.0
VOLT_PER_UNIT = 0.1


def decode_hardware_error(status: int) -> tuple[str, ...]:
    """The named bits set in a Hardware Error Status byte (unknown bits as ``bit<n>``)."""
    return tuple(
        HARDWARE_ERROR_BITS.get(bit, f"bit{bit}") for bit in range(8) if status & (1 << bit)
    )
