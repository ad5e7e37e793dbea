"""`gonio.planner.build`: counts that add up, targets that are valid, reachable and
measured as planned, arrival times that follow from the moves and the dwell, the
benchmark figures only when asked, exposures that follow the expected signal."""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from gonio import brdf, params
from gonio.cli.render import render_summary
from gonio.config import ConfigError
from gonio.planner import build, load_plan, ordering, placement, sampling
from gonio.planner.model import Plan
from gonio.planner.schema import PlanSpec
from gonio.planner.stored import plan_bytes, write_plan
from gonio.progress import hms
from gonio.rig.model import Rig
from gonio.rig.solution import Reason
from tests.support.rigs import with_point_source

PLANS = Path(__file__).resolve().parents[3] / "configs" / "plans"


def spec(**fields: Any) -> PlanSpec:
    """A 300-target Sobol plan; a short iterated search (50 kicks) unless ``kicks`` is
    given (None: the default budget): these tests are about the plan, not its length."""
    data: dict[str, Any] = {
        "name": "test",
        "parametrization": "hybrid",
        "sampling": {"strategy": "sobol", "target": 300},
        "kicks": 50,
    }
    data.update(fields)
    return PlanSpec.model_validate(data)


@pytest.fixture(scope="module")
def plans(rigs: dict[str, Rig]) -> dict[str, Plan]:
    """One small plan per (rig, isotropic), built once, with the benchmark figures."""
    out = {}
    for rig in rigs:
        for iso in (True, False):
            key = f"{rig}-{'iso' if iso else 'aniso'}"
            out[key] = build(spec(isotropic=iso), rigs[rig], bounds=True)
    return out


KEYS = ["arch-iso", "arch-aniso", "in_plane-iso", "in_plane-aniso"]


@pytest.mark.parametrize("key", KEYS)
def test_counts_add_up(plans: dict[str, Plan], key: str) -> None:
    s = plans[key].summary
    assert s.requested == s.invalid + sum(s.refused.values()) + s.kept
    assert s.kept == len(plans[key]) == 300  # a target count is met exactly
    assert s.invalid > 0  # the hybrid box is larger than its domain


@pytest.mark.parametrize("key", KEYS)
def test_targets_are_valid_reachable_and_measured_as_planned(
    plans: dict[str, Plan], key: str
) -> None:
    plan = plans[key]
    rig, p = plan.rig, params.get("hybrid")
    lo, hi = rig.limits[:, 0], rig.limits[:, 1]
    assert np.all((plan.angles >= lo) & (plan.angles <= hi))
    # The pair the chosen pose measures is the planned one (rotated about the normal
    # for isotropic plans): the same coordinates to 1e-10.
    wi, wo = rig.forward(plan.angles)
    np.testing.assert_allclose(wi, plan.wi, atol=1e-12)
    np.testing.assert_allclose(wo, plan.wo, atol=1e-12)
    if plan.spec.isotropic:
        assert p.valid_iso(plan.coords).all()
        got = p.forward_iso(plan.wi, plan.wo)
        d = np.abs(got - plan.coords)
        d[:, 2] = np.minimum(d[:, 2], np.pi - d[:, 2])  # the folded azimuth wraps at π
        assert d.max() < 1e-10
        # The sample stays home: only the arms move.
        assert np.all(plan.angles[:, rig.axes.index("sample_rotation")] == 0.0)
    else:
        assert p.valid(plan.coords).all()
        wi_planned, wo_planned = p.inverse(plan.coords)
        np.testing.assert_allclose(plan.wi, wi_planned, atol=1e-10)
        np.testing.assert_allclose(plan.wo, wo_planned, atol=1e-10)
        assert np.ptp(plan.angles[:, rig.axes.index("sample_rotation")]) > np.pi
    ok, _ = rig.reachable(plan.wi, plan.wo)
    assert ok.all()
    assert not rig._collides(plan.angles).any()


@pytest.mark.parametrize("key", KEYS)
def test_arrival_times_follow_moves_and_dwell(plans: dict[str, Plan], key: str) -> None:
    plan = plans[key]
    rig = plan.rig
    previous = np.vstack([rig.home[None, :], plan.angles[:-1]])
    np.testing.assert_allclose(plan.travel_s, rig.travel_time(previous, plan.angles), rtol=1e-12)
    dwell = rig.spec.settle_s + plan.exposure_s * plan.averages
    np.testing.assert_allclose(np.diff(plan.arrival_s), dwell[:-1] + plan.travel_s[1:], rtol=1e-9)
    assert plan.arrival_s[0] == pytest.approx(plan.travel_s[0])
    s = plan.summary
    assert s.total_s == pytest.approx(plan.arrival_s[-1] + dwell[-1])
    assert s.naive_travel_s is not None and s.lower_bound_travel_s is not None
    assert s.travel_s <= s.naive_travel_s
    assert s.lower_bound_travel_s <= s.travel_s * (1 + 1e-9)
    assert s.lower_bound_exact


