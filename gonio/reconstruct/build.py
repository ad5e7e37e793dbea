"""`reconstruct`: a measured BRDF (`Measured`) → a `Reconstruction` one can evaluate.

The samples' pairs go to the scaled coordinates of a parametrization (the isotropic
reduction for an isotropic run; `gonio.reconstruct.coordinates`), padded across the
seams; their values through a transform (`gonio.reconstruct.transforms`) into an
interpolant (`METHODS`). docs/explanations/reconstruction.md says how each choice was made.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np
from scipy.spatial import QhullError

from gonio.analysis import Measured
from gonio.errors import GonioError, UnknownNameError
from gonio.reconstruct import transforms
from gonio.reconstruct.coordinates import Space, morton_order
from gonio.reconstruct.domain import Domain, spacings
from gonio.reconstruct.grid import GridInterpolant, detect, refuse
from gonio.reconstruct.interpolants import Interpolant, Linear, Rbf
from gonio.reconstruct.lines import (
    ALONG,
    LINE_REACH,
    Lines,
    check_space,
    dense_lines,
    line_set,
    refuse_lines,
)
from gonio.reconstruct.result import Reconstruction
from gonio.types import ArrayLike, FloatArray

#: The interpolation methods, by name.
METHODS = ("linear", "rbf", "grid", "lines", "model+residual")
#: What an unsupported query may be filled with (None: NaN).
EXTRAPOLATIONS = (None, "nearest", "model")
#: The transform interpolated by default (chosen by measurement:
#: docs/explanations/reconstruction.md).
DEFAULT_TRANSFORM = "log"
#: Seam copies are made of the samples within this many typical spacings of a seam
#: (enough for the triangulation to join the two sides; `domain.spacings`).
PAD_SPACINGS = 1.0
#: Samples closer than this (scaled units) are one sample measured repeatedly.
REPEAT = 1e-12


class Model(Protocol):
    """Anything evaluating f(wi, wo) like `gonio.brdf.BRDF` (e.g. a fitted model)."""

    def eval(self, wi: ArrayLike, wo: ArrayLike) -> FloatArray: ...


def reconstruct(
    measured: Measured,
    *,
    method: str = "linear",
    parametrization: str | None = None,
    extrapolate: str | None = None,
    model: Model | None = None,
    transform: str | None = None,
    max_distance: float | None = None,
    lines: np.ndarray | None = None,
) -> Reconstruction:
    """The reconstruction of ``measured`` by ``method`` (one of `METHODS`) in
    ``parametrization`` (default: the plan's).

    ``model``: the analytic model of ``model+residual`` and of ``extrapolate="model"``.
    ``transform``: one of `transforms.TRANSFORMS` (default `DEFAULT_TRANSFORM`; the
    model+residual method interpolates the log ratio to the model instead).
    ``max_distance``: the support distance (scaled units; `gonio.reconstruct.domain`).
    ``lines``: the line of each sample (N,) integers, negative for none (a fly plan's
    sweeps), for ``lines`` and ``rbf`` on line data; default: found from the
    coordinates (`gonio.reconstruct.lines`).
    `GonioError` (one line) for an unknown name or a missing model.
    """
    if method not in METHODS:
        raise UnknownNameError(
            f"unknown reconstruction method {method!r}; expected one of {', '.join(METHODS)}"
        )
    if extrapolate not in EXTRAPOLATIONS:
        raise UnknownNameError(
            f"unknown extrapolation {extrapolate!r}; expected nearest, model or none"
        )
    needs = "method 'model+residual'" if method == "model+residual" else "extrapolate='model'"
    if model is None and (method == "model+residual" or extrapolate == "model"):
        raise GonioError(f"{needs} needs a model (any object with eval(wi, wo)); none given")
    space = Space(parametrization or measured.parametrization, measured.isotropic)
    if method == "model+residual":
        assert model is not None
        if transform is not None:
            raise GonioError("method 'model+residual' interpolates the ratio; drop transform")
        chosen: transforms.Transform = transforms.Ratio(model.eval)
    else:
        chosen = transforms.get(transform or DEFAULT_TRANSFORM)
    if len(measured) == 0:
        raise GonioError(f"{measured.source}: no sample to reconstruct from")

    wi, wo = measured.wi, measured.wo
    f = _columns(measured.f)
    x = space.scaled(wi, wo)
    labels = None if lines is None else np.asarray(lines)
    if labels is not None and labels.shape != (len(x),):
        raise GonioError(f"lines: expected one label per sample ({len(x)}), got {labels.shape}")
    x, wi, wo, f, sigma, labels = _merge_repeats(x, wi, wo, f, _columns(measured.sigma), labels)
    table = np.concatenate([chosen.encode(f, wi, wo), chosen.slope(f, wi, wo) * sigma], axis=1)

    spacing, local = spacings(x)
    margin = PAD_SPACINGS * spacing
    padded = space.pad(x, margin)
    order = morton_order(padded.points)
    points, source = padded.points[order], padded.source[order]
    found = line_set(x, labels)
    dense = dense_lines(x, found)
    if method == "lines":
        check_space(space)
        if dense is None:
            raise refuse_lines(method, found)
    if dense is not None and max_distance is None:
        # Line data: a query between lines is as near its samples as the lines' spacing.
        max_distance = LINE_REACH * dense[1]
    domain = Domain(points, source, local, measured.rig, measured.isotropic, max_distance)
    interpolant: Interpolant
    if method == "grid":
        grid = detect(x)
        if grid is None:
            raise refuse(space.parametrization)
        interpolant = GridInterpolant(grid, table, space)
    elif method in ("lines", "rbf"):
        stretch = None
        if dense is not None:
            stretch = np.ones(space.dims)
            stretch[ALONG] = dense[1] / dense[0]
        interpolant = Rbf(points, table[source], stretch=stretch)
        if method == "lines":
            # Beyond the lines' ends (where the rig stops a line), the stretched rbf.
            interpolant = Lines(x, table, found, space, fallback=interpolant)
            margin = interpolant.margin
    else:
        try:
            interpolant = Linear(points, table[source])
        except QhullError:
            raise GonioError(
                f"{measured.source}: method {method!r}: the {len(x)} samples span no "
                f"{space.dims}-dimensional region of {space.parametrization!r} coordinates; "
                "expected a plan that varies every coordinate"
            ) from None
    return Reconstruction(
        method=method,
        space=space,
        codec=chosen,
        interpolant=interpolant,
        domain=domain,
        source=source,
        samples_f=f,
        extrapolate=extrapolate,
        model=None if model is None else model.eval,
        channels=f.shape[1],
        # A grid's periodic padding repeats its nodes exactly: nothing to blend.
        seam_band=0.0 if method == "grid" else 0.5 * margin,
    )


def _columns(a: FloatArray) -> FloatArray:
    return np.asarray(a, dtype=np.float64).reshape(len(a), -1)


def _merge_repeats(
    x: FloatArray,
    wi: FloatArray,
    wo: FloatArray,
    f: FloatArray,
    sigma: FloatArray,
    labels: np.ndarray | None,
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, np.ndarray | None]:
    """Samples at the same coordinates as one: the mean value, σ of the mean (and the
    first one's line label)."""
    key = np.round(x / REPEAT).astype(np.int64) if len(x) else x
    _, first, inverse, count = np.unique(
        key, axis=0, return_index=True, return_inverse=True, return_counts=True
    )
    if len(first) == len(x):
        return x, wi, wo, f, sigma, labels
    inverse = inverse.ravel()
    n = count[:, None].astype(np.float64)
    mean = np.zeros((len(first), f.shape[1]))
    var = np.zeros_like(mean)
    np.add.at(mean, inverse, f)
    np.add.at(var, inverse, sigma**2)
    kept = None if labels is None else labels[first]
    return x[first], wi[first], wo[first], mean / n, np.sqrt(var) / n, kept
