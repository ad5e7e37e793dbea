"""`PyMeasureDetector` as (command, reply) pairs through PyMeasure's own
`expected_protocol` (no device) for each instrument gonio presets, its failures on the
emulated instruments misbehaving (silence, garbage, a port that goes away: a
`DetectorError` naming the resource, never a hang), and the workaround at our boundary
with PyMeasure pinned."""

from __future__ import annotations

import math
import time
import warnings
from collections.abc import Iterator
from typing import Any

import pytest

pytest.importorskip("pymeasure")

from pymeasure.instruments.keithley import Keithley2000, Keithley6517B
from pymeasure.instruments.srs import SR510, SR830, SR860
from pymeasure.instruments.thorlabs import ThorlabsPM100USB
from pymeasure.test import expected_protocol

from drivers.errors import DetectorError
from drivers.pymeasure import PRESETS, PROPERTIES, SETTLE_TAU, boundary
from drivers.pymeasure.config import settle_tau
from drivers.pymeasure.detector import PyMeasureDetector, PyMeasureDetectorError
from gonio.rig.lab_instrument import PyMeasureInterfaceSpec
from sim.clock import ManualClock, ScaledClock
from sim.peers.visa_instruments import SR830 as EmulatedSR830
from sim.peers.visa_instruments import EmulatedInstrument
from sim.peers.visa_instruments import Keithley2000 as Emulated2000
from tools import pymeasure_properties

SENSOR = "S120C,12345678,01-Jan-2024,1,18,289"


def detector(cls: type, pairs: list[tuple[str | None, str | None]], **fields: Any) -> Any:
    """A detector of the preset of ``cls`` (plus ``fields``) on PyMeasure's protocol
    adapter expecting ``pairs``; used as a context manager yielding (detector, clock)."""
    name = f"{cls.__module__.rsplit('.', 1)[0]}.{cls.__name__}"
    spec = PyMeasureInterfaceSpec.model_validate(
        {"kind": "pymeasure", "instrument": name, "resource": "GPIB0::8::INSTR", **fields}
    )
    return _opened(cls, pairs, spec)


class _opened:
    def __init__(self, cls: type, pairs: list[Any], spec: PyMeasureInterfaceSpec) -> None:
        self.cls, self.pairs, self.spec = cls, pairs, spec

    def __enter__(self) -> tuple[PyMeasureDetector, ManualClock]:
        self.protocol = expected_protocol(self.cls, self.pairs)
        instrument = boundary_enter(self.protocol)
        self.clock = ManualClock()
        self.det = PyMeasureDetector(
            self.spec.config(), clock=self.clock, connect=lambda _: instrument
        )
        self.det.open()
        return self.det, self.clock

    def __exit__(self, *exc: object) -> None:
        self.det.close()
        self.protocol.__exit__(*exc)


def boundary_enter(protocol: Any) -> Any:
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", boundary.SCPI_UNKNOWN_WARNING, FutureWarning)
        return protocol.__enter__()


# -- (command, reply) pairs ---------------------------------------------------------------


def test_sr830_sets_the_time_constant_waits_the_exposure_and_checks_overload() -> None:
    pairs = [
        ("OFSL3", None),  # settings: 24 dB/oct
        ("SENS?", "26"),  # the sensitivity: 1 V full scale
        ("OFLT5", None),  # 0.1 s exposure / 10.1 τ → τ = 3 ms (index 5)
        ("LIAS?", "0"), ("OUTP?3", "0.0125"), ("LIAS?", "0"), ("OUTP?4", "1.5"),  # θ (°)
        ("LIAS?", "0"), ("OUTP?3", "0.0135"), ("LIAS?", "4"), ("OUTP?4", "1.5"),  # overload
        ("LIAS?", "0"), ("OUTP?3", "1.05"), ("LIAS?", "0"), ("OUTP?4", "1.5"),  # > full scale
    ]  # fmt: skip
    with detector(SR830, pairs) as (det, _):
        assert det.dark_subtracted and det.unit == "V" and det.phase_tolerance_deg == 5.0
        a = det.measure(0.1)
        assert (a.value, a.saturated, a.ended_s - a.started_s) == (0.0125, False, 0.1)
        assert a.phase_deg == pytest.approx(1.5)
        assert det.measure(0.1).saturated  # the status byte's overload bit
        assert det.measure(0.1).saturated  # at or above the sensitivity's full scale


