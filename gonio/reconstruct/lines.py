"""Line data and the ``lines`` reconstruction (docs/explanations/reconstruction.md#line-data).

A fly plan's readings lie on lines: along the first coordinate of the scaled space (θh
in Rusinkiewicz's coordinates), densely, at fixed values of the others (θd, φd), the
lines' *positions*, spread coarsely. Found from coordinates alone (`line_labels`:
samples whose positions agree within `LINE_TOLERANCE` lie on one line) or given as a
label per sample.

`Lines` interpolates such data as it was measured: along each line piecewise linearly
in the first coordinate (the line mirrored through a pole at 0, as the space's seam
there requires), then across lines at the query's first coordinate: a thin-plate spline
with an affine part through the `SPLINE_LINES` lines nearest the query's position (a
line that does not reach that coordinate takes no part), or, where fewer than d + 1 of
them reach it, linearly on the Delaunay triangulation of the lines' positions (the
corners that reach it, their weights renormalized); the positions are padded across the
seams. The weights are linear in the table, so the same weights carry the values and
their σ; both stages reproduce what is linear along lines and affine across them, and
the samples themselves. A query is answered inside the positions' hull where the spline
or a corner line answers, elsewhere by a fallback interpolant (the ``lines`` method's:
``rbf`` stretched as on line data), within the support distance of line data. Samples
off every line (stop-and-go targets of a mixed plan) take no part in the lines.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import Delaunay, QhullError, cKDTree

from gonio.errors import GonioError
from gonio.reconstruct.coordinates import Space
from gonio.reconstruct.interpolants import Interpolant
from gonio.types import BoolArray, FloatArray

#: The coordinate lines run along (the first: θh, the half vector's polar angle).
ALONG = 0
#: Samples whose positions (the other coordinates) agree within this many scaled units
#: lie on one line (0.18° in θd, 0.36° in φd).
LINE_TOLERANCE = 2e-3
#: A line holds at least this many samples; fewer are scattered samples.
MIN_LINE_SAMPLES = 4
#: Data have line structure when at least this share of the samples lie on lines …
MIN_LINE_SHARE = 0.5
#: … of which there are at least this many (a triangle's corners, and one more).
MIN_LINES = 4
#: Lines are line data (the first coordinate stretched for ``rbf``, the support widened)
#: when their spacing is at least this many steps along them (a grid's lines are not).
MIN_ELONGATION = 3.0
#: Line data support a query within this many lines' spacings of a sample.
LINE_REACH = 2.0
#: Lines' positions are padded across the seams this many typical line spacings deep …
PAD_LINES = 2.0
#: … but at most this deep (scaled units).
MAX_PAD = 0.25
#: Lines (nearest by position) each query's thin-plate spline across lines goes through.
SPLINE_LINES = 12
#: The smoothing (in the kernel's units) that takes a line not reaching a query out of
#: its spline.
_ABSENT = 1e9
#: Neighbours of a position joined to it when grouping samples into lines.
_GROUP_NEIGHBOURS = 16


@dataclass(frozen=True)
class LineSet:
    """Samples grouped into lines: ``labels`` (N,) the line of each sample (−1: on none),
    ``positions`` (L, d − 1) each line's mean position, ``counts`` (L,) its samples."""

    labels: np.ndarray
    positions: FloatArray
    counts: np.ndarray

    def __len__(self) -> int:
        return len(self.positions)

    @property
    def share(self) -> float:
        """The share of the samples that lie on a line."""
        return float(np.mean(self.labels >= 0)) if len(self.labels) else 0.0

    @property
    def structured(self) -> bool:
        """Enough lines holding enough of the samples (`MIN_LINES`, `MIN_LINE_SHARE`)."""
        return len(self) >= MIN_LINES and self.share >= MIN_LINE_SHARE

    def describe(self) -> str:
        return (
            f"{len(self)} lines of at least {MIN_LINE_SAMPLES} samples holding "
            f"{100 * self.share:.0f} % of them"
        )

    def spacings(self, x: FloatArray) -> tuple[float, float]:
        """The median step along a line and the median distance from a line's position
        to the nearest other line's (scaled units) of the samples ``x`` (N, d)."""
        on = self.labels >= 0
        order = np.lexsort((x[on, ALONG], self.labels[on]))
        t, line = x[on, ALONG][order], self.labels[on][order]
        steps = np.diff(t)[np.diff(line) == 0]
        steps = steps[steps > 0]
        along = float(np.median(steps)) if len(steps) else 1.0
        if len(self) < 2:
            return along, 1.0
        distance, _ = cKDTree(self.positions).query(self.positions, k=2)
        return along, float(np.median(np.asarray(distance)[:, 1]))


