"""The error figure's data: the log error of each test pair, the region each is in, the
binned RMS maps and the scores, the same as `gonio evaluate` computes."""

from __future__ import annotations

import numpy as np
import pytest

from gonio import params
from gonio.plots import error
from gonio.reconstruct import testset
from gonio.reconstruct.metrics import REGIONS, region_masks, scores
from gonio.rig.model import Rig
from tests.support.figures import Lobe


@pytest.fixture(scope="module")
def pairs(rigs: dict[str, Rig]) -> testset.TestSet:
    return testset.draw(rigs["arch"], isotropic=True, size=2000, seed=3)


def truth(wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
    """The lobe, 30 % brighter near the normal, NaN at one pair (left out)."""
    t = Lobe().eval(wi, wo) * (1.0 + 0.3 * wi[:, 2] * wo[:, 2])
    t[7] = np.nan
    return np.asarray(t)


def test_the_log_error_regions_and_scores(pairs: testset.TestSet) -> None:
    data = error.errors(Lobe(), truth, pairs, "hybrid")
    keep = np.ones(len(pairs), bool)
    keep[7] = False
    wi, wo = pairs.wi[keep], pairs.wo[keep]
    c, t = Lobe().eval(wi, wo), truth(pairs.wi, pairs.wo)[keep]
    np.testing.assert_array_equal(data.wi, wi)
    np.testing.assert_array_equal(data.candidate, c)
    np.testing.assert_array_equal(data.truth, t)
    np.testing.assert_allclose(data.log_error, np.log1p(c) - np.log1p(t), rtol=0, atol=1e-15)
    np.testing.assert_array_equal(data.supported, Lobe().supported(wi, wo))
    np.testing.assert_array_equal(data.coords, params.get("hybrid").forward_iso(wi, wo))
    masks = region_masks(wi, wo)
    for i, name in enumerate(REGIONS):
        np.testing.assert_array_equal(data.region == i, masks[name])
        assert data.scores[name] == scores(c[masks[name]], t[masks[name]], wi[masks[name], 2])
    assert data.scores["all"] == scores(c, t, wi[:, 2])
    assert data.scores["all"].count == len(pairs) - 1


def test_the_maps_are_the_rms_log_error_per_bin(pairs: testset.TestSet) -> None:
    data = error.errors(Lobe(), truth, pairs, "hybrid")
    assert [m.axes for m in data.maps] == [(0, 1), (0, 2)]
    for m in data.maps:
        a, b = m.axes
        assert m.rms.shape == (error.BINS, error.BINS)
        np.testing.assert_allclose(m.x_edges, np.linspace(*data.bounds[a], error.BINS + 1))
        np.testing.assert_allclose(m.y_edges, np.linspace(*data.bounds[b], error.BINS + 1))
        i = np.clip(np.searchsorted(m.x_edges, data.coords[:, a], "right") - 1, 0, error.BINS - 1)
        j = np.clip(np.searchsorted(m.y_edges, data.coords[:, b], "right") - 1, 0, error.BINS - 1)
        for cell in {(int(x), int(y)) for x, y in zip(i[:50], j[:50], strict=True)}:
            inside = (i == cell[0]) & (j == cell[1])
            expect = np.sqrt(np.mean(np.square(data.log_error[inside])))
            assert m.rms[cell] == pytest.approx(expect, rel=1e-12)
        empty = np.ones(m.rms.shape, bool)
        empty[i, j] = False
        np.testing.assert_array_equal(np.ma.getmaskarray(m.rms), empty)


def test_a_truth_defined_only_somewhere_limits_the_pairs(pairs: testset.TestSet) -> None:
    where = pairs.wi[:, 2] > 0.7
    data = error.errors(Lobe(), Lobe().eval, pairs, "orthographic", truth_supported=where)
    assert len(data.wi) == np.count_nonzero(where)
    np.testing.assert_array_equal(data.log_error, 0.0)
