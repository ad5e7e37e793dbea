"""The public API of gonio.params: names, shapes, dtypes, bounds, errors."""

import numpy as np
import pytest

import gonio.params as params
from gonio.errors import DomainError, GonioError, UnknownNameError
from gonio.params.cases import away

NAMES = params.names()


def test_the_four_parametrizations_are_registered() -> None:
    assert NAMES == ["spherical", "rusinkiewicz", "orthographic", "hybrid"]
    assert params.get("hybrid").names == ("hbar", "phi_h", "k", "phi_k")
    assert params.get("rusinkiewicz").names == ("theta_h", "phi_h", "theta_d", "phi_d")
    assert params.get("orthographic").names == ("hbar", "phi_h", "kbar", "phi_k")
    assert params.get("spherical").names == ("theta_i", "phi_i", "theta_o", "phi_o")


def test_unknown_name_is_one_clear_error() -> None:
    with pytest.raises(UnknownNameError) as err:
        params.get("halfway")
    assert isinstance(err.value, GonioError)
    assert str(err.value) == (
        "unknown parametrization 'halfway'; expected one of "
        "spherical, rusinkiewicz, orthographic, hybrid"
    )


@pytest.mark.parametrize("name", NAMES)
def test_bounds_contain_every_forward_coordinate(name: str) -> None:
    p = params.get(name)
    assert p.bounds.shape == (4, 2) and p.iso_bounds.shape == (3, 2)
    assert len(p.iso_names) == 3 and p.iso_symmetry
    wi, wo = away(2000, seed=1)
    for coords, bounds in ((p.forward(wi, wo), p.bounds), (p.forward_iso(wi, wo), p.iso_bounds)):
        assert np.all(coords >= bounds[:, 0])
        assert np.all(coords < bounds[:, 1] + 1e-15)


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("lead", [(), (7,), (2, 3), (1, 4, 2)])
def test_any_leading_shape(name: str, lead: tuple[int, ...]) -> None:
    p = params.get(name)
    wi, wo = away(int(np.prod(lead, dtype=int)), seed=2)
    wi, wo = wi.reshape(*lead, 3), wo.reshape(*lead, 3)
    c = p.forward(wi, wo)
    assert c.shape == (*lead, 4) and c.dtype == np.float64
    assert p.valid(c).shape == lead and p.valid(c).dtype == np.bool_
    a, b = p.inverse(c)
    assert a.shape == b.shape == (*lead, 3)
    assert p.forward_iso(wi, wo).shape == (*lead, 3)
    a, b = p.inverse_iso(p.forward_iso(wi, wo))
    assert a.shape == (*lead, 3)
    assert p.valid_iso(p.forward_iso(wi, wo)).shape == lead


@pytest.mark.parametrize("name", NAMES)
def test_directions_broadcast_and_accept_lists(name: str) -> None:
    p = params.get(name)
    wi, wo = away(5, seed=3)
    c = p.forward([0.0, 0.0, 1.0], wo)  # one light direction, five detector directions
    assert c.shape == (5, 4)
    np.testing.assert_array_equal(c, p.forward(np.tile([0.0, 0.0, 1.0], (5, 1)), wo))
    assert p.forward(wi[:, None, :], wo[None, :, :]).shape == (5, 5, 4)


@pytest.mark.parametrize("name", NAMES)
def test_bad_shapes_are_domain_errors(name: str) -> None:
    p = params.get(name)
    with pytest.raises(DomainError, match="last axis of length 3"):
        p.forward(np.zeros((4, 2)), np.zeros((4, 2)))
    with pytest.raises(DomainError, match="do not broadcast"):
        p.forward(np.zeros((4, 3)), np.zeros((5, 3)))
    with pytest.raises(DomainError, match="last axis of length 4"):
        p.inverse(np.zeros((4, 3)))
    with pytest.raises(DomainError, match="last axis of length 3"):
        p.inverse_iso(np.zeros(4))


@pytest.mark.parametrize(
    ("name", "outside"),
    [
        ("spherical", [2.0, 0.0, 0.3, 0.0]),
        ("spherical", [-0.1, 0.0, 0.3, 0.0]),
        ("rusinkiewicz", [1.2, 0.0, 1.2, 0.0]),
        ("rusinkiewicz", [0.1, 0.0, 1.7, 0.0]),
        ("orthographic", [0.8, 0.0, 0.5, 0.0]),
        ("orthographic", [-0.1, 0.0, 0.1, 0.0]),
        ("hybrid", [0.9, 0.0, 0.9, 0.0]),
        ("hybrid", [0.6, 0.0, 0.7, 0.0]),
        ("hybrid", [0.1, 0.0, -0.2, 0.0]),
    ],
)
def test_inverse_refuses_invalid_coordinates(name: str, outside: list[float]) -> None:
    p = params.get(name)
    coords = np.array([p.forward(*away(1, seed=4))[0], outside, outside])
    assert p.valid(coords).tolist() == [True, False, False]
    with pytest.raises(DomainError) as err:
        p.inverse(coords)
    assert "2 of 3 coordinate rows are outside the valid domain" in str(err.value)
    assert "first at index (1,)" in str(err.value)


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_coordinates_are_never_valid(name: str, bad: float) -> None:
    p = params.get(name)
    good = p.forward(*away(1, seed=5))[0]
    for j in range(4):
        c = good.copy()
        c[j] = bad
        assert not p.valid(c)
        with pytest.raises(DomainError):
            p.inverse(c)


@pytest.mark.parametrize("name", NAMES)
def test_scalar_pair_gives_plain_vectors(name: str) -> None:
    p = params.get(name)
    c = p.forward([0.6, 0.0, 0.8], [0.0, 0.6, 0.8])
    assert c.shape == (4,)
    a, b = p.inverse(c)
    np.testing.assert_allclose(a, [0.6, 0.0, 0.8], atol=1e-15)
    np.testing.assert_allclose(b, [0.0, 0.6, 0.8], atol=1e-15)
    assert bool(p.valid(c)) is True
