"""What `PyMeasureDetector` needs to know about an instrument, free of PyMeasure: the
class, the VISA resource, which property is the reading, how an exposure is realised,
what counts as saturated and the ranging policy; and the presets of the tested
instruments (`PRESETS`)."""

from __future__ import annotations

import difflib
import math
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Literal

from drivers.described import described

#: How an exposure is realised.
#:
#: - ``wait``: nothing is set; the driver waits the exposure, then reads.
#: - ``time_constant``: a lock-in amplifier: its output filter's time constant τ is set
#:   to the longest allowed value with ``settle_tau`` · τ ≤ the exposure, the driver
#:   waits the exposure (so the output has settled after a move), then reads.
#: - ``averaging``: the instrument averages ``round(exposure / count_s)`` samples per
#:   reading (a power meter's averaging count), set by ``property`` or ``command``.
#: - ``nplc``: the instrument integrates exposure × ``line_hz`` power-line cycles (a
#:   multimeter's or an electrometer's NPLC), clipped to ``nplc_range``.
ExposureKind = Literal["wait", "time_constant", "averaging", "nplc"]
#: ``fixed``: the range set on the front panel (or by ``settings``) is never changed;
#: ``auto``: the instrument auto-ranges and the driver reads the range back after every
#: sample, keeping each change in `PyMeasureDetector.range_changes`.
Ranging = Literal["fixed", "auto"]

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
#: The fields a preset gives (`PRESETS`): a configuration file may leave them out.
PRESET_FIELDS = frozenset(
    {
        "reading",
        "unit",
        "query",
        "exposure",
        "settings",
        "commands",
        "range_property",
        "saturate_at_range",
        "overload_property",
        "overload_mask",
        "ranging",
        "dark_subtracted",
        "phase_property",
        "phase_tolerance_deg",
    }
)

#: The value a Keithley (and many SCPI meters) returns for an over-range reading.
OVERFLOW = 9.9e37

_NAME = re.compile(r"[A-Za-z_]\w*")
_DOTTED = re.compile(r"[A-Za-z_]\w*(\.[A-Za-z_]\w*)+")


class PyMeasureConfigError(ValueError):
    """A configuration field is invalid; the message starts with the field's name."""


