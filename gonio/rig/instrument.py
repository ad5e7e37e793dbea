"""The rig file's instrument sections: what the light, the detector and the reference
standard are, beside where their chains put them (`gonio.rig.schema`).

- ``light``: the source's kind (``collimated``, its beam diameter in
  ``constraints.beam_diameter_mm``; or ``point``, at ``distance_mm`` from the sample
  centre) and its ``switch``: ``none`` (the light cannot be switched: a dark reading is
  taken another way, e.g. with the beam blocked) or ``serial`` (commands on a serial
  port, `SerialSwitchSpec`).
- ``detector``: its collecting solid angle, exposure range, readout dead time, averaging
  limit and ``interface``: ``simulated``, ``serial`` (every field of
  `drivers.serial_detector.SerialDetectorConfig`, as the driver declares it:
  `SerialInterfaceSpec`, `gonio.rig.driver_spec`) or
  ``pymeasure`` (a PyMeasure instrument class, `gonio.rig.lab_instrument`).
- ``reference``: the Lambertian standard read for calibration, and where.

A value here is never repeated in a scene file (`gonio.scene` refuses it).
"""

from __future__ import annotations

import dataclasses
import math
import re
from typing import TYPE_CHECKING, Annotated, Any, Literal

from pydantic import Field, field_validator, model_validator

from drivers.light import SerialLightConfig
from drivers.serial_detector import (
    SerialDetectorConfig,
    SerialDetectorValueError,
    SerialStreamConfig,
)
from gonio.config import Strict, excerpt, field_error
from gonio.config_schema import InSchema
from gonio.rig.driver_spec import driver_model
from gonio.rig.lab_instrument import PyMeasureInterfaceSpec

#: Lengths on the sample (mm): a micrometre to 10 m, beyond any laboratory rig.
LENGTH_RANGE_MM = (1e-3, 1e4)
#: A point source's distance from the sample (mm): a millimetre (nearer, a lamp is no
#: point) to 100 m.
DISTANCE_RANGE_MM = (1.0, 1e5)

#: A command as the JSON Schema says it: not blank (`_check_command` checks the rest).
Command = Annotated[str, InSchema(pattern=r"\S")]

#: Line endings by name (a YAML file may also give the characters, e.g. ``"\r\n"``).
LINE_ENDINGS = {"lf": "\n", "crlf": "\r\n", "cr": "\r"}
#: What a file may write for a line ending: a name or the characters.
LineEnding = Literal["lf", "crlf", "cr", "\n", "\r\n", "\r"]
#: What a line ending is, in the words of the serial detector's (`drivers.described`).
LINE_ENDING = next(
    f.metadata["doc"] for f in dataclasses.fields(SerialDetectorConfig) if f.name == "line_ending"
)


def _line_ending_name(v: Any) -> Any:
    """``"\\r\\n"`` → ``"crlf"`` (the names are what the models store)."""
    return next((name for name, chars in LINE_ENDINGS.items() if v == chars), v)


def _tagged(v: Any) -> Any:
    """A bare kind (``switch: none``, ``interface: simulated``) means that kind with its
    defaults."""
    return {"kind": v} if isinstance(v, str) else v


def _check_pattern(field: str, pattern: str | None) -> None:
    if pattern is None:
        return
    try:
        re.compile(pattern)
    except re.error as exc:
        what = f"{excerpt(pattern)} is not a valid regular expression: {exc}"
        raise field_error(field, what) from None


def _check_command(field: str, command: str | None) -> None:
    if command is None:
        return
    if not command.strip():
        raise field_error(field, "expected a command, got an empty string")
    if "\r" in command or "\n" in command or not command.isascii():
        raise field_error(field, f"expected one line of ASCII text, got {excerpt(command)}")


# -- the light ---------------------------------------------------------------------------


