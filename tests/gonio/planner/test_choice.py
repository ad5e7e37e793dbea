"""The adaptive plan's choice from its survey: it adapts where the error model predicts a
gain, falls back to uniform where the error is flat or the steering estimate does not
explain the survey, and the uniform fallback is the uniform Sobol plan itself; on the
shipped scenes and on materials drawn at random from the model families its log-RMSE is
at most 1.05× the best uniform plan's (a small version of studies/adaptive.py)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from gonio import brdf
from gonio.analysis.measured import Measured
from gonio.cli.render import render_summary
from gonio.planner import adaptive, choice
from gonio.planner.builder import build
from gonio.planner.schema import PlanSpec
from gonio.planner.stored import parse_plan, plan_bytes
from gonio.planner.two_pass import Survey, extend
from gonio.radiometry.bands import band_eval
from gonio.reconstruct import testset
from gonio.reconstruct.build import reconstruct
from gonio.reconstruct.evaluate import evaluate
from gonio.rig.model import Rig
from gonio.scene import load_scene
from gonio.types import BrdfEval
from gonio.workflows.adaptive import estimate
from studies.brdf import random_materials
from studies.reconstruct.synthetic import adaptive_choice, synthesize

ROOT = Path(__file__).resolve().parents[3]
GLOSSY = brdf.create("cook_torrance", alpha=0.1, distribution="ggx", f0=0.04, kd=0.2).eval


@pytest.fixture(scope="module", autouse=True)
def fewer_measure_pairs() -> object:
    """The test measure estimated from 2¹⁵ pairs (a second less per density)."""
    with pytest.MonkeyPatch.context() as m:
        m.setattr(adaptive, "MEASURE_PAIRS", 1 << 15)
        yield


def rig(name: str = "arch") -> Rig:
    return Rig.from_yaml(ROOT / "configs" / "rigs" / f"{name}.yaml")


def errors(e: np.ndarray) -> adaptive.ErrorMap:
    """An error map on 8³ cells, the test measure even over all of them."""
    return adaptive.ErrorMap((8, 8, 8), np.full(512, 1 / 512), e)


def test_a_peaked_error_is_adapted_to() -> None:
    e = np.full(512, 0.01)
    e[100:110] = 10.0
    chosen = choice.choose(errors(e), 0.0, survey=128, total=1000, floor=0.2)
    assert chosen.kind == "adaptive" and chosen.floor == 0.2
    assert chosen.gain > choice.MARGIN and chosen.gain == chosen.gain_estimate
    assert chosen.reason.startswith("adaptive (floor 0.2): predicted gain over uniform")


def test_a_flat_error_is_sampled_uniformly() -> None:
    chosen = choice.choose(errors(np.ones(512)), 0.0, survey=128, total=1000, floor=0.2)
    assert chosen.kind == "uniform" and chosen.floor == 1.0
    assert chosen.gain == pytest.approx(1.0)
    assert chosen.reason.startswith("uniform: the adaptive density's predicted gain")


def test_an_estimate_that_does_not_explain_the_survey_is_not_followed() -> None:
    e = np.full(512, 0.01)
    e[100:110] = 10.0
    trusted = choice.choose(errors(e), 0.05, survey=128, total=1000, floor=0.2)
    doubted = choice.choose(errors(e), 0.6, survey=128, total=1000, floor=0.2)
    assert trusted.kind == "adaptive" and doubted.kind == "uniform"
    assert doubted.gain_estimate == trusted.gain_estimate and doubted.gain < choice.MARGIN
    assert "leaves 60% of the survey's variation" in doubted.reason
    forced = choice.choose(errors(e), 0.6, survey=128, total=1000, floor=0.2, margin=0.0)
    assert forced.kind == "adaptive" and forced.gain == doubted.gain


def test_the_misfit_is_the_unexplained_share_of_the_variance() -> None:
    f = np.linspace(0.0, 5.0, 50)
    assert choice.survey_misfit(f, f) == 0.0
    assert choice.survey_misfit(np.full(50, np.log1p(f).mean()), f) == pytest.approx(1.0, 0.2)
    assert choice.survey_misfit(np.zeros((50, 3)), np.ones((50, 3))) == 1.0  # flat, missed
    rgb = np.stack([f, f, f], axis=1)
    assert choice.survey_misfit(rgb, rgb) == 0.0


def plan_spec(target: int, survey: int, strategy: str = "adaptive") -> PlanSpec:
    sampling: dict[str, object] = {"strategy": strategy, "target": target, "seed": 4}
    if strategy == "adaptive":
        sampling["adaptive"] = {"survey": survey}
    return PlanSpec.model_validate(
        {"name": "choice", "parametrization": "rusinkiewicz", "kicks": 10, "sampling": sampling}
    )


def extended(survey: object, f: BrdfEval) -> object:
    assert hasattr(survey, "wi")
    values = np.asarray(f(survey.wi, survey.wo), dtype=np.float64)
    m = Measured(survey.wi, survey.wo, values, 0.01 * (values + 1), "rusinkiewicz", True,
                 survey.rig, None, "luminance", "test")  # fmt: skip
    told = Survey(survey.summary.requested, m.wi, m.wo, m.f)
    return extend(survey, estimate(m, survey.spec.sampling.options().model), told)


def test_the_uniform_fallback_is_the_uniform_plan_and_the_summary_says_so() -> None:
    arch = rig()
    survey = build(plan_spec(90, 40), arch)
    flat = brdf.create("lambert", albedo=0.5).eval  # nothing to adapt to
    whole = extended(survey, flat)
    uniform = build(plan_spec(90, 40, "sobol"), arch)
    assert whole.summary.second_pass is not None
    assert whole.summary.second_pass.startswith("uniform: ")
    order = np.argsort(whole.generated)
    assert np.array_equal(whole.coords[order], uniform.coords[np.argsort(uniform.generated)])
    assert "second pass" in render_summary(whole) and "uniform: " in render_summary(whole)
    assert parse_plan(plan_bytes(whole), "stored").summary.second_pass == (
        whole.summary.second_pass
    )
    glossy = extended(survey, GLOSSY)
    assert glossy.summary.second_pass is not None
    assert glossy.summary.second_pass.startswith("adaptive (floor 0.2): ")


def scene(stem: str) -> BrdfEval:
    loaded = load_scene(ROOT / "configs" / "scenes" / f"{stem}.yaml")
    return band_eval(loaded.material.model(), "luminance")


#: Named cases: the shipped isotropic scenes (studies/adaptive.py also has the
#: anisotropic brushed metal), a rough conductor with no diffuse part, and materials
#: drawn at random from the model families.
CASES = {
    "glossy_metal": lambda: scene("glossy_metal"),
    "matte": lambda: scene("matte"),
    "seed000_specular": lambda: scene("seed000_specular"),
    "conductor0.2": lambda: (
        brdf.create(
            "cook_torrance", alpha=0.2, distribution="ggx", fresnel="conductor", ior=0.42, k=2.35
        ).eval
    ),
    **{f"random{s}": (lambda s=s: random_materials.draw(s)[1]) for s in range(8)},
}


@pytest.mark.slow
@pytest.mark.parametrize("name", list(CASES))
def test_adaptive_is_never_much_worse_than_uniform(name: str) -> None:
    truth = CASES[name]()
    arch = rig("arch_point" if name == "seed000_specular" else "arch")
    pairs = testset.draw(arch, isotropic=True, size=3000)

    def error(m: Measured) -> float:
        c = reconstruct(m, method="rbf", extrapolate="nearest")
        value = evaluate(c, truth, arch, isotropic=True, test_set=pairs).regions["all"]
        assert value.scores.log_rmse is not None
        return value.scores.log_rmse

    n, best_uniform, best_adaptive = 400, np.inf, np.inf
    for parametrization in ("rusinkiewicz", "hybrid"):
        uniform = synthesize(truth, arch, parametrization, True, n, seed=3, sigma_floor=1.0)
        both, _ = adaptive_choice(truth, arch, parametrization, True, n, seed=3, sigma_floor=1.0)
        best_uniform = min(best_uniform, error(uniform))
        best_adaptive = min(best_adaptive, error(both))
    assert best_adaptive <= 1.05 * best_uniform
    if name == "glossy_metal":  # it still adapts there, and gains (≥ 1.8× from 500 on)
        assert best_uniform >= 1.5 * best_adaptive
