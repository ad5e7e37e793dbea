"""Named extremes, exactly and within 1e-12, 1e-9, 1e-6, against the float64 bound.

The bound is computed in arbitrary precision (studies.params.exact): the error that
moving each exact coordinate by the half ulp float64 cannot resolve already causes.
"""

import numpy as np
import pytest

import gonio.params as params
from gonio.params import cases
from studies.params import accuracy, exact

NAMES = params.names()
CASES = [(e, d) for e in cases.EXTREMES for d in cases.DISTANCES]


@pytest.mark.parametrize(("extreme", "distance"), CASES)
def test_extremes_are_valid_finite_and_within_ten_times_the_bound(
    extreme: str, distance: float
) -> None:
    wi, wo = cases.near(extreme, distance, 8, seed=21)
    for name in NAMES:
        p = params.get(name)
        c = p.forward(wi, wo)
        assert np.all(np.isfinite(c)), name
        assert np.all(p.valid(c)), name
        a, b = p.inverse(c)
        assert np.all(np.isfinite(a)) and np.all(np.isfinite(b)), name
        measured = cases.roundtrip_error(wi, wo, a, b)
        bound = exact.roundtrip_bounds(name, wi, wo)
        assert np.all(measured <= 10.0 * bound), (name, measured.max(), bound.max())


@pytest.mark.parametrize("name", NAMES)
def test_no_configuration_ever_changes(name: str) -> None:
    """At and near every extreme the round trip never lands on another pair (O(1) error)."""
    for extreme, distance in CASES:
        wi, wo = cases.near(extreme, distance, 500, seed=22)
        assert accuracy.measured_errors(name, wi, wo).max() < 1e-7, (extreme, distance)


def test_what_loses_precision_and_what_does_not() -> None:
    """Spherical and Rusinkiewicz keep a few ulps at every extreme; orthographic loses
    digits when either direction grazes, hybrid only when both do."""
    worst: dict[tuple[str, str], float] = {}
    for extreme, distance in CASES:
        wi, wo = cases.near(extreme, distance, 300, seed=23)
        for name in NAMES:
            e = float(accuracy.measured_errors(name, wi, wo).max())
            worst[name, extreme] = max(worst.get((name, extreme), 0.0), e)
    for extreme in cases.EXTREMES:
        assert worst["spherical", extreme] < 2e-15
        assert worst["rusinkiewicz", extreme] < 4e-15
    for extreme in ("grazing_i", "grazing_o"):
        assert worst["orthographic", extreme] > 1e-9  # sqrt(1 − ‖ω̄‖²) at ω·n → 0
        assert worst["hybrid", extreme] < 1e-14  # hz stays O(1)
    for extreme in ("grazing_both", "retro_grazing", "opposite_grazing"):
        assert 1e-9 < worst["hybrid", extreme] < 5e-8  # hz → 0: about √ε
        assert 1e-9 < worst["orthographic", extreme] < 5e-8


def test_exact_named_pairs_round_trip() -> None:
    for label, (wi, wo) in cases.NAMED_PAIRS.items():
        for name in NAMES:
            p = params.get(name)
            a, b = p.inverse(p.forward(wi, wo))
            err = float(cases.roundtrip_error(wi, wo, a, b))
            assert err <= float(accuracy.error_envelope(name, wi, wo)), (label, name, err)


