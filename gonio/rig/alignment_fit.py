"""The misalignment a mirror scan measures: `fit` finds the `Alignment` whose forward
kinematics put each observed specular peak where a mirror reflects, by nonlinear least
squares (scipy's), with its covariance (from the peaks' stated location errors, scaled
by the reduced χ² where the peaks scatter more than those: the Birge ratio), and says
which parameters the scan cannot determine instead of setting them silently.

An observation is a pose (joint angles as the rig file reads them) at which the detector
saw the peak of a first-surface mirror seated as the sample, and the angular standard
error of that location (rad). At the true geometry a mirror sends the light along its
reflection about the true normal: in the true sample frame (`Rig.geometry`),
ωo = (−ωi,x, −ωi,y, ωi,z). Each peak gives two residuals, (ωo + ωi)ₓ,ᵧ / σ: the two
angles (rad, to first order) by which the true reflection misses the detector.

Parameters (`PARAMETERS`): each axis's zero offset; the sample tilt as its two
components (α cos β, α sin β), smooth through no tilt; the height; the light's and the
detector's pointing errors (two angles each). Which combinations a scan determines:
the singular values of the whitened Jacobian at no misalignment, a direction whose
standard error would exceed `UNDETERMINED_RAD` (or `UNDETERMINED_MM`) being
undetermined. The fit moves only along the determined combinations (an undetermined
one stays at no error: the least-norm solution, so two parameters that act alike, such
as an axis's zero offset and a pointing error about that axis, share what they do
together). A parameter with more than `SHARE` of its unit vector outside them is
reported as undetermined (no standard error), named with why and what would determine
it (`gonio.rig.alignment_hints`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from gonio.errors import GonioError
from gonio.rig import alignment_hints
from gonio.rig.alignment import Alignment
from gonio.rig.model import Rig
from gonio.types import FloatArray

#: A parameter's standard error (rad) above which the scan does not determine it: a
#: tenth of a degree, three times the accuracy an alignment is for.
UNDETERMINED_RAD = math.radians(0.1)
#: The same for the height (mm).
UNDETERMINED_MM = 0.1
#: The share of a parameter in an undetermined direction above which it is undetermined.
SHARE = 1e-3


def parameters(rig: Rig) -> tuple[str, ...]:
    """The fitted parameters' names, in their order: ``zero_offset.<axis>`` per axis,
    ``tilt_x``, ``tilt_y``, ``height_mm``, ``light_pointing_x``, ``light_pointing_y``,
    ``detector_pointing_x``, ``detector_pointing_y``."""
    return (
        *(f"zero_offset.{name}" for name in rig.axes),
        "tilt_x",
        "tilt_y",
        "height_mm",
        "light_pointing_x",
        "light_pointing_y",
        "detector_pointing_x",
        "detector_pointing_y",
    )


def as_alignment(rig: Rig, p: FloatArray) -> Alignment:
    """The `Alignment` of the parameter vector ``p`` (`parameters` order; rad, mm)."""
    a = len(rig.axes)
    tx, ty = p[a], p[a + 1]
    return Alignment(
        zero_offset=p[:a],
        tilt=np.hypot(tx, ty),
        tilt_azimuth=np.arctan2(ty, tx),
        height_mm=p[a + 2],
        light_pointing=p[a + 3 : a + 5],
        detector_pointing=p[a + 5 : a + 7],
    )


def vector(rig: Rig, alignment: Alignment) -> FloatArray:
    """The parameter vector (P,) (`parameters` order; rad, mm) of one ``alignment``: the
    inverse of `as_alignment`."""
    a = alignment
    tilt = float(a.tilt)
    return np.concatenate(
        [
            np.broadcast_to(a.zero_offset, (len(rig.axes),)),
            [tilt * math.cos(float(a.tilt_azimuth)), tilt * math.sin(float(a.tilt_azimuth))],
            [float(a.height_mm)],
            a.light_pointing,
            a.detector_pointing,
        ]
    ).astype(np.float64)


def stated_covariance(rig: Rig) -> FloatArray:
    """The covariance (P, P) (`parameters` order; rad², mm²) its alignment file states of
    the rig's alignment: the fitted parameters' standard errors and correlations, 0 for a
    parameter the fit did not determine, and everywhere without a file or fit record."""
    names = parameters(rig)
    out = np.zeros((len(names), len(names)))
    record = None if rig.alignment_file is None else rig.alignment_file.fit
    if record is None:
        return out
    index = [names.index(name) for name in record.parameters]
    radians = np.array([1.0 if n == "height_mm" else math.pi / 180.0 for n in record.parameters])
    out[np.ix_(index, index)] = record.covariance() * np.outer(radians, radians)
    return out


def miss(rig: Rig, angles: FloatArray, alignment: Alignment) -> FloatArray:
    """(M, 2): how far (rad, first order) the true mirror reflection misses the detector
    at each pose (M, A): (ωo + ωi)ₓ,ᵧ in the true sample frame."""
    g = rig.geometry(np.asarray(angles, dtype=np.float64), alignment)
    return np.asarray((g.wo + g.wi)[..., :2], dtype=np.float64)


@dataclass(frozen=True)
class AlignmentFit:
    """A fitted alignment: ``values`` and ``errors`` (standard errors; rad, mm; NaN where
    undetermined) by `names`; ``determined`` per parameter; ``residuals_rad`` (M, 2) at
    the solution; ``chi2`` and its degrees of freedom; ``hints`` per undetermined
    parameter."""

    names: tuple[str, ...]
    values: FloatArray
    errors: FloatArray
    determined: np.ndarray
    covariance: FloatArray
    residuals_rad: FloatArray
    chi2: float
    dof: int
    hints: dict[str, str]
    alignment: Alignment

    @property
    def reduced_chi2(self) -> float:
        return self.chi2 / self.dof if self.dof > 0 else math.nan


def _scale(names: Sequence[str]) -> FloatArray:
    """Each parameter's bound on its standard error (rad, or mm for the height)."""
    return np.array([UNDETERMINED_MM if n == "height_mm" else UNDETERMINED_RAD for n in names])


