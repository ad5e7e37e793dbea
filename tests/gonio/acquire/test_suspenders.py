"""The engine's pause conditions (`gonio.acquire.suspenders`) and calibration schedule
(`gonio.acquire.schedule.Calibrations`), without devices: what trips, in words, and the
steps of a health pause."""

from __future__ import annotations

from drivers.values import Health
from gonio.acquire.health import assess
from gonio.acquire.schedule import Calibrations, Every
from gonio.acquire.suspenders import Step, Suspension, health_suspenders
from gonio.rig.schema import HealthLimitsSpec

LIMITS = HealthLimitsSpec(max_temperature_c=65.0, min_voltage_v=10.0, max_voltage_v=14.8)


def test_the_rigs_suspenders_report_temperatures_then_supplies() -> None:
    health = {
        "a": Health(70.0, 9.5),
        "b": Health(35.0, 12.0),
        "c": Health(66.5, 12.0, ("overheating",)),
    }
    found = assess(health, health_suspenders(LIMITS))
    assert found.problems == [
        "a at 70 °C (limit 65)",
        "c at 66.5 °C (limit 65)",
        "a supply 9.5 V (limits 10–14.8)",
    ]
    assert found.flags == {"c": ["overheating"]}
    assert assess({"b": Health(65.0, 14.8)}, health_suspenders(LIMITS)).problems == []


def test_a_suspension_pauses_once_waits_and_resumes() -> None:
    suspension = Suspension(started_s=100.0, timeout_minutes=0.5)
    assert suspension.consult(["hot"]) is Step.PAUSE
    assert suspension.consult(["hot"]) is Step.WAIT
    assert not suspension.expired(129.9) and suspension.expired(130.0)
    assert suspension.reason() == "paused 0.5 min for hot; it did not clear"
    assert suspension.consult([]) is Step.RESUME
    assert suspension.paused_s(112.5) == 12.5
    assert Suspension(0.0, 1.0).consult([]) is Step.GO


def test_calibrations_open_and_close_a_run() -> None:
    calibrations = Calibrations(Every(samples=15, minutes=None))
    assert calibrations.opening(resuming=False, on_resume=True) == "start"
    calibrations.done(0, 1.0, 0.05)
    assert (calibrations.k, calibrations.at_count, calibrations.exposure_s) == (1, 0, 0.05)
    assert calibrations.opening(resuming=False, on_resume=True) is None
    assert calibrations.opening(resuming=True, on_resume=True) == "resume"
    assert calibrations.opening(resuming=True, on_resume=False) is None
    assert not calibrations.due(14, 2.0) and calibrations.due(15, 2.0)
    calibrations.done(30, 3.0, 0.025)
    assert not calibrations.closing(30, measuring=False)  # a run that ended, resumed
    assert calibrations.closing(30, measuring=True) and calibrations.closing(31, measuring=False)
