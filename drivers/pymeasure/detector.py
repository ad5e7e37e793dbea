"""`PyMeasureDetector`: the device contract's `Detector` on an instrument driven by
its PyMeasure class (a lock-in amplifier, an optical power meter, an electrometer, a
multimeter), configured by `PyMeasureDetectorConfig`.

Each sample realises the exposure as the configuration says (a lock-in: its time
constant set and the exposure waited; a power meter: its averaging count; a meter: its
integration in power-line cycles), reads the reading property and decides whether it is
saturated. Every failure is a `PyMeasureDetectorError` (a `DetectorError`) of one line
naming the resource; every read is bounded by the VISA timeout (the instrument's own
integration plus ``timeout_s``), so a silent instrument never hangs a run.
"""

from __future__ import annotations

import contextlib
import logging
import math
import numbers
import re
import statistics
from collections.abc import Callable, Iterator
from typing import Any

from drivers.base import Clock, SystemClock
from drivers.devices import Resource
from drivers.errors import DetectorError, DeviceClosed
from drivers.pymeasure import boundary
from drivers.pymeasure.config import OVERFLOW, PyMeasureDetectorConfig, unknown_property
from drivers.values import RangeChange, Reading

log = logging.getLogger(__name__)

#: Builds the instrument for a configuration (a test passes PyMeasure's protocol adapter).
Connect = Callable[[PyMeasureDetectorConfig], Any]


class PyMeasureDetectorError(DetectorError):
    """The instrument failed: ``resource`` says which, the message what happened."""

    def __init__(self, message: str, *, resource: str) -> None:
        super().__init__(message)
        self.resource = resource


class PyMeasureDetectorClosed(PyMeasureDetectorError, DeviceClosed):
    """The detector is not open; nothing was sent."""


def connect(config: PyMeasureDetectorConfig) -> Any:
    """The instrument of ``config`` on its VISA resource (`boundary.construct`)."""
    cls = boundary.load_class(config.instrument)
    kwargs: dict[str, Any] = {"visa_library": config.visa_library}
    for name in ("read_termination", "write_termination", "baud_rate"):
        value = getattr(config, name)
        if value is not None:
            kwargs[name] = value
    kwargs["timeout"] = max(1, round(config.timeout_s * 1000))
    return boundary.construct(cls, config.resource, **kwargs)


