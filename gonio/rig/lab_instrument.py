"""The rig file's ``detector.interface: {kind: pymeasure, ...}``: a detector read through
a PyMeasure instrument class over PyVISA (a lock-in amplifier, an optical power meter,
an electrometer, a multimeter; docs/how-to/lab-detectors.md). For the instruments of
`drivers.pymeasure.PRESETS` only ``instrument`` and ``resource`` are needed; every
other field overrides the preset. Checked without importing PyMeasure (the rig loads
no serial stack): every property named (a setting, the reading, the range, the status)
of a preset's class must be one the class declares (`drivers.pymeasure.PROPERTIES`,
read from the classes); another class's are checked when the detector opens. Numbers
are bounded by what an instrument takes (the module's constants say why).
"""

from __future__ import annotations

import re
from typing import Annotated, Any, Literal

from pydantic import Field, field_validator, model_validator

from drivers.pymeasure import (
    PRESETS,
    PROPERTIES,
    ExposureConfig,
    PyMeasureConfigError,
    PyMeasureDetectorConfig,
    unknown_property,
)
from gonio.config import Strict, field_error
from gonio.config_schema import InSchema

#: The largest magnitude of a number a setting gives: above any instrument's frequency
#: (a lock-in's reaches 500 kHz), range or count; and the smallest nonzero one: below any
#: sensitivity or range (an electrometer's 20 pA).
MAX_SETTING = 1e9
MIN_SETTING = 1e-15
#: How long an answer may take beyond the integration (s): VISA's timeout is a 32-bit
#: count of milliseconds (49.7 days at most, the exposure added); an instrument silent
#: for an hour is not answering.
MAX_TIMEOUT_S = 3600.0
#: The slowest and the fastest serial line (baud): the slowest standard rate, and
#: USB-serial adapters' fastest (FTDI's FT2232H).
BAUD_RANGE = (50, 12_000_000)
#: The largest reading a full scale or a time constant may give (V, A, W; s): nine
#: orders above a volt, an ampere, a watt (a meter's over-range marker, 9.9e37, is
#: recognised on its own).
MAX_READING = 1e9
#: A status register's bits (SCPI's are 16, PyMeasure's status properties at most 32).
MAX_MASK = 2**32 - 1
#: Settle time in time constants: 99.9 % at 24 dB/oct is 13 τ; a hundred is generous.
MAX_SETTLE_TAU = 100.0
#: The longest averaged sample of a power meter (s; a PM100's is 0.3 ms).
MAX_COUNT_S = 60.0
#: The largest averaging count (a PM100's is 16 bits; ten million is generous).
MAX_COUNT = 10_000_000
#: The power line's frequency (Hz): railways' 16.7 Hz to aircraft's 400 Hz.
LINE_HZ_RANGE = (16.0, 400.0)
#: The power-line cycles an integrating meter takes (a Keithley's 0.01…10, a 34465A's
#: 0.001…100).
NPLC_RANGE = (1e-4, 1000.0)

Setting = float | int | str | bool
SettingValue = Annotated[
    Setting,
    InSchema(
        anyOf=[
            {"type": "number", "minimum": -MAX_SETTING, "maximum": MAX_SETTING},
            {"type": "string"},
            {"type": "boolean"},
        ]
    ),
]
_DOTTED = re.compile(r"[A-Za-z_]\w*(\.[A-Za-z_]\w*)+")
#: A number YAML 1.1 reads as text: an exponent without a dot (``1e-3``).
_EXPONENT = re.compile(r"[-+]?[0-9]+[eE][-+]?[0-9]+")