def test_bounds_only_when_asked(rigs: dict[str, Rig], plans: dict[str, Plan]) -> None:
    """Without ``bounds`` the benchmark figures are not computed (None, and absent from
    the summary table); the plan itself is the same, bit for bit."""
    with_bounds = plans["arch-iso"]
    plain = build(spec(), rigs["arch"])
    s = plain.summary
    assert s.naive_travel_s is None and s.naive_total_s is None
    assert s.lower_bound_travel_s is None and s.lower_bound_s is None
    assert s.lower_bound_exact is None and plain.bound_wall_s is None
    for name in ("coords", "angles", "travel_s", "arrival_s", "exposure_s", "generated"):
        assert np.array_equal(getattr(plain, name), getattr(with_bounds, name)), name
    assert s.travel_s == with_bounds.summary.travel_s
    text = render_summary(plain)
    assert "in generation order" not in text and "lower bound (MST)" not in text
    shown = render_summary(with_bounds)
    assert "in generation order" in shown and "lower bound (MST)" in shown


def test_same_seed_same_plan(rigs: dict[str, Rig]) -> None:
    a = build(spec(), rigs["arch"])
    b = build(spec(), rigs["arch"])
    assert np.array_equal(a.coords, b.coords)
    assert np.array_equal(a.angles, b.angles)
    c = build(spec(sampling={"strategy": "sobol", "target": 300, "seed": 9}), rigs["arch"])
    assert not np.array_equal(a.coords, c.coords)


def test_the_same_spec_orders_the_same(rig: Rig) -> None:
    """Built twice, bit for bit the same plan: the same order, poses, moves."""
    a = build(spec(isotropic=False), rig)
    b = build(spec(isotropic=False), rig)
    assert np.array_equal(a.generated, b.generated)
    assert a.summary.moves == b.summary.moves > 0
    assert a.summary.converged
    assert a == b and plan_bytes(a) == plan_bytes(b)


@pytest.mark.parametrize("moves", [0, 25])
def test_a_binding_move_budget_is_machine_independent_and_reported(
    rigs: dict[str, Rig], moves: int
) -> None:
    """A move budget that binds stops both passes at the same place whatever the time
    cap: a huge cap and the default give the same plan; the summary says it did not
    converge and why."""
    plans = [
        build(spec(isotropic=False, max_moves=moves, time_budget_s=cap), rigs["in_plane"])
        for cap in (1e9, 120.0)
    ]
    for plan in plans:
        s = plan.summary
        assert not s.converged and s.stopped == "move budget"
        assert s.moves == s.max_moves == moves
        assert (
            f"ordering                  stopped at the move budget ({moves} moves): not converged"
            in (render_summary(plan))
        )
    huge, normal = plans
    assert np.array_equal(huge.generated, normal.generated)
    assert np.array_equal(huge.angles.view(np.int64), normal.angles.view(np.int64))
    free = build(spec(isotropic=False), rigs["in_plane"])
    assert free.summary.converged and free.summary.moves > moves
    assert free.summary.travel_s < huge.summary.travel_s


def test_the_time_cap_is_reported_with_its_consequence(rigs: dict[str, Rig]) -> None:
    plan = build(spec(time_budget_s=1e-9), rigs["arch"])
    s = plan.summary
    assert s.stopped == "time cap" and not s.converged
    line = next(x for x in render_summary(plan).splitlines() if x.startswith("  ordering  "))
    assert line.startswith("  ordering                  stopped at the time cap (1e-09 s, after ")
    assert line.endswith("kicks): not converged, and this order depends on the machine's speed")


def test_the_default_budget_converges_and_says_so(rigs: dict[str, Rig]) -> None:
    plan = build(spec(kicks=None), rigs["arch"])
    s = plan.summary
    assert s.converged and s.stopped == "converged"
    assert s.max_moves == ordering.default_moves(300) == 3100
    assert 0 < s.moves < s.max_moves
    assert s.max_kicks == ordering.default_kicks(300) == 450 == s.kicks
    assert 0 < s.kicks_kept < s.kicks
    assert (
        f"ordering                  converged after {s.moves} moves, then 450 kicks "
        f"({s.kicks_kept} kept); budgets 3,100 and 450"
    ) in render_summary(plan)