class NoSwitchSpec(Strict):
    """The light cannot be switched by the program: the dark reading is taken another
    way (a shutter or a cap; the simulator models it as the source giving no light)."""

    kind: Literal["none"] = Field(description="none: the light cannot be switched.")


class SerialSwitchSpec(Strict):
    """A light switched by one-line commands on a serial port (a relay board, a lamp
    controller). ``ack``: a regex a line answering ``on_command``/``off_command`` must
    match (no answer is read without it). ``query_command``: asks the state; the
    answer matches ``on_reply`` when on, ``off_reply`` when off. ``warmup_s``: how long
    the source needs after switching on before readings are stable."""

    kind: Literal["serial"] = Field(description="serial: commands on a serial port.")
    port: str = Field(min_length=1, description="The serial port, e.g. /dev/ttyUSB1.")
    baud: int = Field(9600, gt=0, description="The baud rate.")
    line_ending: Literal["lf", "crlf", "cr"] = Field(
        "lf",
        description=LINE_ENDING,
    )
    on_command: Command = Field(description="The command that switches the light on (one line).")
    off_command: Command = Field(description="The command that switches the light off (one line).")
    ack: str | None = Field(
        None,
        description="A Python regex the answer to on_command and off_command must match (none: no "
        "answer is read).",
    )
    query_command: Command | None = Field(
        None, description="A command asking the light's state (with on_reply and off_reply)."
    )
    on_reply: str | None = Field(
        None,
        description="A Python regex the answer to query_command matches when on.",
    )
    off_reply: str | None = Field(
        None,
        description="A Python regex the answer to query_command matches when off.",
    )
    timeout_s: float = Field(1.0, gt=0, description="How long an answer may take (s).")
    warmup_s: float = Field(
        0.0,
        ge=0,
        description="How long the source needs after switching on until readings are stable (s).",
    )

    @model_validator(mode="before")
    @classmethod
    def _yaml_booleans(cls, data: Any) -> Any:
        if isinstance(data, dict) and any(isinstance(k, bool) for k in data):
            raise ValueError(
                "YAML reads the keys on: and off: as true and false; expected on_command: "
                "and off_command:"
            )
        return data

    @field_validator("line_ending", mode="before", json_schema_input_type=LineEnding)
    @classmethod
    def _ending(cls, v: Any) -> Any:
        return _line_ending_name(v)

    @model_validator(mode="after")
    def _usable(self) -> SerialSwitchSpec:
        for name in ("on_command", "off_command", "query_command"):
            _check_command(name, getattr(self, name))
        for name in ("ack", "on_reply", "off_reply"):
            _check_pattern(name, getattr(self, name))
        if self.query_command is not None:
            for name in ("on_reply", "off_reply"):
                if getattr(self, name) is None:
                    raise field_error(name, "expected a regex for the answer to query_command")
        elif self.on_reply is not None or self.off_reply is not None:
            raise field_error("query_command", "expected the command that on_reply answers")
        return self

    @property
    def line_ending_chars(self) -> str:
        return LINE_ENDINGS[self.line_ending]

    def config(self) -> SerialLightConfig:
        """The driver's configuration (`drivers.light.SerialLightConfig`)."""
        return SerialLightConfig(
            port=self.port,
            baud=self.baud,
            on=self.on_command,
            off=self.off_command,
            ack=self.ack,
            error_reply=None,
            query=self.query_command,
            on_reply=self.on_reply,
            off_reply=self.off_reply,
            line_ending=self.line_ending_chars,
            timeout_s=self.timeout_s,
            warmup_s=self.warmup_s,
        )


SwitchSpec = Annotated[NoSwitchSpec | SerialSwitchSpec, Field(discriminator="kind")]


