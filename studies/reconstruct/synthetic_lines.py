"""Line data synthesized without the planner or the engine, for benchmarks and tests of
the reconstruction from fly sweeps: lines along θh at fixed (θd, φd) of Rusinkiewicz's
isotropic coordinates, the positions a Sobol set over [0, π/2] × [0, π), each line
sampled every ``step_deg`` from θh = 0, kept where valid and where the rig reaches the
pair (`Rig.solve`), valued by a BRDF function, noise-free."""

from __future__ import annotations

import math

import numpy as np
from scipy.stats import qmc

from gonio import params
from gonio.analysis import Measured
from gonio.rig import Rig
from gonio.types import BrdfEval, FloatArray


def line_coordinates(
    lines: int, step_deg: float, *, seed: int = 0
) -> tuple[FloatArray, np.ndarray]:
    """(θh, θd, φd) in radians (N, 3) of ``lines`` lines along θh in [0, π/2) every
    ``step_deg`` degrees at Sobol (θd, φd), and each point's line (N,)."""
    m = max(0, math.ceil(math.log2(max(lines, 1))))
    position = qmc.Sobol(2, scramble=True, seed=seed).random_base2(m)[:lines]
    position *= [math.pi / 2, math.pi]
    theta_h = np.arange(0.0, math.pi / 2, math.radians(step_deg))
    n = len(theta_h)
    coords = np.empty((lines * n, 3))
    coords[:, 0] = np.tile(theta_h, lines)
    coords[:, 1:] = np.repeat(position, n, axis=0)
    return coords, np.repeat(np.arange(lines), n)


def synthesize_lines(
    f: BrdfEval,
    rig: Rig,
    lines: int,
    step_deg: float,
    *,
    seed: int = 0,
    relative_sigma: float = 0.01,
) -> tuple[Measured, np.ndarray]:
    """A `Measured` of ``f`` on `line_coordinates` (isotropic, Rusinkiewicz) kept where
    valid and reachable, σ = relative_sigma·|f|, and each sample's line (N,)."""
    p = params.get("rusinkiewicz")
    coords, label = line_coordinates(lines, step_deg, seed=seed)
    valid = p.valid_iso(coords)
    wi, wo = p.inverse_iso(coords[valid])
    ok = rig.solve(wi, wo, isotropic=True).ok
    wi, wo, label = wi[ok], wo[ok], label[valid][ok]
    value = np.asarray(f(wi, wo), dtype=np.float64)
    measured = Measured(
        wi=wi,
        wo=wo,
        f=value,
        sigma=relative_sigma * np.abs(value),
        parametrization="rusinkiewicz",
        isotropic=True,
        rig=rig,
        scene_text=None,
        band="luminance",
        source=f"{lines} synthetic lines every {step_deg:g}°",
    )
    return measured, label