def fit(rig: Rig, angles: FloatArray, sigma_rad: FloatArray) -> AlignmentFit:
    """The alignment the observed peaks at joint angles ``angles`` (M, A), each located
    to ``sigma_rad`` (M,) (rad), say; see the module. `GonioError` (one line) when there
    are fewer residuals than determined parameters, or no parameter is determined."""
    angles = np.asarray(angles, dtype=np.float64)
    sigma = np.broadcast_to(np.asarray(sigma_rad, dtype=np.float64), angles.shape[:1])
    if angles.ndim != 2 or angles.shape[1] != len(rig.axes):
        raise GonioError(f"alignment fit: expected peaks (M, {len(rig.axes)}) of joint angles")
    if not (np.all(np.isfinite(angles)) and np.all(sigma > 0) and np.all(np.isfinite(sigma))):
        raise GonioError("alignment fit: expected finite peaks with positive uncertainties")
    names = parameters(rig)
    n = len(names)

    def residuals(p: FloatArray) -> FloatArray:
        return (miss(rig, angles, as_alignment(rig, p)) / sigma[:, None]).ravel()

    scale = _scale(names)
    basis, determined = _directions(residuals, n, scale)
    if not len(basis):
        raise GonioError("alignment fit: the peaks determine no parameter; measure more poses")
    if 2 * len(angles) <= len(basis):
        raise GonioError(
            f"alignment fit: {len(angles)} peaks give {2 * len(angles)} residuals for "
            f"{len(basis)} determined combinations of parameters; expected more peaks"
        )

    def along(x: FloatArray) -> FloatArray:
        return np.asarray(scale * (basis.T @ x), dtype=np.float64)

    result = least_squares(lambda x: residuals(along(x)), np.zeros(len(basis)), method="lm")
    values = along(result.x)
    jac = np.asarray(result.jac, dtype=np.float64)
    # p = diag(scale) Bᵀ x: the covariance of x carried to the parameters
    carry = scale[:, None] * basis.T
    r = residuals(values)
    dof = len(r) - len(basis)
    # the peaks' stated error is a bound; where they scatter more, the scatter says more
    birge = max(1.0, float(r @ r) / dof) if dof > 0 else 1.0
    covariance = birge * (carry @ np.linalg.pinv(jac.T @ jac) @ carry.T)
    errors = np.where(determined, np.sqrt(np.diag(covariance)), np.nan)
    undetermined = [name for name, ok in zip(names, determined, strict=True) if not ok]
    hints = alignment_hints.hints(rig, names, undetermined, lambda p: as_alignment(rig, p))
    return AlignmentFit(
        names=names,
        values=values,
        errors=errors,
        determined=determined,
        covariance=covariance,
        residuals_rad=(r.reshape(-1, 2) * sigma[:, None]),
        chi2=float(r @ r),
        dof=dof,
        hints=hints,
        alignment=as_alignment(rig, values),
    )