class LightSpec(Strict):
    """What the light is, beside its chain: a distant ``collimated`` beam (its diameter
    is ``constraints.beam_diameter_mm``) or a ``point`` source ``distance_mm`` from the
    sample centre along ωi; and its switch."""

    kind: Literal["collimated", "point"] = Field(
        "collimated",
        description="collimated: a distant beam (its diameter is constraints.beam_diameter_mm); "
        "point: a lamp distance_mm from the sample centre.",
    )
    distance_mm: float | None = Field(
        None,
        ge=DISTANCE_RANGE_MM[0],
        le=DISTANCE_RANGE_MM[1],
        description="The point source's distance from the sample centre (mm); only with kind: "
        "point, and required then.",
    )
    switch: SwitchSpec = Field(
        NoSwitchSpec(kind="none"),
        description="none (the light cannot be switched: the dark reading is taken another way) "
        "or a serial switch (kind: serial).",
    )

    @field_validator("switch", mode="before", json_schema_input_type=Literal["none"] | SwitchSpec)
    @classmethod
    def _bare_kind(cls, v: Any) -> Any:
        return _tagged(v)

    @model_validator(mode="after")
    def _distance(self) -> LightSpec:
        if self.kind == "point" and self.distance_mm is None:
            raise field_error("distance_mm", "Field required for a point source (kind: point)")
        if self.kind == "collimated" and self.distance_mm is not None:
            raise field_error(
                "distance_mm", "a collimated beam has no distance; expected it with kind: point"
            )
        return self


# -- the detector ------------------------------------------------------------------------


class SimulatedInterfaceSpec(Strict):
    """The simulated detector (`sim.virtual.devices.detector.SimDetector`); the scene file
    gives its sensor."""

    kind: Literal["simulated"] = Field(description="simulated: the scene file gives its sensor.")


_DRIVER_FIELDS = tuple(f.name for f in dataclasses.fields(SerialDetectorConfig))

if TYPE_CHECKING:

    class _StreamFields(Strict):
        """The fields of `SerialStreamConfig`'s `driver_model` read off the spec."""

        max_rate_hz: float

    class _InterfaceFields(Strict):
        """The fields of the serial interface's `driver_model` read off the spec."""

        kind: Literal["serial"]
        line_ending: Literal["lf", "crlf", "cr"]
        init: tuple[str, ...]
        stream: SerialStreamSpec | None

else:
    _StreamFields = driver_model("StreamFields", SerialStreamConfig)


class SerialStreamSpec(_StreamFields):
    """A serial detector's streaming mode: every field of `SerialStreamConfig`
    (docs/reference/serial_detector.md, "Streaming"), checked by the driver's rules."""

    def config(self) -> SerialStreamConfig:
        """The driver's `SerialStreamConfig`."""
        return SerialStreamConfig(**self.model_dump())


if not TYPE_CHECKING:
    _InterfaceFields = driver_model(
        "InterfaceFields",
        SerialDetectorConfig,
        kind=("serial", "serial: a line-based detector on a serial port."),
        types={"line_ending": Literal["lf", "crlf", "cr"], "stream": SerialStreamSpec | None},
        defaults={"line_ending": _line_ending_name(SerialDetectorConfig.line_ending)},
    )


class SerialInterfaceSpec(_InterfaceFields):
    """A line-based serial detector: every field of `SerialDetectorConfig`, with its
    defaults (docs/reference/serial_detector.md), ``line_ending`` by name (``lf``, ``crlf``,
    ``cr``). Templates and regular expressions are checked by the driver's own rules
    when the rig is read, each mistake reported at its field."""

    @field_validator("line_ending", mode="before", json_schema_input_type=LineEnding)
    @classmethod
    def _ending(cls, v: Any) -> Any:
        return _line_ending_name(v)

    @model_validator(mode="after")
    def _driver_accepts(self) -> SerialInterfaceSpec:
        self.config()
        return self

    def config(self) -> SerialDetectorConfig:
        """The driver's configuration; a `field_error` at the field the driver refuses."""
        values = dict(self)
        del values["kind"]
        values["line_ending"] = LINE_ENDINGS[self.line_ending]
        values["stream"] = None if self.stream is None else self.stream.config()
        try:
            return SerialDetectorConfig(**values)
        except SerialDetectorValueError as exc:
            message = str(exc).partition("invalid configuration: ")[2] or str(exc)
            raise field_error(*self._field_of(message)) from None

    def _field_of(self, message: str) -> tuple[str, str]:
        """(field, message without the field's name) of a driver's message, which
        starts with the field's name (an init command's: with "init command")."""
        if message.startswith("init command "):
            i = next((i for i, c in enumerate(self.init) if repr(c) in message), None)
            rest = message.removeprefix("init command ")
            return ("init" if i is None else f"init.{i}"), rest
        if message.startswith("stream."):
            name, _, rest = message.partition(" ")
            return name, rest
        named = [n for n in _DRIVER_FIELDS if message.startswith(f"{n} ")]
        if not named:
            return "kind", message
        field = max(named, key=len)
        return field, message.removeprefix(f"{field} ")


