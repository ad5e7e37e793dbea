"""2D slices of a BRDF in the isotropic coordinates of several parametrizations, side by
side, drawn the way Barla, Belcour & Pacanowski 2015 compare them: one row per
parametrization (hybrid (‖h̄‖, ‖k‖), orthographic (‖h̄‖, ‖k̄‖), halfway/difference
(θh, θd)), one column per value of the third coordinate (φk − φh for the first two, φd
for halfway/difference), ln-shaded values with iso-lines.

Each pixel is a point of the parametrization's isotropic box; its pair comes from
``inverse_iso`` (φh = 0). A pixel is masked where the point is outside the valid domain
(drawn dark grey) or where the surface has no data there (its ``supported`` is False,
or its value is NaN; drawn light grey): only what the surface measured is shaded.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gonio import params
from gonio.errors import GonioError
from gonio.plots import Surface, drawn, label, require_matplotlib, save, supported, symbol, values
from gonio.types import BoolArray, FloatArray

#: Pixels per side of each slice.
RESOLUTION = 121
#: The parametrizations compared, one row each.
PARAMETRIZATIONS = ("hybrid", "orthographic", "rusinkiewicz")
#: The default values of the third coordinate (degrees).
DEFAULT_ANGLES_DEG = (0.0, 45.0, 90.0)
#: Values below this (sr⁻¹) are shaded as it (a log scale has no 0).
FLOOR = 1e-4
#: Figure size (inches) of one slice.
PANEL_IN = (3.4, 3.0)
#: Outside the domain, no data.
OUTSIDE, UNSUPPORTED = "0.35", "0.85"


@dataclass(frozen=True)
class Slice:
    """One slice: the surface at ``coords`` (R, R, 3), rows along the second coordinate
    (``y``), columns along the first (``x``), the third fixed at ``angle`` (rad).
    ``f``: values in sr⁻¹, NaN where not ``valid`` (outside the domain); ``masked``: not
    valid, not supported, or where the surface declines to answer (NaN): what the figure
    leaves unshaded."""

    parametrization: str
    names: tuple[str, str, str]
    angle: float
    x: FloatArray
    y: FloatArray
    coords: FloatArray
    f: FloatArray
    valid: BoolArray
    supported: BoolArray

    @property
    def masked(self) -> BoolArray:
        return np.asarray(~(self.valid & self.supported & np.isfinite(self.f)), dtype=np.bool_)


@dataclass(frozen=True)
class Slices:
    """``rows[i][j]``: parametrization i at angle j."""

    rows: list[list[Slice]]
    title: str


def check_angles(angles_deg: Sequence[float], option: str = "--phi-k") -> None:
    """`GonioError` unless every angle is finite and in [0°, 180°)."""
    for a in angles_deg:
        if not (math.isfinite(a) and 0.0 <= a < 180.0):
            raise GonioError(f"{option} {a:g}: expected an angle in degrees in [0, 180)")


def slices(
    surface: Surface,
    angles_deg: Sequence[float] = DEFAULT_ANGLES_DEG,
    *,
    parametrizations: Sequence[str] = PARAMETRIZATIONS,
    resolution: int = RESOLUTION,
    title: str = "",
) -> Slices:
    """The slices of ``surface`` (see the module docstring) at the third coordinate's
    values ``angles_deg`` (degrees, in [0, 180))."""
    check_angles(angles_deg)
    rows = [
        [_slice(surface, params.get(name), math.radians(a), resolution) for a in angles_deg]
        for name in parametrizations
    ]
    return Slices(rows, title)


def _slice(surface: Surface, p: params.Parametrization, angle: float, n: int) -> Slice:
    bounds = np.asarray(p.iso_bounds, dtype=np.float64)
    x = np.linspace(bounds[0, 0], bounds[0, 1], n)
    y = np.linspace(bounds[1, 0], bounds[1, 1], n)
    gx, gy = np.meshgrid(x, y, indexing="xy")
    coords = np.stack([gx, gy, np.full_like(gx, angle)], axis=-1)
    flat = coords.reshape(-1, 3)
    valid = p.valid_iso(flat)
    f = np.full(len(flat), np.nan)
    has_data = np.zeros(len(flat), dtype=np.bool_)
    if valid.any():
        wi, wo = p.inverse_iso(flat[valid])
        f[valid] = values(surface, wi, wo)
        has_data[valid] = supported(surface, wi, wo)
    return Slice(
        parametrization=p.name,
        names=p.iso_names,
        angle=angle,
        x=x,
        y=y,
        coords=coords,
        f=f.reshape(n, n),
        valid=valid.reshape(n, n),
        supported=has_data.reshape(n, n),
    )


def figure_size(data: Slices) -> tuple[float, float]:
    """The figure's size in inches."""
    rows, cols = len(data.rows), len(data.rows[0])
    return PANEL_IN[0] * cols + 2.2, PANEL_IN[1] * rows + 1.4


