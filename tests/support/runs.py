"""Simulated runs for the reconstruction, evaluation, fitting and export tests: a plan
and a scene written into a folder, acquired in-process by `gonio acquire` on the
simulated backend into a real run file, each built once per test session."""

from __future__ import annotations

import hashlib
from pathlib import Path
from typing import Any

import yaml

from gonio.cli import main

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
RIGS = CONFIGS / "rigs"
SCENES = CONFIGS / "scenes"

#: Effects of the shipped scenes that add noise (dropped for a noise-free run).
NOISE = ("shot_noise", "read_noise", "dark_current", "quantization", "source_drift")


def scene_spec(
    base: str = "glossy_metal",
    *,
    material: dict[str, Any] | None = None,
    noise: bool = True,
    band: str | None = None,
    seed: int | None = None,
    effects: list[str] | None = None,
) -> dict[str, Any]:
    """A shipped scene's spec with its material, noise, detector band or seed replaced.
    ``noise=False`` drops the noise effects (and position errors); ``effects`` replaces
    the effect list outright."""
    spec: dict[str, Any] = yaml.safe_load((SCENES / f"{base}.yaml").read_text())
    if material is not None:
        spec["material"] = material
    raw = spec.get("effects") or {}
    chosen = dict.fromkeys(raw) if isinstance(raw, list) else dict(raw)
    if effects is not None:
        chosen = dict.fromkeys(effects)
    elif not noise:
        chosen = {k: v for k, v in chosen.items() if k not in NOISE and k != "position_error"}
    spec["effects"] = chosen
    if band is not None:
        spec["detector"]["band"] = band
    if seed is not None:
        spec["seed"] = seed
    return spec


def plan_spec(
    targets: int = 300,
    *,
    parametrization: str = "hybrid",
    isotropic: bool = True,
    strategy: str = "sobol",
    rig: str = "arch",
    seed: int = 3,
    exposure_s: float = 0.05,
    averages: int = 1,
) -> dict[str, Any]:
    """A uniform plan on a shipped rig, calibrated at the start, every 500 targets and
    at the end (the plan's ordering keeps the default search)."""
    return {
        "name": f"test-{parametrization}-{targets}",
        "rig": str(RIGS / f"{rig}.yaml"),
        "parametrization": parametrization,
        "isotropic": isotropic,
        "sampling": {"strategy": strategy, "target": targets, "seed": seed},
        "exposure": {"seconds": exposure_s, "averages": averages},
        "time_budget_s": 60,
        "acquisition": {"calibration": {"every_samples": 500, "dark": True, "averages": 16}},
    }


def simulated_run(folder: Path, plan: dict[str, Any], scene: dict[str, Any]) -> Path:
    """The run file of ``plan`` measured on ``scene`` in ``folder``, acquired once (a
    file named by the specs' hash is reused)."""
    key = hashlib.sha256(yaml.safe_dump([plan, scene]).encode()).hexdigest()[:16]
    out = folder / f"run-{key}.sqlite"
    if out.is_file():
        return out
    plan_file, scene_file = folder / f"plan-{key}.yaml", folder / f"scene-{key}.yaml"
    plan_file.write_text(yaml.safe_dump(plan, sort_keys=False))
    scene_file.write_text(yaml.safe_dump(scene, sort_keys=False))
    code = main(["acquire", str(plan_file), "--scene", str(scene_file), "-o", str(out), "-q"])
    assert code == 0, f"gonio acquire exited {code}"
    return out