def test_sr830_keeps_the_time_constant_while_the_exposure_does_not_change() -> None:
    pairs = [
        ("OFSL3", None), ("SENS?", "26"), ("OFLT5", None),  # 50 ms → τ = 3 ms
        ("LIAS?", "0"), ("OUTP?3", "0.01"), ("LIAS?", "0"), ("OUTP?4", "0"),
        ("LIAS?", "0"), ("OUTP?3", "0.03"), ("LIAS?", "0"), ("OUTP?4", "179"),
        ("LIAS?", "0"), ("OUTP?3", "0.02"), ("LIAS?", "0"), ("OUTP?4", "-179"),
    ]  # fmt: skip
    with detector(SR830, pairs) as (det, _):
        det.measure(0.05)
        r = det.measure(0.05, 2)
    assert (
        r.n == 2 and r.value == pytest.approx(0.025) and r.std == pytest.approx(0.01 / math.sqrt(2))
    )
    # The phases' mean is taken on the circle: 179° and −179° average to 180°, not 0°.
    assert r.phase_deg is not None and abs(r.phase_deg) == pytest.approx(180.0)


def test_sr860_shares_the_lockin_preset() -> None:
    pairs = [
        ("OFSL 3", None), ("SCAL?", "0"),  # 1 V
        ("OFLT 9", None),  # 1 s / 10.1 → τ = 30 ms (the SR860 lists from 1 µs)
        ("OUTP? 2", "0.25"), ("OUTP? 3", "-2.0"),
    ]  # fmt: skip
    with detector(SR860, pairs) as (det, _):
        assert det.measure(1.0).value == 0.25


def test_pm100usb_sets_the_averaging_count_for_the_exposure() -> None:
    pairs = [
        ("SYST:SENSOR:IDN?", SENSOR),
        ("SENS:AVER:COUN 167", None),  # 50 ms / 0.3 ms
        ("MEAS:POW?", "1.234E-03"),
    ]
    with detector(ThorlabsPM100USB, pairs, full_scale=0.05) as (det, _):
        r = det.measure(0.05)
    assert r.value == 1.234e-3 and not r.saturated
    assert r.exposure_s == pytest.approx(167 * 3e-4)  # what the meter integrated


def test_keithley6517b_reads_current_in_nplc_and_logs_range_changes() -> None:
    # `:READ?`, not the class's `current` (`:MEAS?`, which resets the NPLC: config.py).
    pairs = [
        (":SENS:FUNC 'CURR'", None), (":SENS:CURR:RANG:AUTO 1", None),
        (":SENS:CURR:RANG?", "2.000000E-09"),
        (":SENS:CURR:NPLC 1", None),  # 20 ms at 50 Hz
        (":READ?", "+1.500000E-09NADC,+0000000.100secs,+00001rdng#"),
        (":SENS:CURR:RANG?", "2.000000E-09"),
        (":READ?", "+2.500000E-09NADC,+0000000.200secs,+00002rdng#"),
        (":SENS:CURR:RANG?", "2.000000E-08"),  # auto-ranged up
        (":READ?", "+9.900000E+37NADC,+0000000.300secs,+00003rdng#"),  # over-range
        (":SENS:CURR:RANG?", "2.000000E-08"),
    ]  # fmt: skip
    with detector(Keithley6517B, pairs) as (det, _):
        assert det.measure(0.02).value == 1.5e-9
        assert det.measure(0.02).value == 2.5e-9
        assert det.measure(0.02).saturated
    assert [(c.old, c.new) for c in det.range_changes] == [(2e-9, 2e-8)]


