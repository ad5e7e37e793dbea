"""Every setting the documentation gives for each preset instrument, applied as a
rehearsal applies it: the rig file's section validated by the rig schema, the
unmodified PyMeasure class over pyvisa-py on the emulated instrument's pty, the setting
written on opening and a reading taken; then the class reads the setting back. And
every property the class declares (``drivers/pymeasure/properties.py``): each read, and
each the class controls written back with what was read, the emulator answering every
query and refusing nothing but the commands PyMeasure itself misspells. One emulator
per instrument for the module."""

from __future__ import annotations

import contextlib
import os
import warnings
from collections.abc import Callable, Iterator
from typing import Any

import pytest

from drivers.pymeasure import PROPERTIES
from sim.clock import ScaledClock
from sim.peers.visa_instruments import EMULATORS, FULL_SCALE, EmulatedInstrument

pytest.importorskip("pymeasure")

from drivers.pymeasure import boundary
from drivers.pymeasure.detector import PyMeasureDetector
from gonio.rig.lab_instrument import PyMeasureInterfaceSpec

SPEEDUP = 100.0
CLASSES = {
    "sr830": "pymeasure.instruments.srs.SR830",
    "sr860": "pymeasure.instruments.srs.SR860",
    "pm100usb": "pymeasure.instruments.thorlabs.ThorlabsPM100USB",
    "keithley6517b": "pymeasure.instruments.keithley.Keithley6517B",
    "keithley2000": "pymeasure.instruments.keithley.Keithley2000",
}

#: Each setting docs/how-to/lab-detectors.md and the rig reference give, by instrument:
#: the presets' own, the sections' examples and the front-panel advice (as the class
#: names its values).
DOCUMENTED: list[tuple[str, str, Any]] = [
    ("sr830", "filter_slope", 24),
    ("sr830", "sensitivity", 0.01),
    ("sr830", "input_config", "A"),
    ("sr830", "input_config", "I (1 MOhm)"),
    ("sr830", "input_config", "I (100 MOhm)"),
    ("sr830", "input_coupling", "AC"),
    ("sr830", "input_grounding", "Ground"),
    ("sr830", "reference_source", "External"),
    ("sr830", "reference_source_trigger", "POS EDGE"),
    ("sr830", "reserve", "Normal"),
    ("sr830", "reserve", "Low Noise"),
    ("sr830", "filter_synchronous", True),
    ("sr860", "filter_slope", 3),
    ("sr860", "sensitivity", 0.01),
    ("sr860", "input_config", "A"),
    ("sr860", "input_coupling", "AC"),
    ("sr860", "input_grounding", "Ground"),
    ("sr860", "reference_source", "EXT"),
    ("sr860", "reference_source_trigger", "POSTTL"),
    ("sr860", "filter_synchronous", "On"),
    ("pm100usb", "wavelength", 633),
    ("keithley6517b", "current_range", 2e-6),  # set, then auto-ranging (the preset's)
    ("keithley2000", "mode", "voltage"),
    ("keithley2000", "voltage_range", 10),  # set, then auto-ranging (the preset's)
]

#: What PyMeasure 0.16's classes themselves get wrong, by property: the emulator does as
#: the instrument would (refuses the misspelt command: the event status's command-error
#: bit), or PyMeasure raises before sending anything.
DEFECTS = {
    "keithley2000": {"period_threshold": "refused"},  # writes :SENS:PRE:THR…
    # DDEF? i answers "j,k" (display, ratio), which the class cannot map to a name
    "sr830": {"channel1": "ValueError", "channel2": "ValueError"},
    "sr860": {
        "filter_advanced": "refused",  # writes ADVFIL, the SR860's is ADVFILT
        "horizontal_time_div": "refused",  # writes GSDP, the SR860's is GSPD
        "reference_externalinput": "TypeError",  # its command "REFZ&d" formats nothing
    },
    # a photodiode sensor: the class refuses to ask its energy, sending nothing
    "pm100usb": {"energy": "AttributeError"},
}


def _signal(cls: str) -> float:
    """A thousandth of the instrument's default full scale: within every range set."""
    return 1e-3 * FULL_SCALE[cls]


@pytest.fixture(scope="module")
def emulator() -> Iterator[Callable[[str], EmulatedInstrument]]:
    """The running emulator of an instrument (started on first use, reset per use)."""
    running: dict[str, EmulatedInstrument] = {}

    def get(name: str) -> EmulatedInstrument:
        cls = CLASSES[name]
        if name not in running:
            level = _signal(cls)
            device = EMULATORS[cls](lambda t: level, speedup=SPEEDUP)
            device.start()
            running[name] = device
        device = running[name]
        device.answer("*RST")
        device.clear()
        return device

    yield get
    for device in running.values():
        device.stop()
        assert device.error is None


