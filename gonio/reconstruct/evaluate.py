"""A reconstruction scored against a truth on the fixed test set, overall and by region
(docs/explanations/evaluation.md): `evaluate` returns an `Evaluation` (JSON, a table).

Which pairs count: the test set's pairs where the truth is defined (finite, and inside
its ``supported`` mask when the truth is itself a reconstruction). Of those, a region
reports how many it holds (``pairs``), the fraction the candidate supports
(``coverage``: its ``supported`` mask, 1 for a candidate without one) and the metrics
over every one of them: a pair outside the candidate's support is scored with the value
its fill gives there (a reconstruction's ``extrapolate``), and a candidate that declines
a pair (NaN) is an error. ``only_supported=True`` scores the supported pairs only.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Final

import numpy as np

from gonio.errors import GonioError
from gonio.reconstruct import testset
from gonio.reconstruct.metrics import METRICS, REGIONS, Scores, region_masks, scores
from gonio.reconstruct.result import values_and_support
from gonio.reconstruct.testset import TestSet
from gonio.reconstruct.truth import Candidate, Truth
from gonio.rig import Rig
from gonio.types import BoolArray, BrdfEval, FloatArray

#: The row of every pair, before the regions.
ALL = "all"
#: The fill of a reconstruction scored on every pair unless another is named
#: (`gonio.reconstruct.result.Reconstruction._nearby`): the CLI's and the sweep files'
#: default.
DEFAULT_FILL: Final = "nearest"
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
    `gonio.reconstruct.metrics.REGIONS` to its `RegionResult`; ``only_supported``: only
    the supported pairs were scored; ``fill``: what the candidate answers outside its
    support (None: it says nothing of it, or supports every pair)."""

    candidate: str
    truth: str
    test_pairs: int
    seed: int
    regions: dict[str, RegionResult]
    only_supported: bool = False
    fill: str | None = None

    @property
    def scored(self) -> str:
        """Which pairs the scores are over, in words."""
        if self.only_supported:
            return "the pairs inside the support only"
        if self.fill is None:
            return "every pair"
        return f"every pair (outside the support: {self.fill} fill)"

    def to_json(self) -> dict[str, Any]:
        return {
            "candidate": self.candidate,
            "truth": self.truth,
            "test_set": {"pairs": self.test_pairs, "seed": self.seed},
            "only_supported": self.only_supported,
            "fill": self.fill,
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
            f"scored: {self.scored}; coverage: the share inside the support",
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
    only_supported: bool = False,
) -> Evaluation:
    """Score ``candidate`` against ``truth`` on a test set; see the module docstring.

    Parameters
    ----------
    candidate : Candidate
        Anything with ``eval(wi, wo)`` (sr⁻¹), optionally ``supported(wi, wo)`` and
        ``extrapolate`` (its fill outside the support, stated in the result).
    truth : Truth or callable
        A `Truth`, or any f(wi, wo) in sr⁻¹.
    rig : Rig
        The rig whose measurable pairs the default test set is drawn from.
    isotropic : bool
        As the run was planned.
    test_set : TestSet, optional
        Default: `gonio.reconstruct.testset.draw` of ``rig``.
    candidate_label : str
        The candidate's name in the result.
    only_supported : bool
        Score only the pairs the candidate supports (default: every pair).

    Returns
    -------
    Evaluation
        The scores overall and by region; `GonioError` (one line) when the candidate
        declines (NaN) a pair it is to be scored on.
    """
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
    due = supported if only_supported else np.ones(len(wi), dtype=np.bool_)
    declined = due & ~answered
    if declined.any():
        outside = bool((declined & ~supported).any())
        raise GonioError(
            f"{candidate_label} has no value at {np.count_nonzero(declined)} of {len(wi)} "
            f"test pairs ({'outside' if outside else 'inside'} its support); "
            + (
                f"give it a fill (extrapolate={DEFAULT_FILL!r}) or score the supported pairs only"
                if outside
                else "expected a value at every pair it supports"
            )
        )
    fill = getattr(candidate, "extrapolate", None)
    masks = {ALL: np.ones(len(wi), dtype=np.bool_), **region_masks(wi, wo)}
    regions = {}
    for name, mask in masks.items():
        used = mask & supported if only_supported else mask
        count = int(np.count_nonzero(mask))
        regions[name] = RegionResult(
            pairs=count,
            coverage=float(np.mean(supported[mask])) if count else None,
            scores=scores(c[used], t[used], wi[used, 2]),
        )
    return Evaluation(
        candidate_label,
        truth.label,
        len(pairs),
        pairs.seed,
        regions,
        only_supported=only_supported,
        fill=None if fill is None or bool(supported.all()) else str(fill),
    )


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


__all__ = ["DEFAULT_FILL", "REGIONS", "Evaluation", "RegionResult", "evaluate"]
