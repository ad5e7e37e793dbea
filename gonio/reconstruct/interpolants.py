"""Interpolants of scattered samples in the scaled coordinate space.

An interpolant is built from points (P, d) and a table (P, K) of columns (the
transformed values and their uncertainties, channel by channel) and, called on
queries (M, d) with the index of each one's nearest point (M,), returns the
interpolated table (M, K) and where it is defined (M,).
Both are linear in the table, so the same weights carry the values and their σ.

- `Linear`: piecewise linear on the Delaunay triangulation (barycentric weights).
- `Rbf`: scipy's RBFInterpolator, thin-plate spline plus a linear polynomial, on the
  ``neighbors`` nearest samples of each query.
The grid interpolant lives in `gonio.reconstruct.grid`.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from functools import cached_property

import numpy as np
from scipy.interpolate import RBFInterpolator
from scipy.spatial import ConvexHull, Delaunay

from gonio.errors import GonioError
from gonio.types import BoolArray, FloatArray

#: A simplex whose |det| is below this fraction of the product of its edge lengths
#: (Hadamard's bound) is flat: no barycentric coordinates, never "containing" a query.
FLAT_SIMPLEX = 1e-10
#: Barycentric coordinates down to −`INSIDE` count as inside a simplex (scipy's eps).
INSIDE = 100 * float(np.finfo(np.float64).eps)
#: ... and down to −`BROAD` for a query that would leave the hull (scipy's eps_broad).
BROAD = float(np.sqrt(INSIDE))
#: Steps of the vectorized walk before the queries still walking are judged by the
#: hull's facets (`Linear.outside`) and the rest searched for (`Linear.search`).
MAX_STEPS = 64
#: The face a walk leaves a flat simplex by, step by step, when no face is on the
#: query's side (`Linear._leave_flat`): fixed random turns, the same for every query
#: (its answer does not depend on its batch) and out of step with any short cycle.
FLAT_TURNS = np.random.default_rng(0).integers(0, 1 << 16, MAX_STEPS)
#: Queries × simplices whose coordinates that search holds at once, one axis at a time.
SEARCH_BLOCK = 1 << 16
#: Neighbours of each query the ``rbf`` method solves with (scipy's ``neighbors``).
RBF_NEIGHBORS = 32
#: An ``rbf`` value farther than this many half-ranges of the samples' columns from
#: their middle is the sign of an ill-conditioned solve (a spline through the samples
#: stays within a few; in log f, 10 half-ranges of a glossy run's are e^±80).
RBF_RANGE = 10.0


class Interpolant(ABC):
    """Interpolated columns (M, K) and the defined mask (M,) at scaled points (M, d),
    given the index of each one's nearest point (M,)."""

    @abstractmethod
    def __call__(self, x: FloatArray, nearest: np.ndarray) -> tuple[FloatArray, BoolArray]: ...