class TestConventionsWhereAnAzimuthIsUndefined:
    def test_spherical_phi_is_zero_at_normal_incidence(self) -> None:
        p = params.get("spherical")
        for n in ([0.0, 0.0, 1.0], [-0.0, -0.0, 1.0]):
            c = p.forward(n, [0.0, -0.0, 1.0])
            assert c.tolist() == [0.0, 0.0, 0.0, 0.0]

    def test_halfway_phi_h_is_zero_in_the_mirror_configuration(self) -> None:
        wi = cases.direction(0.7, 2.0)
        wo = cases.mirror(wi)
        for name in ("rusinkiewicz", "orthographic", "hybrid"):
            c = params.get(name).forward(wi, wo)
            assert c[1] == 0.0, name
            a, b = params.get(name).inverse(c)
            np.testing.assert_allclose(a, wi, atol=1e-15)
            np.testing.assert_allclose(b, wo, atol=1e-15)

    def test_phi_k_and_phi_d_are_zero_at_retro_reflection(self) -> None:
        w = cases.direction(0.7, 2.0)
        assert params.get("hybrid").forward(w, w)[3] == 0.0
        assert params.get("orthographic").forward(w, w)[3] == 0.0
        r = params.get("rusinkiewicz").forward(w, w)
        assert r[2] == 0.0 and r[3] == 0.0

    def test_opposite_grazing_in_rusinkiewicz(self) -> None:
        wi = cases.elevated(0.0, 1.0)
        c = params.get("rusinkiewicz").forward(wi, -wi)
        np.testing.assert_allclose(c, [0.0, 0.0, np.pi / 2, 1.0], atol=1e-15)
        a, b = params.get("rusinkiewicz").inverse(c)
        np.testing.assert_allclose(a, wi, atol=4e-16)
        np.testing.assert_allclose(b, -wi, atol=4e-16)

    def test_both_at_the_normal(self) -> None:
        n = [0.0, 0.0, 1.0]
        for name in NAMES:
            c = params.get(name).forward(n, n)
            expected = {"rusinkiewicz": [0, 0, 0, 0], "spherical": [0, 0, 0, 0]}.get(name, [0] * 4)
            assert c.tolist() == expected
            a, b = params.get(name).inverse(c)
            assert a.tolist() == n and b.tolist() == n


def _appendix_inverse(c: np.ndarray, quadrant: bool) -> tuple[np.ndarray, np.ndarray]:
    """The appendix of Barla, Belcour & Pacanowski 2015, transcribed
    literally (θk by arctan, or by atan2 with the quadrant right),
    hz = sqrt(1 − ‖k‖² − ‖h̄‖²) clipped at 0."""
    hb, ph, k, pk = (c[:, j] for j in range(4))
    hz = np.sqrt(np.maximum(1 - k * k - hb * hb, 0.0))
    a = hb * np.cos(ph - pk)
    if quadrant:
        tk = np.arctan2(hz, -a)
    else:
        with np.errstate(divide="ignore"):
            tk = np.arctan(-hz / a)
    kv = k[:, None] * np.stack([np.sin(tk) * np.cos(pk), np.sin(tk) * np.sin(pk), np.cos(tk)], 1)
    h = np.stack([hb * np.cos(ph), hb * np.sin(ph), hz], 1)
    return h + kv, h - kv


def test_the_appendix_transcribed_literally_returns_other_configurations() -> None:
    p = params.get("hybrid")
    wi, wo = cases.away(2000, seed=24)
    c = p.forward(wi, wo)
    # Principal-value arctan: θk ∈ (−π/2, π/2) gives kz ≥ 0, i.e. ωi and ωo swapped
    # whenever ωi is the lower one — half of all generic pairs.
    a, b = _appendix_inverse(c, quadrant=False)
    lower = wi[:, 2] < wo[:, 2]
    np.testing.assert_allclose(a[lower], wo[lower], atol=1e-12)
    np.testing.assert_allclose(a[~lower], wi[~lower], atol=1e-12)
    # With the quadrant right it is exact away from the horizon...
    a, b = _appendix_inverse(c, quadrant=True)
    assert cases.roundtrip_error(wi, wo, a, b).max() < 1e-14
    # ...but within 1e-9 of both directions grazing, most pairs come back as other pairs.
    for extreme in ("grazing_both", "opposite_grazing"):
        wi, wo = cases.near(extreme, 1e-9, 1000, seed=25)
        c = p.forward(wi, wo)
        a, b = _appendix_inverse(c, quadrant=True)
        assert np.mean(cases.roundtrip_error(wi, wo, a, b) > 0.1) > 0.3
        a, b = p.inverse(c)  # clamping |kz| ≤ hz keeps every pair
        assert cases.roundtrip_error(wi, wo, a, b).max() < 5e-8
