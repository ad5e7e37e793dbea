"""Slices of a surface in three parametrizations: each pixel is the surface at the pair
its coordinates map to, masked outside the domain and where the surface has no data; the
figure is a whole PNG of the stated size."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from gonio import params
from gonio.errors import GonioError
from gonio.plots import slices
from tests.support.figures import Lobe, capture, pixels, png_size


@pytest.fixture(scope="module")
def data() -> slices.Slices:
    return slices.slices(Lobe(), (0.0, 90.0), resolution=25, title="a lobe")


def test_one_row_per_parametrization_one_column_per_angle(data: slices.Slices) -> None:
    assert [[s.parametrization for s in row] for row in data.rows] == [
        ["hybrid"] * 2,
        ["orthographic"] * 2,
        ["rusinkiewicz"] * 2,
    ]
    assert [s.angle for s in data.rows[0]] == [0.0, math.pi / 2]
    for row in data.rows:
        for s in row:
            assert s.names == params.get(s.parametrization).iso_names
            assert s.f.shape == s.valid.shape == s.supported.shape == (25, 25)
            np.testing.assert_array_equal(s.coords[..., 2], s.angle)
            np.testing.assert_array_equal(s.coords[0, :, 0], s.x)  # columns: x
            np.testing.assert_array_equal(s.coords[:, 0, 1], s.y)  # rows: y


def test_each_pixel_is_the_surface_at_the_inverse_mapped_pair(data: slices.Slices) -> None:
    lobe = Lobe()
    for row in data.rows:
        for s in row:
            p = params.get(s.parametrization)
            np.testing.assert_array_equal(s.valid, p.valid_iso(s.coords))
            assert s.valid.any()
            assert s.angle != 0.0 or not s.valid.all()  # φ = 0: every domain is cut
            wi, wo = p.inverse_iso(s.coords[s.valid])
            np.testing.assert_array_equal(s.f[s.valid], lobe.eval(wi, wo))
            np.testing.assert_array_equal(s.supported[s.valid], lobe.supported(wi, wo))
            assert np.isnan(s.f[~s.valid]).all()
            assert not s.supported[~s.valid].any()
            np.testing.assert_array_equal(s.masked, ~s.valid | ~s.supported)


def test_hybrid_equals_orthographic_at_90_degrees(data: slices.Slices) -> None:
    """k is tangent there (Barla et al. 2015, section 3): the same slice."""
    hybrid, orthographic = data.rows[0][1], data.rows[1][1]
    np.testing.assert_array_equal(hybrid.valid, orthographic.valid)
    np.testing.assert_allclose(hybrid.f, orthographic.f, rtol=1e-12, equal_nan=True)


def test_a_flat_surface_without_support_is_masked_only_outside_the_domain(
    tmp_path: Path,
) -> None:
    """…and is drawn without iso-lines (none in its range) and without a warning."""

    class Flat:
        def eval(self, wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
            return np.full(len(wi), 1 / math.pi)

    data = slices.slices(Flat(), (30.0,), parametrizations=("hybrid",), resolution=9)
    (s,) = data.rows[0]
    np.testing.assert_array_equal(s.masked, ~s.valid)
    slices.draw(data, tmp_path / "flat.png")  # a warning would fail the test
    assert png_size(tmp_path / "flat.png") == pixels(slices.figure_size(data))


@pytest.mark.parametrize("angle", [-1.0, 180.0, math.nan])
def test_an_angle_outside_0_180_is_refused(angle: float) -> None:
    with pytest.raises(GonioError, match=r"--phi-k .*: expected an angle in degrees in \[0, 180\)"):
        slices.slices(Lobe(), (angle,))


def test_a_value_the_surface_declines_to_give_is_masked() -> None:
    class Partial(Lobe):
        def eval(self, wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
            f = super().eval(wi, wo)
            return np.where(wi[:, 0] > 0.3, np.nan, f)

    (s,) = slices.slices(Partial(), (90.0,), parametrizations=("hybrid",), resolution=15).rows[0]
    declined = s.valid & np.isnan(s.f)
    assert declined.any()
    assert s.masked[declined].all()


def test_the_figure_shades_the_data_and_is_a_png_of_its_size(
    data: slices.Slices, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from matplotlib.collections import QuadMesh

    figures = capture(monkeypatch, slices)
    path = tmp_path / "slices.png"
    slices.draw(data, path)
    assert png_size(path) == pixels(slices.figure_size(data)) == (900, 1040)
    (fig,) = figures
    panels = [ax for ax in fig.axes if ax.get_title()]  # type: ignore[attr-defined]
    assert len(panels) == 6
    for ax, s in zip(panels, [s for row in data.rows for s in row], strict=True):
        background, shade = (c for c in ax.collections if isinstance(c, QuadMesh))
        shown = shade.get_array()
        np.testing.assert_array_equal(np.ma.getmaskarray(shown).reshape(s.f.shape), s.masked)
        np.testing.assert_allclose(
            shown.reshape(s.f.shape)[~s.masked], np.log10(np.maximum(s.f[~s.masked], 1e-4))
        )
        np.testing.assert_array_equal(background.get_array().reshape(s.f.shape), s.valid)


def test_a_surface_with_no_data_anywhere_is_drawn_grey(tmp_path: Path) -> None:
    class Nowhere(Lobe):
        def supported(self, wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
            return np.zeros(len(wi), dtype=bool)

    data = slices.slices(Nowhere(), (10.0,), parametrizations=("orthographic",), resolution=9)
    assert data.rows[0][0].masked.all()
    slices.draw(data, tmp_path / "grey.png")
    assert png_size(tmp_path / "grey.png") == pixels(slices.figure_size(data))
