"""The public surface of gonio.brdf: names, create, params, flags, shapes, RGB, errors."""

from __future__ import annotations

import inspect

import numpy as np
import pytest

import gonio.brdf as brdf
from gonio.brdf.registry import model_class
from gonio.errors import DomainError, GonioError, UnknownNameError
from studies.brdf.examples import EXAMPLES, example_models, label

REQUIRED = {
    "lambert",
    "phong",
    "blinn_phong",
    "cosine_quadratic",
    "cosine_quadratic_modified",
    "schlick_lobe",
    "cook_torrance",
    "ggx_anisotropic",
    "fresnel_test_function",
    "specular_test_function",
    "grazing_test_function",
}

rng = np.random.default_rng(7)


def _random_directions(shape: tuple[int, ...]) -> np.ndarray:
    v = rng.normal(size=(*shape, 3))
    v[..., 2] = np.abs(v[..., 2])
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def test_names_lists_every_required_model():
    assert set(brdf.names()) >= REQUIRED
    assert all(isinstance(n, str) for n in brdf.names())


def test_every_registered_name_is_its_class_name():
    # The registry names each model without importing its module; the class it loads
    # must be the BRDF of that name.
    for name in brdf.names():
        cls = model_class(name)
        assert issubclass(cls, brdf.BRDF) and cls.name == name


def test_every_registered_model_has_an_example():
    # Models read from a file (a `path` parameter) are tested with their own files.
    analytic = {
        n for n in brdf.names() if "path" not in inspect.signature(model_class(n)).parameters
    }
    assert {name for name, _ in EXAMPLES} == analytic


def test_unknown_name_lists_the_known_ones():
    with pytest.raises(UnknownNameError) as err:
        brdf.create("torrance_sparrow")
    message = str(err.value)
    assert "torrance_sparrow" in message
    assert all(name in message for name in brdf.names())
    assert isinstance(err.value, GonioError)


@pytest.mark.parametrize(("name", "params"), EXAMPLES, ids=[n for n, _ in EXAMPLES])
def test_params_recreate_the_same_model(name, params):
    model = brdf.create(name, **params)
    assert model.name == name
    again = brdf.create(model.name, **model.params)
    assert again.params == model.params
    wi, wo = _random_directions((50,)), _random_directions((50,))
    np.testing.assert_array_equal(again.eval(wi, wo), model.eval(wi, wo))


def test_flags():
    for model in example_models():
        assert isinstance(model.reciprocal, bool), label(model)
        assert isinstance(model.isotropic, bool), label(model)
        assert isinstance(model.physically_based, bool), label(model)
        assert isinstance(model.is_rgb, bool), label(model)
    physical = {m.name for m in example_models() if m.physically_based}
    assert physical == {
        "lambert",
        "phong",
        "blinn_phong",
        "cook_torrance",
        "ggx_anisotropic",
        "sum",
    }
    assert not brdf.create("ggx_anisotropic", alpha_x=0.1, alpha_y=0.2).isotropic
    assert brdf.create("ggx_anisotropic", alpha_x=0.2, alpha_y=0.2).isotropic


@pytest.mark.parametrize("model", example_models(), ids=label)
def test_shapes_broadcast(model):
    wi = _random_directions((4, 1))
    wo = _random_directions((1, 5))
    tail = (3,) if model.is_rgb else ()
    out = model.eval(wi, wo)
    assert out.shape == (4, 5, *tail)
    assert out.dtype == np.float64
    assert model.eval([0.0, 0.0, 1.0], [0.0, 0.0, 1.0]).shape == tail
    assert model.eval(wi[0, 0], wo).shape == (1, 5, *tail)
    # broadcasting agrees with explicit pairs
    a, b = np.broadcast_arrays(wi, wo)
    np.testing.assert_array_equal(out, model.eval(a.copy(), b.copy()))


def test_bad_direction_shapes():
    model = brdf.create("lambert", albedo=0.5)
    with pytest.raises(DomainError):
        model.eval([0.0, 1.0], [0.0, 0.0, 1.0])
    with pytest.raises(DomainError):
        model.eval(np.zeros((3, 3)), np.zeros((4, 3)))
    with pytest.raises(DomainError):
        model.eval(1.0, [0.0, 0.0, 1.0])