def test_keithley2000_reads_volts_in_nplc() -> None:
    pairs = [
        (":CONF:VOLT:DC", None), (":SENS:VOLT:RANG:AUTO 1", None),
        (":SENS:VOLT:RANG?", "1.000000E+01"),
        (":SENS:VOLT:NPLC 10", None),  # 0.2 s at 50 Hz; 0.5 s is clipped to 10 NPLC
        (":READ?", "+1.23456789E+00"), (":SENS:VOLT:RANG?", "1.000000E+01"),
    ]  # fmt: skip
    with detector(Keithley2000, pairs) as (det, _):
        r = det.measure(0.5)
    assert r.value == pytest.approx(1.23456789) and r.exposure_s == pytest.approx(0.2)


def test_an_answer_that_is_not_a_number_names_the_resource() -> None:
    pairs = [
        (":CONF:VOLT:DC", None), (":SENS:VOLT:RANG:AUTO 1", None), (":SENS:VOLT:RANG?", "10"),
        (":SENS:VOLT:NPLC 1", None), (":READ?", "OVFL"),
    ]  # fmt: skip
    with detector(Keithley2000, pairs) as (det, _), pytest.raises(DetectorError) as err:
        det.measure(0.02)
    assert str(err.value) == "GPIB0::8::INSTR: voltage answered 'OVFL', not a number"


def test_settle_tau_is_the_99_percent_step_response_of_cascaded_rc_stages() -> None:
    # One RC stage reaches 99 % at ln(100) τ; four stages (24 dB/oct) at about 10.05 τ.
    assert settle_tau(6) == pytest.approx(math.log(100), rel=1e-9)
    t = settle_tau(24)
    assert 1 - math.exp(-t) * (1 + t + t**2 / 2 + t**3 / 6) == pytest.approx(0.99, abs=1e-9)
    assert SETTLE_TAU == {6: 4.7, 12: 6.7, 18: 8.5, 24: 10.1}


# -- the boundary -------------------------------------------------------------------------


def test_pymeasure_still_warns_about_scpi_on_construction_and_the_boundary_silences_it() -> None:
    # When this fails, PyMeasure stopped warning: remove the filter in boundary.construct.
    with pytest.warns(FutureWarning, match=boundary.SCPI_UNKNOWN_WARNING):
        Keithley2000(expected_protocol(Keithley2000, []).__enter__().adapter)
    from pymeasure.adapters import ProtocolAdapter

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        boundary.construct(Keithley2000, ProtocolAdapter([]))


def test_a_class_that_does_not_exist_is_one_line_at_open() -> None:
    spec = PyMeasureInterfaceSpec.model_validate({
        "kind": "pymeasure", "instrument": "pymeasure.instruments.srs.SR999",
        "resource": "GPIB0::8::INSTR", "reading": "x", "exposure": {"kind": "wait"},
    })  # fmt: skip
    det = PyMeasureDetector(spec.config())
    with pytest.raises(
        PyMeasureDetectorError, match=r"^GPIB0::8::INSTR: .*no PyMeasure instrument"
    ):
        det.open()
    assert not det.is_open


def test_a_property_another_class_lacks_is_one_line_at_open_before_any_command() -> None:
    spec = PyMeasureInterfaceSpec.model_validate({
        "kind": "pymeasure", "instrument": "pymeasure.instruments.srs.SR510",
        "resource": "GPIB0::8::INSTR", "reading": "output", "exposure": {"kind": "wait"},
        "settings": {"sensitivty": 0.01},
    })  # fmt: skip
    with expected_protocol(SR510, []) as instrument:  # no command is written
        det = PyMeasureDetector(spec.config(), connect=lambda _: instrument)
        with pytest.raises(PyMeasureDetectorError) as caught:
            det.open()
    assert str(caught.value) == (
        "GPIB0::8::INSTR: settings.sensitivty: SR510 has no property 'sensitivty'; "
        "did you mean 'sensitivity'?"
    )
    assert not det.is_open


def test_the_presets_properties_are_those_pymeasure_declares() -> None:
    """drivers/pymeasure/properties.py (what the rig file is checked against without
    PyMeasure) is what the installed PyMeasure's classes declare; when not, run
    ``python -m tools.pymeasure_properties``."""
    assert pymeasure_properties.PATH.read_text() == pymeasure_properties.text()
    assert PROPERTIES.keys() == PRESETS.keys()


# -- the emulated instruments misbehaving -------------------------------------------------


