"""The sum model: values, colours, flags, its material checks and its written form."""

from __future__ import annotations

import numpy as np
import pytest

from gonio import brdf
from gonio.brdf.composite import spec_of
from gonio.brdf.material import MaterialError, albedo_bound, build
from gonio.errors import DomainError

LAMBERT = {"name": "lambert", "albedo": (0.1, 0.3, 0.5)}
GGX = {"name": "cook_torrance", "alpha": 0.2, "f0": 0.04}


def _directions(n: int, seed: int) -> np.ndarray:
    v = np.random.default_rng(seed).normal(size=(n, 3))
    v[:, 2] = np.abs(v[:, 2])
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def test_sum_is_the_sum_of_its_components_channel_by_channel():
    wi, wo = _directions(100, 1), _directions(100, 2)
    total = brdf.create("sum", components=[LAMBERT, GGX]).eval(wi, wo)
    lam = brdf.create("lambert", albedo=LAMBERT["albedo"]).eval(wi, wo)
    spec = brdf.create("cook_torrance", alpha=0.2, f0=0.04).eval(wi, wo)
    assert total.shape == (100, 3)
    np.testing.assert_allclose(total, lam + spec[:, None], rtol=1e-14)


def test_below_the_horizon_is_zero_and_grey_sums_stay_grey():
    model = brdf.create("sum", components=[{"name": "lambert", "albedo": 0.5}, GGX])
    assert not model.is_rgb
    assert model.eval([0.0, 0.6, -0.8], [0.0, 0.0, 1.0]) == 0.0


def test_flags_follow_the_components():
    aniso = {"name": "ggx_anisotropic", "alpha_x": 0.1, "alpha_y": 0.3}
    assert brdf.create("sum", components=[LAMBERT, GGX]).isotropic
    assert not brdf.create("sum", components=[LAMBERT, aniso]).isotropic


@pytest.mark.parametrize(
    "components", [[], "lambert", [{"albedo": 0.3}], [{"name": "lamb", "albedo": 0.2}], [3]]
)
def test_bad_components_are_one_domain_error(components):
    with pytest.raises(DomainError):
        brdf.create("sum", components=components)


def test_written_form_builds_the_same_model():
    model = brdf.create("sum", components=[LAMBERT, GGX])
    spec = spec_of(model)
    assert spec["components"][0] == {"name": "lambert", "albedo": [0.1, 0.3, 0.5]}
    again = build("sum", {k: v for k, v in spec.items() if k != "name"})
    wi, wo = _directions(50, 3), _directions(50, 4)
    np.testing.assert_array_equal(again.eval(wi, wo), model.eval(wi, wo))


def test_material_checks_each_component_and_the_total():
    with pytest.raises(MaterialError) as bad:
        build("sum", {"components": [LAMBERT, {"name": "cook_torrance", "alpha": -1.0}]})
    assert bad.value.param == "components.1.alpha"
    with pytest.raises(MaterialError, match=r"add up to 1\.04"):
        build("sum", {"components": [{"name": "lambert", "albedo": 0.6}, GGX | {"f0": 0.44}]})
    ok = build("sum", {"components": [{"name": "lambert", "albedo": 0.5}, GGX | {"f0": 0.5}]})
    np.testing.assert_allclose(albedo_bound(ok), 1.0)
