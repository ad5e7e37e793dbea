"""The in-plane curves: the pairs are in the plane of incidence with the mirror at
θo = θi, the lines are the surface's and the truth's values there, and the samples drawn
are exactly those near each plane, at their signed θo."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from gonio.errors import GonioError
from gonio.plots import polar
from tests.support.figures import Lobe, capture, pixels, png_size

THETA_MAX = math.radians(80.0)


def rotated(w: np.ndarray, phi: float) -> np.ndarray:
    c, s = math.cos(phi), math.sin(phi)
    return np.asarray(w @ np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]]))


def test_the_in_plane_pairs_put_the_mirror_at_theta_o_equal_theta_i() -> None:
    wi, wo = polar.in_plane(math.radians(30.0), np.radians([-30.0, 0.0, 30.0]))
    np.testing.assert_allclose(wi, [[0.5, 0.0, math.sqrt(3) / 2]] * 3, atol=1e-15)
    np.testing.assert_allclose(wo[2], wi[2] * [-1.0, -1.0, 1.0], atol=1e-15)  # the mirror
    np.testing.assert_allclose(wo[0], wi[0], atol=1e-15)  # retro-reflection
    np.testing.assert_allclose(wo[1], [0.0, 0.0, 1.0], atol=1e-15)


@given(
    theta_i=st.floats(1.0, 80.0),
    theta_o=st.floats(-80.0, 80.0),
    phi=st.floats(0.0, 360.0),
    off=st.floats(0.0, 20.0),
)
def test_a_sample_is_near_the_plane_within_the_tolerance_at_its_signed_theta_o(
    theta_i: float, theta_o: float, phi: float, off: float
) -> None:
    """A pair built in the plane, tilted ``off`` degrees out of it and turned about the
    normal by ``phi``: near the curve of its θi iff off ≤ 5°, at its own θo when in it."""
    wi, wo = polar.in_plane(math.radians(theta_i), np.radians([theta_o]))
    t, o = math.radians(theta_o), math.radians(off)
    wo = np.array([[-math.sin(t) * math.cos(o), math.sin(o), math.cos(t) * math.cos(o)]])
    wi, wo = rotated(wi, math.radians(phi)), rotated(wo, math.radians(phi))
    tol = math.radians(5.0)
    near, signed = polar.near_plane(wi, wo, math.radians(theta_i), tol)
    tilt = math.asin(abs(math.sin(o)))  # the angle of ωo to the plane
    if abs(tilt - tol) > 1e-9:
        assert near[0] == (tilt <= tol)
    if off == 0.0:
        assert signed[0] == pytest.approx(t, abs=1e-9)
    far, _ = polar.near_plane(wi, wo, math.radians(theta_i) + 2 * tol, tol)
    assert not far[0]


def test_at_normal_incidence_every_plane_is_the_plane_of_incidence() -> None:
    wi = np.array([[0.0, 0.0, 1.0]] * 2)
    wo = np.array([[0.6, 0.0, 0.8], [0.0, 0.0, 1.0]])
    near, signed = polar.near_plane(wi, wo, 0.0, math.radians(1.0))
    assert near.all()
    np.testing.assert_allclose(signed, [math.atan2(0.6, 0.8), 0.0])


def test_the_lines_are_the_surface_and_the_truth_at_the_plotted_angles() -> None:
    lobe = Lobe()
    rng = np.random.default_rng(1)
    theta = rng.uniform(0.0, 1.3, (2, 400))
    phi = rng.uniform(0.0, 2 * np.pi, (2, 400))
    dirs = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], -1)
    wi, wo = dirs
    f = lobe.eval(wi, wo)
    sigma = 0.01 * f

    def truth(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        return np.asarray(2.0 * lobe.eval(a, b))

    data = polar.polar(
        lobe,
        (wi, wo, f, sigma),
        THETA_MAX,
        (0.0, 45.0),
        truth=truth,
        tolerance_deg=8.0,
        truth_label="twice",
    )
    assert [c.theta_i for c in data.curves] == [0.0, math.radians(45.0)]
    assert data.truth_label == "twice"
    for c in data.curves:
        np.testing.assert_allclose(c.theta_o, np.linspace(-THETA_MAX, THETA_MAX, polar.POINTS))
        expect_wi = np.broadcast_to([math.sin(c.theta_i), 0.0, math.cos(c.theta_i)], c.wi.shape)
        expect_wo = np.stack([-np.sin(c.theta_o), 0 * c.theta_o, np.cos(c.theta_o)], -1)
        np.testing.assert_allclose(c.wi, expect_wi, atol=1e-15)
        np.testing.assert_allclose(c.wo, expect_wo, atol=1e-15)
        np.testing.assert_array_equal(c.surface, lobe.eval(c.wi, c.wo))
        np.testing.assert_array_equal(c.supported, lobe.supported(c.wi, c.wo))
        assert c.truth is not None
        np.testing.assert_array_equal(c.truth, 2.0 * c.surface)
        near, signed = polar.near_plane(wi, wo, c.theta_i, math.radians(8.0))
        assert 0 < np.count_nonzero(near) < 40
        np.testing.assert_array_equal(c.sample_f, f[near])
        np.testing.assert_array_equal(c.sample_sigma, sigma[near])
        np.testing.assert_array_equal(c.sample_theta_o, signed[near])


def test_without_a_truth_there_is_no_truth_line() -> None:
    empty = np.empty((0, 3))
    data = polar.polar(Lobe(), (empty, empty, np.empty(0), np.empty(0)), THETA_MAX, (10.0,))
    assert data.truth_label is None
    assert data.curves[0].truth is None
    assert len(data.curves[0].sample_f) == 0


@pytest.mark.parametrize("theta_i", [-1.0, 80.5, math.inf])
def test_an_angle_of_incidence_beyond_the_rig_is_refused(theta_i: float) -> None:
    expected = r"--theta-i .*: expected an angle in degrees in \[0, 80\]"
    with pytest.raises(GonioError, match=expected):
        polar.polar(Lobe(), (np.empty((0, 3)),) * 2 + (np.empty(0),) * 2, THETA_MAX, (theta_i,))


def test_the_figure_draws_the_curves_and_samples_and_is_a_png_of_its_size(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    lobe = Lobe()
    wi, wo = polar.in_plane(math.radians(30.0), np.radians([10.0, 30.0, 50.0]))
    f = lobe.eval(wi, wo)
    data = polar.polar(
        lobe, (wi, wo, f, 0.1 * f), THETA_MAX, (30.0,), truth=lobe.eval, truth_label="the lobe"
    )
    figures = capture(monkeypatch, polar)
    path = tmp_path / "polar.png"
    polar.draw(data, path)
    assert png_size(path) == pixels(polar.FIGSIZE) == (900, 550)
    (ax,) = figures[0].axes  # type: ignore[attr-defined]
    solid, dotted, dashed = ax.lines[:3]
    c = data.curves[0]
    deg = np.degrees(c.theta_o)
    for line in (solid, dotted, dashed):
        np.testing.assert_array_equal(line.get_xdata(), deg)
    np.testing.assert_array_equal(solid.get_ydata(), np.where(c.supported, c.surface, np.nan))
    np.testing.assert_array_equal(dotted.get_ydata(), np.where(c.supported, np.nan, c.surface))
    np.testing.assert_array_equal(dashed.get_ydata(), c.truth)
    points = ax.lines[3]  # the error bars' markers
    np.testing.assert_allclose(points.get_xdata(), [10.0, 30.0, 50.0])
    np.testing.assert_array_equal(points.get_ydata(), f)