@dataclass(frozen=True)
class ExposureConfig:
    """How an exposure is realised (see `ExposureKind`). ``property``: the instrument's
    property set (``time_constant``, ``averaging``, ``nplc``); ``command``: instead of a
    property, a command template with ``{count}`` (``averaging``) or ``{nplc}``;
    ``values``: the time constants allowed (s; empty: the class's ``TIME_CONSTANTS``)."""

    kind: ExposureKind = field(
        default="wait", metadata=described("wait, time_constant, averaging or nplc.")
    )
    property: str | None = field(
        default=None,
        metadata=described(
            "The instrument's property set: the time constant, averaging count or NPLC."
        ),
    )
    command: str | None = field(
        default=None,
        metadata=described(
            "Instead of a property: a command template of {count} (averaging) or {nplc}, e.g. "
            "'SENS:AVER:COUN {count:d}'."
        ),
    )
    settle_tau: float = field(
        default=10.0,
        metadata=described(
            "time_constant: the settle time in time constants (99 %: 5 at 6 dB/oct, 7 at 12, "
            "9 at 18, 10 at 24).",
            gt=0,
            le=MAX_SETTLE_TAU,
        ),
    )
    values: tuple[float, ...] = field(
        default=(),
        metadata=described(
            "time_constant: the allowed time constants (s; empty: the class's).",
            items={"gt": 0, "le": MAX_READING},
        ),
    )
    count_s: float = field(
        default=3e-4,
        metadata=described("averaging: seconds per averaged sample.", gt=0, le=MAX_COUNT_S),
    )
    max_count: int = field(
        default=10_000,
        metadata=described("averaging: the largest count.", ge=1, le=MAX_COUNT),
    )
    line_hz: float = field(
        default=50.0,
        metadata=described(
            "nplc: the power line's frequency (Hz).", ge=LINE_HZ_RANGE[0], le=LINE_HZ_RANGE[1]
        ),
    )
    nplc_range: tuple[float, float] = field(
        default=(0.01, 10.0),
        metadata=described(
            "nplc: the [min, max] NPLC the instrument accepts.",
            items={"ge": NPLC_RANGE[0], "le": NPLC_RANGE[1]},
        ),
    )

    def __post_init__(self) -> None:
        if self.property is not None and _NAME.fullmatch(self.property) is None:
            raise PyMeasureConfigError(f"exposure.property {self.property!r} is not a name")
        settable = self.kind in ("averaging", "nplc", "time_constant")
        if settable and (self.property is None) == (self.command is None):
            raise PyMeasureConfigError(
                f"exposure.property expected (or exposure.command, not both) for kind {self.kind!r}"
            )
        if self.kind == "time_constant" and self.command is not None:
            raise PyMeasureConfigError("exposure.command a time constant is set by property")
        if self.command is not None:
            key = "count" if self.kind == "averaging" else "nplc"
            try:
                self.command.format(**{key: 1})
            except (KeyError, IndexError, ValueError) as exc:
                raise PyMeasureConfigError(
                    f"exposure.command {self.command!r} is not a template of {{{key}}}: {exc}"
                ) from None
        for name in ("settle_tau", "count_s", "line_hz"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise PyMeasureConfigError(f"exposure.{name} must be > 0, got {value!r}")
        if self.max_count < 1:
            raise PyMeasureConfigError(f"exposure.max_count must be ≥ 1, got {self.max_count}")
        lo, hi = self.nplc_range
        if not 0 < lo <= hi:
            raise PyMeasureConfigError(f"exposure.nplc_range expected 0 < min ≤ max, got {lo, hi}")
        if any(not (math.isfinite(v) and v > 0) for v in self.values):
            raise PyMeasureConfigError("exposure.values must all be > 0 (s)")

    def realised_s(self, exposure_s: float, time_constants: tuple[float, ...]) -> float:
        """The exposure the instrument integrates for ``exposure_s`` (s)."""
        if self.kind == "averaging":
            return self.count(exposure_s) * self.count_s
        if self.kind == "nplc":
            return self.nplc(exposure_s) / self.line_hz
        return exposure_s

    def count(self, exposure_s: float) -> int:
        return max(1, min(self.max_count, round(exposure_s / self.count_s)))

    def nplc(self, exposure_s: float) -> float:
        lo, hi = self.nplc_range
        return min(hi, max(lo, round(exposure_s * self.line_hz, 2)))

    def time_constant(self, exposure_s: float, allowed: tuple[float, ...]) -> float:
        """The longest allowed τ with ``settle_tau`` · τ ≤ ``exposure_s`` (the shortest
        allowed when none is that short)."""
        fitting = [t for t in allowed if self.settle_tau * t <= exposure_s * (1 + 1e-9)]
        return max(fitting) if fitting else min(allowed)


@dataclass(frozen=True, kw_only=True)
class PyMeasureDetectorConfig:
    """A detector read through a PyMeasure instrument class.

    ``instrument``: the class's dotted name; ``resource``: its VISA resource string
    (``GPIB0::8::INSTR``, ``USB0::…::INSTR``, ``ASRL/dev/ttyUSB1::INSTR``);
    ``visa_library``: PyVISA's backend (``""``: the system's, ``"@py"``: pyvisa-py);
    ``read_termination`` / ``write_termination`` / ``baud_rate``: the connection's
    (None: PyVISA's defaults); ``timeout_s``: how long an answer may take beyond the
    instrument's own integration (s). ``reading``: the property read per sample, in
    ``unit``; ``query``: instead of that property, a command whose answer's first
    number is the reading; ``settings``: properties set on opening, in order; ``commands``: commands
    written on opening, after them. Saturated: an ``|value|`` at or above
    ``full_scale``, at or above the range (``range_property``, with
    ``saturate_at_range``) or `OVERFLOW`, or a status (``overload_property``, read
    after the exposure) with a bit of ``overload_mask`` set. ``std_property``: the
    instrument's own standard deviation, when it reports one. ``dark_subtracted``: the
    reading carries no dark or ambient signal (a lock-in behind a chopped source).
    ``phase_property``: a lock-in's phase (°), read after each sample; a drift of it
    from the reference reading's beyond ``phase_tolerance_deg`` is journaled.
    """

    instrument: str = field(
        metadata=described(
            "The PyMeasure class's dotted name, e.g. pymeasure.instruments.srs.SR830."
        )
    )
    resource: str = field(
        metadata=described(
            "The VISA resource: GPIB0::8::INSTR, USB0::0x1313::0x8072::P2000000::INSTR, "
            "ASRL/dev/ttyUSB1::INSTR.",
            min_length=1,
        )
    )
    visa_library: str = field(
        default="",
        metadata=described("PyVISA's backend: '' (the system's VISA), '@py' (pyvisa-py)."),
    )
    read_termination: str | None = field(
        default=None,
        metadata=described(
            "What ends an answer (none: PyVISA's default; an SR830 on RS-232: \\r)."
        ),
    )
    write_termination: str | None = field(
        default=None,
        metadata=described("What ends a command (none: PyVISA's default, \\r\\n)."),
    )
    baud_rate: int | None = field(
        default=None,
        metadata=described("A serial instrument's baud rate.", ge=BAUD_RANGE[0], le=BAUD_RANGE[1]),
    )
    timeout_s: float = field(
        default=2.0,
        metadata=described(
            "How long an answer may take beyond the instrument's integration (s).",
            gt=0,
            le=MAX_TIMEOUT_S,
        ),
    )
    reading: str = field(
        metadata=described("The property read per sample, e.g. magnitude (none: the preset's).")
    )
    unit: str = field(
        default="", metadata=described("The reading's unit, e.g. V (none: the preset's).")
    )
    query: str | None = field(
        default=None,
        metadata=described(
            "Instead of the reading property: a command whose answer's first number is the "
            "reading, e.g. ':READ?' (none: the preset's)."
        ),
    )
    exposure: ExposureConfig = field(
        default_factory=ExposureConfig,
        metadata=described("How an exposure is realised (none: the preset's)."),
    )
    settings: tuple[tuple[str, Any], ...] = field(
        default=(),
        metadata=described(
            "Properties set on opening, in order, e.g. {filter_slope: 24, sensitivity: 0.01} "
            "(none: the preset's)."
        ),
    )
    commands: tuple[str, ...] = field(
        default=(),
        metadata=described("Commands written on opening, after settings (none: the preset's)."),
    )
    range_property: str | None = field(
        default=None,
        metadata=described("The property holding the range or sensitivity (none: the preset's)."),
    )
    saturate_at_range: bool = field(
        default=False,
        metadata=described("A reading at or above the range is saturated (none: the preset's)."),
    )
    full_scale: float | None = field(
        default=None,
        metadata=described(
            "A reading at or above this is saturated (none: no such limit).",
            gt=0,
            le=MAX_READING,
        ),
    )
    overload_property: str | None = field(
        default=None,
        metadata=described("A status property read after each sample (none: the preset's)."),
    )
    overload_mask: int = field(
        default=0,
        metadata=described(
            "The status bits that mean overload (none: the preset's).", ge=1, le=MAX_MASK
        ),
    )
    ranging: Ranging = field(
        default="fixed",
        metadata=described(
            "fixed: the range is never changed; auto: the instrument auto-ranges and each "
            "change is logged (none: the preset's)."
        ),
    )
    std_property: str | None = field(
        default=None,
        metadata=described("A property with the instrument's own standard deviation."),
    )
    dark_subtracted: bool = field(
        default=False,
        metadata=described(
            "The reading carries no dark or ambient signal (a lock-in behind a chopper; none: "
            "the preset's)."
        ),
    )
    phase_property: str | None = field(
        default=None,
        metadata=described(
            "A lock-in's phase property (°), read after each sample and compared with the "
            "reference reading's, e.g. theta (none: the preset's)."
        ),
    )
    phase_tolerance_deg: float = field(
        default=5.0,
        metadata=described(
            "How far the phase may drift from the reference reading's before an event is "
            "journaled (°; none: the preset's, 5).",
            gt=0,
            le=180,
        ),
    )

    def __post_init__(self) -> None:
        if _DOTTED.fullmatch(self.instrument) is None:
            raise PyMeasureConfigError(
                f"instrument {self.instrument!r} is not a dotted class name, e.g. "
                "pymeasure.instruments.srs.SR830"
            )
        if self.query is not None and not self.query.strip():
            raise PyMeasureConfigError("query expected a command, got an empty string")
        if not self.resource.strip():
            raise PyMeasureConfigError("resource expected a VISA resource, got an empty string")
        names = ("reading", "range_property", "overload_property", "std_property", "phase_property")
        for name in names:
            value = getattr(self, name)
            if value is not None and _NAME.fullmatch(value) is None:
                raise PyMeasureConfigError(f"{name} {value!r} is not a property name")
        for i, (name, _) in enumerate(self.settings):
            if _NAME.fullmatch(name) is None:
                raise PyMeasureConfigError(f"settings.{i} {name!r} is not a property name")
        if not (math.isfinite(self.timeout_s) and self.timeout_s > 0):
            raise PyMeasureConfigError(f"timeout_s must be > 0, got {self.timeout_s!r}")
        if self.full_scale is not None and not self.full_scale > 0:
            raise PyMeasureConfigError(f"full_scale must be > 0, got {self.full_scale!r}")
        if self.saturate_at_range and self.range_property is None:
            raise PyMeasureConfigError("range_property expected with saturate_at_range")
        if self.ranging == "auto" and self.range_property is None:
            raise PyMeasureConfigError("range_property expected with ranging: auto")
        if self.overload_mask and self.overload_property is None:
            raise PyMeasureConfigError("overload_property expected with overload_mask")
        if self.overload_property is not None and self.overload_mask <= 0:
            raise PyMeasureConfigError("overload_mask expected > 0 with overload_property")
        tolerance = self.phase_tolerance_deg
        if not (math.isfinite(tolerance) and 0 < tolerance <= 180):
            raise PyMeasureConfigError(
                f"phase_tolerance_deg must be in (0, 180] degrees, got {tolerance!r}"
            )


def unknown_property(
    config: PyMeasureDetectorConfig, known: frozenset[str]
) -> tuple[str, str] | None:
    """(field, message) of the first property ``config`` names (a setting, the reading,
    the range, the status, the deviation, the phase, the exposure's) that is not in
    ``known`` (the instrument class's, `drivers.pymeasure.boundary.properties`), the
    message with the nearest known name; None when every one is known."""
    named: list[tuple[str, str]] = [(f"settings.{n}", n) for n, _ in config.settings]
    fields = ("range_property", "overload_property", "std_property", "phase_property")
    named += [(f, getattr(config, f)) for f in fields if getattr(config, f) is not None]
    if config.query is None:
        named.append(("reading", config.reading))
    if config.exposure.property is not None:
        named.append(("exposure.property", config.exposure.property))
    for where, name in named:
        if name not in known:
            near = difflib.get_close_matches(name, sorted(known), n=1)
            hint = f"; did you mean {near[0]!r}?" if near else ""
            short = config.instrument.rpartition(".")[2]
            return where, f"{short} has no property {name!r}{hint}"
    return None


def settle_tau(slope_db_oct: int, fraction: float = 0.99) -> float:
    """A lock-in's settle time in time constants: when the step response of its output
    filter (``slope_db_oct`` / 6 cascaded RC stages, 6 dB/octave each) reaches
    ``fraction`` of its final value (99 %: 4.6 τ at 6 dB/oct, 6.6 at 12, 8.4 at 18,
    10.0 at 24)."""
    stages = slope_db_oct // 6
    if stages < 1 or slope_db_oct % 6 or not 0 < fraction < 1:
        raise ValueError(f"expected a slope of 6, 12, 18 or 24 dB/oct, got {slope_db_oct}")

    def step(t: float) -> float:
        return 1 - math.exp(-t) * sum(t**k / math.factorial(k) for k in range(stages))

    lo, hi = 0.0, 100.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if step(mid) < fraction else (lo, mid)
    return hi


#: The 99 % settle time (τ) of each filter slope (dB/octave), rounded up to 0.1 τ.
SETTLE_TAU = {slope: math.ceil(settle_tau(slope) * 10) / 10 for slope in (6, 12, 18, 24)}

_LOCKIN: dict[str, Any] = {
    "reading": "magnitude",
    "unit": "V",
    "exposure": {
        "kind": "time_constant",
        "property": "time_constant",
        "settle_tau": SETTLE_TAU[24],
    },
    "settings": (("filter_slope", 24),),
    "range_property": "sensitivity",
    "saturate_at_range": True,
    "dark_subtracted": True,
    "phase_property": "theta",
}

#: What gonio sets for the instruments it is tested with, by class name: the rig file's
#: section needs only ``instrument`` and ``resource`` for these (and may override any).
PRESETS: Mapping[str, Mapping[str, Any]] = {
    "pymeasure.instruments.srs.SR830": {
        **_LOCKIN,
        "overload_property": "lia_status",
        "overload_mask": 0b111,  # input, filter and output overload
    },
    # PyMeasure's SR860 takes the filter slope as an index (3: 24 dB/oct), the SR830 in dB.
    "pymeasure.instruments.srs.SR860": {**_LOCKIN, "settings": (("filter_slope", 3),)},
    "pymeasure.instruments.thorlabs.ThorlabsPM100USB": {
        "reading": "power",
        "unit": "W",
        "exposure": {"kind": "averaging", "command": "SENS:AVER:COUN {count:d}"},
    },
    # PyMeasure's `current` asks `:MEAS?`, which in SCPI is CONFigure + READ?, and
    # Keithley describes CONFigure as returning the function's settings to their reset
    # values: the NPLC set per exposure might not hold (not checked on an instrument).
    # `:READ?` measures with the settings as they are.
    "pymeasure.instruments.keithley.Keithley6517B": {
        "reading": "current",
        "query": ":READ?",
        "unit": "A",
        "exposure": {"kind": "nplc", "property": "current_nplc"},
        "commands": (":SENS:FUNC 'CURR'", ":SENS:CURR:RANG:AUTO 1"),
        "range_property": "current_range",
        "ranging": "auto",
    },
    "pymeasure.instruments.keithley.Keithley2000": {
        "reading": "voltage",
        "unit": "V",
        "exposure": {"kind": "nplc", "property": "voltage_nplc"},
        "settings": (("mode", "voltage"),),
        "commands": (":SENS:VOLT:RANG:AUTO 1",),
        "range_property": "voltage_range",
        "ranging": "auto",
    },
}