class PyMeasureDetector(Resource):
    """A detector read through a PyMeasure instrument class (module docstring).

    Parameters
    ----------
    config
        The instrument, its resource and how gonio uses it.
    clock
        Stamps the readings and waits the exposures (s).
    exposure_range_s
        The shortest and longest exposure accepted (s).
    connect
        Builds the instrument (default: `connect`, on the VISA resource).
    """

    def __init__(
        self,
        config: PyMeasureDetectorConfig,
        *,
        clock: Clock | None = None,
        exposure_range_s: tuple[float, float] = (1e-3, 60.0),
        connect: Connect = connect,
    ) -> None:
        lo, hi = exposure_range_s
        if not 0 < lo <= hi < math.inf:
            raise ValueError(f"exposure_range_s must be 0 < min ≤ max < inf, got {lo, hi}")
        self._config = config
        self._clock = clock or SystemClock()
        self._range = (float(lo), float(hi))
        self._connect = connect
        self._instrument: Any = None
        self._applied: object = None
        self._instrument_range: float | None = None
        self._time_constants: tuple[float, ...] = ()
        self._stale = False  # a failed exchange may leave a late answer to discard
        #: Answers a resync after a failed exchange discarded (late ones), so far.
        self.late_answers = 0
        self.range_changes: list[RangeChange] = []

    # -- what the engine may ask -------------------------------------------------------

    @property
    def resource(self) -> str:
        return self._config.resource

    @property
    def config(self) -> PyMeasureDetectorConfig:
        return self._config

    @property
    def exposure_range_s(self) -> tuple[float, float]:
        return self._range

    @property
    def dark_subtracted(self) -> bool:
        """Whether a reading carries no dark or ambient signal (a lock-in amplifier
        behind a chopped source): the calibration needs no dark reading."""
        return self._config.dark_subtracted

    @property
    def phase_tolerance_deg(self) -> float | None:
        """How far (°) the phase may drift from the reference reading's (None: the
        phase is not read)."""
        return None if self._config.phase_property is None else self._config.phase_tolerance_deg

    @property
    def unit(self) -> str:
        """The reading's unit (e.g. V, W, A)."""
        return self._config.unit

    @property
    def time_constants(self) -> tuple[float, ...]:
        """A lock-in's allowed time constants (s, ascending; known once open; empty for
        other exposure kinds)."""
        return self._time_constants

    @property
    def is_open(self) -> bool:
        return self._instrument is not None

    # -- lifecycle ---------------------------------------------------------------------

    def open(self) -> None:
        """Open the instrument and apply ``settings`` and ``commands``; on a failure
        the connection is released again."""
        if self._instrument is not None:
            return
        cfg = self._config
        try:
            instrument = self._connect(cfg)
        except LookupError as exc:
            raise self._error(
                f"{exc} (is the instruments extra installed? pip install 'gonio[instruments]')"
            ) from None
        except boundary.INSTRUMENT_ERRORS as exc:
            raise self._error(f"cannot open the instrument: {_reason(exc)}") from exc
        self._instrument = instrument
        self._applied = None
        try:
            unknown = unknown_property(cfg, boundary.properties(type(instrument)))
            if unknown is not None:
                raise self._error(f"{unknown[0]}: {unknown[1]}")
            with self._talking("setting it up"):
                for name, value in cfg.settings:
                    setattr(instrument, name, value)
                for command in cfg.commands:
                    instrument.write(command)
                self._instrument_range = self._read_range()
            exposure = cfg.exposure
            if exposure.kind == "time_constant":
                allowed = exposure.values or tuple(getattr(instrument, "TIME_CONSTANTS", ()))
                if not allowed:
                    raise self._error(
                        f"{cfg.instrument} lists no TIME_CONSTANTS; give exposure.values"
                    )
                self._time_constants = tuple(sorted(float(t) for t in allowed))
        except BaseException:
            self._release()
            raise
        log.debug("%s: opened %s", cfg.resource, cfg.instrument)

    def close(self) -> None:
        """Release the connection (idempotent)."""
        self._release()

    def _release(self) -> None:
        instrument, self._instrument = self._instrument, None
        if instrument is None:
            return
        try:
            boundary.close(instrument)
        except Exception as exc:  # nothing more can be done
            log.debug("%s: error while closing: %s", self.resource, exc)

    # -- measuring -----------------------------------------------------------------------

    def measure(self, exposure_s: float, averages: int = 1) -> Reading:
        """Expose ``averages`` times for ``exposure_s`` s each and return the mean.

        ``std``: the sample standard deviation of the readings (ddof 1; 0 for one),
        or the instrument's own (``std_property``) for one sample.
        """
        if self._instrument is None:
            raise PyMeasureDetectorClosed(
                f"{self.resource}: the detector is not open", resource=self.resource
            )
        exposure, n = self._check(exposure_s, averages)
        cfg = self._config
        started = self._clock.now()
        if self._stale:  # what the failed exchange's answer may still be on its way
            with self._talking(f"resynchronizing ({boundary.IDENTIFY})"):
                late = boundary.sync(self._instrument, 3 * self._config.timeout_s)
            if late:
                log.warning("%s: discarded %d late answer(s)", self.resource, late)
            self.late_answers += late
            self._stale = False
        self._apply_exposure(exposure)
        samples: list[float] = []
        stds: list[float] = []
        phases: list[float] = []
        saturated = False
        for _ in range(n):
            value, std, flagged = self._sample(exposure)
            samples.append(value)
            if std is not None:
                stds.append(std)
            if cfg.phase_property is not None:
                with self._talking(f"reading {cfg.phase_property}"):
                    phase = getattr(self._instrument, cfg.phase_property)
                phases.append(self._number(cfg.phase_property, phase))
            saturated = saturated or flagged
        own = stds[0] if stds else 0.0
        std_value = statistics.stdev(samples) if n > 1 else own
        realised = cfg.exposure.realised_s(exposure, self._time_constants)
        return Reading(
            value=statistics.fmean(samples),
            std=std_value,
            n=n,
            saturated=saturated,
            started_s=started,
            ended_s=self._clock.now(),
            raw=tuple(samples),
            exposure_s=None if math.isclose(realised, exposure, rel_tol=1e-9) else realised,
            phase_deg=_circular_mean(phases) if phases else None,
        )

    def _check(self, exposure_s: object, averages: object) -> tuple[float, int]:
        if isinstance(exposure_s, bool) or not isinstance(exposure_s, numbers.Real):
            raise self._error(f"exposure_s must be a number of seconds, got {exposure_s!r}")
        exposure = float(exposure_s)
        lo, hi = self._range
        if not (math.isfinite(exposure) and lo <= exposure <= hi):
            raise self._error(
                f"exposure {exposure_s!r} s is outside the detector's range [{lo:g}, {hi:g}] s"
            )
        if isinstance(averages, bool) or not isinstance(averages, numbers.Integral):
            raise self._error(f"averages must be an integer ≥ 1, got {averages!r}")
        if averages < 1:
            raise self._error(f"averages must be an integer ≥ 1, got {averages!r}")
        return exposure, int(averages)

    def _apply_exposure(self, exposure_s: float) -> None:
        """Set the time constant, averaging count or NPLC for ``exposure_s`` (only when
        it changes) and the VISA timeout that goes with it."""
        spec = self._config.exposure
        inst = self._instrument
        if spec.kind == "time_constant":
            setting: object = spec.time_constant(exposure_s, self._time_constants)
            integrates = 0.0
        elif spec.kind == "averaging":
            setting = spec.count(exposure_s)
            integrates = spec.realised_s(exposure_s, ())
        elif spec.kind == "nplc":
            setting = spec.nplc(exposure_s)
            integrates = spec.realised_s(exposure_s, ())
        else:
            return
        if setting == self._applied:
            return
        self._applied = None
        with self._talking(f"setting the exposure ({spec.kind} {setting})"):
            boundary.set_timeout(inst, integrates + self._config.timeout_s)
            if spec.property is not None:
                setattr(inst, spec.property, setting)
            else:
                assert spec.command is not None  # the configuration checked
                key = "count" if spec.kind == "averaging" else "nplc"
                inst.write(spec.command.format(**{key: setting}))
        self._applied = setting

    def _sample(self, exposure_s: float) -> tuple[float, float | None, bool]:
        """One reading: (value, the instrument's std or None, saturated)."""
        cfg = self._config
        inst = self._instrument
        if cfg.exposure.kind in ("wait", "time_constant"):
            self._clock.sleep(exposure_s)  # the output settles (a lock-in) / integrates
        with self._talking(f"reading {cfg.reading}"):
            if cfg.overload_property is not None:
                getattr(inst, cfg.overload_property)  # clears the latched status bits
            if cfg.query is not None:
                value = self._number(cfg.reading, _first_number(inst.values(cfg.query)))
            else:
                value = self._number(cfg.reading, getattr(inst, cfg.reading))
            overloaded = False
            if cfg.overload_property is not None:
                status = getattr(inst, cfg.overload_property)
                overloaded = bool(int(status) & cfg.overload_mask)
            std = None
            if cfg.std_property is not None:
                std = abs(self._number(cfg.std_property, getattr(inst, cfg.std_property)))
            if cfg.ranging == "auto":
                self._note_range(self._read_range())
        saturated = overloaded or abs(value) >= OVERFLOW
        if cfg.full_scale is not None and abs(value) >= cfg.full_scale:
            saturated = True
        top = self._instrument_range
        if cfg.saturate_at_range and top is not None and abs(value) >= top:
            saturated = True
        return value, std, saturated

    def _read_range(self) -> float | None:
        name = self._config.range_property
        if name is None:
            return None
        return abs(self._number(name, getattr(self._instrument, name)))

    def _note_range(self, new: float | None) -> None:
        if new is None or new == self._instrument_range:
            return
        change = RangeChange(self._clock.now(), self._instrument_range, new)
        self.range_changes.append(change)
        log.info("%s: range %s → %s %s", self.resource, change.old, new, self.unit)
        self._instrument_range = new

    def _number(self, name: str, value: object) -> float:
        if isinstance(value, list | tuple) and len(value) == 1:
            value = value[0]
        if isinstance(value, bool) or not isinstance(value, numbers.Real):
            raise self._error(f"{name} answered {value!r}, not a number")
        number = float(value)
        if math.isnan(number):
            raise self._error(f"{name} answered {value!r}, not a number")
        return number

    @contextlib.contextmanager
    def _talking(self, what: str) -> Iterator[None]:
        try:
            yield
        except PyMeasureDetectorError:
            raise
        except boundary.INSTRUMENT_ERRORS as exc:
            self._stale = True
            if boundary.is_timeout(exc):
                raise self._error(f"{what}: no answer (timed out)") from exc
            raise self._error(f"{what}: {_reason(exc)}") from exc

    def _error(self, message: str) -> PyMeasureDetectorError:
        return PyMeasureDetectorError(f"{self.resource}: {message}", resource=self.resource)


#: A number at the start of an answer's field, e.g. ``+1.234E-09`` of ``+1.234E-09NADC``.
_LEADING_NUMBER = re.compile(r"[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?")


def _first_number(values: list[Any]) -> object:
    """The first field of an answer as a number: PyMeasure's float, or the number a
    field starts with (a Keithley's ``+1.234E-09NADC``); else the field as it is."""
    if not values:
        return values
    first = values[0]
    if isinstance(first, str):
        match = _LEADING_NUMBER.match(first.strip())
        if match is not None:
            return float(match.group(0))
    return first


def _circular_mean(degrees: list[float]) -> float:
    """The mean of angles (°) on the circle, in (−180, 180]."""
    rad = [math.radians(d) for d in degrees]
    return math.degrees(math.atan2(sum(map(math.sin, rad)), sum(map(math.cos, rad))))


def _reason(exc: BaseException) -> str:
    text = " ".join(str(exc).split()) or type(exc).__name__
    return text if len(text) <= 200 else text[:197] + "..."
