"""Noise-free measurements of uniform plans for accuracy studies, without the engine.

A noise-free simulated run with no optical effect measures f(ωi, ωo) of the scene's
material exactly at the pairs its plan reached; `uniform_samples` gives those
measurements directly: the plan's points placed uniformly in a parametrization's box
(`gonio.planner.placement`), kept where valid and reachable, valued by the model. The
ordering and the acquisition, which do not change the values, are skipped
(tests/gonio/reconstruct/test_study.py holds this to a real run).
"""

from __future__ import annotations

import numpy as np

from gonio.planner.placement import directions, place
from gonio.planner.schema import PlanSpec
from gonio.reconstruct.measured import Measured
from gonio.rig.model import Rig
from gonio.types import BrdfEval


def uniform_samples(
    truth: BrdfEval,
    rig: Rig,
    *,
    parametrization: str,
    targets: int,
    isotropic: bool = True,
    strategy: str = "sobol",
    seed: int = 3,
) -> Measured:
    """About ``targets`` noise-free samples of ``truth`` uniform in ``parametrization``
    (exactly ``targets`` for a sequence strategy; grids keep about that many)."""
    spec = PlanSpec.model_validate(
        {
            "name": "study",
            "parametrization": parametrization,
            "isotropic": isotropic,
            "sampling": {"strategy": strategy, "target": targets, "seed": seed},
        }
    )
    coords, _ = place(spec, rig, "study")
    _, wi, wo = directions(spec, coords)
    ok = rig.solve(wi, wo, isotropic=isotropic).ok
    wi, wo = wi[ok], wo[ok]
    f = np.asarray(truth(wi, wo), dtype=np.float64)
    return Measured(
        wi=wi,
        wo=wo,
        f=f,
        sigma=np.zeros_like(f),
        parametrization=parametrization,
        isotropic=isotropic,
        rig=rig,
        scene_text=None,
        band="luminance",
        source=f"{targets} noise-free samples uniform in {parametrization}",
    )