class PyMeasureExposureSpec(Strict):
    """How an exposure is realised: ``wait`` (the exposure is waited, then the reading
    read), ``time_constant`` (a lock-in: the longest τ with settle_tau · τ ≤ the exposure
    is set, the exposure waited), ``averaging`` (a power meter: round(exposure / count_s)
    samples averaged) or ``nplc`` (a meter: exposure × line_hz power-line cycles)."""

    kind: Literal["wait", "time_constant", "averaging", "nplc"] = Field(
        description="wait, time_constant, averaging or nplc."
    )
    property: str | None = Field(
        None,
        description="The instrument's property set: the time constant, averaging count or NPLC.",
    )
    command: str | None = Field(
        None,
        description="Instead of a property: a command template of {count} (averaging) or "
        "{nplc}, e.g. 'SENS:AVER:COUN {count:d}'.",
    )
    settle_tau: float = Field(
        10.0,
        gt=0,
        le=MAX_SETTLE_TAU,
        description="time_constant: the settle time in time constants (99 %: 5 at 6 dB/oct, "
        "7 at 12, 9 at 18, 10 at 24).",
    )
    values: tuple[Annotated[float, Field(gt=0, le=MAX_READING)], ...] = Field(
        (), description="time_constant: the allowed time constants (s; empty: the class's)."
    )
    count_s: float = Field(
        3e-4, gt=0, le=MAX_COUNT_S, description="averaging: seconds per averaged sample."
    )
    max_count: int = Field(10_000, ge=1, le=MAX_COUNT, description="averaging: the largest count.")
    line_hz: float = Field(
        50.0,
        ge=LINE_HZ_RANGE[0],
        le=LINE_HZ_RANGE[1],
        description="nplc: the power line's frequency (Hz).",
    )
    nplc_range: tuple[
        Annotated[float, Field(ge=NPLC_RANGE[0], le=NPLC_RANGE[1])],
        Annotated[float, Field(ge=NPLC_RANGE[0], le=NPLC_RANGE[1])],
    ] = Field((0.01, 10.0), description="nplc: the [min, max] NPLC the instrument accepts.")


