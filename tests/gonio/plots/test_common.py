"""The helpers every figure shares (gonio/plots/__init__.py): one channel per value, a
surface's support, the axis labels."""

from __future__ import annotations

import numpy as np

from gonio import params
from gonio.plots import LABELS, label, one_channel, supported, values


class Rgb:
    def eval(self, wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
        return np.stack([wi[:, 2], wo[:, 2], np.zeros(len(wi))], axis=-1)


def test_an_rgb_value_is_drawn_as_the_mean_of_its_channels() -> None:
    wi = np.array([[0.0, 0.0, 1.0], [0.6, 0.0, 0.8]])
    wo = np.array([[0.0, 0.6, 0.8], [0.0, 0.0, 1.0]])
    np.testing.assert_allclose(values(Rgb(), wi, wo), [0.6, 0.6])
    np.testing.assert_array_equal(one_channel([1.0, 2.0]), [1.0, 2.0])


def test_a_surface_without_support_has_data_everywhere() -> None:
    wi = np.array([[0.0, 0.0, 1.0]] * 3)
    np.testing.assert_array_equal(supported(Rgb(), wi, wi), [True] * 3)


def test_every_coordinate_has_a_label() -> None:
    for name in params.names():
        p = params.get(name)
        for coordinate in (*p.names, *p.iso_names):
            assert coordinate in LABELS, coordinate
    assert label("other") == "other"
