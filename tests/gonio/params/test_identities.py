"""The identities of Barla, Belcour & Pacanowski 2015, checked numerically.

They are in the paper's section 3 and appendix.

Where an identity does not hold in general the test shows where it fails and checks
the relation that does hold (derived in docs/explanations/parametrizations.md).
"""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import gonio.params as params
from gonio.params.cases import away, near
from tests.gonio.params.strategies import batch, pair

pairs = st.lists(pair(), min_size=1, max_size=16).map(batch)


def quantities(wi: np.ndarray, wo: np.ndarray) -> dict[str, np.ndarray]:
    h, k = (wi + wo) / 2, (wi - wo) / 2
    rus = params.get("rusinkiewicz").forward(wi, wo)
    hyb = params.get("hybrid").forward(wi, wo)
    return {
        "h": h,
        "k": k,
        "hnorm": np.linalg.norm(h, axis=-1),
        "knorm": np.linalg.norm(k, axis=-1),
        "hbar": np.linalg.norm(h[..., :2], axis=-1),
        "theta_h": rus[..., 0],
        "theta_d": rus[..., 2],
        "phi_h": rus[..., 1],
        "phi_d": rus[..., 3],
        "phi_k": hyb[..., 3],
        # θk: k's polar angle, straight from its definition.
        "theta_k": np.arctan2(np.linalg.norm(k[..., :2], axis=-1), k[..., 2]),
    }


@given(pairs)
def test_norms_add_up_and_h_is_orthogonal_to_k(ab: tuple) -> None:
    q = quantities(*ab)
    np.testing.assert_allclose(q["hnorm"] ** 2 + q["knorm"] ** 2, 1.0, atol=1e-15)
    np.testing.assert_allclose(np.sum(q["h"] * q["k"], axis=-1), 0.0, atol=1e-15)


@given(pairs)
def test_cos_theta_d_is_the_norm_of_h(ab: tuple) -> None:
    q = quantities(*ab)
    np.testing.assert_allclose(np.cos(q["theta_d"]), q["hnorm"], atol=1e-15)
    np.testing.assert_allclose(q["hnorm"], np.sqrt(1.0 - q["knorm"] ** 2), atol=1e-7)


@given(pairs)
def test_hbar_is_sin_theta_h_cos_theta_d(ab: tuple) -> None:
    q = quantities(*ab)
    np.testing.assert_allclose(q["hbar"], np.sin(q["theta_h"]) * np.cos(q["theta_d"]), atol=1e-15)


def test_section_3_squares_the_wrong_side() -> None:
    """Section 3 writes ‖h̄‖² = sin θh cos θd; the appendix's own derivation,
    ‖h̄‖² = (1 − cos²θh)(1 − sin²θd), gives ‖h̄‖ = sin θh cos θd."""
    q = quantities(*away(1000, seed=31))
    section_3 = np.sin(q["theta_h"]) * np.cos(q["theta_d"])
    assert np.abs(q["hbar"] ** 2 - section_3).max() > 0.1
    appendix = (1 - np.cos(q["theta_h"]) ** 2) * (1 - np.sin(q["theta_d"]) ** 2)
    np.testing.assert_allclose(q["hbar"] ** 2, appendix, atol=1e-15)


@given(pairs)
def test_theta_k_formula_with_its_quadrant(ab: tuple) -> None:
    """tan θk = −(h·n) / (‖h̄‖ cos(φh − φk)), read as θk = atan2(h·n, −‖h̄‖ cos(φh − φk))."""
    q = quantities(*ab)
    hz = q["h"][..., 2]
    a = q["hbar"] * np.cos(q["phi_h"] - q["phi_k"])
    # Off the horizon (hz well above √ε) the formula reproduces θk exactly.
    ok = (hz > 1e-4) & (q["knorm"] > 1e-6)
    np.testing.assert_allclose(np.arctan2(hz, -a)[ok], q["theta_k"][ok], atol=1e-11)


def test_theta_k_as_a_principal_value_arctangent_fails_when_wi_is_lower() -> None:
    wi, wo = away(1000, seed=32)
    q = quantities(wi, wo)
    hz = q["h"][..., 2]
    a = q["hbar"] * np.cos(q["phi_h"] - q["phi_k"])
    principal = np.arctan(-hz / a)  # in (−π/2, π/2): cos θk > 0, kz > 0 always
    lower = wi[:, 2] < wo[:, 2]
    # Right where ωi is the higher one; off by exactly π (k → −k) where it is lower.
    np.testing.assert_allclose(principal[~lower], q["theta_k"][~lower], atol=1e-12)
    np.testing.assert_allclose(principal[lower], q["theta_k"][lower] - np.pi, atol=1e-12)
    assert 0.3 < lower.mean() < 0.7


@given(pairs)
def test_grazing_product(ab: tuple) -> None:
    """(ωi·n)(ωo·n) = 1 − ‖h̄‖² − ‖k‖²(1 + cos²θk)."""
    wi, wo = ab
    q = quantities(wi, wo)
    rhs = 1 - q["hbar"] ** 2 - q["knorm"] ** 2 * (1 + np.cos(q["theta_k"]) ** 2)
    np.testing.assert_allclose(wi[..., 2] * wo[..., 2], rhs, atol=2e-15)


def test_phi_k_is_phi_h_plus_phi_d_only_in_special_cases() -> None:
    """The appendix's φk = φh + φd holds only when θh = 0 or φd is a multiple of π/2;
    in general tan(φk − φh) = tan φd / cos θh (k̄ is d̄ rotated by θh about ĥ's
    tangent axis, which shortens its component along h̄ by cos θh)."""
    q = quantities(*away(2000, seed=33))
    rel = np.mod(q["phi_k"] - q["phi_h"], 2 * np.pi)
    claimed = np.mod(q["phi_d"], 2 * np.pi)
    gap = np.abs(np.angle(np.exp(1j * (rel - claimed))))
    assert gap.max() > 0.1  # not an identity
    derived = np.mod(
        np.arctan2(np.sin(q["phi_d"]), np.cos(q["theta_h"]) * np.cos(q["phi_d"])), 2 * np.pi
    )
    np.testing.assert_allclose(np.angle(np.exp(1j * (rel - derived))), 0.0, atol=1e-12)
    # The special cases where it does hold: θh = 0 (mirror) and φd ∈ {0, π/2, π, 3π/2}.
    wi, wo = near("mirror", 0.0, 200, seed=34)
    q = quantities(wi, wo)
    rel = np.mod(q["phi_k"] - q["phi_h"], 2 * np.pi)
    assert np.abs(np.angle(np.exp(1j * (rel - q["phi_d"])))).max() < 1e-12


def test_orthographic_and_hybrid_agree_when_k_is_tangent() -> None:
    """At φk − φh = 90° k lies in the tangent plane: ‖k‖ = ‖k̄‖ (Barla et al. 2015, section 3)."""
    c3 = np.array([[0.3, 0.5, np.pi / 2], [0.6, 0.2, np.pi / 2], [0.0, 0.9, np.pi / 2]])
    a, b = params.get("hybrid").inverse_iso(c3)
    np.testing.assert_allclose(params.get("orthographic").forward_iso(a, b), c3, atol=1e-15)


@pytest.mark.parametrize("phi_rel", [0.0, 0.7, 2.0])
def test_they_differ_otherwise(phi_rel: float) -> None:
    a, b = params.get("hybrid").inverse_iso([0.3, 0.5, phi_rel])
    ortho = params.get("orthographic").forward_iso(a, b)
    assert ortho[1] < 0.5 - 1e-3
