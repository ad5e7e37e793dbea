"""Reciprocity, rotation invariance, and finite non-negative values at the extremes."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

import gonio.brdf as brdf
from studies.brdf.examples import example_models, label

MODELS = example_models()
RECIPROCAL = [m for m in MODELS if m.reciprocal]
ISOTROPIC = [m for m in MODELS if m.isotropic]

# Unit-square samples → directions in the closed upper hemisphere; u = 1 is exactly
# grazing (z = 0), u = 0 exactly normal. hypothesis favours both ends.
unit = st.floats(0.0, 1.0, allow_nan=False)
samples = arrays(np.float64, (16, 4), elements=unit)


def _directions(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    theta, phi = u * (np.pi / 2), v * (2 * np.pi)
    s = np.where(u == 1.0, 1.0, np.sin(theta))
    z = np.where(u == 1.0, 0.0, np.cos(theta))
    return np.stack([s * np.cos(phi), s * np.sin(phi), z], -1)


def _pairs(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return _directions(x[:, 0], x[:, 1]), _directions(x[:, 2], x[:, 3])


def _rotate_z(w: np.ndarray, angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.stack([c * w[..., 0] - s * w[..., 1], s * w[..., 0] + c * w[..., 1], w[..., 2]], -1)


def test_every_model_is_reciprocal():
    # The flag is honest for all of them: Phong's cos ψ = 2 cos θi cos θo − wi·wo is symmetric.
    assert all(m.reciprocal for m in MODELS)


@pytest.mark.parametrize("model", RECIPROCAL, ids=label)
@settings(max_examples=40)
@given(x=samples)
def test_reciprocity(model, x):
    wi, wo = _pairs(x)
    np.testing.assert_allclose(model.eval(wi, wo), model.eval(wo, wi), rtol=1e-12, atol=0.0)


# Named cases: normal, grazing, retro-reflection, mirror, opposite horizon directions.
SPECIAL = np.array(
    [
        [[0, 0, 1], [0, 0, 1]],
        [[1, 0, 0], [1, 0, 0]],
        [[1, 0, 0], [-1, 0, 0]],
        [[1, 0, 0], [0, 1, 0]],
        [[1, 0, 0], [0, 0, 1]],
        [[0.6, 0, 0.8], [-0.6, 0, 0.8]],
        [[0.6, 0, 0.8], [0.6, 0, 0.8]],
        [[0.6, 0, 0.8], [0, 0.6, 0.8]],
        [[0, 0.6, 0.8], [1, 0, 0]],
        [[1, 0, 1e-300], [-1, 0, 1e-300]],
        [[1, 0, 1e-310], [1, 0, 5e-324]],
        [[1, 0, 1e-12], [-1, 0, 1e-12]],
        [[1, 0, 1e-12], [0, 0, 1]],
    ],
    dtype=np.float64,
)
SPECIAL /= np.linalg.norm(SPECIAL, axis=-1, keepdims=True)


@pytest.mark.parametrize("model", MODELS, ids=label)
def test_extremes_are_finite_non_negative_and_reciprocal(model):
    wi, wo = SPECIAL[:, 0], SPECIAL[:, 1]
    with np.errstate(all="raise", under="ignore"):
        f, g = model.eval(wi, wo), model.eval(wo, wi)
    assert np.all(np.isfinite(f))
    assert np.all(f >= 0.0)
    np.testing.assert_allclose(f, g, rtol=1e-12, atol=0.0)


@pytest.mark.parametrize("model", MODELS, ids=label)
def test_random_pairs_raise_no_floating_point_error(model):
    rng = np.random.default_rng(3)
    v = rng.normal(size=(2, 20000, 3))
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    v[:, :200, 2] = 0.0  # exactly grazing, renormalized below
    v[:, :200] /= np.linalg.norm(v[:, :200], axis=-1, keepdims=True)
    with np.errstate(all="raise", under="ignore"):
        f = model.eval(v[0], v[1])
    assert np.all(np.isfinite(f))
    assert np.all(f >= 0.0)
    below = (v[0, :, 2] < 0) | (v[1, :, 2] < 0)
    assert np.all(f[below] == 0.0)
    assert np.any(f[~below] > 0.0)


@pytest.mark.parametrize("model", MODELS, ids=label)
def test_below_the_horizon_is_zero(model):
    up = np.array([0.6, 0.0, 0.8])
    down = np.array([0.6, 0.0, -0.8])
    assert np.all(model.eval(up, down) == 0.0)
    assert np.all(model.eval(down, up) == 0.0)
    assert np.all(model.eval(down, down) == 0.0)
    assert np.all(model.eval(up, [1.0, 0.0, -1e-300]) == 0.0)


@pytest.mark.parametrize("model", ISOTROPIC, ids=label)
@settings(max_examples=40)
@given(x=samples, angle=st.floats(0.0, 2 * np.pi))
def test_rotation_about_the_normal(model, x, angle):
    wi, wo = _pairs(x)
    f = model.eval(wi, wo)
    g = model.eval(_rotate_z(wi, angle), _rotate_z(wo, angle))
    np.testing.assert_allclose(g, f, rtol=1e-9, atol=1e-12)


def test_anisotropic_ggx_is_not_rotation_invariant():
    model = brdf.create("ggx_anisotropic", alpha_x=0.05, alpha_y=0.3)
    wi = np.array([np.sin(0.5), 0.0, np.cos(0.5)])
    wo = np.array([-np.sin(0.7), 0.0, np.cos(0.7)])
    f = model.eval(wi, wo)
    g = model.eval(_rotate_z(wi, np.pi / 2), _rotate_z(wo, np.pi / 2))
    assert not model.isotropic
    assert g > 3.0 * f
