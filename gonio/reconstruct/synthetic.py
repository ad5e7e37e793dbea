"""Measured samples synthesized without the acquisition engine: a plan-like uniform
placement in a parametrization's coordinates (Sobol, or a grid of cell centres), kept
where valid and reachable by the rig, mapped to pairs and valued by a BRDF function.
For benchmarks, studies and tests of the reconstruction."""

from __future__ import annotations

import numpy as np
from scipy.stats import qmc

from gonio import params
from gonio.reconstruct.measured import Measured
from gonio.rig.model import Rig
from gonio.types import BrdfEval, FloatArray


def placed(
    rig: Rig,
    parametrization: str,
    isotropic: bool,
    n: int,
    *,
    seed: int = 0,
    grid: int | None = None,
) -> tuple[FloatArray, FloatArray]:
    """About ``n`` pairs (Sobol; exactly n) or the kept cells of a ``grid``-per-axis
    grid, each (N, 3), as a plan of that parametrization would place them."""
    p = params.get(parametrization)
    bounds = np.asarray(p.iso_bounds if isotropic else p.bounds, dtype=np.float64)
    d = len(bounds)
    if grid is not None:
        centres = (np.arange(grid) + 0.5) / grid
        unit = np.stack(np.meshgrid(*[centres] * d, indexing="ij"), axis=-1).reshape(-1, d)
    else:
        drawn = (8 if d == 3 else 16) * n  # enough to keep n after the domain and the rig
        unit = qmc.Sobol(d, scramble=True, seed=seed).random_base2(int(np.ceil(np.log2(drawn))))
    coords = bounds[:, 0] + unit * (bounds[:, 1] - bounds[:, 0])
    valid = p.valid_iso(coords) if isotropic else p.valid(coords)
    coords = coords[valid]
    wi, wo = p.inverse_iso(coords) if isotropic else p.inverse(coords)
    ok = rig.reachable(wi, wo, isotropic=isotropic)[0]
    wi, wo = wi[ok], wo[ok]
    return (wi, wo) if grid is not None else (wi[:n], wo[:n])


def synthesize(
    f: BrdfEval,
    rig: Rig,
    parametrization: str,
    isotropic: bool,
    n: int,
    *,
    seed: int = 0,
    grid: int | None = None,
    relative_sigma: float = 0.01,
) -> Measured:
    """A `Measured` of ``f`` at `placed` pairs, noise-free, with σ = relative_sigma·|f|."""
    wi, wo = placed(rig, parametrization, isotropic, n, seed=seed, grid=grid)
    values = np.asarray(f(wi, wo), dtype=np.float64)
    return Measured(
        wi=wi,
        wo=wo,
        f=values,
        sigma=relative_sigma * np.abs(values),
        parametrization=parametrization,
        isotropic=isotropic,
        rig=rig,
        scene_text=None,
        band="rgb" if values.ndim == 2 else "luminance",
        source=f"synthetic {parametrization} {'isotropic' if isotropic else 'anisotropic'}",
    )
