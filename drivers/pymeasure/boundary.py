"""Every call into PyMeasure and PyVISA themselves, in one place (the
``instruments`` extra: ``pip install 'gonio[instruments]'``): loading an instrument
class by name, opening it on a VISA resource, the exceptions that mean the instrument
failed, and setting the connection's timeout.

The one workaround: PyMeasure 0.16's ``SCPIUnknownMixin`` (of ``ThorlabsPM100USB`` and
``Keithley2000``, among others) warns with a ``FutureWarning`` every time such an
instrument is constructed, asking the user to tell PyMeasure's maintainers whether the
device speaks SCPI. That says nothing to a gonio user and turns into an error where
warnings are errors, so `construct` silences exactly that message
(tests/drivers/test_pymeasure_boundary.py pins that PyMeasure still warns; when it no
longer does, the filter goes).
"""

from __future__ import annotations

import importlib
import warnings
from typing import Any

# The `instruments` extra: imported only when a rig names a pymeasure detector.
import pyvisa
from pymeasure.instruments import Instrument

#: The message PyMeasure's ``SCPIUnknownMixin`` warns with (a regular expression).
SCPI_UNKNOWN_WARNING = r"It is not known whether this device support SCPI commands"

#: What an instrument that fails raises through PyMeasure: PyVISA's errors (a timeout is
#: a ``VisaIOError``), the port going away, a reply PyMeasure cannot parse or convert.
INSTRUMENT_ERRORS: tuple[type[BaseException], ...] = (
    pyvisa.errors.Error,
    OSError,
    ValueError,
    TypeError,
    IndexError,
    KeyError,
    AttributeError,
)


def is_timeout(exc: BaseException) -> bool:
    """Whether ``exc`` is PyVISA's timeout."""
    return (
        isinstance(exc, pyvisa.errors.VisaIOError)
        and exc.error_code == pyvisa.constants.StatusCode.error_timeout
    )


def load_class(dotted: str) -> type[Instrument]:
    """The PyMeasure instrument class named ``dotted`` (``module.Class``); `LookupError`
    with a one-line reason if there is none."""
    module_name, _, name = dotted.rpartition(".")
    try:
        module = importlib.import_module(module_name)
    except ImportError as exc:
        raise LookupError(f"cannot import {module_name!r}: {exc}") from None
    cls = getattr(module, name, None)
    if not (isinstance(cls, type) and issubclass(cls, Instrument)):
        raise LookupError(f"{module_name!r} has no PyMeasure instrument class {name!r}")
    return cls


def properties(cls: type[Instrument]) -> frozenset[str]:
    """The public properties an instrument class declares (PyMeasure's
    ``Instrument.control``, ``measurement`` and ``setting`` make class properties, as
    does a plain ``@property``), its bases' included: what a rig file may name as a
    setting or a reading. Read from the class, never from an instance."""
    return frozenset(
        name
        for klass in cls.__mro__
        for name, value in vars(klass).items()
        if isinstance(value, property) and not name.startswith("_")
    )


def construct(cls: type[Instrument], adapter: Any, **kwargs: Any) -> Instrument:
    """``cls(adapter, **kwargs)`` — a resource string or a PyMeasure adapter — without
    PyMeasure's SCPI-unknown warning (the module docstring)."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", SCPI_UNKNOWN_WARNING, FutureWarning)
        return cls(adapter, **kwargs)


def set_timeout(instrument: Instrument, seconds: float) -> None:
    """Set the VISA connection's timeout (the one PyVISA's reads wait at most)."""
    connection = getattr(instrument.adapter, "connection", None)
    if connection is not None:
        connection.timeout = max(1, round(seconds * 1000))


#: The common query every IEEE 488.2 instrument answers with its identification.
IDENTIFY = "*IDN?"


def sync(instrument: Instrument, seconds: float, most: int = 100) -> int:
    """After a failed exchange: ask `IDENTIFY` and discard every answer before its own
    (four comma-separated fields, IEEE 488.2), so a late answer to the failed query is
    never read as the next one's (the instrument answers in order). Each read waits at
    most ``seconds``; a timeout propagates (the sync is then still needed). Returns how
    many answers were discarded; the connection's timeout is restored."""
    connection = getattr(instrument.adapter, "connection", None)
    before = getattr(connection, "timeout", None)
    set_timeout(instrument, seconds)
    discarded = 0
    try:
        instrument.write(IDENTIFY)
        while discarded < most:
            if instrument.read().count(",") >= 3:
                return discarded
            discarded += 1
    finally:
        if connection is not None and before is not None:
            connection.timeout = before
    raise pyvisa.errors.VisaIOError(pyvisa.constants.StatusCode.error_timeout)


def close(instrument: Instrument) -> None:
    """Release the instrument's connection (not ``shutdown()``, which may change the
    instrument's state, e.g. switch an electrometer's source)."""
    instrument.adapter.close()
