"""`evaluate`: which pairs count, the coverage, the regions, JSON and the table."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from gonio.errors import GonioError
from gonio.reconstruct import Evaluation, evaluate, testset
from gonio.reconstruct.evaluate import ALL
from gonio.reconstruct.metrics import METRICS, REGIONS, region_masks
from gonio.reconstruct.truth import Truth
from gonio.rig.model import Rig
from gonio.types import BoolArray, FloatArray
from tests.support.rigs import direction


def lambert(wi: FloatArray, wo: FloatArray) -> FloatArray:
    return np.full(wi.shape[:-1], 0.1)


class Scaled:
    """A candidate: ``factor`` × Lambert, supported where ωi is within 45° of the normal,
    NaN (it declines) where ωo is beyond 60°."""

    def __init__(self, factor: float) -> None:
        self.factor = factor

    def eval(self, wi: FloatArray, wo: FloatArray) -> FloatArray:
        return np.where(wo[:, 2] < 0.5, np.nan, self.factor * lambert(wi, wo))

    def supported(self, wi: FloatArray, wo: FloatArray) -> BoolArray:
        return np.asarray(wi[:, 2] > math.cos(math.pi / 4))


@pytest.fixture(scope="module")
def arch(rigs: dict[str, Rig]) -> Rig:
    return rigs["arch"]


@pytest.fixture(scope="module")
def pairs(arch: Rig) -> testset.TestSet:
    return testset.draw(arch, isotropic=True, size=4000)


def test_the_truth_itself_scores_zero_with_full_coverage(arch: Rig) -> None:
    class Exact:
        def eval(self, wi: FloatArray, wo: FloatArray) -> FloatArray:
            return lambert(wi, wo) * (1 + wi[:, 2])

    result = evaluate(
        Exact(), lambda wi, wo: lambert(wi, wo) * (1 + wi[:, 2]), arch, isotropic=True
    )
    assert result.test_pairs == testset.DEFAULT_SIZE and result.seed == testset.DEFAULT_SEED
    assert list(result.regions) == [ALL, *REGIONS]
    for region in result.regions.values():
        assert region.coverage == 1.0 and region.scores.count == region.pairs > 0
        assert all(getattr(region.scores, m) == 0.0 for m in METRICS)
    assert sum(result.regions[r].pairs for r in REGIONS) == result.regions[ALL].pairs


class Filled(Scaled):
    """`Scaled` with a fill: ``factor`` × Lambert inside the support, 3 × outside."""

    extrapolate = "triple"

    def eval(self, wi: FloatArray, wo: FloatArray) -> FloatArray:
        inside = self.supported(wi, wo)
        return np.where(inside, self.factor, 3.0) * lambert(wi, wo)


def test_every_pair_is_scored_with_the_fill_outside_the_support(
    arch: Rig, pairs: testset.TestSet
) -> None:
    result = evaluate(Filled(2.0), lambert, arch, isotropic=True, test_set=pairs)
    everything = result.regions[ALL]
    inside = pairs.wi[:, 2] > math.cos(math.pi / 4)
    assert everything.pairs == everything.scores.count == len(pairs)
    assert everything.coverage == pytest.approx(np.mean(inside))
    share = np.mean(inside)
    expected = math.sqrt(share * math.log(1.2 / 1.1) ** 2 + (1 - share) * math.log(1.3 / 1.1) ** 2)
    assert everything.scores.log_rmse == pytest.approx(expected, rel=1e-12)
    assert result.fill == "triple" and not result.only_supported
    assert result.scored == "every pair (outside the support: triple fill)"
    assert "scored: every pair (outside the support: triple fill)" in result.table()
    masks = region_masks(pairs.wi, pairs.wo)
    for name in REGIONS:
        assert result.regions[name].pairs == np.count_nonzero(masks[name])


def test_only_supported_scores_the_pairs_inside_the_support(
    arch: Rig, pairs: testset.TestSet
) -> None:
    result = evaluate(
        Filled(2.0), lambert, arch, isotropic=True, test_set=pairs, only_supported=True
    )
    everything = result.regions[ALL]
    assert everything.pairs == len(pairs)
    assert everything.scores.count == np.count_nonzero(pairs.wi[:, 2] > math.cos(math.pi / 4))
    s = everything.scores
    assert s.log_rmse == pytest.approx(math.log(1.2 / 1.1), rel=1e-12)
    assert s.rel_rmse == s.rel_median == s.rel_p95 == pytest.approx(1.0, rel=1e-12)
    cos = pairs.wi[pairs.wi[:, 2] > math.cos(math.pi / 4), 2]
    expected = math.sqrt(np.mean((np.log1p(0.2 * cos) - np.log1p(0.1 * cos)) ** 2))
    assert s.cos_log_rmse == pytest.approx(expected, rel=1e-12)
    assert result.scored == "the pairs inside the support only"
    assert result.to_json()["only_supported"] is True


def test_a_candidate_without_a_value_at_a_pair_it_is_scored_on_is_one_line(
    arch: Rig, pairs: testset.TestSet
) -> None:
    # Scaled declines where ωo is beyond 60°, inside its support and outside.
    for only in (False, True):
        with pytest.raises(GonioError) as err:
            evaluate(
                Scaled(2.0),
                lambert,
                arch,
                isotropic=True,
                test_set=pairs,
                only_supported=only,
                candidate_label="twice",
            )
        said = str(err.value)
        assert said.startswith("twice has no value at ") and "\n" not in said
        assert ("give it a fill" in said) != only


def test_a_truth_that_is_a_reconstruction_counts_only_where_it_is_defined(
    arch: Rig, pairs: testset.TestSet
) -> None:
    def supported(wi: FloatArray, wo: FloatArray) -> BoolArray:
        return np.asarray(wi[:, 0] > 0)

    def partial(wi: FloatArray, wo: FloatArray) -> FloatArray:
        return np.where(wo[:, 0] > 0, np.inf, lambert(wi, wo))

    truth = Truth("a run's reconstruction", partial, supported)
    result = evaluate(Filled(1.0), truth, arch, isotropic=True, test_set=pairs, only_supported=True)
    assert result.truth == "a run's reconstruction"
    kept = (pairs.wi[:, 0] > 0) & (pairs.wo[:, 0] <= 0)
    assert result.regions[ALL].pairs == np.count_nonzero(kept)
    assert result.regions[ALL].scores.log_rmse == 0.0


def test_an_rgb_candidate_meets_a_grey_truth_channel_by_channel(
    arch: Rig, pairs: testset.TestSet
) -> None:
    class Rgb:
        def eval(self, wi: FloatArray, wo: FloatArray) -> FloatArray:
            return np.stack([lambert(wi, wo), lambert(wi, wo), 2 * lambert(wi, wo)], -1)

    result = evaluate(Rgb(), lambert, arch, isotropic=True, test_set=pairs)
    assert result.regions[ALL].scores.rel_median == 0.0
    assert result.regions[ALL].scores.rel_p95 == pytest.approx(1.0)
    with pytest.raises(GonioError, match="compare RGB with RGB"):
        evaluate(Filled(1.0), Rgb().eval, arch, isotropic=True, test_set=pairs)


def _only_rest() -> testset.TestSet:
    wi, wo = direction(np.array([20.0, 30.0]), 0.0), direction(np.array([40.0, 45.0]), 90.0)
    return testset.TestSet(wi=wi, wo=wo, seed=0, drawn=2)


def test_json_and_table_say_the_same_and_mark_empty_regions(arch: Rig) -> None:
    result = evaluate(
        Filled(2.0), lambert, arch, isotropic=True, test_set=_only_rest(), candidate_label="twice"
    )
    assert isinstance(result, Evaluation)
    data = json.loads(json.dumps(result.to_json(), allow_nan=False))
    assert data["candidate"] == "twice" and data["test_set"] == {"pairs": 2, "seed": 0}
    assert data["only_supported"] is False and data["fill"] is None  # both supported
    assert data["regions"]["rest"]["pairs"] == data["regions"]["rest"]["scored"] == 2
    assert data["regions"]["mirror"] == {
        "pairs": 0,
        "coverage": None,
        "scored": 0,
        **dict.fromkeys(METRICS),
    }
    lines = result.table().splitlines()
    assert lines[0] == "twice vs truth"
    assert lines[2] == "scored: every pair; coverage: the share inside the support"
    assert lines[3].split()[:3] == ["region", "pairs", "coverage"]
    rows = {line.split()[0]: line.split() for line in lines[4:]}
    assert list(rows) == [ALL, *REGIONS]
    assert rows["mirror"][1:] == ["0"] + ["—"] * 6
    assert rows["rest"][1:4] == ["2", "100.0", "%"]
    assert float(rows["rest"][4]) == pytest.approx(math.log(1.2 / 1.1), rel=1e-3)
