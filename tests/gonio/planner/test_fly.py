"""Fly plans: sweeps within the rig's limits, velocities within the blur budget and the
axes' max velocity, readings and duration as an independent computation predicts, the
summary's lines, the stored plan read back bit for bit, and acquisition refused on the
backends that do not sweep yet."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

import gonio.planner.fly.thin as fly_thin
from gonio.cli.render import render_summary
from gonio.config import ConfigError
from gonio.planner import build, plan_bytes, read_plan, write_plan
from gonio.planner.blur import blur_budget_of_width
from gonio.planner.fly import THINNED, sweep_axis
from gonio.planner.model import Plan
from gonio.planner.schema import PlanSpec
from gonio.planner.stored import parse_plan
from gonio.rig.constraints import separation
from gonio.rig.model import Rig
from gonio.rig.solution import Reason
from gonio.workflows.preflight import refuse_fly
from tests.conftest import CONFIGS, RIG_FILES

FLY = CONFIGS / "plans" / "fly.yaml"


def fly_spec(**fly: Any) -> PlanSpec:
    options = {"rate_hz": 50.0, **fly}
    return PlanSpec.model_validate(
        {
            "name": "fly-test",
            "parametrization": "rusinkiewicz",
            "sampling": {"strategy": "fly", "target": 1200, "seed": 4, "fly": options},
            "kicks": 20,
        }
    )


CASES = {
    "arch": {"rate_hz": 50.0, "blur_deg": 0.4},
    "arch-fast": {"rate_hz": 20.0, "integration_s": 0.02, "blur_deg": 2.0},
    "in_plane": {"rate_hz": 50.0, "blur_deg": 0.4},
    "in_plane-light": {"segment": "light_arc", "rate_hz": 50.0, "lobe_width_deg": 2.0},
}


@pytest.fixture(scope="module")
def plans(rigs: dict[str, Rig]) -> dict[str, Plan]:
    return {name: build(fly_spec(**fly), rigs[name.split("-")[0]]) for name, fly in CASES.items()}


@pytest.fixture(params=list(CASES))
def plan(request: pytest.FixtureRequest, plans: dict[str, Plan]) -> Plan:
    return plans[request.param]


def test_commanded_poses_are_within_the_limits_and_outside_the_keep_out_boxes(plan: Plan) -> None:
    rig, w = plan.rig, plan.sweeps
    assert w is not None and len(w) > 1
    lo, hi = rig.limits[:, 0], rig.limits[:, 1]
    for poses in (w.start, w.entry, w.exit, w.stop, plan.angles):
        assert np.all((poses >= lo) & (poses <= hi))
    # Every pose the axes pass through from run-up to overrun, 0.01° apart.
    for a, b in zip(w.start, w.stop, strict=True):
        steps = int(np.abs(b - a).max() / math.radians(0.01)) + 2
        path = a + np.linspace(0.0, 1.0, steps)[:, None] * (b - a)
        path[-1] = b  # a + (b - a) may differ from b by an ulp
        _, commandable = rig.pose_reasons(path)
        assert commandable.all()


def test_every_reading_measures_a_reachable_pair_at_its_own_pose(plan: Plan) -> None:
    reasons, _ = plan.rig.pose_reasons(plan.angles)
    assert np.all(reasons == Reason.OK)
    wi, wo = plan.rig.forward(plan.angles)
    np.testing.assert_allclose(wi, plan.wi, atol=1e-12)
    np.testing.assert_allclose(wo, plan.wo, atol=1e-12)


def test_velocities_respect_the_blur_budget_and_the_axes_max_velocity(plan: Plan) -> None:
    rig, w, fly = plan.rig, plan.sweeps, plan.spec.sampling.fly_options()
    assert w is not None and plan.summary.fly is not None
    assert np.all(np.abs(w.velocity) <= rig.velocity * (1 + 1e-12))
    moving = np.flatnonzero(np.any(w.velocity != 0, axis=0))
    assert moving.tolist() == [sweep_axis(rig, fly)]  # one axis sweeps, the rest still
    # The smear of each reading: its directions at integration start and end.
    velocity = np.repeat(w.velocity, w.count, axis=0)
    half = 0.5 * fly.integration * velocity
    wi0, wo0 = rig.forward(plan.angles - half)
    wi1, wo1 = rig.forward(plan.angles + half)
    smear = np.degrees(np.maximum(separation(wi0, wi1), separation(wo0, wo1)))
    assert smear.max() <= fly.blur * (1 + 1e-6)
    assert smear.max() <= plan.summary.fly.smear_max_deg * (1 + 1e-6)
    if fly.lobe_width_deg is not None:
        share = fly.lobe_fraction  # none: the blur budget of the width (gonio.planner.blur)
        budget = blur_budget_of_width(fly.lobe_width_deg, fly.blur_tolerance)
        assert fly.blur == pytest.approx(budget if share is None else share * fly.lobe_width_deg)


def test_readings_and_duration_as_an_independent_computation_predicts(plan: Plan) -> None:
    rig, w, s = plan.rig, plan.sweeps, plan.summary
    assert w is not None and s.fly is not None
    j = sweep_axis(rig, plan.spec.sampling.fly_options())
    period, t_int = w.period_s, w.integration_s
    here, t, n = rig.home, 0.0, 0
    for k in range(len(w)):
        v = abs(float(w.velocity[k, j]))
        ramp = v / float(rig.acceleration[j])
        # the ramps cover v² / 2a each side of the constant-velocity part
        assert abs(w.entry[k, j] - w.start[k, j]) == pytest.approx(v * ramp / 2)
        assert abs(w.exit[k, j] - w.entry[k, j]) == pytest.approx(
            v * ((w.streamed[k] - 1) * period + t_int)
        )
        t += float(rig.travel.time(here, w.start[k])) + rig.spec.settle_s + ramp
        assert w.cruise_at_s[k] == pytest.approx(t)
        assert w.first[k] == n
        rows = slice(n, n + int(w.count[k]))
        # the targets: stream readings (integer slots) kept by the thinning, in order,
        # the first and the last streamed ones among them
        ks = np.round((plan.arrival_s[rows] - t) / period)
        np.testing.assert_allclose(plan.arrival_s[rows], t + ks * period, rtol=0, atol=1e-9)
        assert ks[0] == 0 and ks[-1] == w.streamed[k] - 1 and np.all(np.diff(ks) > 0)
        mids = w.entry[k] + w.velocity[k] * (ks * period + t_int / 2)[:, None]
        np.testing.assert_allclose(plan.angles[rows], mids, rtol=0, atol=1e-9)
        t += (w.streamed[k] - 1) * period + t_int + ramp
        here, n = w.stop[k], n + int(w.count[k])
    assert n == len(plan) == s.kept >= plan.spec.sampling.target
    assert s.total_s == pytest.approx(t)
    assert s.fly.cruise_s + s.fly.ramps_s + s.fly.moves_s == pytest.approx(t)
    assert s.dwell_s == pytest.approx(len(plan) * t_int)
    # Stop-and-go: the same readings, a move, settle and one integration each.
    previous = np.vstack([rig.home, plan.angles[:-1]])
    expected = rig.travel.time(previous, plan.angles).sum() + len(plan) * (
        rig.spec.settle_s + t_int
    )
    assert s.fly.stop_and_go_s == pytest.approx(expected)
    assert s.fly.stop_and_go_s > 3 * s.total_s  # thinning keeps about half the stream
    # Requested readings: kept or refused with a reason.
    assert s.requested == s.kept + sum(s.refused.values())
    assert 0.0 <= s.fly.coverage_tv_uniform < s.fly.coverage_tv <= 1.0
    assert 0.0 < s.fly.coverage_gap_uniform < s.fly.coverage_gap < 1.0
    # thinned: streamed and not kept, or cut with a sweep's ends (none kept there)
    assert s.kept <= s.fly.streamed == int(w.streamed.sum()) <= s.kept + s.refused[THINNED]


def test_readings_are_the_generated_ones_in_a_new_order(plan: Plan) -> None:
    assert sorted(plan.generated.tolist()) == list(range(len(plan)))


def test_the_summary_names_the_sweeps_and_the_trade(plans: dict[str, Plan]) -> None:
    text = render_summary(plans["arch"])
    s = plans["arch"].summary
    assert s.fly is not None
    assert "plan 'fly-test': isotropic rusinkiewicz, fly, rig 'arch-4axis'" in text
    assert f"  {'sweeps':<26}{s.fly.segments:>9}   (on {s.fly.lines} lines)" in text
    assert "  readings                       " in text
    assert f"(50 Hz, 20 ms each; {s.fly.streamed} streamed, thinned" in text
    per_hour = 3600 * s.kept / s.total_s
    assert f"  {'readings per hour':<26}{per_hour:>9,.0f}   (stop-and-go: " in text
    assert f"{s.fly.stop_and_go_s / s.total_s:.1f}× faster)" in text
    assert f"  {'coverage (TV distance)':<26}{s.fly.coverage_tv:>9.3f}" in text
    assert f"  {'largest empty ball':<26}{s.fly.coverage_gap:>9.3f}" in text
    assert "refused: ramp" in text and "refused: thinned" in text


def test_a_stored_fly_plan_reads_back_bit_for_bit(plans: dict[str, Plan], tmp_path: Path) -> None:
    plan = plans["in_plane-light"]
    path = tmp_path / "fly.csv"
    write_plan(plan, path)
    again = read_plan(path)
    assert again == plan
    assert again.sweeps == plan.sweeps and again.summary.fly == plan.summary.fly
    assert plan_bytes(again) == path.read_bytes()


def test_a_stored_plan_with_altered_sweeps_is_refused(plans: dict[str, Plan]) -> None:
    raw = plan_bytes(plans["arch"]).decode()
    lines = raw.split("\n")
    at = next(i for i, line in enumerate(lines) if line.startswith("# sweeps: "))
    sweeps = json.loads(lines[at].removeprefix("# sweeps: "))
    sweeps["count"][0] += 1
    lines[at] = "# sweeps: " + json.dumps(sweeps)
    with pytest.raises(ConfigError, match=r"hashes\.file_sha256"):
        parse_plan("\n".join(lines).encode(), "x.csv")
    without = "\n".join(line for line in lines if not line.startswith("# sweeps: "))
    with pytest.raises(ConfigError, match=r"x\.csv"):
        parse_plan(without.encode(), "x.csv")


def test_a_stop_and_go_plan_stores_no_sweeps(quick_plan: Plan) -> None:
    raw = plan_bytes(quick_plan)
    assert (
        b"# sweeps:" not in raw
        and b'"fly":' not in raw.split(b"\n# hashes")[0].split(b"# summary: ")[1]
    )
    assert quick_plan.sweeps is None and not quick_plan.is_fly


def test_the_shipped_fly_plan_plans_and_hardware_refuses_it(
    run_gonio: Any, tmp_path: Path, plans: dict[str, Plan]
) -> None:
    out = tmp_path / "fly.csv"
    result = run_gonio("plan", str(FLY), "-o", str(out))
    code, stdout, err = result.returncode, result.stdout, result.stderr
    assert code == 0, err
    assert "readings per hour" in stdout and f"to {out}" in stdout
    assert read_plan(out).sweeps is not None
    refuse_fly(plans["arch"], "simulated")
    refuse_fly(plans["arch"], "rehearsal")  # its simulated detector streams
    with pytest.raises(ConfigError, match="simulated and rehearsal backends only") as info:
        refuse_fly(plans["arch"], "hardware")
    assert "\n" not in str(info.value)
    lockin = dataclasses.replace(
        plans["arch"], rig=Rig.from_yaml(CONFIGS / "rigs/arch_lockin.yaml")
    )
    with pytest.raises(ConfigError, match="pymeasure detector cannot stream") as info:
        refuse_fly(lockin, "rehearsal")
    assert "\n" not in str(info.value)


@pytest.mark.parametrize(
    ("fly", "field", "message"),
    [
        ({"rate_hz": 100, "integration_s": 0.02}, "sampling.fly.integration_s", "at most"),
        ({"blur_deg": 1, "lobe_width_deg": 3}, "sampling.fly.blur_deg", "not both"),
        ({"rate_hz": 0}, "sampling.fly.rate_hz", "greater than or equal to 1"),
        ({"segment": "diagonal"}, "sampling.fly.segment", "detector_arc"),
    ],
)
def test_bad_fly_options_are_one_line_naming_the_field(
    tmp_path: Path, run_gonio: Any, fly: dict[str, Any], field: str, message: str
) -> None:
    data = yaml.safe_load(FLY.read_text())
    data["rig"] = str(RIG_FILES["arch"])
    data["sampling"]["fly"] = fly
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(data))
    result = run_gonio("plan", str(path))
    code, out, err = result.returncode, result.stdout, result.stderr
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and f": {field}: " in err and message in err, err


def test_fly_options_belong_to_the_fly_strategy() -> None:
    with pytest.raises(ValueError, match="options of the fly strategy"):
        PlanSpec.model_validate(
            {"name": "x", "sampling": {"strategy": "sobol", "target": 10, "fly": {}}}
        )


def test_a_ramp_is_half_of_a_trapezoidal_move_that_just_reaches_the_velocity(
    rigs: dict[str, Rig],
) -> None:
    travel = rigs["arch"].travel
    v = np.array([0.0, 0.0, 0.5, 0.0])
    t, d = travel.ramp(v)
    a = travel.acceleration[2]
    assert t == pytest.approx(0.5 / a) and d[2] == pytest.approx(0.5**2 / (2 * a))
    # a move over twice the ramp's distance peaks at v exactly: twice the ramp's time
    assert travel.time(np.zeros(4), 2 * d) == pytest.approx(2 * t)


def test_the_thinning_and_the_anchor_gap_bring_the_readings_nearer_uniform(
    rigs: dict[str, Rig], monkeypatch: pytest.MonkeyPatch
) -> None:
    def figures(rig: Rig) -> Any:
        spec = fly_spec(rate_hz=100.0, blur_deg=0.5).model_dump()
        spec["sampling"]["target"] = 8000
        plan = build(PlanSpec.model_validate(spec), rig)
        assert plan.summary.fly is not None
        return plan.summary.fly

    thinned = figures(rigs["arch"])
    # Every streamed reading kept (a zero quantile keeps all), every anchor taken: the
    # readings evenly spaced in time along the arcs, as the layout alone gives them.
    monkeypatch.setattr(fly_thin, "THIN_QUANTILE", 0.0)
    monkeypatch.setattr(fly_thin, "ANCHOR_GAP", 0.0)
    monkeypatch.setattr(fly_thin, "THIN_GUESS", 1.0)
    raw = figures(rigs["arch"])
    assert raw.streamed < thinned.streamed
    assert thinned.coverage_tv < 0.7 * raw.coverage_tv
    assert thinned.coverage_gap < raw.coverage_gap
