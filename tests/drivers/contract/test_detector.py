"""The `drivers.base.Detector` contract, rule by rule, on every detector backend."""

from __future__ import annotations

import math

import pytest

from drivers.base import dark_subtracted, phase_tolerance_deg, range_changes, reading_unit
from drivers.errors import DetectorError, DeviceClosed
from drivers.values import RangeChange
from tests.drivers.contract.conftest import DetectorHarness


def test_lifecycle_close_is_idempotent_and_closed_measures_nothing(
    detectors: DetectorHarness,
) -> None:
    det = detectors.make(False)
    det.close()  # never opened
    before = detectors.activity()
    with pytest.raises(DeviceClosed):
        det.measure(0.01)
    with det:
        det.open()  # already open: nothing happens
        assert det.is_open
        det.measure(0.01)
    assert not det.is_open
    det.close()
    after = detectors.activity()
    with pytest.raises(DeviceClosed):
        det.measure(0.01)
    assert detectors.activity() == after != before


def test_every_reading_is_stamped_with_the_clock(detectors: DetectorHarness) -> None:
    with detectors.make(False) as det:
        t0 = detectors.clock_now()
        a = det.measure(0.01, 3)
        b = det.measure(0.02)
        t1 = detectors.clock_now()
    assert t0 <= a.started_s < a.ended_s <= b.started_s < b.ended_s <= t1
    assert a.ended_s - a.started_s >= 3 * 0.01 - 1e-12  # three exposures
    assert a.middle_s == (a.started_s + a.ended_s) / 2
    assert a.n == 3 and len(a.raw) == 3 and a.value == pytest.approx(sum(a.raw) / 3)
    assert a.std >= 0 and not a.saturated


def test_bad_exposures_and_averages_are_refused_before_anything_is_exposed(
    detectors: DetectorHarness,
) -> None:
    with detectors.make(False) as det:
        lo, hi = det.exposure_range_s
        assert 0 < lo < hi < math.inf
        before = detectors.activity()
        for exposure in (lo / 2, hi * 2, 0.0, -1.0, math.nan, math.inf):
            with pytest.raises(DetectorError):
                det.measure(exposure)
        for averages in (0, -3):
            with pytest.raises(DetectorError):
                det.measure(0.01, averages)
        assert detectors.activity() == before


def test_a_saturated_reading_is_returned_flagged_not_raised(detectors: DetectorHarness) -> None:
    with detectors.make(True) as det:
        reading = det.measure(1.0)
    assert reading.saturated
    assert math.isfinite(reading.value) and reading.value > 0


def test_what_a_detector_may_also_say_is_readable_closed_and_holds_while_open(
    detectors: DetectorHarness,
) -> None:
    det = detectors.make(False)
    closed = (dark_subtracted(det), reading_unit(det), phase_tolerance_deg(det))
    assert isinstance(closed[0], bool) and isinstance(closed[1], str) and closed[1]
    lockin = detectors.name in ("sr830", "sr860")
    assert closed[0] is lockin  # a lock-in's readings carry no dark or ambient signal
    with det:
        reading = det.measure(0.01, 2)
        assert (dark_subtracted(det), reading_unit(det), phase_tolerance_deg(det)) == closed
        changes = range_changes(det)
    assert all(isinstance(c, RangeChange) for c in changes)
    assert [c.at_s for c in changes] == sorted(c.at_s for c in changes)
    # A detector with a phase tolerance reads the phase with every reading.
    assert (reading.phase_deg is not None) is (closed[2] is not None) is lockin
