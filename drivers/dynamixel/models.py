"""One control table per Dynamixel X-series model, from the ROBOTIS e-manual.

The XM430-W350's table (:mod:`drivers.dynamixel.control_table`, plus the items only the
emulator uses: Startup Configuration, the feedforward gains, Backup Ready and the
Indirect Address/Data blocks) is the base; every other model is that table with its
differences, as its e-manual page lists them (emanual.robotis.com/docs/en/dxl/x/<page>/;
each `Model` records its page). What differs between the models:

* XL430-W250, 2XL430-W250: no Current Limit (38) nor Goal Current (102); Present Load
  (126, 0.1 %) where the others have Present Current; operating modes 1, 3, 4, 16;
  voltage limits 6.0-14.0 V;
* XL330-M077/M288, XC330-M181/M288/T181/T288: currents in 1 mA; Velocity Limit up to
  2,047; PWM Slope (62); baud rates 0-6 (no 4.5 Mbps); Protocol Type 2-22; 20 Indirect
  Address/Data slots (168-206, 208-227) and a table ending at 227;
* XM540-W150/W270: Current Limit up to 2,047; External Port Mode 1-3 (56-58) and Data
  1-3 (152-156);
* XH430-W210/W350: Current Limit up to 648;
* and each model's defaults (Velocity Limit, gains, temperature and voltage limits).

Startup Configuration (60) and Backup Ready (147) come with firmware 45 (e-manual,
Protocol 2.0, "Control Table Backup"); every model here has them at that firmware, as
the pages of the XL430-W250, XL330-M288 and XC330 list them.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, Literal

from drivers.dynamixel.control_table import ITEMS as BASE_ITEMS
from drivers.dynamixel.control_table import OPERATING_MODES, Area, Item

#: The e-manual's pages of the X series.
EMANUAL = "https://emanual.robotis.com/docs/en/dxl/x/"

#: Indirect blocks of the X430/X540 tables: (first slot, address of its Indirect
#: Address, address of its Indirect Data, slots).
X430_INDIRECT: tuple[tuple[int, int, int, int], ...] = ((1, 168, 224, 28), (29, 578, 634, 28))
#: The X330's one block of 20 slots.
X330_INDIRECT: tuple[tuple[int, int, int, int], ...] = ((1, 168, 208, 20),)

ALL_MODES = frozenset(OPERATING_MODES.values())
#: XL430: velocity, position, extended position, PWM (no current control).
XL430_MODES = frozenset({1, 3, 4, 16})


def indirect_items(blocks: tuple[tuple[int, int, int, int], ...], end: int) -> tuple[Item, ...]:
    """Indirect Address n (2 bytes, RAM, 64 … ``end``, default its Indirect Data's
    address) and Indirect Data n (1 byte) for every slot of ``blocks``."""
    items: list[Item] = []
    for first, address_at, data_at, count in blocks:
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
                    low=64,
                    high=end,
                )
            )
            items.append(Item(f"indirect_data_{n}", data, 1, Area.RAM, True, low=0, high=255))
    return tuple(items)


_FIRMWARE_45: tuple[Item, ...] = (
    Item("startup_configuration", 60, 1, Area.EEPROM, True, default=0, low=0, high=3),
    Item("backup_ready", 147, 1, Area.RAM, False, default=0),
)
_FEEDFORWARD: tuple[Item, ...] = (
    Item("feedforward_2nd_gain", 88, 2, Area.RAM, True, default=0, low=0, high=16383),
    Item("feedforward_1st_gain", 90, 2, Area.RAM, True, default=0, low=0, high=16383),
)


@dataclass(frozen=True)
class Model:
    """One model's control table: ``items`` in address order, the Operating Mode values
    it accepts, its Indirect blocks, the e-manual ``page`` the figures come from, and
    the unit of its current registers (mA; None where it has none)."""

    number: int
    name: str
    page: str
    items: tuple[Item, ...]
    modes: frozenset[int]
    indirect: tuple[tuple[int, int, int, int], ...]
    current_ma: float | None
    by_name: dict[str, Item] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "by_name", {it.name: it for it in self.items})

    @property
    def table_end(self) -> int:
        """One past the last address of the table."""
        last = max(self.items, key=lambda it: it.address)
        return last.address + last.size

    def has(self, name: str) -> bool:
        return name in self.by_name

    def item(self, name: str) -> Item:
        """The register ``name`` of this model (KeyError saying the model lacks it)."""
        try:
            return self.by_name[name]
        except KeyError:
            raise KeyError(f"the {self.name} has no control-table item {name!r}") from None

    @cached_property
    def item_at(self) -> tuple[Item | None, ...]:
        """The item each address 0 … `table_end` − 1 belongs to (None: reserved)."""
        out: list[Item | None] = [None] * self.table_end
        for it in self.items:
            out[it.address : it.address + it.size] = [it] * it.size
        return tuple(out)


def _model(
    base: Model,
    number: int,
    name: str,
    page: str,
    *,
    changes: Mapping[str, Mapping[str, Any] | None] = {},
    extra: tuple[Item, ...] = (),
    modes: frozenset[int] | None = None,
    indirect: tuple[tuple[int, int, int, int], ...] | None = None,
    current_ma: float | Literal["base"] | None = "base",
) -> Model:
    """``base`` with the item ``changes`` (name → fields to replace, None: absent), the
    ``extra`` items, and another model number, name, page, modes, Indirect blocks."""
    blocks = base.indirect if indirect is None else indirect
    kept: list[Item] = []
    for it in base.items:
        if it.name.startswith("indirect_"):
            continue
        change = changes.get(it.name, {})
        if change is None:
            continue
        if it.name == "model_number":
            change = {**change, "default": number}
        kept.append(dataclasses.replace(it, **change))
    end = max(data_at + count for _, _, data_at, count in blocks) - 1
    items = kept + list(extra) + list(indirect_items(blocks, end))
    return Model(
        number,
        name,
        EMANUAL + page + "/",
        tuple(sorted(items, key=lambda it: it.address)),
        base.modes if modes is None else modes,
        blocks,
        base.current_ma if current_ma == "base" else current_ma,
    )


_BASE = Model(
    1020,
    "XM430-W350",
    EMANUAL + "xm430-w350/",
    tuple(
        sorted(
            BASE_ITEMS + _FIRMWARE_45 + _FEEDFORWARD + indirect_items(X430_INDIRECT, 661),
            key=lambda it: it.address,
        )
    ),
    ALL_MODES,
    X430_INDIRECT,
    2.69,
)


def _current(limit: int) -> dict[str, Mapping[str, Any]]:
    """Current Limit (default and top) ``limit``, Goal Current within ±``limit``."""
    return {
        "current_limit": {"default": limit, "high": limit},
        "goal_current": {"low": -limit, "high": limit},
    }


def _voltage(
    low: int, high: int, max_default: int, min_default: int
) -> dict[str, Mapping[str, Any]]:
    return {
        "max_voltage_limit": {"default": max_default, "low": low, "high": high},
        "min_voltage_limit": {"default": min_default, "low": low, "high": high},
    }


def _gains(vi: int, vp: int, pd: int, pi: int, pp: int) -> dict[str, Mapping[str, Any]]:
    return {
        "velocity_i_gain": {"default": vi},
        "velocity_p_gain": {"default": vp},
        "position_d_gain": {"default": pd},
        "position_i_gain": {"default": pi},
        "position_p_gain": {"default": pp},
    }


# -- the X430/X540 family ------------------------------------------------------------------

_XM430_W210 = _model(
    _BASE,
    1030,
    "XM430-W210",
    "xm430-w210",
    changes={"velocity_limit": {"default": 330}, **_voltage(95, 160, 160, 95)},
)
_XH430_W350 = _model(
    _BASE,
    1000,
    "XH430-W350",
    "xh430-w350",
    changes={
        "velocity_limit": {"default": 130},
        "position_p_gain": {"default": 900},
        **_current(648),
        **_voltage(95, 160, 160, 95),
    },
)
_XH430_W210 = _model(
    _XH430_W350,
    1010,
    "XH430-W210",
    "xh430-w210",
    changes={"velocity_limit": {"default": 210}},
)
_EXTERNAL_PORTS: tuple[Item, ...] = tuple(
    Item(f"external_port_mode_{n}", 55 + n, 1, Area.EEPROM, True, default=3, low=0, high=3)
    for n in (1, 2, 3)
) + tuple(
    Item(f"external_port_data_{n}", 150 + 2 * n, 2, Area.RAM, True, low=0, high=0xFFFF)
    for n in (1, 2, 3)
)
_XM540_W270 = _model(
    _BASE,
    1120,
    "XM540-W270",
    "xm540-w270",
    changes={"velocity_limit": {"default": 128}, **_current(2047), **_voltage(95, 160, 160, 95)},
    extra=_EXTERNAL_PORTS,
)
_XM540_W150 = _model(
    _XM540_W270,
    1130,
    "XM540-W150",
    "xm540-w150",
    changes={"velocity_limit": {"default": 230}},
)

_XL430_CHANGES: dict[str, Mapping[str, Any] | None] = {
    "current_limit": None,
    "goal_current": None,
    "present_current": None,
    "temperature_limit": {"default": 72},
    **_voltage(60, 140, 140, 60),
    **_gains(1000, 100, 4000, 0, 640),
    "velocity_limit": {"default": 265},
}
_PRESENT_LOAD = Item("present_load", 126, 2, Area.RAM, False, signed=True, unit="0.1 %")
_XL430_W250 = _model(
    _BASE,
    1060,
    "XL430-W250",
    "xl430-w250",
    changes=_XL430_CHANGES,
    extra=(_PRESENT_LOAD,),
    modes=XL430_MODES,
    current_ma=None,
)
_2XL430_W250 = _model(
    _XL430_W250,
    1090,
    "2XL430-W250",
    "2xl430-w250",
    changes={"velocity_limit": {"default": 250}, **_gains(1800, 100, 2000, 0, 640)},
)

# -- the X330 family -----------------------------------------------------------------------

_PWM_SLOPE = Item(
    "pwm_slope", 62, 1, Area.EEPROM, True, unit="1.977 mV/ms", default=140, low=1, high=255
)
_X330_CHANGES: dict[str, Mapping[str, Any] | None] = {
    "baud_rate": {"high": 6},
    "protocol_type": {"low": 2, "high": 22},
    "temperature_limit": {"default": 70},
    "velocity_limit": {"high": 2047},
    "goal_velocity": {"low": -2047, "high": 2047},
}
_XL330_M288 = _model(
    _BASE,
    1200,
    "XL330-M288",
    "xl330-m288",
    changes={
        **_X330_CHANGES,
        "drive_mode": {"allowed": frozenset({0, 1, 4, 5})},
        "shutdown": {"default": 53},
        "velocity_limit": {"default": 445, "high": 2047},
        **_current(1750),
        **_voltage(31, 70, 70, 35),
        **_gains(1600, 180, 0, 0, 400),
    },
    extra=(_PWM_SLOPE,),
    indirect=X330_INDIRECT,
    current_ma=1.0,
)
_XL330_M077 = _model(
    _XL330_M288,
    1190,
    "XL330-M077",
    "xl330-m077",
    changes={"velocity_limit": {"default": 1620}, **_gains(400, 40, 0, 400, 400)},
)
_XC330_M288 = _model(
    _XL330_M288,
    1240,
    "XC330-M288",
    "xc330-m288",
    changes={
        "drive_mode": {"allowed": _BASE.by_name["drive_mode"].allowed},
        "shutdown": {"default": 52},
        "velocity_limit": {"default": 350},
        **_current(2352),
        **_gains(1600, 50, 500, 0, 1100),
    },
)
_XC330_M181 = _model(
    _XC330_M288,
    1230,
    "XC330-M181",
    "xc330-m181",
    changes={"velocity_limit": {"default": 545}, **_gains(1400, 100, 500, 0, 1200)},
)
_XC330_T288 = _model(
    _XC330_M288,
    1220,
    "XC330-T288",
    "xc330-t288",
    changes={
        "velocity_limit": {"default": 320},
        "pwm_slope": {"default": 255},
        **_current(910),
        **_voltage(55, 140, 140, 55),
        **_gains(1200, 40, 0, 0, 900),
    },
)
_XC330_T181 = _model(
    _XC330_T288,
    1210,
    "XC330-T181",
    "xc330-t181",
    changes={"velocity_limit": {"default": 510}},
)

#: Every model the driver and the emulator know, by model number.
MODELS: dict[int, Model] = {
    m.number: m
    for m in (
        _BASE,
        _XM430_W210,
        _XH430_W210,
        _XH430_W350,
        _XM540_W150,
        _XM540_W270,
        _XL430_W250,
        _2XL430_W250,
        _XL330_M077,
        _XL330_M288,
        _XC330_M181,
        _XC330_M288,
        _XC330_T181,
        _XC330_T288,
    )
}
#: Model number → name.
MODEL_NAMES: dict[int, str] = {n: m.name for n, m in MODELS.items()}
#: The table a motor of an unknown model number is taken to have (the XM430-W350's).
DEFAULT_MODEL = _BASE


def model(number: int) -> Model:
    """The model of ``number``; for an unknown number, the XM430-W350's table under it."""
    known = MODELS.get(number)
    if known is not None:
        return known
    return dataclasses.replace(_BASE, number=number, name=f"model {number}")


def model_number(name_or_number: str | int) -> int:
    """The model number of a model name (e.g. ``"XL430-W250"``) or of a number."""
    if isinstance(name_or_number, int):
        return name_or_number
    for number, name in MODEL_NAMES.items():
        if name.lower() == name_or_number.strip().lower():
            return number
    raise ValueError(
        f"unknown motor model {name_or_number!r}; known: {', '.join(MODEL_NAMES.values())}"
    )