def peak_offsets(offsets: FloatArray, values: FloatArray) -> FloatArray:
    """Where each scan (rows of ``values`` (M, K), read at the ``offsets`` (K,) of one
    joint, evenly spaced, rad) peaks, as an offset (M,): the vertex of the parabola
    through the logarithm of the largest reading and its two neighbours (a Gaussian
    peak's exact location), held within a step of the largest reading. A peak on the
    scan's edge is refused (`GonioError`): the scan missed it."""
    offsets = np.asarray(offsets, dtype=np.float64)
    values = np.asarray(values, dtype=np.float64)
    if values.ndim != 2 or values.shape[1] != len(offsets) or len(offsets) < 3:
        raise GonioError("peak: expected scans (M, K) of three readings or more")
    k = np.argmax(values, axis=1)
    if np.any((k == 0) | (k == len(offsets) - 1)) or not np.all(values.max(axis=1) > 0):
        raise GonioError("peak: a scan's largest reading is on its edge; widen the scan")
    rows = np.arange(len(values))
    a, b, c = (
        np.log(np.maximum(values[rows, k + d], np.finfo(np.float64).tiny)) for d in (-1, 0, 1)
    )
    step = offsets[1] - offsets[0]
    curvature = a - 2.0 * b + c
    shift = np.where(
        curvature < 0, 0.5 * step * (a - c) / np.where(curvature < 0, curvature, -1.0), 0.0
    )
    return np.asarray(offsets[k] + np.clip(shift, -step, step), dtype=np.float64)


def peak_at(x: FloatArray, values: FloatArray) -> float:
    """Where one scan peaks (rad): the vertex of the parabola through the logarithm of
    the largest reading and its neighbours, at the angles ``x`` (K,) the joint was read
    back at (any spacing: readings at one angle are averaged, as a motor's ticks give
    them), held within its neighbours. `GonioError` when the largest is on the scan's
    edge (the scan missed the peak) or fewer than three angles were read."""
    x = np.asarray(x, dtype=np.float64)
    at, where = np.unique(x, return_inverse=True)
    if len(at) < 3:
        raise GonioError("peak: a scan read fewer than three distinct angles; widen its step")
    mean = np.bincount(where, weights=np.asarray(values, dtype=np.float64)) / np.bincount(where)
    k = int(np.argmax(mean))
    if k in (0, len(at) - 1) or not mean[k] > 0:
        raise GonioError("peak: a scan's largest reading is on its edge; widen the scan")
    xs, ys = at[k - 1 : k + 2], np.log(np.maximum(mean[k - 1 : k + 2], np.finfo(np.float64).tiny))
    a, b, _ = np.polyfit(xs - xs[1], ys, 2)
    vertex = xs[1] - b / (2.0 * a) if a < 0 else xs[1]
    return float(np.clip(vertex, xs[0], xs[2]))


def _directions(
    residuals: Callable[[FloatArray], FloatArray], n: int, scale: FloatArray
) -> tuple[FloatArray, np.ndarray]:
    """The combinations of parameters the whitened residuals determine, as rows (k, n)
    in units of each parameter's ``scale`` (the right singular vectors of the Jacobian
    at no misalignment, by central differences, whose standard error stays within the
    scale), and which parameters lie within them (less than `SHARE` of their unit vector
    outside)."""
    step = 1e-6
    columns = []
    for i in range(n):
        e = np.zeros(n)
        e[i] = step * scale[i]
        columns.append((residuals(e) - residuals(-e)) / (2 * step))
    jac = np.stack(columns, axis=1)  # per unit of each parameter's scale
    _, s, vt = np.linalg.svd(jac, full_matrices=True)
    s = np.concatenate([s, np.zeros(n - len(s))])
    strong = s >= 1.0
    share_outside = np.sum(vt[~strong] ** 2, axis=0)
    return np.asarray(vt[strong], dtype=np.float64), np.asarray(
        share_outside <= SHARE, dtype=np.bool_
    )


__all__ = [
    "AlignmentFit",
    "as_alignment",
    "fit",
    "miss",
    "parameters",
    "peak_at",
    "peak_offsets",
    "stated_covariance",
    "vector",
]