InterfaceSpec = Annotated[
    SimulatedInterfaceSpec | SerialInterfaceSpec | PyMeasureInterfaceSpec,
    Field(discriminator="kind"),
]


class DetectorSpec(Strict):
    """What the detector is, beside its chain: the solid angle it collects (seen from
    the sample), the exposures it accepts, its dead time after each exposure, the most
    averages one reading may ask for (none: no limit) and how it is reached."""

    aperture_sr: float = Field(
        gt=0, le=2 * math.pi, description="The solid angle collected, seen from the sample (sr)."
    )
    exposure_range_s: tuple[Annotated[float, InSchema(exclusiveMinimum=0)], float] = Field(
        (1e-4, 60.0), description="[shortest, longest] exposure the detector accepts (s)."
    )
    readout_s: float = Field(0.0, ge=0, description="The dead time after each exposure (s).")
    max_averages: int | None = Field(
        None, ge=1, description="The most averages one reading may ask for (none: no limit)."
    )
    interface: InterfaceSpec = Field(
        SimulatedInterfaceSpec(kind="simulated"),
        description="How the detector is reached: simulated, a serial detector (kind: serial) or "
        "a PyMeasure instrument (kind: pymeasure).",
    )

    @field_validator(
        "interface", mode="before", json_schema_input_type=Literal["simulated"] | InterfaceSpec
    )
    @classmethod
    def _bare_kind(cls, v: Any) -> Any:
        return _tagged(v)

    @model_validator(mode="after")
    def _range(self) -> DetectorSpec:
        lo, hi = self.exposure_range_s
        if not 0 < lo <= hi:
            raise field_error(
                "exposure_range_s", f"expected [min, max] with 0 < min ≤ max, got [{lo}, {hi}]"
            )
        return self


# -- the reference standard ----------------------------------------------------------------


class ReferenceSpec(Strict):
    """The Lambertian standard read for calibration (e.g. a 99 % diffuse target), with
    the light at ``theta_i_deg`` and the detector at ``theta_o_deg`` on the far side of
    the normal, both in the sample's x-z plane (the classic 0°/45°). ``diameter_mm``:
    the standard's diameter; none (the default) means it is the sample's size
    (``constraints.sample_diameter_mm``: the standard sits in the sample holder).
    `gonio.acquire.reference.reference_geometry` refuses a geometry at which the
    standard would not fill what the calibration assumes."""

    albedo: float = Field(0.99, gt=0, le=1, description="The standard's reflectance.")
    theta_i_deg: float = Field(
        0.0, ge=0, lt=90, description="The light's polar angle, toward +x (°)."
    )
    theta_o_deg: float = Field(
        45.0, ge=0, lt=90, description="The detector's polar angle, toward −x (°)."
    )
    diameter_mm: float | None = Field(
        None,
        ge=LENGTH_RANGE_MM[0],
        le=LENGTH_RANGE_MM[1],
        description="The standard's diameter (mm; none: constraints.sample_diameter_mm, the "
        "standard read in the sample holder).",
    )
