"""A reconstruction's error against a truth over the domain, and by region: the pairs of
the fixed test set (`gonio.reconstruct.testset`, what `gonio evaluate` scores), the
log error e = ln(1 + c⁺) − ln(1 + t⁺) of each (c: the reconstruction, t: the truth, in
sr⁻¹), its RMS in bins of the plan's isotropic coordinates (two maps: the first
coordinate against the second and against the third), and the scores of each region
(`gonio.reconstruct.metrics.REGIONS`) as bars.

Pairs where the truth is not finite, or the reconstruction declines to answer (NaN),
are left out; `gonio plot --kind error` gives the reconstruction the fill `gonio
evaluate` gives it, so that every pair is scored as there. An empty bin is masked
(white).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.stats import binned_statistic_2d

from gonio import params
from gonio.plots import (
    Surface,
    drawn,
    label,
    one_channel,
    require_matplotlib,
    save,
    supported,
    values,
)
from gonio.reconstruct import REGIONS, Scores, TestSet, region_masks, scores
from gonio.types import BoolArray, BrdfEval, FloatArray

#: Bins per axis of the maps.
BINS = 24
#: The figure's size (inches).
FIGSIZE = (16.0, 5.0)
#: The coordinate pairs of the two maps.
MAPS = ((0, 1), (0, 2))


@dataclass(frozen=True)
class ErrorMap:
    """The RMS log error (``x_bins`` × ``y_bins`` bins, masked where empty; row i is the
    i-th bin of coordinate ``axes[0]``) over two of the isotropic coordinates."""

    axes: tuple[int, int]
    x_edges: FloatArray
    y_edges: FloatArray
    rms: np.ma.MaskedArray


@dataclass(frozen=True)
class Errors:
    """The test pairs used (N), their isotropic ``coords`` (N, 3) in ``parametrization``,
    the reconstruction's and the truth's values, the log error, where the reconstruction
    has data, the region of each pair (an index into `REGIONS`), the two maps and the
    scores of "all" and of each region."""

    wi: FloatArray
    wo: FloatArray
    coords: FloatArray
    names: tuple[str, str, str]
    bounds: FloatArray
    candidate: FloatArray
    truth: FloatArray
    log_error: FloatArray
    supported: BoolArray
    region: np.ndarray
    maps: list[ErrorMap]
    scores: dict[str, Scores]
    parametrization: str
    title: str


def errors(
    surface: Surface,
    truth: BrdfEval,
    test_set: TestSet,
    parametrization: str,
    *,
    truth_supported: BoolArray | None = None,
    title: str = "",
) -> Errors:
    """The errors of ``surface`` against ``truth`` on ``test_set`` (see the module
    docstring), mapped in ``parametrization``'s isotropic coordinates;
    ``truth_supported``: where a truth that is itself a reconstruction is defined."""
    wi, wo = test_set.wi, test_set.wo
    t = one_channel(truth(wi, wo))
    keep = np.isfinite(t)
    if truth_supported is not None:
        keep &= truth_supported
    wi, wo, t = wi[keep], wo[keep], t[keep]
    c = values(surface, wi, wo)
    answered = np.isfinite(c)
    wi, wo, t, c = wi[answered], wo[answered], t[answered], c[answered]
    log_error = np.log1p(np.maximum(c, 0.0)) - np.log1p(np.maximum(t, 0.0))
    masks = region_masks(wi, wo)
    region = np.zeros(len(wi), dtype=np.intp)
    for i, name in enumerate(REGIONS):
        region[masks[name]] = i
    by_region = {"all": scores(c, t, wi[:, 2])}
    by_region |= {name: scores(c[m], t[m], wi[m, 2]) for name, m in masks.items()}
    p = params.get(parametrization)
    coords = p.forward_iso(wi, wo)
    bounds = np.asarray(p.iso_bounds, dtype=np.float64)
    maps = [_map(coords, log_error, bounds, axes) for axes in MAPS]
    return Errors(
        wi=wi, wo=wo, coords=coords, names=p.iso_names, bounds=bounds, candidate=c, truth=t,
        log_error=log_error, supported=supported(surface, wi, wo), region=region, maps=maps,
        scores=by_region, parametrization=p.name, title=title,
    )  # fmt: skip


def _map(
    coords: FloatArray, log_error: FloatArray, bounds: FloatArray, axes: tuple[int, int]
) -> ErrorMap:
    a, b = axes
    mean_square, x_edges, y_edges, _ = binned_statistic_2d(
        coords[:, a],
        coords[:, b],
        np.square(log_error),
        statistic="mean",
        bins=BINS,
        range=[bounds[a], bounds[b]],
    )
    rms = np.ma.masked_invalid(np.sqrt(mean_square))
    return ErrorMap(axes, np.asarray(x_edges), np.asarray(y_edges), rms)


def draw(data: Errors, path: str | Path, *, format: str | None = None) -> None:
    """Draw ``data`` to ``path``: the two maps on one colour scale, then the regions'
    log-RMSE as bars, each with its pairs and the reconstruction's coverage."""
    plt = require_matplotlib()
    fig, axes = plt.subplots(1, 3, figsize=FIGSIZE, constrained_layout=True)
    top = max((float(m.rms.max()) for m in data.maps if m.rms.count()), default=1.0)
    image = None
    for m, ax in zip(data.maps, axes[:2], strict=True):
        a, b = m.axes
        x, y = drawn(data.names[a], m.x_edges), drawn(data.names[b], m.y_edges)
        image = ax.pcolormesh(x, y, m.rms.T, cmap="inferno", vmin=0.0, vmax=top)
        ax.set_xlabel(label(data.names[a]))
        ax.set_ylabel(label(data.names[b]))
        ax.set_title(f"RMS log error over {data.parametrization} coordinates")
    if image is not None:
        fig.colorbar(image, ax=axes[:2], label="RMS of ln(1 + c) − ln(1 + t)", shrink=0.9)
    names = ["all", *REGIONS]
    heights = [data.scores[n].log_rmse or 0.0 for n in names]
    bars = axes[2].bar(names, heights, color=["0.3", "#fdae6b", "#6baed6", "#9e9ac8", "#74c476"])
    for i, bar in enumerate(bars):
        mask = np.ones(len(data.region), bool) if i == 0 else data.region == i - 1
        count = int(np.count_nonzero(mask))
        cover = f"{100 * np.mean(data.supported[mask]):.0f} %" if count else "—"
        top_centre = (bar.get_x() + bar.get_width() / 2, bar.get_height())
        axes[2].annotate(
            f"{count} pairs\ncoverage {cover}", top_centre, ha="center", va="bottom", fontsize=8
        )
    axes[2].set_ylabel("log-RMSE")
    axes[2].set_ylim(0.0, max(heights, default=0.0) * 1.3 + 1e-6)
    axes[2].set_title("by region (gonio evaluate's metric)")
    fig.suptitle(data.title)
    save(fig, path, format)
