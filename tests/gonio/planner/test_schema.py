"""The plan file's defaults that a study chose (docs/explanations/tradeoff.md "The study")."""

from __future__ import annotations

from gonio.planner.schema import PlanSpec


def test_the_default_parametrization_is_the_one_the_study_recommends() -> None:
    spec = PlanSpec.model_validate({"name": "p", "sampling": {"strategy": "sobol", "target": 10}})
    assert spec.parametrization == "rusinkiewicz"
