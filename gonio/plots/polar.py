"""The in-plane BRDF at several angles of incidence: the surface (a reconstruction) and,
when given, a truth or fitted model as lines, the measured samples near each plane with
their 1σ error bars.

In the plane of incidence, ωi = (sin θi, 0, cos θi) and ωo = (−sin θo, 0, cos θo) with a
signed θo in [−θmax, θmax] (the rig's limit): θo > 0 on the far side of the normal from
the light, so the mirror direction is θo = θi. The surface's line is solid where it has
data (``supported``) and dotted elsewhere.

A sample is drawn with the curve of θi when its own θi is within ``tolerance`` of it and
its ωo within ``tolerance`` of its own plane of incidence (the plane of n and ωi): the
plane is turned about the normal to φi = 0, which assumes an isotropic material.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gonio.errors import GonioError
from gonio.plots import Surface, one_channel, require_matplotlib, save, supported, values
from gonio.types import BoolArray, BrdfEval, FloatArray

#: The default angles of incidence (degrees).
DEFAULT_THETA_I_DEG = (0.0, 30.0, 60.0)
#: How far (degrees) a sample may be from a curve's θi and from its plane of incidence.
DEFAULT_TOLERANCE_DEG = 5.0
#: Points per curve.
POINTS = 241
#: The figure's size (inches).
FIGSIZE = (9.0, 5.5)
#: Values below this (sr⁻¹) are not drawn on the log axis.
FLOOR = 1e-4


@dataclass(frozen=True)
class Curve:
    """One angle of incidence ``theta_i`` (rad): the pairs (``wi``, ``wo``, (M, 3)) at the
    signed ``theta_o`` (M,) rad, the surface's values there and where it has data, the
    truth's values (None without a truth), and the samples near the plane: their signed
    θo (K,) rad, values and 1σ uncertainties (sr⁻¹)."""

    theta_i: float
    theta_o: FloatArray
    wi: FloatArray
    wo: FloatArray
    surface: FloatArray
    supported: BoolArray
    truth: FloatArray | None
    sample_theta_o: FloatArray
    sample_f: FloatArray
    sample_sigma: FloatArray


@dataclass(frozen=True)
class Polar:
    curves: list[Curve]
    surface_label: str
    truth_label: str | None
    title: str


def check_theta_i(theta_i_deg: Sequence[float], theta_max: float) -> None:
    """`GonioError` unless every θi (degrees) is in [0°, θmax] (``theta_max`` in rad)."""
    limit = math.degrees(theta_max)
    for t in theta_i_deg:
        if not (math.isfinite(t) and 0.0 <= t <= limit):
            raise GonioError(
                f"--theta-i {t:g}: expected an angle in degrees in [0, {limit:g}] "
                "(the rig's θ limit)"
            )


def in_plane(theta_i: float, theta_o: FloatArray) -> tuple[FloatArray, FloatArray]:
    """The pairs (M, 3) of the plane of incidence at φi = 0 (see the module docstring)."""
    theta_o = np.asarray(theta_o, dtype=np.float64)
    zero = np.zeros_like(theta_o)
    wi = np.stack(
        [np.full_like(theta_o, math.sin(theta_i)), zero, np.full_like(theta_o, math.cos(theta_i))],
        axis=-1,
    )
    wo = np.stack([-np.sin(theta_o), zero, np.cos(theta_o)], axis=-1)
    return wi, wo


def near_plane(
    wi: FloatArray, wo: FloatArray, theta_i: float, tolerance: float
) -> tuple[BoolArray, FloatArray]:
    """Which pairs (N, 3) are within ``tolerance`` (rad) of the in-plane curve of
    ``theta_i``, and every pair's signed θo in its own plane of incidence (rad; a pair
    at normal incidence has every plane: its ωo's own)."""
    wi = np.asarray(wi, dtype=np.float64)
    wo = np.asarray(wo, dtype=np.float64)
    tangent = wi[:, :2]
    length = np.linalg.norm(tangent, axis=-1)
    normal_incidence = length <= 1e-12
    wo_tangent = wo[:, :2]
    fallback = wo_tangent / np.maximum(np.linalg.norm(wo_tangent, axis=-1, keepdims=True), 1e-300)
    ex = np.where(
        normal_incidence[:, None], -fallback, tangent / np.maximum(length, 1e-300)[:, None]
    )
    ey = np.stack([-ex[:, 1], ex[:, 0]], axis=-1)
    off_plane = np.arcsin(np.clip(np.abs(np.sum(wo_tangent * ey, axis=-1)), 0.0, 1.0))
    theta_o = np.arctan2(-np.sum(wo_tangent * ex, axis=-1), wo[:, 2])
    own_theta_i = np.arctan2(length, wi[:, 2])
    near = (np.abs(own_theta_i - theta_i) <= tolerance) & (off_plane <= tolerance)
    return np.asarray(near, dtype=np.bool_), np.asarray(theta_o, dtype=np.float64)


