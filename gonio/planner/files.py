"""Plan files: the plan file a user writes (YAML) read with its rig (`load_plan_source`,
`load_plan`) and built into a `Plan` (`PlanSource.build`); the plan as stored is
`gonio.planner.stored`'s."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from gonio import planner  # its face: the builder (scipy, numba) loads when a plan is built
from gonio.config import ConfigError, line_of, load, read_bytes, read_yaml
from gonio.planner.model import Plan, content_hash
from gonio.planner.schema import PlanSpec
from gonio.rig import Rig


@dataclass(frozen=True)
class PlanSource:
    """A plan file as read: its path and bytes, the validated spec and the rig (which
    keeps its own bytes, `Rig.text`)."""

    path: Path
    text: bytes
    spec: PlanSpec
    rig: Rig

    def content_hash(self, scene_text: bytes | None = None) -> str:
        return content_hash(self.text, self.rig.text, scene_text, self.rig.alignment_text)

    def build(self, *, bounds: bool = False) -> Plan:
        """`build` with this file's text (so the plan carries its hash)."""
        return planner.build(
            self.spec, self.rig, where=str(self.path), bounds=bounds, text=self.text
        )


def load_plan_source(path: str | Path, rig_path: str | Path | None = None) -> PlanSource:
    """The plan file, its bytes and its rig (``rig_path`` overrides the ``rig`` field).
    Each file is read once: what is validated is exactly what is hashed."""
    path = Path(path)
    text = read_bytes(path)
    spec = load(path, PlanSpec, raw=text)
    if rig_path is None:
        if spec.rig is None:
            raise ConfigError(f"{path}: rig: no rig file named; give one here or with --rig")
        rig_path = path.parent / spec.rig
        try:
            folder = Path(rig_path).is_dir()
        except OSError:  # a name too long, say: reading the rig file below says why
            folder = False
        if folder:
            line = line_of(read_yaml(path, text)[1], ("rig",))
            raise ConfigError(f"{path}:{line}: rig: {rig_path} is a folder; expected a rig file")
    return PlanSource(path, text, spec, Rig.from_yaml(rig_path))


def load_plan(path: str | Path, rig_path: str | Path | None = None) -> tuple[PlanSpec, Rig]:
    """The plan file and its rig (``rig_path`` overrides the plan's ``rig`` field); see
    `load_plan_source` to keep the plan file's bytes as well."""
    source = load_plan_source(path, rig_path)
    return source.spec, source.rig