def line_labels(x: FloatArray, tolerance: float = LINE_TOLERANCE) -> np.ndarray:
    """The line of each scaled sample (N, d) found from its coordinates: samples whose
    positions (every coordinate but the first) lie within ``tolerance`` of each other,
    directly or through others, form a line; a line of fewer than `MIN_LINE_SAMPLES`
    is none (−1). Labels are 0 … L − 1 in the order of each line's first sample."""
    n = len(x)
    if n == 0:
        return np.zeros(0, dtype=np.intp)
    across = np.delete(np.asarray(x, dtype=np.float64), ALONG, axis=1)
    # Positions that round to one cell of a quarter tolerance are one (exact lines: one
    # position each), then cells within the tolerance are joined.
    cell = np.round(across / (0.25 * tolerance)).astype(np.int64)
    _, first, inverse = np.unique(cell, axis=0, return_index=True, return_inverse=True)
    inverse = inverse.ravel()
    distinct = across[first]
    k = min(_GROUP_NEIGHBOURS, len(distinct))
    distance, near = cKDTree(distinct).query(distinct, k=k, distance_upper_bound=tolerance)
    distance = np.asarray(distance).reshape(len(distinct), k)
    near = np.asarray(near).reshape(len(distinct), k)
    joined = np.isfinite(distance)
    rows = np.repeat(np.arange(len(distinct)), k)[joined.ravel()]
    graph = coo_matrix(
        (np.ones(len(rows)), (rows, near[joined])), shape=(len(distinct), len(distinct))
    )
    _, component = connected_components(graph, directed=False)
    labels = component[inverse]
    counts = np.bincount(labels)
    labels = np.where(counts[labels] >= MIN_LINE_SAMPLES, labels, -1)
    return _renumbered(labels)


def line_set(x: FloatArray, labels: np.ndarray | None = None) -> LineSet:
    """The lines of the scaled samples ``x`` (N, d): from ``labels`` (N,) when given
    (negative: on no line; a line of fewer than `MIN_LINE_SAMPLES` is none), else found
    by `line_labels`."""
    if labels is None:
        found = line_labels(x)
    else:
        given = np.asarray(labels)
        if given.shape != (len(x),) or not np.issubdtype(given.dtype, np.integer):
            raise GonioError(
                f"line labels: expected one integer per sample ({len(x)}), got shape "
                f"{given.shape} of {given.dtype}"
            )
        _, dense = np.unique(np.where(given < 0, -1, given), return_inverse=True)
        dense = dense.ravel() - (1 if (given < 0).any() else 0)
        counts = np.bincount(dense[dense >= 0], minlength=1)
        found = np.where(
            (dense >= 0) & (counts[np.maximum(dense, 0)] >= MIN_LINE_SAMPLES), dense, -1
        )
        found = _renumbered(found)
    on = found >= 0
    lines = int(found.max()) + 1 if on.any() else 0
    counts = np.bincount(found[on], minlength=lines)
    across = np.delete(np.asarray(x, dtype=np.float64), ALONG, axis=1)
    positions = np.zeros((lines, across.shape[1]))
    for axis in range(across.shape[1]):  # a short loop over coordinates
        positions[:, axis] = np.bincount(found[on], weights=across[on, axis], minlength=lines)
    positions /= np.maximum(counts, 1)[:, None]
    return LineSet(found, positions, counts)


def dense_lines(x: FloatArray, lines: LineSet) -> tuple[float, float] | None:
    """(step along a line, spacing of lines) of the samples ``x`` (N, d) when their
    ``lines`` make them line data (structured, spaced `MIN_ELONGATION` steps or more);
    None otherwise."""
    if not lines.structured:
        return None
    along, across = lines.spacings(x)
    return (along, across) if across >= MIN_ELONGATION * along else None


