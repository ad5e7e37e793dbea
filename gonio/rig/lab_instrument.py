"""The rig file's ``detector.interface: {kind: pymeasure, ...}``: a detector read through
a PyMeasure instrument class over PyVISA (a lock-in amplifier, an optical power meter,
an electrometer, a multimeter; docs/how-to/lab-detectors.md). For the instruments of
`drivers.pymeasure.PRESETS` only ``instrument`` and ``resource`` are needed; every
other field overrides the preset. Checked without importing PyMeasure: the class is
loaded when the detector is opened.
"""

from __future__ import annotations

import re
from typing import Annotated, Any, Literal

from pydantic import Field, field_validator, model_validator

from drivers.pymeasure import (
    PRESETS,
    ExposureConfig,
    PyMeasureConfigError,
    PyMeasureDetectorConfig,
)
from gonio.config import Strict, field_error
from gonio.config_schema import InSchema

Setting = float | int | str | bool
_DOTTED = re.compile(r"[A-Za-z_]\w*(\.[A-Za-z_]\w*)+")


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
        description="time_constant: the settle time in time constants (99 %: 5 at 6 dB/oct, "
        "7 at 12, 9 at 18, 10 at 24).",
    )
    values: tuple[float, ...] = Field(
        (), description="time_constant: the allowed time constants (s; empty: the class's)."
    )
    count_s: float = Field(3e-4, gt=0, description="averaging: seconds per averaged sample.")
    max_count: int = Field(10_000, ge=1, description="averaging: the largest count.")
    line_hz: float = Field(50.0, gt=0, description="nplc: the power line's frequency (Hz).")
    nplc_range: tuple[float, float] = Field(
        (0.01, 10.0), description="nplc: the [min, max] NPLC the instrument accepts."
    )


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
    baud_rate: int | None = Field(None, gt=0, description="A serial instrument's baud rate.")
    timeout_s: float = Field(
        2.0,
        gt=0,
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
    settings: dict[str, Setting] | None = Field(
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
        None, gt=0, description="A reading at or above this is saturated (none: no such limit)."
    )
    overload_property: str | None = Field(
        None, description="A status property read after each sample (none: the preset's)."
    )
    overload_mask: int | None = Field(
        None, ge=1, description="The status bits that mean overload (none: the preset's)."
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

    @model_validator(mode="after")
    def _driver_accepts(self) -> PyMeasureInterfaceSpec:
        self.config()
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
