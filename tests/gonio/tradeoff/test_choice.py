"""The choice of plan for a budget: candidates fitted to 90 s of instrument time on the
arch rig, their errors predicted for the glossy gold (θh lines chosen) and the matte
material (stop-and-go chosen), and the rule, which never prefers a fly plan predicted
worse than the best stop-and-go one."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from gonio.errors import GonioError
from gonio.planner.files import load_plan
from gonio.planner.schema import PlanSpec
from gonio.reconstruct import testset
from gonio.reconstruct.truth import Truth
from gonio.rig.model import Rig
from gonio.tradeoff.choice import (
    CANDIDATES,
    MARGIN,
    METHODS,
    Choice,
    Fitted,
    best_stop,
    fit,
    material_guess,
    pick,
    predict,
)
from gonio.tradeoff.spec import FLY, STOP
from tests.conftest import CONFIGS

# One worker builds the fitted plans once.
pytestmark = pytest.mark.xdist_group("chosen-plans")

BUDGET_S = 90.0
GOLD = str(CONFIGS / "scenes" / "glossy_metal_fly.yaml")
MATTE = "cook_torrance:alpha=0.5,distribution=ggx,fresnel=schlick,f0=0.04,kd=0.6"


@pytest.fixture(scope="module")
def quick() -> tuple[PlanSpec, Rig]:
    spec, rig = load_plan(CONFIGS / "plans" / "quick.yaml")
    return spec.model_copy(update={"kicks": 20}), rig


@pytest.fixture(scope="module")
def fitted(quick: tuple[PlanSpec, Rig]) -> tuple[Fitted, ...]:
    return fit(*quick, BUDGET_S)


def _choice(quick: tuple[PlanSpec, Rig], fitted: tuple[Fitted, ...], guess: str) -> Choice:
    _, rig = quick
    material = material_guess(guess, parametrization="hybrid", isotropic=True, rig=rig)
    pairs = testset.draw(rig, isotropic=True, size=2000, seed=14)
    return predict(fitted, material, rig, budget_s=BUDGET_S, test_set=pairs)


@pytest.fixture(scope="module")
def gold(quick: tuple[PlanSpec, Rig], fitted: tuple[Fitted, ...]) -> Choice:
    return _choice(quick, fitted, GOLD)


@pytest.fixture(scope="module")
def matte(quick: tuple[PlanSpec, Rig], fitted: tuple[Fitted, ...]) -> Choice:
    return _choice(quick, fitted, MATTE)


def test_every_candidate_is_fitted_to_the_budget(fitted: tuple[Fitted, ...]) -> None:
    # The shipped candidates, then the quick plan as written (Sobol in hybrid).
    names = [f.candidate.name for f in fitted]
    assert names == [*(c.name for c in CANDIDATES), "as written: sobol, hybrid"]
    for one in fitted:
        assert one.plan is not None, one.error
        assert 0.85 * BUDGET_S <= one.plan.summary.total_s <= BUDGET_S
        assert one.plan.is_fly == (one.candidate.motion == FLY)
    plans = {f.candidate.name: f.plan for f in fitted}
    warped = plans["warped, rusinkiewicz"]
    assert warped is not None and warped.spec.sampling.warps["theta_h"].power == 2.0
    lines = plans["θh lines, 1°"]
    assert lines is not None and lines.spec.sampling.fly_options().segment == "theta_h_line"
    assert lines.spec.sampling.fly_options().blur == 1.0
    # A fly plan takes many times the samples of stop-and-go in the same time.
    sobol = plans["sobol, rusinkiewicz"]
    assert sobol is not None and len(lines) > 10 * len(sobol)


def test_glossy_gold_chooses_theta_h_lines(gold: Choice) -> None:
    assert gold.chosen.is_fly and gold.chosen.name.startswith("θh lines")
    assert gold.best_stop is not None and gold.best_stop.log_rmse is not None
    assert gold.chosen.log_rmse is not None
    # Lines along the fast direction: well under the best stop-and-go plan's error.
    assert gold.chosen.log_rmse < 0.7 * gold.best_stop.log_rmse
    assert gold.chosen.log_rmse == min(p.log_rmse or math.inf for p in gold.predictions)
    assert gold.chosen.plan is gold.plan and gold.plan.is_fly
    assert gold.test_pairs == 2000 and gold.test_seed == 14


def test_matte_chooses_stop_and_go(matte: Choice) -> None:
    assert not matte.chosen.is_fly
    assert matte.chosen is matte.best_stop
    fly = min(p.log_rmse or math.inf for p in matte.predictions if p.is_fly)
    assert matte.chosen.log_rmse is not None and matte.chosen.log_rmse < fly


def test_predictions_depend_on_the_material_not_the_plans(gold: Choice, matte: Choice) -> None:
    for g, m in zip(gold.predictions, matte.predictions, strict=True):
        assert (g.name, g.seconds, g.samples) == (m.name, m.seconds, m.samples)
        assert g.method in METHODS and m.method in METHODS
        if g.method == m.method:  # the same reconstruction: the same support
            assert (g.gap, g.coverage) == (m.gap, m.coverage)
        assert g.log_rmse is not None and m.log_rmse is not None
        assert g.log_rmse > 1.5 * m.log_rmse  # the glossy lobe is harder to interpolate
        assert g.coverage is not None and 0.3 < g.coverage <= 1.0
        assert g.gap is not None and 0.0 < g.gap < math.sqrt(3)


def test_a_budget_nothing_fits_is_one_line(quick: tuple[PlanSpec, Rig]) -> None:
    spec, rig = quick
    fitted = fit(spec, rig, 0.5, CANDIDATES[:1])
    assert fitted[0].plan is None and "fits 0.5 s" in fitted[0].error
    pairs = testset.draw(rig, isotropic=True, size=100, seed=1)
    truth = Truth("zero", lambda wi, wo: 0.0 * wi[..., 0])
    with pytest.raises(GonioError, match=r"^no candidate plan fits 0.5 s \(sobol, rusinkiewicz: "):
        predict(fitted, truth, rig, budget_s=0.5, test_set=pairs)
    with pytest.raises(GonioError, match="a time budget must be a positive"):
        fit(spec, rig, -1.0)


def test_material_guesses(quick: tuple[PlanSpec, Rig]) -> None:
    _, rig = quick
    kw = {"parametrization": "hybrid", "isotropic": True, "rig": rig}
    assert "cook_torrance" in material_guess(MATTE, **kw).label  # type: ignore[arg-type]
    for bad, words in [
        ("scene", "expected a material guess"),
        (str(CONFIGS / "plans" / "quick.yaml") + ".missing.yaml", "cannot read it"),
        (str(CONFIGS / "rigs"), "no such file"),
        ("cook_torrance:alpha=", "cannot read"),
        ("no_such_model:alpha=0.1", "no_such_model"),
    ]:
        with pytest.raises(GonioError, match=words):
            material_guess(bad, **kw)  # type: ignore[arg-type]


_errors = st.one_of(st.none(), st.floats(0.0, 1.0), st.sampled_from([0.01, 0.02, math.nan]))


@given(st.lists(st.tuples(_errors, st.sampled_from([STOP, FLY])), min_size=1, max_size=8))
def test_the_rule_never_prefers_a_fly_plan_predicted_worse(
    rows: list[tuple[float | None, str]],
) -> None:
    errors, motions = [e for e, _ in rows], [m for _, m in rows]
    chosen = pick(errors, motions)
    usable = [e for e in errors if e is not None and math.isfinite(e)]
    if not usable:
        assert chosen is None
        return
    assert chosen is not None
    stop = best_stop(errors, motions)
    if stop is not None:
        stop_error = errors[stop]
        assert stop_error is not None and motions[stop] == STOP
        assert motions[chosen] == STOP or errors[chosen] * MARGIN <= stop_error  # type: ignore[operator]
    else:
        assert errors[chosen] == min(usable)


def test_a_fly_plan_needs_the_margin() -> None:
    assert pick([0.02, 0.02], [FLY, STOP]) == 1
    assert pick([0.019, 0.02], [FLY, STOP]) == 1  # better, not by the margin
    assert pick([0.02 / MARGIN, 0.02], [FLY, STOP]) == 0
    assert pick([None, math.nan, 0.3], [STOP, STOP, FLY]) == 2
    assert pick([None], [STOP]) is None and best_stop([0.1], [FLY]) is None