class Linear(Interpolant):
    """Piecewise-linear interpolation on the Delaunay triangulation of the points.

    Two costs of scipy's ``find_simplex`` are avoided (docs/explanations/reconstruction.md#speed):
    it computes the simplices' barycentric transforms one at a time with a condition
    estimate each (5 s for the 130 000 simplices of 20 000 points in 3-D, 19 s in
    4-D; here one batched inverse, `barycentric_transforms`, from the triangulation's
    public ``points`` and ``simplices``), and its walk starts from the previous query's
    simplex and falls back to a search of every simplex when it meets a flat one
    (exact seam copies and grids make cospherical points, hence flat simplices): 4.5 s
    per 100 000 queries. Here all queries walk at once (`locate`), each from the most
    regular simplex of its nearest sample, and leave a flat simplex toward the side of
    its hyperplane the query is on; a query not arrived after `MAX_STEPS` is outside
    the hull if it lies beyond a facet of it (`outside`), else searched for in every
    simplex (`search`).
    """

    def __init__(self, points: FloatArray, table: FloatArray) -> None:
        self.table = np.asarray(table, dtype=np.float64)
        self.tri = Delaunay(points)
        #: (S, d + 1, d): the layout of scipy's ``Delaunay.transform``, computed here.
        self.transform, regular = transforms_and_regularity(self.tri.points, self.tri.simplices)
        #: (S,): simplices with no barycentric coordinates (`FLAT_SIMPLEX`).
        self.flat = np.isnan(self.transform[:, 0, 0])
        #: (P,): the most regular simplex each point is a vertex of (−1: none), where
        #: a walk from that point starts (a sliver's coordinates steer it badly).
        self.start = most_regular(self.tri.simplices, regular, len(self.tri.points))

    def __call__(self, x: FloatArray, nearest: np.ndarray) -> tuple[FloatArray, BoolArray]:
        simplex = self.locate(x, nearest)
        defined = simplex >= 0
        s = np.where(defined, simplex, 0)
        weights = self._barycentric(x, s)
        corners = np.take(self.table, np.take(self.tri.simplices, s, axis=0), axis=0)
        out = np.einsum("mv,mvk->mk", weights, corners)  # corners (M, d + 1, K)
        return np.where(defined[:, None], out, np.nan), np.asarray(defined, dtype=np.bool_)

    def _barycentric(self, x: FloatArray, s: np.ndarray) -> FloatArray:
        d = x.shape[1]
        # take copies whole rows, several times faster than transform[s] (which copies
        # the (d + 1) × d values one at a time): so below for every gather of rows.
        t = np.take(self.transform, s, axis=0)
        c = np.empty((len(s), d + 1))
        c[:, :d] = np.einsum("mij,mj->mi", t[:, :d, :], x - t[:, d, :])
        c[:, d] = 1.0
        for j in range(d):  # a short loop over axes: numpy's sum over a 3-long axis is slow
            c[:, d] -= c[:, j]
        return c

    def locate(self, x: FloatArray, nearest: np.ndarray) -> np.ndarray:
        """The simplex containing each query (−1 outside the hull), by a visibility walk
        from the most regular simplex of its nearest point: step across the face
        opposite the most negative barycentric coordinate until none is negative
        (inside) or that face is on the hull (outside: the hull is convex); out of a
        flat simplex as `_leave_flat` chooses. A query still walking after `MAX_STEPS`
        (a walk among slivers and flat simplices may circle) is outside if `outside`
        says so, else left to `search`. Each query walks on its own: its batch does not
        change where it arrives. The walking queries are kept packed (their points,
        simplices and rows), the arrived ones dropped at each step."""
        start = self.start[nearest]
        s = np.where(start >= 0, start, 0)  # the simplex of each walking query
        found = np.full(len(x), -1, dtype=np.intp)
        active = np.arange(len(x))  # the rows of the walking queries
        walking = x
        faces = self.tri.neighbors.shape[1]
        neighbors = self.tri.neighbors.ravel()
        for step in range(MAX_STEPS):
            c = self._barycentric(walking, s)
            flat = np.take(self.flat, s)
            # The lowest coordinate and the first axis holding it (np.argmin's), column
            # by column (a reduction over a 4-long axis is slow). A flat simplex's row
            # is NaN throughout (it has no coordinates).
            k = np.zeros(len(s), dtype=np.intp)
            lowest = c[:, 0]
            for axis in range(1, faces):
                k = np.where(c[:, axis] < lowest, axis, k)
                lowest = np.minimum(lowest, c[:, axis])
            if flat.any():
                k[flat] = self._leave_flat(walking[flat], s[flat], step)
            after = np.take(neighbors, s * faces + k)
            # At the hull a query may lean out by rounding (a sliver's coordinates carry
            # more): scipy's broad tolerance then decides. NaN (flat) is never inside.
            inside = ~flat & ((lowest >= -INSIDE) | ((after < 0) & (lowest >= -BROAD)))
            found[active[inside]] = s[inside]
            onward = ~inside & (after >= 0)
            onward |= flat & (after < 0)  # keep it: the next step picks another face
            s = np.compress(onward, np.where(after >= 0, after, s))
            walking = np.compress(onward, walking, axis=0)
            active = np.compress(onward, active)
            if len(active) == 0:
                break
        if len(active):
            active = active[~self.outside(x[active])]
        if len(active):
            found[active] = self.search(x[active])
        return found

    def _leave_flat(self, x: FloatArray, s: np.ndarray, step: int) -> np.ndarray:
        """The face to leave each flat simplex s (M,) by, for queries x (M, d): of the
        faces whose neighbour (not flat) lies on the query's side of the flat simplex's
        hyperplane (the query's coordinate at that neighbour's far vertex is positive),
        the one into the neighbour that holds the query deepest (largest lowest
        coordinate). Without one (a query in that hyperplane; neighbours flat or beyond
        the hull), the face `FLAT_TURNS` gives this step, the same for every query."""
        rows = np.arange(len(s))
        faces = self.tri.neighbors.shape[1]
        depth = np.full((len(s), faces), -np.inf)
        for j in range(faces):  # a short loop over the d + 1 faces
            n = self.tri.neighbors[s, j]
            usable = (n >= 0) & ~self.flat[np.maximum(n, 0)]
            n = np.where(usable, n, 0)
            c = self._barycentric(x, n)
            far = np.argmax(self.tri.neighbors[n] == s[:, None], axis=1)  # n's face toward s
            beyond = c[rows, far] > 0.0
            depth[:, j] = np.where(usable & beyond, np.min(c, axis=1), -np.inf)
        k = np.asarray(np.argmax(depth, axis=1), dtype=np.intp)
        k[np.isneginf(depth[rows, k])] = FLAT_TURNS[step % len(FLAT_TURNS)] % faces
        return k

    @cached_property
    def hull(self) -> FloatArray:
        """(F, d + 1): the facets of the points' convex hull, as scipy's public
        ``ConvexHull.equations`` (unit outward normal n and offset b, n·x + b > 0
        beyond the facet)."""
        return np.asarray(ConvexHull(self.tri.points).equations, dtype=np.float64)

    def outside(self, x: FloatArray) -> BoolArray:
        """True for queries (M, d) farther beyond a facet of the hull than
        d · `BROAD` times the diagonal of the points' bounding box: no simplex holds
        them within the walk's tolerances (a query whose coordinates in a simplex are
        all at least −`BROAD` lies within d · `BROAD` times its diameter of it), so
        `search` would not find one."""
        d = x.shape[1]
        diagonal = float(np.linalg.norm(self.tri.max_bound - self.tri.min_bound))
        beyond = x @ self.hull[:, :d].T + self.hull[:, d]
        return np.asarray(np.max(beyond, axis=1) > d * BROAD * diagonal, dtype=np.bool_)

    def search(self, x: FloatArray) -> np.ndarray:
        """The simplex each query (M, d) is deepest in, among every simplex (−1 outside
        the hull): the one whose lowest barycentric coordinate is largest, taken if that
        coordinate is at least −`INSIDE`, or −`BROAD` across a face on the hull or shared
        with a flat simplex (the walk's tolerances). Flat simplices contain nothing.
        Costs M × S coordinates: for the few queries the walk leaves inside the hull."""
        nsimplex, d = self.transform.shape[0], self.transform.shape[2]
        flat = np.isnan(self.transform[:, 0, 0])
        inverse = np.where(flat[:, None, None], 0.0, self.transform[:, :d, :])  # (S, d, d)
        # c_i = (T⁻¹ (x − r))_i = (T⁻¹ x)_i − (T⁻¹ r)_i: a matrix product per axis and block.
        shift = np.einsum("sij,sj->si", inverse, np.nan_to_num(self.transform[:, d, :]))
        lenient = self.tri.neighbors < 0
        lenient |= np.where(lenient, False, flat[np.maximum(self.tri.neighbors, 0)])
        every = np.arange(nsimplex)
        found = np.full(len(x), -1, dtype=np.intp)
        block = max(1, SEARCH_BLOCK // nsimplex)
        for start in range(0, len(x), block):
            q = x[start : start + block]
            lowest = np.full((len(q), nsimplex), np.inf)
            k = np.zeros(lowest.shape, dtype=np.intp)
            last = np.ones(lowest.shape)
            for axis in range(d + 1):  # a short loop over axes, each (m, S) at once
                if axis < d:
                    c = q @ inverse[:, axis, :].T - shift[:, axis]
                    last -= c
                else:
                    c = last
                lower = c < lowest
                lowest = np.where(lower, c, lowest)
                k[lower] = axis
            lowest[:, flat] = -np.inf
            tolerance = np.where(lenient[every, k], BROAD, INSIDE)
            score = np.where(lowest >= -tolerance, lowest, -np.inf)
            best = np.argmax(score, axis=1)
            ok = np.isfinite(score[np.arange(len(q)), best])
            found[start : start + block] = np.where(ok, best, -1)
        return found


def barycentric_transforms(points: FloatArray, simplices: np.ndarray) -> FloatArray:
    """The barycentric transforms of simplices (S, d + 1) of points (P, d), in the layout
    of scipy's ``Delaunay.transform`` (S, d + 1, d): T⁻¹ in the first d rows and the
    last vertex r in the last, with T c = x − r (c the first d coordinates, the last is
    1 − Σ c); NaN for flat simplices (|det T| ≤ `FLAT_SIMPLEX` × Hadamard's bound)."""
    return transforms_and_regularity(points, simplices)[0]


def transforms_and_regularity(
    points: FloatArray, simplices: np.ndarray
) -> tuple[FloatArray, FloatArray]:
    """`barycentric_transforms` and each simplex's regularity (S,), from one determinant:
    |det T| over Hadamard's bound (the product of T's column lengths), 1 for edges at
    right angles, 0 for a flat simplex, small for a sliver."""
    v = points[simplices]  # (S, d + 1, d)
    d = v.shape[2]
    r = v[:, d, :]
    t = np.transpose(v[:, :d, :] - r[:, None, :], (0, 2, 1))  # columns v_j − r
    det = np.abs(np.linalg.det(t))
    bound = np.prod(np.linalg.norm(t, axis=1), axis=1)
    flat = ~(det > FLAT_SIMPLEX * bound)
    t[flat] = np.eye(d)
    inv = np.linalg.inv(t)
    inv[flat] = np.nan
    out = np.empty((len(v), d + 1, d))
    out[:, :d, :] = inv
    out[:, d, :] = np.where(flat[:, None], np.nan, r)
    regular: FloatArray = np.divide(det, bound, out=np.zeros(len(v)), where=bound > 0)
    return out, regular


def most_regular(simplices: np.ndarray, regular: FloatArray, points: int) -> np.ndarray:
    """For each of ``points`` points (P,), the most regular of the simplices (S, d + 1)
    it is a vertex of, by their regularity ``regular`` (S,) (`transforms_and_regularity`)
    to 9 decimals (congruent simplices, a grid's, tie whatever the rounding of their
    determinants) and of equals the last; −1 for a point in none."""
    order = np.argsort(np.round(regular, 9), kind="stable")
    rank = np.empty(len(order), dtype=np.int64)
    rank[order] = np.arange(len(order))
    best = np.full(points, -1, dtype=np.int64)
    np.maximum.at(best, simplices.ravel(), np.repeat(rank, simplices.shape[1]))
    return np.where(best >= 0, order[np.maximum(best, 0)], -1).astype(np.intp)


class Rbf(Interpolant):
    """Thin-plate-spline RBF with a linear polynomial on each query's nearest
    `RBF_NEIGHBORS` points; defined everywhere (the domain mask bounds it).

    ``stretch`` (d,): factors the coordinates are multiplied by first (None: none). On
    line data the first axis is stretched until a line's step is as long as the lines'
    spacing: unstretched, a query's nearest points are one line's collinear samples, on
    which a linear polynomial is not determined (a singular or ill-conditioned solve).
    """

    def __init__(
        self, points: FloatArray, table: FloatArray, stretch: FloatArray | None = None
    ) -> None:
        neighbors = min(RBF_NEIGHBORS, len(points))
        self.stretch = np.ones(points.shape[1]) if stretch is None else np.asarray(stretch)
        low, high = np.min(table, axis=0), np.max(table, axis=0)
        self.centre = 0.5 * (low + high)
        #: Half the range of each column, at least 10⁻⁶ of its magnitude (a constant column).
        floor = 1e-6 * np.maximum(np.maximum(np.abs(low), np.abs(high)), 1e-300)
        self.spread = np.maximum(0.5 * (high - low), floor)
        self.rbf = RBFInterpolator(
            points * self.stretch,
            table,
            neighbors=neighbors,
            kernel="thin_plate_spline",
            degree=1,
        )

    def __call__(self, x: FloatArray, nearest: np.ndarray) -> tuple[FloatArray, BoolArray]:
        try:
            out = np.asarray(self.rbf(x * self.stretch), dtype=np.float64)
            lost = not np.all(np.abs(out - self.centre) <= RBF_RANGE * self.spread)
        except np.linalg.LinAlgError:
            lost = True
        if lost:
            raise GonioError(
                "method 'rbf': the samples nearest some queries lie on a line or a plane "
                "(a linear polynomial is not determined there: a singular or "
                "ill-conditioned solve); expected samples that vary every coordinate"
            )
        return out, np.ones(len(x), dtype=np.bool_)