# A sum's colours live in its components (tests/gonio/brdf/test_composite.py).
RGB_CASES = [
    (name, params)
    for name, params in EXAMPLES
    if brdf.create(name, **params).is_rgb and name != "sum"
]


@pytest.mark.parametrize(("name", "params"), RGB_CASES, ids=[n for n, _ in RGB_CASES])
def test_rgb_channels_equal_grey_models(name, params):
    model = brdf.create(name, **params)
    wi, wo = _random_directions((200,)), _random_directions((200,))
    out = model.eval(wi, wo)
    assert out.shape == (200, 3)
    for j in range(3):
        grey = {k: (v[j] if isinstance(v, tuple) else v) for k, v in model.params.items()}
        channel = brdf.create(name, **grey)
        assert not channel.is_rgb
        np.testing.assert_allclose(out[:, j], channel.eval(wi, wo), rtol=1e-13, atol=0.0)


def test_a_colour_parameter_makes_the_model_rgb():
    assert brdf.create("lambert", albedo=[0.1, 0.2, 0.3]).is_rgb
    assert brdf.create("lambert", albedo=np.array([0.1, 0.2, 0.3])).is_rgb
    assert not brdf.create("lambert", albedo=np.float64(0.3)).is_rgb
    assert brdf.create("cook_torrance", alpha=0.1, kd=(0.1, 0.1, 0.1)).is_rgb
    assert brdf.create("cook_torrance", alpha=0.1, f0=(0.9, 0.6, 0.3)).is_rgb


BAD = [
    ("lambert", {}),
    ("lambert", {"albedo": -0.1}),
    ("lambert", {"albedo": float("nan")}),
    ("lambert", {"albedo": (0.1, 0.2)}),
    ("lambert", {"albedo": "grey"}),
    ("lambert", {"albedo": True}),
    ("lambert", {"albedo": 0.5, "rho": 0.5}),
    ("phong", {"n": -1.0}),
    ("phong", {"n": float("inf")}),
    ("phong", {"n": 10.0, "ks": -0.5}),
    ("blinn_phong", {"n": 10.0, "kd": (0.1, -0.1, 0.1)}),
    ("cosine_quadratic_modified", {"n": 10.0, "xi": "0.463"}),
    ("cosine_quadratic_modified", {"n": 10.0, "xi": 0.0}),
    ("cook_torrance", {"alpha": 0.0}),
    ("cook_torrance", {"alpha": -0.1}),
    ("cook_torrance", {"alpha": 0.1, "distribution": "phong"}),
    ("cook_torrance", {"alpha": 0.1, "fresnel": "exact"}),
    ("cook_torrance", {"alpha": 0.1, "fresnel": "conductor", "ior": 0.2}),
    ("cook_torrance", {"alpha": 0.1, "fresnel": "dielectric", "f0": 0.04}),
    ("cook_torrance", {"alpha": 0.1, "fresnel": "dielectric", "ior": 0.0}),
    ("cook_torrance", {"alpha": 0.1, "fresnel": "schlick", "f0": 1.5}),
    ("cook_torrance", {"alpha": 0.1, "fresnel": "none", "k": 1.0}),
    ("cook_torrance", {"alpha": 0.1, "fresnel": "conductor", "ior": 0.2, "k": -1.0}),
    ("ggx_anisotropic", {"alpha_x": 0.1}),
    ("ggx_anisotropic", {"alpha_x": 0.1, "alpha_y": 0.0}),
]


@pytest.mark.parametrize(("name", "params"), BAD, ids=[f"{n}-{p}" for n, p in BAD])
def test_bad_parameters_are_domain_errors(name, params):
    with pytest.raises(DomainError):
        brdf.create(name, **params)


def test_missing_or_unknown_parameter_message_lists_accepted():
    with pytest.raises(DomainError, match=r"accepted: alpha, distribution, fresnel"):
        brdf.create("cook_torrance", alpha=0.1, roughness=0.2)