def _open(cls: str, device: EmulatedInstrument) -> Any:
    instrument = boundary.construct(
        boundary.load_class(cls), f"ASRL{device.path}::INSTR", visa_library="@py",
        read_termination=device.terminator, timeout=500,
    )  # fmt: skip
    return instrument


@pytest.mark.parametrize(("name", "prop", "value"), DOCUMENTED)
def test_each_documented_setting_rehearses(
    name: str, prop: str, value: Any, emulator: Callable[[str], EmulatedInstrument]
) -> None:
    cls = CLASSES[name]
    device = emulator(name)
    spec = PyMeasureInterfaceSpec.model_validate({
        "kind": "pymeasure", "instrument": cls, "resource": f"ASRL{device.path}::INSTR",
        "visa_library": "@py", "read_termination": device.terminator, "timeout_s": 0.5,
        "settings": {prop: value},
        **({"full_scale": FULL_SCALE[cls]} if name == "pm100usb" else {}),
    })  # fmt: skip
    detector = PyMeasureDetector(
        spec.config(), clock=ScaledClock(SPEEDUP), exposure_range_s=(1e-3, 10.0)
    )
    with detector:
        reading = detector.measure(0.05)
    assert reading.value == pytest.approx(_signal(cls), rel=1e-6)
    assert not reading.saturated
    instrument = _open(cls, device)
    try:
        if prop.endswith("_range"):  # the preset's auto-ranging followed the reading
            assert _signal(cls) <= getattr(instrument, prop) < value
        else:
            assert getattr(instrument, prop) == pytest.approx(value)
    finally:
        boundary.close(instrument)
    assert device.refusals == [] and device.status.esr == 0, device.commands


@pytest.mark.parametrize("name", list(CLASSES))
def test_every_property_of_the_class_is_answered(
    name: str, emulator: Callable[[str], EmulatedInstrument]
) -> None:
    """Each property read; each one the class controls written with what was read and
    read again, equal. What fails is exactly PyMeasure's own defects (`DEFECTS`); a
    property the class implements only for SCPI instruments sends nothing."""
    cls = CLASSES[name]
    device = emulator(name)
    instrument = _open(cls, device)
    klass = type(instrument)
    outcomes: dict[str, str] = {}
    try:
        for prop in sorted(PROPERTIES[cls]):
            sent = len(device.commands)
            device.status.clear()
            try:
                with warnings.catch_warnings():  # the classes' deprecated aliases
                    warnings.simplefilter("ignore", FutureWarning)
                    value = getattr(instrument, prop)
                if getattr(klass, prop).fset is not None:
                    with contextlib.suppress(LookupError):  # a measurement: nothing sent
                        setattr(instrument, prop, value)
                        again = getattr(instrument, prop)
                        assert again == value, (prop, value, again)
            except NotImplementedError:  # not a SCPI instrument to PyMeasure
                assert len(device.commands) == sent, prop
                continue
            except (ValueError, TypeError, AttributeError) as exc:
                outcomes[prop] = type(exc).__name__
                continue
            instrument.ask("*IDN?")  # what was sent before it has been handled
            if device.status.esr:
                outcomes[prop] = "refused"
    finally:
        boundary.close(instrument)
    assert outcomes == DEFECTS.get(name, {})


def _users(path: str) -> list[int]:
    """The processes holding ``path`` open (as ``fuser`` finds them: /proc/*/fd)."""
    users = []
    for pid in filter(str.isdigit, os.listdir("/proc")):
        with contextlib.suppress(OSError):
            for fd in os.listdir(f"/proc/{pid}/fd"):
                with contextlib.suppress(OSError):
                    if os.readlink(f"/proc/{pid}/fd/{fd}") == path:
                        users.append(int(pid))
                        break
    return users


@pytest.mark.skipif(not os.path.isdir("/proc/self/fd"), reason="needs /proc")
def test_the_emulated_port_has_no_user_until_a_host_opens_it(
    emulator: Callable[[str], EmulatedInstrument],
) -> None:
    """The emulator holds only the pty's master: before a host opens the port and
    after it closes it no process has the port open, and a host opening it again is
    answered."""
    device = emulator("pm100usb")
    assert _users(device.path) == []
    for _ in range(2):
        instrument = _open(CLASSES["pm100usb"], device)
        try:
            assert _users(device.path) == [os.getpid()]  # the host's, pyvisa-py's fd
            assert instrument.ask("*IDN?").strip() == device.identity
        finally:
            boundary.close(instrument)
        assert _users(device.path) == []
