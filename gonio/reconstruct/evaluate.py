"""A reconstruction scored against a truth on the fixed test set, overall and by region
(docs/explanations/evaluation.md): `evaluate` returns an `Evaluation` (JSON, a table).

Which pairs count: the test set's pairs where the truth is defined (finite, and inside
its ``supported`` mask when the truth is itself a reconstruction). Of those, a region
reports how many it holds (``pairs``), the fraction the candidate supports
(``coverage``: its ``supported`` mask, 1 for a candidate without one) and the metrics
over the pairs where the candidate's value is finite in every channel: an unsupported
pair counts with whatever the candidate's extrapolation fills in, and is left out only
where the candidate declines to answer (NaN).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from gonio.errors import GonioError
from gonio.reconstruct import testset
from gonio.reconstruct.metrics import METRICS, REGIONS, Scores, region_masks, scores
from gonio.reconstruct.result import values_and_support
from gonio.reconstruct.testset import TestSet
from gonio.reconstruct.truth import Candidate, Truth
from gonio.rig.model import Rig
from gonio.types import BoolArray, BrdfEval, FloatArray

#: The row of every pair, before the regions.
ALL = "all"
#: Column headings of the table, per metric.
HEADINGS = {
    "log_rmse": "log-RMSE",
    "cos_log_rmse": "cos log-RMSE",
    "rel_rmse": "rel RMSE",
    "rel_median": "rel median",
    "rel_p95": "rel p95",
}


@dataclass(frozen=True)
class RegionResult:
    """One region's pairs, the candidate's coverage of them and its scores."""

    pairs: int
    coverage: float | None  # None: no pair
    scores: Scores

    def to_json(self) -> dict[str, Any]:
        scored = self.scores.to_json()
        scored["scored"] = scored.pop("count")
        return {"pairs": self.pairs, "coverage": self.coverage, **scored}


@dataclass(frozen=True)
class Evaluation:
    """A candidate's scores: ``regions`` maps "all" and each region of
    `gonio.reconstruct.metrics.REGIONS` to its `RegionResult`."""

    candidate: str
    truth: str
    test_pairs: int
    seed: int
    regions: dict[str, RegionResult]

    def to_json(self) -> dict[str, Any]:
        return {
            "candidate": self.candidate,
            "truth": self.truth,
            "test_set": {"pairs": self.test_pairs, "seed": self.seed},
            "regions": {name: r.to_json() for name, r in self.regions.items()},
        }

    def table(self) -> str:
        """The scores as a text table, one row per region (— for an empty one)."""
        heads = ["region", "pairs", "coverage", *(HEADINGS[m] for m in METRICS)]
        rows = [
            [
                name,
                str(r.pairs),
                "—" if r.coverage is None else f"{100 * r.coverage:.1f} %",
                *(_number(getattr(r.scores, m)) for m in METRICS),
            ]
            for name, r in self.regions.items()
        ]
        widths = [max(len(row[j]) for row in [heads, *rows]) for j in range(len(heads))]
        lines = [
            f"{self.candidate} vs {self.truth}",
            f"test set: {self.test_pairs} pairs (seed {self.seed}), uniform in dωi dωo over "
            "what the rig measures",
        ]
        for row in [heads, *rows]:
            cells = [c.rjust(w) for c, w in zip(row, widths, strict=True)]
            cells[0] = row[0].ljust(widths[0])
            lines.append("  ".join(cells).rstrip())
        return "\n".join(lines)


def _number(value: float | None) -> str:
    return "—" if value is None else f"{value:.4g}"


def evaluate(
    candidate: Candidate,
    truth: Truth | BrdfEval,
    rig: Rig,
    *,
    isotropic: bool,
    test_set: TestSet | None = None,
    candidate_label: str = "candidate",
) -> Evaluation:
    """Score ``candidate`` against ``truth`` (a `Truth`, or any f(wi, wo)) on
    ``test_set`` (default: `gonio.reconstruct.testset.draw` of ``rig`` with
    ``isotropic`` as the run was planned); see the module docstring."""
    if not isinstance(truth, Truth):
        truth = Truth("truth", truth)
    pairs = test_set if test_set is not None else testset.draw(rig, isotropic=isotropic)
    wi, wo = pairs.wi, pairs.wo
    t = np.asarray(truth.eval(wi, wo), dtype=np.float64)
    defined = _finite_rows(t)
    if truth.supported is not None:
        defined &= np.asarray(truth.supported(wi, wo), dtype=np.bool_)
    wi, wo, t = wi[defined], wo[defined], t[defined]
    c, mask = values_and_support(candidate, wi, wo)
    c, t = _matched(c, t, candidate_label, truth.label)
    supported: BoolArray = np.ones(len(wi), dtype=np.bool_) if mask is None else mask
    answered = _finite_rows(c)
    masks = {ALL: np.ones(len(wi), dtype=np.bool_), **region_masks(wi, wo)}
    regions = {}
    for name, mask in masks.items():
        used = mask & answered
        count = int(np.count_nonzero(mask))
        regions[name] = RegionResult(
            pairs=count,
            coverage=float(np.mean(supported[mask])) if count else None,
            scores=scores(c[used], t[used], wi[used, 2]),
        )
    return Evaluation(candidate_label, truth.label, len(pairs), pairs.seed, regions)


def _finite_rows(values: FloatArray) -> BoolArray:
    finite = np.isfinite(values).reshape(len(values), -1)
    return np.asarray(finite.all(axis=1), dtype=np.bool_)


def _matched(
    c: FloatArray, t: FloatArray, candidate: str, truth: str
) -> tuple[FloatArray, FloatArray]:
    """Candidate and truth values of one shape: a one-channel truth is compared with each
    channel of an RGB candidate; an RGB truth with a one-channel candidate is an error."""
    if c.shape == t.shape:
        return c, t
    if t.ndim == 1 and c.ndim == 2 and len(t) == len(c):
        return c, np.broadcast_to(t[:, None], c.shape)
    raise GonioError(
        f"{candidate} gives values of shape {c.shape[1:] or 'one channel'} but {truth} "
        f"gives {t.shape[1:] or 'one channel'}; compare RGB with RGB"
    )


__all__ = ["REGIONS", "Evaluation", "RegionResult", "evaluate"]