@pytest.mark.parametrize("strategy", ["sobol", "halton", "random"])
def test_sequence_strategies_keep_the_first_points_that_fit(
    rigs: dict[str, Rig], strategy: str
) -> None:
    """The kept targets are exactly the first `target` usable points of the sequence in
    generation order: uniform in the coordinates, nothing chosen by hand."""
    s = spec(sampling={"strategy": strategy, "target": 200, "seed": 3})
    plan = build(s, rigs["in_plane"])

    stream = sampling.Sequence(strategy, 3, 3)
    batches = -(-plan.summary.requested // placement.BATCH)
    unit = np.vstack([stream.draw(placement.BATCH) for _ in range(batches)])
    drawn = sampling.to_box(
        unit[: plan.summary.requested],
        params.get("hybrid").iso_bounds,
        np.ones(3),
    )
    kept = placement.kept_mask(s, rigs["in_plane"], drawn)
    assert kept.sum() == 200 and kept[-1]
    assert sorted(map(tuple, plan.coords)) == sorted(map(tuple, drawn[kept]))


def test_grid_counts_place_every_cell(rigs: dict[str, Rig]) -> None:
    s = spec(sampling={"strategy": "grid", "counts": {"hbar": 6, "k": 5, "phi_k_minus_phi_h": 4}})
    plan = build(s, rigs["arch"])
    assert plan.summary.requested == 120
    assert plan.summary.grid_shape == (6, 5, 4)
    # Cell centres: hbar at (i + 1/2)/6.
    hbar = np.unique(plan.coords[:, 0])
    assert np.allclose(hbar * 6 - 0.5, np.round(hbar * 6 - 0.5))


def test_grid_target_reaches_the_target(rigs: dict[str, Rig]) -> None:
    plan = build(spec(sampling={"strategy": "stratified", "target": 400, "seed": 1}), rigs["arch"])
    assert plan.summary.kept >= 400 * 0.8
    shape = plan.summary.grid_shape
    assert shape is not None and len(set(shape)) == 1


def test_warp_densifies_near_the_specular_peak(rigs: dict[str, Rig]) -> None:
    flat = build(spec(sampling={"strategy": "sobol", "target": 600}), rigs["arch"])
    warped = build(
        spec(sampling={"strategy": "sobol", "target": 600, "warps": {"hbar": {"power": 2}}}),
        rigs["arch"],
    )
    assert np.mean(warped.coords[:, 0] < 0.2) > 1.8 * np.mean(flat.coords[:, 0] < 0.2)


def test_unreachable_target_count_is_a_config_error(
    rigs: dict[str, Rig], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(placement, "MAX_DRAWN", 8192)
    with pytest.raises(ConfigError, match=r"^here: sampling.target: only \d+ of 8000"):
        build(spec(sampling={"strategy": "random", "target": 8000}), rigs["arch"], where="here")


@pytest.mark.parametrize(
    ("sampling", "field"),
    [
        (
            {"strategy": "sobol", "target": 1_000_001},
            r"sampling.target: expected at most 1,000,000 targets, got 1,000,001 \(planning "
            r"needs about 4 KB of memory",
        ),
        (
            {"strategy": "stratified", "target": 2_000_000},
            "sampling.target: expected at most 1,000,000 targets, got 2,000,000",
        ),
        (
            {"strategy": "grid", "counts": {"hbar": 1000, "k": 1000, "phi_k_minus_phi_h": 10}},
            "sampling.counts: a 1000×1000×10 grid is 10,000,000 points; expected at most",
        ),
    ],
    ids=["sequence", "grid-from-target", "grid-counts"],
)
def test_plans_too_large_are_refused_before_any_work(
    rigs: dict[str, Rig], sampling: dict[str, Any], field: str
) -> None:
    with pytest.raises(ConfigError, match=f"^here: {field}"):
        build(spec(sampling=sampling), rigs["arch"], where="here")


def test_a_grid_keeping_more_targets_than_the_cap_is_refused(
    rigs: dict[str, Rig], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(placement, "MAX_TARGETS", 1000)
    counts = {"hbar": 20, "k": 20, "phi_k_minus_phi_h": 10}
    with pytest.raises(ConfigError, match=r"^here: sampling.counts: expected at most 1,000 "):
        build(spec(sampling={"strategy": "grid", "counts": counts}), rigs["arch"], where="here")


def test_csv_part_reads_with_any_csv_reader(plans: dict[str, Plan], tmp_path: Path) -> None:
    """Past the ``#`` header the stored plan is plain CSV, floats written exactly."""
    plan = plans["arch-aniso"]
    path = tmp_path / "plan.csv"
    write_plan(plan, path)
    with path.open(encoding="utf-8") as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    assert len(rows) == len(plan)
    assert list(rows[0])[:6] == ["index", "generated", "hbar", "phi_h", "k", "phi_k"]
    for name in ("wi_x", "wo_z", "light_elevation_rad", "sample_rotation_rad", "arrival_s"):
        assert name in rows[0]
    got = np.array([[float(r[f"{a}_rad"]) for a in plan.rig.axes] for r in rows])
    assert np.array_equal(got, plan.angles)  # repr floats: exact
    coords = np.array([[float(r[n]) for n in plan.coordinate_names] for r in rows])
    assert np.array_equal(coords, plan.coords)
    assert [int(r["index"]) for r in rows] == list(range(len(plan)))
    assert [float(r["arrival_s"]) for r in rows] == plan.arrival_s.tolist()
    assert [float(r["travel_s"]) for r in rows] == plan.travel_s.tolist()
    assert sorted(int(r["generated"]) for r in rows) == sorted(plan.generated.tolist())


def test_adaptive_exposure_follows_the_expected_signal(rigs: dict[str, Rig]) -> None:
    adapt = {
        "material": {"name": "cook_torrance", "alpha": 0.2, "fresnel": "schlick", "f0": 0.04},
        "min_s": 0.02,
        "max_s": 0.5,
        "max_averages": 4,
    }
    plan = build(spec(exposure={"seconds": 0.1, "averages": 1, "adapt": adapt}), rigs["arch"])

    model = brdf.create("cook_torrance", alpha=0.2, fresnel="schlick", f0=0.04)
    # A collimated beam's whole power lands on the sample: the signal goes as f cos θo.
    signal = model.eval(plan.wi, plan.wo) * plan.wo[:, 2]
    assert plan.exposure_s.min() >= 0.02 and plan.exposure_s.max() <= 0.5
    assert plan.averages.min() >= 1 and plan.averages.max() <= 4
    # Inside the clip range the exposure is exactly base × median / signal.
    inside = (plan.exposure_s > 0.02) & (plan.exposure_s < 0.5)
    assert inside.sum() > 50
    ref = float(np.median(signal[signal > 0]))
    np.testing.assert_allclose(plan.exposure_s[inside], 0.1 * ref / signal[inside], rtol=1e-9)
    # Dark targets at the maximum exposure average more; bright ones do not.
    assert plan.averages[plan.exposure_s == 0.5].max() > 1
    assert np.all(plan.averages[plan.exposure_s < 0.5] == 1)
    # A point source's irradiance goes as cos θi, the view's area cancels cos θo.
    point = build(
        spec(exposure={"seconds": 0.1, "averages": 1, "adapt": adapt}),
        with_point_source(rigs["arch"]),
    )
    signal = model.eval(point.wi, point.wo) * point.wi[:, 2]
    inside = (point.exposure_s > 0.02) & (point.exposure_s < 0.5)
    ref = float(np.median(signal[signal > 0]))
    np.testing.assert_allclose(point.exposure_s[inside], 0.1 * ref / signal[inside], rtol=1e-9)


def test_constant_exposure_without_adapt(plans: dict[str, Plan]) -> None:
    plan = plans["arch-iso"]
    assert np.all(plan.exposure_s == 0.1) and np.all(plan.averages == 1)


@pytest.mark.parametrize("name", ["quick", "isotropic_hybrid", "anisotropic"])
def test_shipped_plans_build(name: str) -> None:
    s, rig = load_plan(PLANS / f"{name}.yaml")
    # A few kicks, and the bounds (seconds at 5 000 targets) on the small plan only: fast.
    plan = build(s.model_copy(update={"kicks": 100}), rig, bounds=name == "quick")
    assert len(plan) > 0
    if name == "quick":
        assert plan.summary.lower_bound_travel_s is not None
        assert plan.summary.travel_s <= 1.05 * plan.summary.lower_bound_travel_s
    # The default move budget leaves the shipped plans converged, as the time budget did.
    assert plan.summary.converged and plan.summary.moves < plan.summary.max_moves
    text = render_summary(plan)
    for line in ("requested", "outside the domain", "refused: blind spot", "kept"):
        assert line in text
    assert hms(plan.summary.total_s) in text


def test_shipped_plan_sizes() -> None:
    """The shipped plans are what the README says: ≈ 500, ≈ 5 000 and anisotropic."""
    sizes = {}
    for name in ("quick", "isotropic_hybrid", "anisotropic"):
        s, rig = load_plan(PLANS / f"{name}.yaml")
        sizes[name] = (s, rig)
    assert sizes["quick"][0].sampling.target == 500
    assert sizes["isotropic_hybrid"][0].sampling.target == 5000
    assert not sizes["anisotropic"][0].isotropic


def test_rig_override(tmp_path: Path) -> None:
    _, rig = load_plan(PLANS / "quick.yaml", PLANS.parent / "rigs" / "in_plane.yaml")
    assert rig.spec.type == "in_plane"


def test_hms() -> None:
    assert hms(0) == "0:00:00"
    assert hms(3599.6) == "1:00:00"
    assert hms(90061) == "25:01:01"


def test_reason_labels_cover_the_summary(plans: dict[str, Plan]) -> None:
    assert set(plans["arch-iso"].summary.refused) == {r.label for r in Reason if r != Reason.OK}
