"""The adaptive strategy's two passes planned: the survey, then the second
pass from its samples, appended; deterministic, reachable, stored bit for bit; and more
accurate than a uniform plan of as many samples on a glossy material."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from pydantic import ValidationError

from gonio import brdf
from gonio.analysis.measured import Measured
from gonio.cli.render import render_summary
from gonio.planner import adaptive
from gonio.planner.builder import build
from gonio.planner.model import ARRAYS, Plan, same_bits
from gonio.planner.schema import PlanSpec
from gonio.planner.stored import parse_plan, plan_bytes
from gonio.planner.two_pass import Survey, extend, second_pass
from gonio.reconstruct import testset
from gonio.reconstruct.build import reconstruct
from gonio.reconstruct.evaluate import evaluate
from gonio.rig.model import Rig
from gonio.types import BrdfEval
from gonio.workflows.adaptive import estimate
from studies.reconstruct.synthetic import synthesize, synthesize_adaptive

ARCH = Path(__file__).resolve().parents[3] / "configs" / "rigs" / "arch.yaml"
GLOSSY = brdf.create("cook_torrance", alpha=0.1, distribution="ggx", f0=0.04, kd=0.2).eval


@pytest.fixture(scope="module", autouse=True)
def fewer_measure_pairs() -> object:
    """The test measure estimated from 2¹⁵ pairs (a second less per density)."""
    with pytest.MonkeyPatch.context() as m:
        m.setattr(adaptive, "MEASURE_PAIRS", 1 << 15)
        yield


@pytest.fixture(scope="module")
def rig() -> Rig:
    return Rig.from_yaml(ARCH)


def spec(target: int, survey: int, **options: object) -> PlanSpec:
    return PlanSpec.model_validate(
        {
            "name": "adaptive",
            "parametrization": "rusinkiewicz",
            "kicks": 10,
            "sampling": {
                "strategy": "adaptive",
                "target": target,
                "seed": 4,
                "adaptive": {"survey": survey, **options},
            },
        }
    )


def measured(f: BrdfEval, plan_or_rig: Plan | Rig, wi: np.ndarray, wo: np.ndarray) -> Measured:
    rig = plan_or_rig.rig if isinstance(plan_or_rig, Plan) else plan_or_rig
    values = np.asarray(f(wi, wo), dtype=np.float64)
    return Measured(
        wi, wo, values, 0.01 * values, "rusinkiewicz", True, rig, None, "luminance", "test"
    )


def steering(m: Measured, plan: PlanSpec) -> BrdfEval:
    """The estimate ``plan``'s second pass is steered by, from the survey's samples."""
    return estimate(m, plan.sampling.options().model)


def extended(survey: Plan, f: BrdfEval) -> Plan:
    """``survey`` and its second pass, its samples of ``f`` measured at the planned pairs."""
    m = measured(f, survey, survey.wi, survey.wo)
    return extend(
        survey, steering(m, survey.spec), Survey(survey.summary.requested, m.wi, m.wo, m.f)
    )


@pytest.fixture(scope="module")
def planned(rig: Rig) -> tuple[Plan, Plan]:
    survey = build(spec(90, 40, edge=0.2), rig)
    return survey, extended(survey, GLOSSY)


def test_the_survey_then_the_second_pass(planned: tuple[Plan, Plan]) -> None:
    survey, whole = planned
    assert survey.is_survey and len(survey) == 40
    assert "the other 50 targets are planned from its measurements" in render_summary(survey)
    assert "planned from its measurements" not in render_summary(whole)
    assert not whole.is_survey and len(whole) == 90 and whole.summary.kept == 90
    for name in ("coords", "angles", "arrival_s", "generated"):
        np.testing.assert_array_equal(getattr(whole, name)[:40], getattr(survey, name))
    assert np.all(np.diff(whole.arrival_s) > 0)
    assert len(set(whole.generated.tolist())) == 90


def test_every_target_is_reachable_and_the_plan_stores_bit_for_bit(
    planned: tuple[Plan, Plan], rig: Rig
) -> None:
    _, whole = planned
    assert np.all(rig.reachable(whole.wi, whole.wo, isotropic=True)[0])
    assert parse_plan(plan_bytes(whole), "stored") == whole


def test_the_same_survey_gives_the_same_second_pass(planned: tuple[Plan, Plan], rig: Rig) -> None:
    survey, whole = planned
    again = extended(survey, GLOSSY)
    assert all(same_bits(getattr(again, n), getattr(whole, n)) for n in ARRAYS)
    other = extended(survey, lambda wi, wo: 2 * GLOSSY(wi, wo) + 0.1)
    assert not np.array_equal(other.coords, whole.coords)


def test_adaptive_options_are_checked() -> None:
    with pytest.raises(ValidationError, match="target: expected more targets"):
        PlanSpec.model_validate(spec(100, 100).model_dump())
    raw = spec(200, 100).model_dump()
    raw["sampling"]["strategy"] = "sobol"
    with pytest.raises(ValidationError, match="adaptive: options of the adaptive strategy"):
        PlanSpec.model_validate(raw)


def test_adaptive_beats_uniform_at_equal_count(rig: Rig) -> None:
    n = 500
    pairs = testset.draw(rig, isotropic=True, size=4000)
    # The second pass as `extend` plans it (`second_pass`), without the engine.
    both = synthesize_adaptive(
        GLOSSY, rig, "rusinkiewicz", True, n, seed=4, adaptive={"survey": 128}
    )
    uniform = synthesize(GLOSSY, rig, "rusinkiewicz", True, n, seed=4)
    assert len(both) == len(uniform) == n

    def error(m: Measured) -> float:
        c = reconstruct(m, method="rbf", extrapolate="nearest")
        value = evaluate(c, GLOSSY, rig, isotropic=True, test_set=pairs).regions["all"]
        assert value.scores.log_rmse is not None
        return value.scores.log_rmse

    assert error(both) < 0.75 * error(uniform)  # measured: 0.0098 against 0.0156


def test_an_unknown_steering_model_is_refused_when_the_plan_is_read() -> None:
    with pytest.raises(ValidationError, match=r"unknown family 'gxx'.*or survey: no model"):
        spec(200, 100, model="lambert+gxx")


def test_steering_by_the_survey_alone_is_deterministic(rig: Rig) -> None:
    plan = spec(200, 64, model="survey")
    survey = synthesize(GLOSSY, rig, "rusinkiewicz", True, 64, seed=4)
    values = Survey(64, survey.wi, survey.wo, survey.f)
    a, chosen = second_pass(plan, rig, steering(survey, plan), values, 136)
    b, _ = second_pass(plan, rig, steering(survey, plan), values, 136)
    assert a.tobytes() == b.tobytes() and chosen.kind == "adaptive"
    fit = spec(200, 64)
    fitted, _ = second_pass(fit, rig, steering(survey, fit), values, 136)
    assert not np.array_equal(a, fitted)