def _renumbered(labels: np.ndarray) -> np.ndarray:
    """Labels ≥ 0 renumbered 0 … L − 1 in the order of their first sample; −1 kept."""
    out = np.full(len(labels), -1, dtype=np.intp)
    on = labels >= 0
    if on.any():
        _, first, inverse = np.unique(labels[on], return_index=True, return_inverse=True)
        rank = np.empty(len(first), dtype=np.intp)
        rank[np.argsort(first, kind="stable")] = np.arange(len(first))
        out[on] = rank[inverse.ravel()]
    return out


class Lines(Interpolant):
    """Interpolation of line data: along each line, then across lines (module doc).

    ``x`` (N, d) the scaled samples, ``table`` (N, K) their columns, ``lines`` their
    `LineSet` (structured), ``space`` the space they are in (its seams); ``fallback``
    answers the queries the lines do not (e.g. beyond a line's end).
    """

    def __init__(
        self,
        x: FloatArray,
        table: FloatArray,
        lines: LineSet,
        space: Space,
        fallback: Interpolant | None = None,
    ) -> None:
        check_space(space)
        self.fallback = fallback
        on = lines.labels >= 0
        t, label, rows = x[on, ALONG], lines.labels[on], np.asarray(table, dtype=np.float64)[on]
        if _mirrors_along(space):
            # The pole at 0 of the first coordinate: (−t, position) is (t, position).
            up = t > 0.0
            t, label = np.concatenate([t, -t[up]]), np.concatenate([label, label[up]])
            rows = np.concatenate([rows, rows[up]])
        order = np.lexsort((t, label))
        self.t, self.label, self.table = t[order], label[order], rows[order]
        n = len(lines)
        self.start = np.searchsorted(self.label, np.arange(n), side="left")
        self.end = np.searchsorted(self.label, np.arange(n), side="right")  # one past the last
        self.low, self.high = self.t[self.start], self.t[self.end - 1]
        span = float(np.max(np.abs(self.t))) + 1.0
        #: Offsets that make (line, t) one sorted key: line × stride + t.
        self.stride = 2.0 * span + 1.0
        self.key = self.label * self.stride + self.t
        _, spacing = lines.spacings(x)
        self.margin = min(PAD_LINES * spacing, MAX_PAD)
        positions = lines.positions
        dummy = np.full((n, 1), 0.5)  # a first coordinate clear of its pole
        full = np.insert(positions, ALONG, dummy[:, 0], axis=1)
        padded = space.pad(full, self.margin)
        self.corner_line = padded.source
        across = np.delete(padded.points, ALONG, axis=1)
        self.positions_tree = cKDTree(across)
        self.neighbours = min(SPLINE_LINES, len(across))
        self.scale = spacing
        try:
            self.tri = Delaunay(across)
        except QhullError:
            raise GonioError(
                f"method 'lines': the {n} lines' positions span no region of the other "
                "coordinates; expected lines spread across them"
            ) from None

    def __call__(self, x: FloatArray, nearest: np.ndarray) -> tuple[FloatArray, BoolArray]:
        a = np.delete(x, ALONG, axis=1)
        t = x[:, ALONG]
        simplex = self.tri.find_simplex(a)
        inside = simplex >= 0
        s = np.where(inside, simplex, 0)
        transform = self.tri.transform[s]  # (M, d', d' + 1 rows) scipy's public layout
        dims = a.shape[1]
        bary = np.empty((len(x), dims + 1))
        bary[:, :dims] = np.einsum("mij,mj->mi", transform[:, :dims, :], a - transform[:, dims, :])
        bary[:, dims] = 1.0 - bary[:, :dims].sum(axis=1)
        bary = np.clip(bary, 0.0, None)
        line = self.corner_line[self.tri.simplices[s]]  # (M, d' + 1)
        values, reached = self._along(line, np.broadcast_to(t[:, None], line.shape))
        weight = np.where(reached & inside[:, None], bary, 0.0)
        total = weight.sum(axis=1)
        defined = inside & (total > 0.0)
        weight = weight / np.where(total > 0.0, total, 1.0)[:, None]
        out = np.einsum("mv,mvk->mk", weight, values)
        rows = np.flatnonzero(inside)
        if self.neighbours > dims + 1 and len(rows):
            spline, solved = self._spline(a[rows], t[rows])
            out[rows[solved]] = spline[solved]
            defined[rows[solved]] = True
        rest = np.flatnonzero(~defined)
        if self.fallback is not None and len(rest):
            out[rest], defined[rest] = self.fallback(x[rest], nearest[rest])
        return np.where(defined[:, None], out, np.nan), np.asarray(defined, dtype=np.bool_)

    def _spline(self, a: FloatArray, t: FloatArray) -> tuple[FloatArray, BoolArray]:
        """The thin-plate spline (with an affine part) through the `SPLINE_LINES` lines
        nearest each query's position (M, d'), each read at its first coordinate t (M,);
        a line that does not reach t takes no part (its point gets a smoothing of
        `_ABSENT`). Solved where at least d' + 2 of them reach t."""
        distance, index = self.positions_tree.query(a, k=self.neighbours)
        line = self.corner_line[index]  # (M, k)
        values, reached = self._along(line, np.broadcast_to(t[:, None], line.shape))
        m, k, dims = len(a), self.neighbours, a.shape[1]
        solved = reached.sum(axis=1) >= dims + 2
        local = (self.tri.points[index] - a[:, None, :]) / self.scale  # (M, k, d')
        gap = np.linalg.norm(local[:, :, None, :] - local[:, None, :, :], axis=-1)
        system = np.zeros((m, k + dims + 1, k + dims + 1))
        system[:, :k, :k] = _tps(gap)
        system[:, np.arange(k), np.arange(k)] += np.where(reached, 0.0, _ABSENT)
        system[:, :k, k] = system[:, k, :k] = 1.0
        system[:, :k, k + 1 :] = local
        system[:, k + 1 :, :k] = np.transpose(local, (0, 2, 1))
        rhs = np.zeros((m, k + dims + 1, values.shape[2]))
        rhs[:, :k] = np.where(reached[:, :, None], values, 0.0)
        system[~solved] = np.eye(k + dims + 1)  # left to the linear interpolation
        coefficients = np.linalg.solve(system, rhs)
        at_query = _tps(np.asarray(distance) / self.scale)  # (M, k): kernel to the query
        out = np.einsum("mk,mkc->mc", at_query, coefficients[:, :k]) + coefficients[:, k]
        return out, np.asarray(solved & np.isfinite(out).all(axis=1), dtype=np.bool_)

    def _along(self, line: np.ndarray, t: FloatArray) -> tuple[FloatArray, BoolArray]:
        """The columns (..., K) of each ``line`` (...) at first coordinates ``t`` (...),
        piecewise linear between its samples, and where the line reaches t."""
        reached = (t >= self.low[line]) & (t <= self.high[line])
        j = np.searchsorted(self.key, line * self.stride + t, side="right")
        j = np.clip(j, self.start[line] + 1, self.end[line] - 1)
        t0, t1 = self.t[j - 1], self.t[j]
        step = t1 - t0
        w = np.clip(np.where(step > 0, (t - t0) / np.where(step > 0, step, 1.0), 0.5), 0.0, 1.0)
        values = (1.0 - w)[..., None] * self.table[j - 1] + w[..., None] * self.table[j]
        return values, np.asarray(reached, dtype=np.bool_)


