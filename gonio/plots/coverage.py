"""The coverage of a plan, drawn the way the figures of Barla, Belcour &
Pacanowski 2015 show the hybrid domain.

Top row: slices of the plane of the first two isotropic coordinates (‖h̄‖, ‖k‖ for
hybrid) at a few values of the third (φk − φh, reciprocity-folded), shaded by what
happens to a pair there: outside the parametrization's domain, refused by the rig (one
colour per reason) or measurable, with the domain's boundary drawn and the plan's
targets within the slab around each slice marked. Anisotropic plans are drawn in the
same coordinates (their targets' pairs reduced with ``forward_iso``; the shading is for
the rig with its rotation stage in use, at φh = 0). Bottom row: the targets' ωi and ωo
on the hemisphere (x, y of the unit vector, so the rim is the horizon), coloured by
measuring order, with the rig's θ limit dashed.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from gonio import params
from gonio.planner import Plan
from gonio.plots import drawn, label, quantity, require_matplotlib, save, symbol
from gonio.rig import Reason
from gonio.types import FloatArray

#: Pixels per side of each slice image.
RESOLUTION = 160
#: Slices drawn (evenly spaced over the slice coordinate's range).
SLICES = 4
#: Colours: outside the domain, measurable, then one per refusal reason.
COLOURS = {
    "outside the domain": "#bdbdbd",
    "measurable": "#ffffff",
    Reason.THETA_MAX.label: "#fdae6b",
    Reason.BLIND_SPOT.label: "#9e9ac8",
    Reason.FOOTPRINT.label: "#74c476",
    Reason.AXIS_LIMIT.label: "#6baed6",
    Reason.COLLISION.label: "#fb6a4a",
    Reason.VIEW_OFF_SAMPLE.label: "#fdd0a2",
}


def classify(plan: Plan, coords: FloatArray) -> np.ndarray:
    """Per isotropic-coordinate point (N, 3): −1 outside the domain, else the rig's
    `Reason` (0: measurable) for the pair ``inverse_iso`` gives."""
    p = params.get(plan.spec.parametrization)
    valid = p.valid_iso(coords)
    out = np.full(len(coords), -1, dtype=np.int8)
    if valid.any():
        wi, wo = p.inverse_iso(coords[valid])
        out[valid] = plan.rig.solve(wi, wo, isotropic=plan.spec.isotropic).reasons
    return out


def slice_values(bounds: FloatArray) -> FloatArray:
    """The third coordinate's values at the centres of `SLICES` equal slabs."""
    lo, hi = bounds[2]
    return np.asarray(lo + (hi - lo) / SLICES * (np.arange(SLICES) + 0.5), dtype=np.float64)


def plot_coverage(plan: Plan, path: str | Path, *, format: str | None = None) -> None:
    """Write the coverage figure of ``plan`` to ``path`` (``format``, default: the one
    matplotlib knows from the suffix, PNG without one)."""
    plt = require_matplotlib()
    from matplotlib.colors import ListedColormap  # optional: the plot extra
    from matplotlib.patches import Patch  # optional: the plot extra

    p = params.get(plan.spec.parametrization)
    bounds = np.asarray(p.iso_bounds, dtype=np.float64)
    names = p.iso_names
    targets = plan.coords if plan.spec.isotropic else p.forward_iso(plan.wi, plan.wo)
    xs = np.linspace(bounds[0, 0], bounds[0, 1], RESOLUTION)
    ys = np.linspace(bounds[1, 0], bounds[1, 1], RESOLUTION)
    gx, gy = np.meshgrid(xs, ys, indexing="xy")
    half_slab = 0.5 * (bounds[2, 1] - bounds[2, 0]) / SLICES

    labels = list(COLOURS)
    cmap = ListedColormap([COLOURS[k] for k in labels])
    # Image value → colour index: −1 → 0 (outside), Reason r → r + 1.
    fig = plt.figure(figsize=(4.0 * SLICES, 8.2), constrained_layout=True)
    grid = fig.add_gridspec(2, SLICES)
    for i, value in enumerate(slice_values(bounds)):
        coords = np.stack([gx.ravel(), gy.ravel(), np.full(gx.size, value)], axis=-1)
        kind = classify(plan, coords).reshape(gx.shape)
        ax = fig.add_subplot(grid[0, i])
        ax.imshow(
            kind + 1,
            origin="lower",
            cmap=cmap,
            extent=(*drawn(names[0], bounds[0]), *drawn(names[1], bounds[1])),
            vmin=-0.5,
            vmax=len(labels) - 0.5,
            interpolation="nearest",
            aspect="auto",
        )
        x, y = drawn(names[0], gx), drawn(names[1], gy)
        ax.contour(x, y, (kind >= 0).astype(float), levels=[0.5], colors="k", linewidths=1.0)
        near = np.abs(targets[:, 2] - value) <= half_slab
        x, y = drawn(names[0], targets[near, 0]), drawn(names[1], targets[near, 1])
        ax.plot(x, y, ".", ms=2.0, color="k")
        slab = f"{quantity(names[2], value)} ± {quantity(names[2], half_slab)}"
        ax.set_title(f"{symbol(names[2])} = {slab}\n{near.sum()} targets")
        ax.set_xlabel(label(names[0]))
        ax.set_ylabel(label(names[1]))

    order = np.arange(len(plan))
    theta_max = plan.rig.theta_max
    for j, (w, name) in enumerate(((plan.wi, "ωi (light)"), (plan.wo, "ωo (detector)"))):
        ax = fig.add_subplot(grid[1, j])
        _hemisphere(ax, theta_max)
        dots = ax.scatter(w[:, 0], w[:, 1], c=order, s=3.0, cmap="viridis")
        ax.set_title(f"{name} on the hemisphere (x, y)")
    fig.colorbar(dots, ax=ax, label="measuring order")
    legend = fig.add_subplot(grid[1, 2:])
    legend.axis("off")
    handles = [
        Patch(facecolor=COLOURS[k], edgecolor="k", label=k.replace("_", " ")) for k in labels
    ]
    handles.append(Patch(facecolor="k", label="targets in the slab"))
    legend.legend(handles=handles, loc="center left", frameon=False)
    legend.text(
        0.55, 0.5, _summary_text(plan), transform=legend.transAxes, va="center", family="monospace"
    )
    fig.suptitle(
        f"plan {plan.spec.name!r}: {len(plan)} targets, "
        f"{'isotropic' if plan.spec.isotropic else 'anisotropic'} "
        f"{plan.spec.parametrization}, rig {plan.rig.spec.name!r}"
    )
    save(fig, path, format)


def _hemisphere(ax: Any, theta_max: float) -> None:
    t = np.linspace(0.0, 2.0 * np.pi, 361)
    ax.plot(np.cos(t), np.sin(t), color="k", lw=1.0)
    r = np.sin(theta_max)
    ax.plot(r * np.cos(t), r * np.sin(t), color="0.5", lw=0.8, ls="--")
    ax.set_aspect("equal")
    ax.set_xlim(-1.05, 1.05)
    ax.set_ylim(-1.05, 1.05)
    ax.set_xlabel("x")
    ax.set_ylabel("y")


def _summary_text(plan: Plan) -> str:
    s = plan.summary
    lines = [f"requested {s.requested}", f"outside the domain {s.invalid}"]
    lines += [f"refused, {k.replace('_', ' ')} {v}" for k, v in s.refused.items() if v]
    lines.append(f"kept {s.kept}")
    lines.append(f"θ limit of the rig: {np.degrees(plan.rig.theta_max):.1f}° (dashed)")
    return "\n".join(lines)
