"""`gonio.planner.blur.blur_budget_deg`: the smear budget for a bias within a tolerance,
held against the blur bias computed independently (a GGX lobe averaged along an arc)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gonio import brdf
from gonio.errors import DomainError
from gonio.planner.blur import (
    BLUR_K_DEG,
    WIDTH_PER_ALPHA_DEG,
    blur_budget_deg,
    blur_budget_of_width,
)
from gonio.planner.schema import FlySpec


def test_the_budget_scales_with_the_width_and_the_root_of_the_tolerance() -> None:
    assert blur_budget_deg(0.1, 0.005) == pytest.approx(BLUR_K_DEG * 0.1 * math.sqrt(0.005))
    assert blur_budget_deg(0.2, 0.005) == pytest.approx(2 * blur_budget_deg(0.1, 0.005))
    assert blur_budget_deg(0.1, 0.02) == pytest.approx(2 * blur_budget_deg(0.1, 0.005))
    assert blur_budget_deg(0.05) == blur_budget_deg(0.05, 0.005)


@pytest.mark.parametrize(
    ("alpha", "tolerance"),
    [(0.0, 0.005), (-0.1, 0.005), (math.inf, 0.005), (0.1, 0.0), (0.1, 0.5), (0.1, math.nan)],
)
def test_bad_arguments_are_refused_in_one_line(alpha: float, tolerance: float) -> None:
    with pytest.raises(DomainError) as err:
        blur_budget_deg(alpha, tolerance)
    assert "\n" not in str(err.value)


@pytest.mark.parametrize("alpha", [0.02, 0.1, 0.3])
def test_a_smear_within_the_budget_biases_a_ggx_peak_within_the_tolerance(alpha: float) -> None:
    # an in-plane detector arc through the specular peak of an isotropic GGX lobe at 30°
    model = brdf.create("cook_torrance", alpha=alpha, kd=0.0, f0=0.9)
    wi = np.array([[-math.sin(math.radians(30.0)), 0.0, math.cos(math.radians(30.0))]])

    def f(theta_deg: np.ndarray) -> np.ndarray:
        t = np.radians(theta_deg)
        wo = np.stack([np.sin(t), np.zeros_like(t), np.cos(t)], axis=-1)
        return np.asarray(model.eval(np.repeat(wi, len(t), axis=0), wo)).reshape(len(t), -1)[:, 0]

    for tolerance in (0.001, 0.005):
        smear = blur_budget_deg(alpha, tolerance)
        centres = 30.0 + np.linspace(-3 * smear - 60 * alpha, 3 * smear + 60 * alpha, 301)
        arc = centres[:, None] + np.linspace(-smear / 2, smear / 2, 2001)[None, :]
        values = f(arc.ravel()).reshape(arc.shape)
        mean = ((values[:, 1:] + values[:, :-1]) / 2).mean(axis=1)  # trapezoids
        bias = np.abs(mean / f(centres) - 1)
        assert bias.max() <= tolerance
        assert bias.max() >= 0.5 * tolerance  # the budget is not needlessly small


@pytest.mark.parametrize("alpha", [0.02, 0.05, 0.1])
def test_a_lobe_width_names_the_ggx_width_whose_peak_it_spans(alpha: float) -> None:
    # the in-plane detector arc of the test above: the BRDF is half its peak at ± width / 2
    model = brdf.create("cook_torrance", alpha=alpha, kd=0.0, f0=0.9)
    wi = np.array([[-math.sin(math.radians(30.0)), 0.0, math.cos(math.radians(30.0))]])
    width = WIDTH_PER_ALPHA_DEG * alpha
    t = np.radians(30.0 + np.array([0.0, -width / 2, width / 2]))
    wo = np.stack([np.sin(t), np.zeros_like(t), np.cos(t)], axis=-1)
    f = np.asarray(model.eval(np.repeat(wi, 3, axis=0), wo)).reshape(3, -1)[:, 0]
    assert f[1:] / f[0] == pytest.approx([0.5, 0.5], abs=0.06)
    assert blur_budget_of_width(width) == pytest.approx(blur_budget_deg(alpha))


def test_a_fly_plan_naming_a_lobe_width_takes_its_blur_budget() -> None:
    fly = FlySpec(lobe_width_deg=7.0)
    assert fly.blur == pytest.approx(blur_budget_of_width(7.0, 0.005))
    assert fly.blur == pytest.approx(0.11 * 7.0, rel=0.03)
    assert FlySpec(lobe_width_deg=7.0, blur_tolerance=0.02).blur == pytest.approx(2 * fly.blur)
    assert FlySpec(lobe_width_deg=2.0, lobe_fraction=0.25).blur == pytest.approx(0.5)
    assert FlySpec().blur == 0.5