def _tps(r: FloatArray) -> FloatArray:
    """The thin-plate kernel r² ln r (0 at r = 0)."""
    safe = np.where(r > 0.0, r, 1.0)
    return np.asarray(np.where(r > 0.0, r * r * np.log(safe), 0.0), dtype=np.float64)


def check_space(space: Space) -> None:
    """`GonioError` (one line) for a space lines cannot run in: one whose seams move the
    first coordinate (a reciprocal copy, an azimuth along the line), or fewer than two
    other coordinates."""
    periodic = {axis for axis, _ in space.periods}
    shifted = {axis for _, shifts in space.poles for axis, _ in shifts}
    if space.reciprocal_copies or ALONG in periodic | shifted or space.dims < 3:
        raise GonioError(
            f"method 'lines': lines along {space.names[ALONG]} are not lines of "
            f"{'isotropic ' if space.isotropic else ''}{space.parametrization!r} coordinates "
            "(a seam moves it); expected rusinkiewicz, hybrid or orthographic"
        )


def _mirrors_along(space: Space) -> bool:
    """The first coordinate has a pole at 0 that moves no other coordinate."""
    return any(radial == ALONG and not shifts for radial, shifts in space.poles)


def refuse_lines(method: str, lines: LineSet) -> GonioError:
    """The one-line refusal of ``method`` for samples without line structure."""
    return GonioError(
        f"method {method!r} needs samples on lines along the first coordinate at fixed "
        f"others (a fly plan's sweeps); these have {lines.describe()}"
    )
