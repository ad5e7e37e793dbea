"""Measured samples synthesized without the acquisition engine, for benchmarks, studies
and tests of the reconstruction.

A noise-free simulated run with no optical effect measures f(ωi, ωo) of the scene's
material exactly at the pairs its plan reached; `synthesize` gives those measurements
directly: the plan's points placed by the planner in a parametrization's coordinates
(Sobol, or a grid), kept where valid and reachable, valued by a BRDF function. The
ordering and the acquisition, which do not change the values, are skipped
(tests/studies/reconstruct/test_synthetic.py holds this to a real run).
`synthesize_adaptive` does the same for the two passes of an adaptive plan."""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from gonio import params
from gonio.analysis import Measured
from gonio.planner import MARGIN, Choice, PlanSpec, Survey, directions, place, second_pass
from gonio.rig import Rig
from gonio.types import BrdfEval, FloatArray
from gonio.workflows import estimate

if TYPE_CHECKING:
    from collections.abc import Mapping


def placed(
    rig: Rig,
    parametrization: str,
    isotropic: bool,
    n: int,
    *,
    seed: int = 0,
    grid: int | None = None,
) -> tuple[FloatArray, FloatArray]:
    """The pairs a plan of ``parametrization`` keeps, each (N, 3): ``n`` of a Sobol
    sequence, or the kept cells of a ``grid``-per-axis grid, placed by the planner
    (`gonio.planner.placement`) and kept where valid and reachable."""
    p = params.get(parametrization)
    names = p.iso_names if isotropic else p.names
    sampling: dict[str, object] = (
        {"strategy": "sobol", "target": n, "seed": seed}
        if grid is None
        else {"strategy": "grid", "counts": dict.fromkeys(names, grid)}
    )
    spec = _spec(parametrization, isotropic, sampling)
    coords, _ = place(spec, rig, "synthetic")
    return _kept(spec, rig, coords)


def _spec(parametrization: str, isotropic: bool, sampling: dict[str, object]) -> PlanSpec:
    return PlanSpec.model_validate(
        {
            "name": "synthetic",
            "parametrization": parametrization,
            "isotropic": isotropic,
            "sampling": sampling,
        }
    )


def _kept(spec: PlanSpec, rig: Rig, coords: FloatArray) -> tuple[FloatArray, FloatArray]:
    _, wi, wo = directions(spec, coords)
    ok = rig.solve(wi, wo, isotropic=spec.isotropic).ok
    return wi[ok], wo[ok]


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
    sigma_floor: float = 0.0,
) -> Measured:
    """A `Measured` of ``f`` at `placed` pairs, noise-free, with
    σ = relative_sigma·(|f| + sigma_floor) (``sigma_floor`` in sr⁻¹: an absolute part)."""
    wi, wo = placed(rig, parametrization, isotropic, n, seed=seed, grid=grid)
    return _valued(f, rig, parametrization, isotropic, wi, wo, relative_sigma, sigma_floor)


def synthesize_adaptive(
    f: BrdfEval,
    rig: Rig,
    parametrization: str,
    isotropic: bool,
    n: int,
    *,
    seed: int = 0,
    adaptive: Mapping[str, object] | None = None,
    relative_sigma: float = 0.01,
    sigma_floor: float = 0.0,
) -> Measured:
    """A `Measured` of ``f`` at the pairs of an adaptive plan of ``n`` kept targets
    (``adaptive``: its options, `gonio.planner.schema.AdaptiveSpec`): the Sobol survey
    valued like `synthesize`, then the second pass planned from those values and σs
    (`gonio.planner.two_pass.second_pass`, steered by
    `gonio.workflows.adaptive.estimate`: the σs weight the fit) and valued too, survey
    first."""
    return adaptive_choice(
        f,
        rig,
        parametrization,
        isotropic,
        n,
        seed=seed,
        adaptive=adaptive,
        relative_sigma=relative_sigma,
        sigma_floor=sigma_floor,
    )[0]


def adaptive_choice(
    f: BrdfEval,
    rig: Rig,
    parametrization: str,
    isotropic: bool,
    n: int,
    *,
    seed: int = 0,
    adaptive: Mapping[str, object] | None = None,
    relative_sigma: float = 0.01,
    sigma_floor: float = 0.0,
    margin: float = MARGIN,
) -> tuple[Measured, Choice]:
    """`synthesize_adaptive` and the choice its second pass made
    (`gonio.planner.choice`: adaptive, or uniform outright; ``margin`` 0: adaptive
    always)."""
    sampling = {"strategy": "adaptive", "target": n, "seed": seed, "adaptive": adaptive or {}}
    spec = _spec(parametrization, isotropic, sampling)
    coords, _ = place(spec, rig, "synthetic")
    sigma = {"relative_sigma": relative_sigma, "sigma_floor": sigma_floor}
    survey = measured_at(f, spec, rig, coords, **sigma)
    steer = estimate(survey, spec.sampling.options().model)
    measured = Survey(len(coords), survey.wi, survey.wo, survey.f)
    rest, chosen = second_pass(spec, rig, steer, measured, n - len(survey), margin=margin)
    both = replace(
        survey.joined(measured_at(f, spec, rig, rest, **sigma)),
        source=f"synthetic adaptive {parametrization} "
        f"{'isotropic' if isotropic else 'anisotropic'}",
    )
    return both, chosen


def measured_at(
    f: BrdfEval,
    spec: PlanSpec,
    rig: Rig,
    coords: FloatArray,
    *,
    relative_sigma: float = 0.01,
    sigma_floor: float = 0.0,
) -> Measured:
    """A `Measured` of ``f`` at a plan's points ``coords`` (``spec``'s coordinates), kept
    where valid and reachable, valued like `synthesize`."""
    wi, wo = _kept(spec, rig, coords)
    return _valued(
        f, rig, spec.parametrization, spec.isotropic, wi, wo, relative_sigma, sigma_floor
    )


def _valued(
    f: BrdfEval,
    rig: Rig,
    parametrization: str,
    isotropic: bool,
    wi: FloatArray,
    wo: FloatArray,
    relative_sigma: float,
    sigma_floor: float,
) -> Measured:
    values = np.asarray(f(wi, wo), dtype=np.float64)
    return Measured(
        wi=wi,
        wo=wo,
        f=values,
        sigma=relative_sigma * (np.abs(values) + sigma_floor),
        parametrization=parametrization,
        isotropic=isotropic,
        rig=rig,
        scene_text=None,
        band="rgb" if values.ndim == 2 else "luminance",
        source=f"synthetic {parametrization} {'isotropic' if isotropic else 'anisotropic'}",
    )
