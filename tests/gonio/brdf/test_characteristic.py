"""The test functions F, S, G of Barla, Belcour & Pacanowski 2015.

Also the identities the paper's appendix derives for them.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import gonio.brdf as brdf

F = brdf.create("fresnel_test_function")
S = brdf.create("specular_test_function")
G = brdf.create("grazing_test_function")

angle = st.tuples(st.floats(0.0, np.pi / 2), st.floats(0.0, 2 * np.pi))


def _dir(theta: float, phi: float) -> np.ndarray:
    return np.array([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)])


def test_flags():
    for model in (F, S, G):
        assert not model.physically_based
        assert model.reciprocal and model.isotropic
        assert model.params == {}


@settings(max_examples=100)
@given(a=angle, b=angle)
def test_definitions_and_identities(a, b):
    wi, wo = _dir(*a), _dir(*b)
    h, k = (wi + wo) / 2, (wi - wo) / 2
    hn = np.linalg.norm(h)
    if hn < 1e-6:
        return  # θh, θd undefined at wi = −wo
    hhat = h / hn
    cos_d = wi @ hhat
    h_bar = np.hypot(h[0], h[1])
    assert F.eval(wi, wo) == pytest.approx(1 - cos_d, abs=1e-12)
    assert S.eval(wi, wo) == pytest.approx(1 - h_bar, abs=1e-12)
    assert G.eval(wi, wo) == pytest.approx(1 - wi[2] * wo[2], abs=1e-15)
    # appendix: cos²θd = 1 − ‖k‖², ‖h̄‖ = sin θh cos θd (the main text's
    # "‖h̄‖² = sin θh cos θd" drops the squares on the right)
    assert cos_d**2 == pytest.approx(1 - k @ k, abs=1e-12)
    sin_h = np.hypot(hhat[0], hhat[1])
    assert h_bar == pytest.approx(sin_h * cos_d, abs=1e-12)
    # (wi·n)(wo·n) = 1 − ‖h̄‖² − ‖k‖² (1 + cos²θk)
    knorm = np.linalg.norm(k)
    cos_k2 = (k[2] / knorm) ** 2 if knorm > 0 else 0.0
    assert wi[2] * wo[2] == pytest.approx(1 - h_bar**2 - knorm**2 * (1 + cos_k2), abs=1e-12)


def test_the_main_text_squared_form_is_wrong():
    wi, wo = _dir(0.9, 0.0), _dir(0.3, 2.0)
    hhat = (wi + wo) / np.linalg.norm(wi + wo)
    h_bar = np.hypot(*((wi + wo) / 2)[:2])
    sin_h, cos_d = np.sqrt(1 - hhat[2] ** 2), wi @ hhat
    assert h_bar == pytest.approx(sin_h * cos_d, rel=1e-12)
    assert abs(h_bar**2 - sin_h * cos_d) > 0.1


def test_named_values():
    n, grazing = _dir(0.0, 0.0), np.array([1.0, 0.0, 0.0])
    assert F.eval(n, n) == 0.0  # θd = 0
    assert S.eval(n, n) == 1.0  # h̄ = 0
    assert G.eval(n, n) == 0.0
    assert G.eval(grazing, n) == 1.0  # the horizon is G's 1-isoline
    assert F.eval(grazing, -grazing) == 1.0  # wi = −wo: θd = 90°
    assert S.eval(grazing, grazing) == 0.0  # h̄ = wi
    values = np.concatenate(
        [m.eval(np.stack([grazing, n]), np.stack([-grazing, grazing])) for m in (F, S, G)]
    )
    assert np.all((values >= 0) & (values <= 1))
