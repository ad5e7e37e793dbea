"""The Jacobians of gonio.params.conditioning against mpmath, and their singular values
at the singular configurations as documented (docs/explanations/extremes.md)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gonio import params
from gonio.errors import DomainError, UnknownNameError
from gonio.params import cases, conditioning
from studies.params import exact
from studies.params.accuracy import PATH_DISTANCES, path_study

NAMES = params.names()
angle = st.floats(0.1, 1.45)
azimuth = st.floats(0.0, 2 * np.pi, exclude_max=True)


def relative_gap(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


@settings(max_examples=6, deadline=None)
@given(angle, azimuth, angle, azimuth, st.sampled_from(NAMES))
def test_the_jacobian_matches_mpmath_at_interior_points(
    ti: float, pi: float, to: float, po: float, name: str
) -> None:
    wi, wo = cases.direction(ti, pi), cases.direction(to, po)
    if np.linalg.norm(wi - wo) < 0.05 or np.linalg.norm(wi - cases.mirror(wo)) < 0.05:
        return  # keep interior: retro and mirror are tested at known distances below
    frame = conditioning.pair_frame(wi, wo)
    reference = exact.tangent_jacobian(name, wi, wo, frame)
    assert relative_gap(conditioning.tangent_jacobian(name, wi, wo), reference) < 1e-12


@pytest.mark.parametrize("extreme", ["mirror", "retro", "normal_both", "opposite_grazing"])
@pytest.mark.parametrize("name", NAMES)
def test_the_jacobian_matches_mpmath_near_the_singularities(extreme: str, name: str) -> None:
    # At distance d the float64 pair itself is known to ε, so entries to about ε/d.
    for distance in (1e-3, 1e-8):
        wi, wo = cases.near(extreme, distance, 2, seed=3)
        ours = conditioning.tangent_jacobian(name, wi, wo)
        frame = conditioning.pair_frame(wi, wo)
        for j in range(2):
            reference = exact.tangent_jacobian(name, wi[j], wo[j], frame[j])
            assert relative_gap(ours[j], reference) < 1e3 * 2.2e-16 / distance


def test_the_angle_jacobian_of_spherical_is_the_identity_and_its_tangent_one_is_not() -> None:
    wi, wo = cases.away(50, seed=1)
    np.testing.assert_allclose(
        conditioning.angle_jacobian("spherical", wi, wo),
        np.broadcast_to(np.eye(4), (50, 4, 4)),
        atol=1e-15,
    )
    sin_i = np.hypot(wi[:, 0], wi[:, 1])
    tangent = conditioning.tangent_jacobian("spherical", wi, wo)
    np.testing.assert_allclose(tangent[:, 1, 1], 1.0 / sin_i, rtol=1e-14)


def test_angle_and_tangent_jacobians_differ_by_the_column_scaling() -> None:
    wi, wo = cases.uniform(20, seed=4)
    for name in NAMES:
        t = conditioning.tangent_jacobian(name, wi, wo)
        a = conditioning.angle_jacobian(name, wi, wo)
        np.testing.assert_allclose(a[:, :, 0], t[:, :, 0], rtol=1e-15)
        np.testing.assert_allclose(a[:, :, 1], t[:, :, 1] * np.hypot(wi[:, 0], wi[:, 1])[:, None])


def test_singular_values_do_not_depend_on_the_tangent_frame() -> None:
    wi, wo = cases.away(10, seed=2)
    j = conditioning.tangent_jacobian("hybrid", wi, wo)
    turn = np.array([[np.cos(0.7), -np.sin(0.7)], [np.sin(0.7), np.cos(0.7)]])
    rotated = j.copy()
    rotated[:, :, :2] = j[:, :, :2] @ turn
    np.testing.assert_allclose(
        conditioning.singular_values(rotated), conditioning.singular_values(j), rtol=1e-13
    )


# (extreme, parametrization) → the exponent p of the documented law cond ∝ d^-p as the
# distance d → 0: p = 1 where a coordinate's gradient grows (an azimuth or polar angle of
# a vanishing vector) or where the map flattens (σmin ∝ d near the horizon), else 0.
LAWS = {
    ("normal_incidence_i", "spherical"): 1,
    ("normal_incidence_i", "hybrid"): 0,
    ("normal_both", "rusinkiewicz"): 1,
    ("grazing_i", "spherical"): 0,
    ("grazing_i", "orthographic"): 1,
    ("grazing_i", "hybrid"): 0,
    ("grazing_both", "hybrid"): 1,
    ("retro", "spherical"): 0,
    ("retro", "rusinkiewicz"): 1,
    ("retro", "hybrid"): 1,
    ("mirror", "spherical"): 0,
    ("mirror", "orthographic"): 1,
    ("opposite_grazing", "rusinkiewicz"): 1,
    ("opposite_grazing", "hybrid"): 1,
}


@pytest.mark.parametrize(("extreme", "name"), list(LAWS))
def test_the_condition_number_grows_as_documented(extreme: str, name: str) -> None:
    rows = path_study([name], [extreme], distances=(1e-4, 1e-10), samples=8)
    slope = np.log10(rows[1].cond / rows[0].cond) / 6.0
    assert slope == pytest.approx(LAWS[extreme, name], abs=0.02)


def test_spherical_azimuth_gradient_is_one_over_the_distance_at_normal_incidence() -> None:
    for d in (1e-2, 1e-7, 1e-12):
        wi, wo = cases.near("normal_incidence_i", d, 4, seed=0)
        s = conditioning.singular_values(conditioning.tangent_jacobian("spherical", wi, wo))
        np.testing.assert_allclose(s[:, 0], 1.0 / np.sin(d), rtol=1e-12)
        np.testing.assert_allclose(s[:, -1], 1.0, rtol=1e-12)


def test_orthographic_smallest_singular_value_is_the_elevation_at_grazing() -> None:
    # ‖ω̄‖ = cos e: the elevation moves it by sin e ≈ e; nothing else sees the elevation.
    for d in (1e-3, 1e-9):
        wi, wo = cases.near("grazing_i", d, 4, seed=0)
        s = conditioning.singular_values(conditioning.tangent_jacobian("orthographic", wi, wo))
        assert np.all(s[:, -1] <= d) and np.all(s[:, -1] > 0.05 * d)


def test_the_jacobian_is_refused_where_it_does_not_exist() -> None:
    n, w = np.array([0.0, 0.0, 1.0]), cases.direction(0.5, 1.0)
    with pytest.raises(DomainError, match="ωi = n"):
        conditioning.tangent_jacobian("spherical", n, w)
    with pytest.raises(DomainError, match="mirror"):
        conditioning.tangent_jacobian("hybrid", w, cases.mirror(w))
    with pytest.raises(DomainError, match="retro"):
        conditioning.tangent_jacobian("rusinkiewicz", w, w)
    with pytest.raises(DomainError, match="h̄ = 0"):
        conditioning.tangent_jacobian("orthographic", [0.6, 0.8, 0.0], [-0.6, -0.8, 0.0])


def test_an_unknown_name_is_refused_by_name() -> None:
    with pytest.raises(UnknownNameError, match="unknown parametrization 'polar'"):
        conditioning.tangent_jacobian("polar", *cases.away(1))


def test_a_tangent_part_that_underflows_counts_as_zero() -> None:
    tiny = np.array([1e-170, 0.0, 1.0])
    with pytest.raises(DomainError, match="ωi = n"):
        conditioning.tangent_jacobian("spherical", tiny, cases.direction(0.5, 1.0))


def test_a_singular_jacobian_has_an_infinite_condition_number() -> None:
    j = np.diag([1.0, 2.0, 3.0, 0.0])
    assert conditioning.condition_number(j) == np.inf
    assert conditioning.condition_number(np.diag([1.0, 2.0, 4.0, 0.5])) == pytest.approx(8.0)


def test_path_distances_span_1e_minus_1_to_1e_minus_12_two_per_decade() -> None:
    assert PATH_DISTANCES[0] == pytest.approx(0.1) and PATH_DISTANCES[-1] == pytest.approx(1e-12)
    assert len(PATH_DISTANCES) == 23
