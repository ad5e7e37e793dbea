"""Fixtures of the reconstruction tests: measurements synthesized from analytic models
(each built once) and one real simulated run."""

from __future__ import annotations

from pathlib import Path

import pytest

from gonio import brdf
from gonio.analysis.measured import Measured
from gonio.brdf.base import BRDF
from gonio.rig.model import Rig
from studies.reconstruct.synthetic import synthesize
from tests.support.runs import plan_spec, scene_spec, simulated_run

ARCH = Path(__file__).resolve().parents[3] / "configs" / "rigs" / "arch.yaml"


@pytest.fixture(scope="session")
def arch() -> Rig:
    return Rig.from_yaml(ARCH)


@pytest.fixture(scope="session")
def matte() -> BRDF:
    """The matte scene's material: smooth, grey."""
    return brdf.create(
        "cook_torrance", alpha=0.5, distribution="ggx", fresnel="schlick", f0=0.04, kd=0.6
    )


@pytest.fixture(scope="session")
def brushed() -> BRDF:
    """An anisotropic material, wide enough to be sampled by a few thousand points."""
    return brdf.create("ggx_anisotropic", alpha_x=0.2, alpha_y=0.5, fresnel="schlick", f0=0.5)


@pytest.fixture(scope="session")
def matte_iso(arch: Rig, matte: BRDF) -> Measured:
    """1 500 samples of the matte material, hybrid isotropic."""
    return synthesize(matte.eval, arch, "hybrid", True, 1500)


@pytest.fixture(scope="session")
def simulated_matte(runs_dir: Path) -> Measured:
    """A real simulated run: 300 targets on the matte scene, noise off."""
    path = simulated_run(runs_dir, plan_spec(300), scene_spec("matte", noise=False))
    return Measured.from_run(path)
