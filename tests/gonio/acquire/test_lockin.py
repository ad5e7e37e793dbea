"""A lock-in detector in a simulated run (scene ``detector.kind: lockin``): no dark
reading and the reason journaled, its volts a level (divided by no exposure, so
exposures that vary from target to target still give the BRDF), its phase checked
against the reference reading's, range changes journaled as events."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pytest

from drivers.values import RangeChange, Reading
from gonio.acquire.watch import ReadingWatch, phase_drift
from gonio.analysis.summary import error_figures
from gonio.errors import GonioError
from gonio.planner import build
from gonio.planner.schema import PlanSpec
from gonio.rig.model import Rig
from gonio.scene import Scene, load_scene
from gonio.workflows.simulate import simulate_plan
from tests.conftest import CONFIGS


def plan_spec(**exposure: object) -> PlanSpec:
    return PlanSpec.model_validate(
        {
            "name": "t",
            "parametrization": "hybrid",
            "isotropic": True,
            "sampling": {"strategy": "sobol", "target": 40, "seed": 0},
            "exposure": {"seconds": 0.02, "averages": 1, **exposure},
            "time_budget_s": 1,
            "max_moves": 0,
            "kicks": 0,
        }
    )


def lockin(rig: Rig, **detector: object) -> Scene:
    scene = load_scene(CONFIGS / "scenes" / "matte_lockin.yaml", rig)
    return scene.model_copy(update={"detector": scene.detector.model_copy(update=detector)})


def test_a_lockin_run_takes_no_dark_and_its_levels_give_the_brdf(rigs: dict[str, Rig]) -> None:
    rig = rigs["arch"]
    adapt = {"material": {"name": "lambert", "albedo": 0.5}, "min_s": 0.005, "max_s": 0.08}
    plan = build(plan_spec(adapt=adapt), rig)
    assert np.ptp(plan.exposure_s) > 0.01  # exposures vary from target to target
    result = simulate_plan(plan, lockin(rig), seed=3)
    calibrations = [e.data for e in result.run.of_kind("calibration")]
    assert all(c["dark"] is None and c["dark_reason"] == "detector" for c in calibrations)
    assert all(c["unit"] == "V" for c in calibrations)
    rounding = result.calibrated.series.dark_rounding
    assert rounding is None or not rounding.any()  # no ADC code to round
    assert result.calibrated.series.dark_rate_var.tolist() == [0.0] * len(calibrations)
    errors = error_figures(result.run, result.truth)
    assert errors["n"] == 40 and errors["median"] < 0.005, errors
    # Its σ is what its error is: z-scores of unit spread, give or take.
    z = (result.brdf / result.truth - 1.0) / (result.sigma / result.brdf)
    assert 0.5 < np.std(z) < 2.0


def test_a_drifting_phase_is_an_event_per_sample_past_the_tolerance(rigs: dict[str, Rig]) -> None:
    rig = rigs["arch"]
    plan = build(plan_spec(), rig)
    result = simulate_plan(plan, lockin(rig, phase_drift_deg_per_hour=1800.0), seed=3)
    run = result.run
    reference = run.of_kind("calibration")[0]
    assert reference.data["reference"]["phase_tolerance_deg"] == 5.0
    drifts = run.of_kind("phase")
    assert drifts and not run.of_kind("fault")
    started = run.samples["started_s"]
    ref = reference.data["reference"]
    since = started - 0.5 * (ref["started_s"] + ref["ended_s"])
    # 0.5°/s: a sample drifts past 5° some 10 s after the reference reading.
    drifted = {e.target for e in drifts}
    assert drifted >= set(np.flatnonzero(since > 11.0).tolist())
    assert not drifted & set(np.flatnonzero(since < 9.0).tolist())
    for e in drifts:
        assert e.data["drift_deg"] == pytest.approx(
            phase_drift(e.data["phase_deg"], e.data["reference_deg"])
        )
        assert abs(e.data["drift_deg"]) > e.data["tolerance_deg"]


@dataclass
class Ranging:
    """A detector that auto-ranges (its optional ``range_changes``) mid-reading."""

    range_changes: list[RangeChange] = field(default_factory=list)
    unit: str = "A"

    @property
    def exposure_range_s(self) -> tuple[float, float]:
        return (1e-3, 1.0)


def test_the_range_changes_inside_a_reading_are_its_events() -> None:
    detector = Ranging()
    watch = ReadingWatch(detector, offset_s=100.0)  # type: ignore[arg-type]
    reading = Reading(1e-9, 0.0, 1, False, 0.0, 1.0, phase_deg=None)
    assert list(watch.events(reading)) == []
    detector.range_changes += [RangeChange(0.5, 2e-3, 2e-9), RangeChange(0.7, 2e-9, 20e-9)]
    events = list(watch.events(reading))
    assert [k for k, _ in events] == ["range", "range"]
    assert events[0][1] == {"at_s": 100.5, "old": 2e-3, "new": 2e-9, "unit": "A"}
    assert list(watch.events(reading)) == []  # each change once


def test_phase_drift_wraps_around_the_circle() -> None:
    assert phase_drift(179.0, -179.0) == pytest.approx(-2.0)
    assert phase_drift(-179.0, 179.0) == pytest.approx(2.0)
    assert phase_drift(10.0, 4.0) == pytest.approx(6.0)


def test_a_resumed_run_compares_with_the_last_reference_phase_journaled(
    rigs: dict[str, Rig],
) -> None:
    rig = rigs["arch"]
    plan = build(plan_spec(), rig)
    run = simulate_plan(plan, lockin(rig, phase_drift_deg_per_hour=1800.0), seed=3).run
    last = run.of_kind("calibration")[-1].data["reference"]["phase_deg"]
    watch = ReadingWatch.of(Ranging(), 0.0, run)  # type: ignore[arg-type]
    assert (
        watch.reference_deg == last != run.of_kind("calibration")[0].data["reference"]["phase_deg"]
    )


def test_an_overload_is_not_measured_again_at_a_shorter_exposure(rigs: dict[str, Rig]) -> None:
    """A lock-in's overload does not depend on the exposure: a saturated sample is kept
    as it is (not halved in vain) and a saturated reference is one line saying what to
    change."""
    rig = rigs["arch"]
    plan = build(plan_spec(), rig)
    # The glossy metal: full scale 10 mV between the reference (1.4 mV) and its peak.
    glossy = load_scene(CONFIGS / "scenes" / "glossy_metal.yaml", rig).material
    scene = lockin(rig).model_copy(update={"material": glossy})
    s = simulate_plan(plan, scene, seed=3).run.samples
    assert s["saturated"].any() and not s["remeasured"].any()
    with pytest.raises(GonioError, match="raise its range or sensitivity"):
        simulate_plan(plan, lockin(rig, sensitivity_v=1e-4), seed=3)