def polar(
    surface: Surface,
    samples: tuple[FloatArray, FloatArray, FloatArray, FloatArray],
    theta_max: float,
    theta_i_deg: Sequence[float] = DEFAULT_THETA_I_DEG,
    *,
    truth: BrdfEval | None = None,
    tolerance_deg: float = DEFAULT_TOLERANCE_DEG,
    surface_label: str = "reconstruction",
    truth_label: str | None = None,
    title: str = "",
) -> Polar:
    """The in-plane curves of ``surface`` (and ``truth``) at ``theta_i_deg`` (degrees)
    with θo over [−``theta_max``, ``theta_max``] (rad), and the ``samples`` (wi, wo, f,
    sigma) near each plane (see the module docstring)."""
    check_theta_i(theta_i_deg, theta_max)
    swi, swo, sf, ssigma = (np.asarray(a, dtype=np.float64) for a in samples)
    sf, ssigma = one_channel(sf), one_channel(ssigma)
    theta_o = np.linspace(-theta_max, theta_max, POINTS)
    tolerance = math.radians(tolerance_deg)
    curves = []
    for t in theta_i_deg:
        theta_i = math.radians(t)
        wi, wo = in_plane(theta_i, theta_o)
        near, sample_theta_o = near_plane(swi, swo, theta_i, tolerance)
        curves.append(
            Curve(
                theta_i=theta_i,
                theta_o=theta_o,
                wi=wi,
                wo=wo,
                surface=values(surface, wi, wo),
                supported=supported(surface, wi, wo),
                truth=None if truth is None else one_channel(truth(wi, wo)),
                sample_theta_o=sample_theta_o[near],
                sample_f=sf[near],
                sample_sigma=ssigma[near],
            )
        )
    return Polar(curves, surface_label, truth_label if truth is not None else None, title)


def draw(data: Polar, path: str | Path, *, format: str | None = None) -> None:
    """Draw ``data`` to ``path``: f on a log axis against the signed θo in degrees, one
    colour per θi."""
    plt = require_matplotlib()
    fig, ax = plt.subplots(figsize=FIGSIZE, constrained_layout=True)
    colours = plt.get_cmap("viridis")(np.linspace(0.0, 0.85, max(len(data.curves), 1)))
    for c, colour in zip(data.curves, colours, strict=True):
        deg = np.degrees(c.theta_o)
        name = f"θi = {math.degrees(c.theta_i):g}°"
        shown = np.where(c.surface > FLOOR, c.surface, np.nan)
        ax.plot(
            deg,
            np.where(c.supported, shown, np.nan),
            color=colour,
            lw=1.6,
            label=f"{data.surface_label}, {name}",
        )
        ax.plot(deg, np.where(c.supported, np.nan, shown), color=colour, lw=1.0, ls=":")
        if c.truth is not None:
            truth = np.where(c.truth > FLOOR, c.truth, np.nan)
            ax.plot(deg, truth, color=colour, lw=1.0, ls="--")
        if len(c.sample_f):
            lower = np.minimum(c.sample_sigma, c.sample_f - FLOOR * 0.5)
            ax.errorbar(
                np.degrees(c.sample_theta_o),
                np.maximum(c.sample_f, FLOOR),
                yerr=[np.maximum(lower, 0.0), c.sample_sigma],
                fmt="o",
                ms=3.5,
                color=colour,
                ecolor=colour,
                capsize=2.0,
                lw=0.8,
            )
    ax.set_yscale("log")
    ax.set_xlabel("θo (degrees; > 0: the far side of the normal, the mirror at θo = θi)")
    ax.set_ylabel("f (sr⁻¹)")
    handles, _ = ax.get_legend_handles_labels()
    from matplotlib.lines import Line2D  # optional: the plot extra

    handles += [
        Line2D([], [], color="k", ls=":", label="no data there (extrapolated)"),
        Line2D([], [], color="k", marker="o", ls="", label="samples (±1σ) near the plane"),
    ]
    if data.truth_label is not None:
        handles.append(Line2D([], [], color="k", ls="--", label=data.truth_label))
    ax.legend(handles=handles, fontsize=8, loc="best")
    ax.grid(True, which="major", alpha=0.3)
    ax.set_title(data.title, fontsize=10)
    save(fig, path, format)