@pytest.fixture
def sr830() -> Iterator[tuple[EmulatedInstrument, PyMeasureDetector]]:
    device = EmulatedSR830(lambda t: 0.01, speedup=100)
    device.start()
    spec = PyMeasureInterfaceSpec.model_validate({
        "kind": "pymeasure", "instrument": "pymeasure.instruments.srs.SR830",
        "resource": f"ASRL{device.path}::INSTR", "visa_library": "@py",
        "read_termination": "\r", "timeout_s": 0.3,
    })  # fmt: skip
    det = PyMeasureDetector(spec.config(), clock=ScaledClock(100))
    yield device, det
    det.close()
    device.stop()


def test_a_silent_instrument_times_out_naming_the_resource(
    sr830: tuple[EmulatedInstrument, PyMeasureDetector],
) -> None:
    device, det = sr830
    with det:
        det.measure(0.05)
        device.silent()
        t0 = time.monotonic()
        with pytest.raises(DetectorError, match=rf"^ASRL{device.path}::INSTR: .*timed out"):
            det.measure(0.05)
        assert time.monotonic() - t0 < 2.0


def test_a_late_answer_after_a_timeout_is_not_taken_for_the_next_one(
    sr830: tuple[EmulatedInstrument, PyMeasureDetector],
) -> None:
    device, det = sr830
    with det:
        device.slow(0.5)  # beyond the 0.3 s timeout: the status's answer comes late
        with pytest.raises(DetectorError, match=r"timed out"):
            det.measure(0.05)
        device.clear()
        assert det.measure(0.05).value == pytest.approx(0.01)


def test_an_answer_later_than_a_quiet_spell_is_never_taken_for_the_next_one(
    sr830: tuple[EmulatedInstrument, PyMeasureDetector],
) -> None:
    """The late answer comes after the line has been quiet for longer than the timeout
    (listening it out alone would have let it into the next query): the resync's
    *IDN? marks the end of what the instrument still owed."""
    device, det = sr830
    with det:
        assert det.measure(0.05).value == pytest.approx(0.01)
        device.late(0.8)  # the next answer, 0.5 s past the 0.3 s timeout
        with pytest.raises(DetectorError, match=r"timed out"):
            det.measure(0.05)
        before = len(device.commands)
        assert det.measure(0.05).value == pytest.approx(0.01)
        assert det.late_answers == 1
        assert device.commands[before] == "*IDN?"  # the resync came first
        assert det.measure(0.05).value == pytest.approx(0.01)
        assert det.late_answers == 1


def test_garbage_is_a_detector_error_and_the_next_reading_works(
    sr830: tuple[EmulatedInstrument, PyMeasureDetector],
) -> None:
    device, det = sr830
    with det:
        device.garbage(1)  # the status read before the output
        with pytest.raises(DetectorError, match=r"::INSTR: reading magnitude: invalid literal"):
            det.measure(0.05)
        assert det.measure(0.05).value == pytest.approx(0.01)


def test_an_instrument_that_never_answers_at_open_is_one_line() -> None:
    device = Emulated2000(lambda t: 1.0, speedup=100)
    device.start()
    device.silent()
    try:
        spec = PyMeasureInterfaceSpec.model_validate({
            "kind": "pymeasure", "instrument": "pymeasure.instruments.keithley.Keithley2000",
            "resource": f"ASRL{device.path}::INSTR", "visa_library": "@py", "timeout_s": 0.3,
        })  # fmt: skip
        det = PyMeasureDetector(spec.config())
        with pytest.raises(DetectorError, match=r"setting it up: no answer \(timed out\)"):
            det.open()
        assert not det.is_open
    finally:
        device.stop()


def test_a_missing_port_is_one_line_at_open() -> None:
    spec = PyMeasureInterfaceSpec.model_validate({
        "kind": "pymeasure", "instrument": "pymeasure.instruments.keithley.Keithley2000",
        "resource": "ASRL/dev/nonexistent-gonio::INSTR", "visa_library": "@py",
    })  # fmt: skip
    with pytest.raises(DetectorError, match=r"^ASRL/dev/nonexistent-gonio::INSTR: cannot open"):
        PyMeasureDetector(spec.config()).open()
