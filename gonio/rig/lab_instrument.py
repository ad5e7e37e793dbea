"""The rig file's ``detector.interface: {kind: pymeasure, ...}``: a detector read through
a PyMeasure instrument class over PyVISA (a lock-in amplifier, an optical power meter,
an electrometer, a multimeter; docs/how-to/lab-detectors.md). For the instruments of
`drivers.pymeasure.PRESETS` only ``instrument`` and ``resource`` are needed; every
other field overrides the preset. Checked without importing PyMeasure (the rig loads
no serial stack): every property named (a setting, the reading, the range, the status)
of a preset's class must be one the class declares (`drivers.pymeasure.PROPERTIES`,
read from the classes); another class's are checked when the detector opens. Every
field, its default, description and bounds are the driver's
(`drivers.pymeasure.PyMeasureDetectorConfig`, `gonio.rig.driver_spec`); a field a
preset gives (`drivers.pymeasure.PRESET_FIELDS`) may be left out.
"""

from __future__ import annotations

import re
from typing import TYPE_CHECKING, Annotated, Any, Literal

from pydantic import field_validator, model_validator

from drivers.pymeasure import (
    PRESET_FIELDS,
    PRESETS,
    PROPERTIES,
    ExposureConfig,
    PyMeasureConfigError,
    PyMeasureDetectorConfig,
    unknown_property,
)
from gonio.config import Strict, field_error
from gonio.config_schema import InSchema
from gonio.rig.driver_spec import driver_model

#: The largest magnitude of a number a setting gives: above any instrument's frequency
#: (a lock-in's reaches 500 kHz), range or count; and the smallest nonzero one: below any
#: sensitivity or range (an electrometer's 20 pA).
MAX_SETTING = 1e9
MIN_SETTING = 1e-15
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


if TYPE_CHECKING:

    class _ExposureFields(Strict):
        """`ExposureConfig`'s fields, none read off the spec."""

    class _InterfaceFields(Strict):
        """The fields of the PyMeasure interface's `driver_model` read off the spec."""

        kind: Literal["pymeasure"]
        instrument: str

else:
    _ExposureFields = driver_model("ExposureFields", ExposureConfig, required=("kind",))


class PyMeasureExposureSpec(_ExposureFields):
    """How an exposure is realised: ``wait`` (the exposure is waited, then the reading
    read), ``time_constant`` (a lock-in: the longest τ with settle_tau · τ ≤ the exposure
    is set, the exposure waited), ``averaging`` (a power meter: round(exposure / count_s)
    samples averaged) or ``nplc`` (a meter: exposure × line_hz power-line cycles)."""


if not TYPE_CHECKING:
    _InterfaceFields = driver_model(
        "InterfaceFields",
        PyMeasureDetectorConfig,
        kind=("pymeasure", "pymeasure: a PyMeasure instrument class."),
        types={
            "instrument": Annotated[str, InSchema(pattern=f"^{_DOTTED.pattern}$")],
            "exposure": PyMeasureExposureSpec,
            "settings": dict[str, SettingValue],
        },
        optional=PRESET_FIELDS,
    )


class PyMeasureInterfaceSpec(_InterfaceFields):
    """A detector read through a PyMeasure instrument class (`PyMeasureDetectorConfig`):
    the class, its VISA resource and how gonio uses it; the instruments gonio knows
    (`drivers.pymeasure.PRESETS`) need only ``instrument`` and ``resource``."""

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
