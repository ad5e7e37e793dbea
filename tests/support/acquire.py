"""Small plans and runs for the acquisition tests: a plan file with its rig, built
once, and a run acquired on the simulated backend into a real SQLite file."""

from __future__ import annotations

from functools import cache
from pathlib import Path

from gonio.acquire import session
from gonio.planner.plan import Plan, PlanSource, load_plan_source
from sim.scene import Scene
from tests.conftest import CONFIGS

QUICK = CONFIGS / "plans" / "quick.yaml"
MATTE = CONFIGS / "scenes" / "matte.yaml"


def plan_file(
    folder: Path, *, target: int = 40, acquisition: str = "", name: str = "small"
) -> Path:
    """A plan file in ``folder``: the quick plan's sampling with ``target`` targets on
    the arch rig, with an ``acquisition:`` section (YAML text, indented by the caller
    at top level) if given."""
    rig = (CONFIGS / "rigs" / "arch.yaml").resolve()
    text = (
        f"name: {name}\nrig: {rig}\nparametrization: hybrid\nisotropic: true\n"
        f"sampling: {{strategy: sobol, target: {target}, seed: 1}}\n"
        "exposure: {seconds: 0.05, averages: 1}\n"
        f"{acquisition}"
    )
    path = folder / f"{name}.yaml"
    path.write_text(text, encoding="utf-8")
    return path


@cache
def _built(path: str, text: bytes) -> tuple[PlanSource, Plan]:
    source = load_plan_source(Path(path))
    return source, source.build()


def build_plan(path: Path) -> tuple[PlanSource, Plan]:
    """(source, plan) of a plan file (cached by path and content)."""
    return _built(str(path), path.read_bytes())


def scene_file(folder: Path, extra: str = "", base: Path = MATTE, name: str = "scene") -> Path:
    """A scene file in ``folder``: ``base``'s text with ``extra`` YAML appended."""
    path = folder / f"{name}.yaml"
    path.write_text(base.read_text(encoding="utf-8") + extra, encoding="utf-8")
    return path


def acquire(
    plan_path: Path, scene_path: Path, output: Path | None, **kwargs: object
) -> session.Outcome:
    """`session.start` of a plan file in a scene (what `gonio acquire` does)."""
    source, plan = build_plan(plan_path)
    scene, text = session.load_scene_file(scene_path, source.rig)
    files = session.Files(
        source.path, source.text, source.rig.source, source.rig.text, scene_path, text
    )
    return session.start(plan, files, scene=scene, output=output, **kwargs)  # type: ignore[arg-type]


def load(scene_path: Path) -> Scene:
    from sim.scene import load_scene

    return load_scene(scene_path)