def draw(data: Slices, path: str | Path, *, format: str | None = None) -> None:
    """Draw ``data`` to ``path``: log10 f shaded on one colour scale for all slices,
    iso-lines every half decade, masked pixels grey (see the module docstring)."""
    plt = require_matplotlib()
    from matplotlib.colors import ListedColormap  # optional: the plot extra

    kept = [s.f[~s.masked] for row in data.rows for s in row]
    finite = np.concatenate(kept) if kept else np.empty(0)
    logs = np.log10(np.maximum(finite, FLOOR))
    lo, hi = (float(logs.min()), float(logs.max())) if len(logs) else (-1.0, 1.0)
    hi = max(hi, lo + 0.5)
    levels = np.arange(math.floor(2 * lo) / 2, hi + 0.5, 0.5)
    background = ListedColormap([OUTSIDE, UNSUPPORTED])

    # A fixed layout (inches from the edges): constrained layout costs seconds here.
    width, height = figure_size(data)
    fig, axes = plt.subplots(
        len(data.rows), len(data.rows[0]), figsize=(width, height), squeeze=False
    )
    fig.subplots_adjust(
        left=0.7 / width,
        right=1 - 1.5 / width,
        bottom=0.5 / height,
        top=1 - 0.9 / height,
        wspace=0.3,
        hspace=0.45,
    )
    image = None
    for row, ax_row in zip(data.rows, axes, strict=True):
        for s, ax in zip(row, ax_row, strict=True):
            x, y = drawn(s.names[0], s.x), drawn(s.names[1], s.y)
            ax.pcolormesh(
                x, y, s.valid.astype(float), shading="nearest", cmap=background, vmin=0.0, vmax=1.0
            )
            shade = np.ma.masked_array(np.log10(np.maximum(np.nan_to_num(s.f), FLOOR)), s.masked)
            image = ax.pcolormesh(x, y, shade, shading="nearest", cmap="magma", vmin=lo, vmax=hi)
            lit = shade.compressed()
            inside = levels[(levels > lit.min()) & (levels < lit.max())] if lit.size else []
            if len(inside):  # else no iso-line crosses the slice
                ax.contour(
                    x, y, shade, levels=inside, colors="w", linewidths=0.6, linestyles="solid"
                )
            ax.set_xlabel(label(s.names[0]))
            ax.set_ylabel(label(s.names[1]))
            third = f"{symbol(s.names[2])} = {math.degrees(s.angle):g}°"
            ax.set_title(f"{s.parametrization}, {third}")
            ax.set_aspect("auto")
    if image is not None:
        bar = fig.add_axes((1 - 1.1 / width, 0.15, 0.15 / width, 0.7))
        fig.colorbar(image, cax=bar, label="log10 f (sr⁻¹); iso-lines every ½ decade")
    fig.suptitle(
        data.title + "\ndark grey: outside the domain, light grey: no data (not supported)"
    )
    save(fig, path, format)