class PyMeasureInterfaceSpec(Strict):
    """A detector read through a PyMeasure instrument class (`PyMeasureDetectorConfig`):
    the class, its VISA resource and how gonio uses it; the instruments gonio knows
    (`drivers.pymeasure.PRESETS`) need only ``instrument`` and ``resource``."""

    kind: Literal["pymeasure"] = Field(description="pymeasure: a PyMeasure instrument class.")
    instrument: Annotated[str, InSchema(pattern=f"^{_DOTTED.pattern}$")] = Field(
        description="The PyMeasure class's dotted name, e.g. pymeasure.instruments.srs.SR830.",
    )
    resource: str = Field(
        min_length=1,
        description="The VISA resource: GPIB0::8::INSTR, USB0::0x1313::0x8072::P2000000::INSTR, "
        "ASRL/dev/ttyUSB1::INSTR.",
    )
    visa_library: str = Field(
        "", description="PyVISA's backend: '' (the system's VISA), '@py' (pyvisa-py)."
    )
    read_termination: str | None = Field(
        None, description="What ends an answer (none: PyVISA's default; an SR830 on RS-232: \\r)."
    )
    write_termination: str | None = Field(
        None, description="What ends a command (none: PyVISA's default, \\r\\n)."
    )
    baud_rate: int | None = Field(
        None,
        ge=BAUD_RANGE[0],
        le=BAUD_RANGE[1],
        description="A serial instrument's baud rate.",
    )
    timeout_s: float = Field(
        2.0,
        gt=0,
        le=MAX_TIMEOUT_S,
        description="How long an answer may take beyond the instrument's integration (s).",
    )
    reading: str | None = Field(
        None, description="The property read per sample, e.g. magnitude (none: the preset's)."
    )
    unit: str | None = Field(None, description="The reading's unit, e.g. V (none: the preset's).")
    query: str | None = Field(
        None,
        description="Instead of the reading property: a command whose answer's first number is "
        "the reading, e.g. ':READ?' (none: the preset's).",
    )
    exposure: PyMeasureExposureSpec | None = Field(
        None, description="How an exposure is realised (none: the preset's)."
    )
    settings: dict[str, SettingValue] | None = Field(
        None,
        description="Properties set on opening, in order, e.g. {filter_slope: 24, "
        "sensitivity: 0.01} (none: the preset's).",
    )
    commands: tuple[str, ...] | None = Field(
        None, description="Commands written on opening, after settings (none: the preset's)."
    )
    range_property: str | None = Field(
        None, description="The property holding the range or sensitivity (none: the preset's)."
    )
    saturate_at_range: bool | None = Field(
        None, description="A reading at or above the range is saturated (none: the preset's)."
    )
    full_scale: float | None = Field(
        None,
        gt=0,
        le=MAX_READING,
        description="A reading at or above this is saturated (none: no such limit).",
    )
    overload_property: str | None = Field(
        None, description="A status property read after each sample (none: the preset's)."
    )
    overload_mask: int | None = Field(
        None,
        ge=1,
        le=MAX_MASK,
        description="The status bits that mean overload (none: the preset's).",
    )
    ranging: Literal["fixed", "auto"] | None = Field(
        None,
        description="fixed: the range is never changed; auto: the instrument auto-ranges and "
        "each change is logged (none: the preset's).",
    )
    std_property: str | None = Field(
        None, description="A property with the instrument's own standard deviation."
    )
    dark_subtracted: bool | None = Field(
        None,
        description="The reading carries no dark or ambient signal (a lock-in behind a chopper; "
        "none: the preset's).",
    )
    phase_property: str | None = Field(
        None,
        description="A lock-in's phase property (°), read after each sample and compared with "
        "the reference reading's, e.g. theta (none: the preset's).",
    )
    phase_tolerance_deg: float | None = Field(
        None,
        gt=0,
        le=180,
        description="How far the phase may drift from the reference reading's before an event "
        "is journaled (°; none: the preset's, 5).",
    )

    @field_validator("instrument")
    @classmethod
    def _dotted(cls, v: str) -> str:
        if _DOTTED.fullmatch(v) is None:
            raise ValueError(
                f"{v!r} is not a dotted class name; expected e.g. pymeasure.instruments.srs.SR830"
            )
        return v

    @field_validator("settings", mode="before")
    @classmethod
    def _exponents(cls, v: Any) -> Any:
        """A setting written ``1e-3`` is the number (YAML 1.1 reads it as text)."""
        if not isinstance(v, dict):
            return v
        return {
            k: float(x) if isinstance(x, str) and _EXPONENT.fullmatch(x.strip()) else x
            for k, x in v.items()
        }

    @field_validator("settings")
    @classmethod
    def _setting_numbers(cls, v: dict[str, Setting] | None) -> dict[str, Setting] | None:
        for name, value in (v or {}).items():
            if isinstance(value, bool) or not isinstance(value, int | float):
                continue
            if not (value == 0 or MIN_SETTING <= abs(value) <= MAX_SETTING):
                raise field_error(
                    name,
                    f"expected 0 or a magnitude from {MIN_SETTING:g} to {MAX_SETTING:g} "
                    f"(got {value!r})",
                )
        return v

    @model_validator(mode="after")
    def _driver_accepts(self) -> PyMeasureInterfaceSpec:
        config = self.config()
        known = PROPERTIES.get(config.instrument)
        unknown = None if known is None else unknown_property(config, known)
        if unknown is not None:
            raise field_error(*unknown)
        return self

    def config(self) -> PyMeasureDetectorConfig:
        """The driver's configuration: the preset of ``instrument`` overridden by every
        field given; a `field_error` at the field the driver refuses."""
        values: dict[str, Any] = dict(PRESETS.get(self.instrument, {}))
        given = self.model_dump(exclude={"kind"}, exclude_none=True)
        if "settings" in given:
            given["settings"] = tuple(given["settings"].items())
        values.update(given)
        for name in ("reading", "exposure"):
            if name not in values:
                known = ", ".join(sorted(PRESETS))
                raise field_error(
                    name,
                    f"Field required for an instrument with no preset (presets: {known})",
                )
        values["exposure"] = _exposure(values["exposure"])
        try:
            return PyMeasureDetectorConfig(**values)
        except PyMeasureConfigError as exc:
            field, _, message = str(exc).partition(" ")
            raise field_error(field, message) from None


def _exposure(values: dict[str, Any]) -> ExposureConfig:
    try:
        return ExposureConfig(**values)
    except PyMeasureConfigError as exc:
        field, _, message = str(exc).partition(" ")
        raise field_error(field, message) from None
