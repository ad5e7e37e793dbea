"""Where a run's samples are (`gonio plot --kind coverage`): ωi and ωo on the
hemisphere (x, y of the unit vector: the rim is the horizon), and the samples in the
plan's coordinates (the isotropic reduction for an isotropic plan, three projections of
the coordinate box), coloured by value (log10 f) or by residual against a truth.

The residual of a sample is (f − truth) / σ: how many of its own 1σ uncertainties it is
away from the truth (drawn clipped to ±`RESIDUAL_CLIP`). A run with a sample whose σ is 0
(a noise-free simulation) has no σ to count in: its samples are coloured by the relative
residual (f − truth) / max(|truth|, `FLOOR`) instead (clipped to ±`RELATIVE_CLIP`).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from gonio import params
from gonio.errors import GonioError
from gonio.plots import drawn, label, one_channel, require_matplotlib, save
from gonio.types import BrdfEval, FloatArray

#: What the samples can be coloured by.
COLOURS = ("value", "residual")
#: The residual colour scale spans ± this many σ.
RESIDUAL_CLIP = 5.0
#: The relative residual's colour scale spans ± this.
RELATIVE_CLIP = 1.0
#: Values below this (sr⁻¹) are coloured as it.
FLOOR = 1e-4
#: The figure's size (inches).
FIGSIZE = (15.0, 8.0)
#: The coordinate pairs drawn, for three and for four coordinates.
PROJECTIONS = {3: ((0, 1), (0, 2), (1, 2)), 4: ((0, 2), (0, 1), (2, 3))}


@dataclass(frozen=True)
class Coverage:
    """The samples (N): their pairs (N, 3), coordinates (N, 3 or 4) in
    ``parametrization`` (``names``), and the colour of each (``colour``: log10 f, or the
    residual in σ), named ``colour_label``."""

    wi: FloatArray
    wo: FloatArray
    coords: FloatArray
    names: tuple[str, ...]
    bounds: FloatArray
    colour: FloatArray
    colour_by: str
    colour_label: str
    parametrization: str
    theta_max: float
    title: str


def coverage(
    samples: tuple[FloatArray, FloatArray, FloatArray, FloatArray],
    parametrization: str,
    *,
    isotropic: bool,
    theta_max: float,
    colour_by: str = "value",
    truth: BrdfEval | None = None,
    title: str = "",
) -> Coverage:
    """The coverage of the ``samples`` (wi, wo, f, sigma) in ``parametrization`` (see
    the module docstring); ``truth`` is needed to colour by residual."""
    if colour_by not in COLOURS:
        raise GonioError(f"--colour {colour_by}: expected one of {', '.join(COLOURS)}")
    wi, wo, f, sigma = (np.asarray(a, dtype=np.float64) for a in samples)
    f, sigma = one_channel(f), one_channel(sigma)
    p = params.get(parametrization)
    coords = p.forward_iso(wi, wo) if isotropic else p.forward(wi, wo)
    names = p.iso_names if isotropic else p.names
    bounds = np.asarray(p.iso_bounds if isotropic else p.bounds, dtype=np.float64)
    if colour_by == "value":
        colour = np.log10(np.maximum(f, FLOOR))
        colour_label = "log10 f (sr⁻¹)"
    else:
        if truth is None:
            raise GonioError("--colour residual needs a truth (--truth SPEC, or a simulated run)")
        t = one_channel(truth(wi, wo))
        if np.all(sigma > 0.0):
            colour = (f - t) / sigma
            colour_label = "residual (f − truth) / σ"
        else:  # a noise-free simulation: no σ to count in
            colour = (f - t) / np.maximum(np.abs(t), FLOOR)
            colour_label = "relative residual (f − truth) / |truth| (some σ = 0)"
    return Coverage(
        wi=wi,
        wo=wo,
        coords=coords,
        names=tuple(names),
        bounds=bounds,
        colour=colour,
        colour_by=colour_by,
        colour_label=colour_label,
        parametrization=p.name,
        theta_max=theta_max,
        title=title,
    )


def draw(data: Coverage, path: str | Path, *, format: str | None = None) -> None:
    """Draw ``data`` to ``path``: the two hemispheres on top, the three coordinate
    projections below, one colour scale."""
    plt = require_matplotlib()
    if data.colour_by == "value":
        style: dict[str, Any] = {"cmap": "viridis"}
    else:
        clip = RESIDUAL_CLIP if data.colour_label.endswith("/ σ") else RELATIVE_CLIP
        style = {"cmap": "RdBu_r", "vmin": -clip, "vmax": clip}
    width, height = FIGSIZE
    fig = plt.figure(figsize=FIGSIZE)
    # A fixed layout (inches from the edges): constrained layout costs seconds here.
    grid = fig.add_gridspec(
        2,
        3,
        left=0.8 / width,
        right=1 - 1.6 / width,
        bottom=0.6 / height,
        top=1 - 0.8 / height,
        wspace=0.3,
        hspace=0.3,
    )
    dots = None
    for j, (w, name) in enumerate(((data.wi, "ωi (light)"), (data.wo, "ωo (detector)"))):
        ax = fig.add_subplot(grid[0, j])
        _hemisphere(ax, data.theta_max)
        dots = ax.scatter(w[:, 0], w[:, 1], c=data.colour, s=8.0, **style)
        ax.set_title(f"{name} on the hemisphere (x, y)")
    text = fig.add_subplot(grid[0, 2])
    text.axis("off")
    text.text(0.0, 0.5, _summary(data), va="center", family="monospace", fontsize=10)
    for j, (a, b) in enumerate(PROJECTIONS[len(data.names)]):
        ax = fig.add_subplot(grid[1, j])
        x, y = data.names[a], data.names[b]
        dots = ax.scatter(
            drawn(x, data.coords[:, a]), drawn(y, data.coords[:, b]), c=data.colour, s=8.0, **style
        )
        ax.set_xlim(*drawn(x, data.bounds[a]))
        ax.set_ylim(*drawn(y, data.bounds[b]))
        ax.set_xlabel(label(x))
        ax.set_ylabel(label(y))
        ax.set_title(f"{data.parametrization} coordinates")
    if dots is not None:
        bar = fig.add_axes((1 - 1.1 / width, 0.15, 0.15 / width, 0.7))
        fig.colorbar(dots, cax=bar, label=data.colour_label)
    fig.suptitle(data.title)
    save(fig, path, format)


def _hemisphere(ax: Any, theta_max: float) -> None:
    t = np.linspace(0.0, 2.0 * np.pi, 361)
    r = np.sin(theta_max)
    ax.plot(np.cos(t), np.sin(t), color="k", lw=1.0)
    ax.plot(r * np.cos(t), r * np.sin(t), color="0.5", lw=0.8, ls="--")
    ax.set_aspect("equal")
    ax.set_xlim(-1.05, 1.05)
    ax.set_ylim(-1.05, 1.05)


def _summary(data: Coverage) -> str:
    c = data.colour
    lines = [f"{len(c)} samples", f"coloured by {data.colour_by}"]
    if len(c):
        lines.append(f"  min {c.min():.3g}, median {np.median(c):.3g}, max {c.max():.3g}")
    if data.colour_by == "residual" and len(c):
        lines.append(f"  |residual| > 3σ: {np.count_nonzero(np.abs(c) > 3.0)}")
    lines.append(f"θ limit of the rig: {np.degrees(data.theta_max):.1f}° (dashed)")
    return "\n".join(lines)
