"""What a live view needs of a run's stored plan: `PlanInfo`, read from the plan's header
alone (cheap even for a plan of a million targets), and `PlanArrays`, from its parsed
targets. `parse_in_background` parses a large stored plan in another process and sends
back its arrays and the run's measured targets (`gonio.store.follow.RunFollower` starts
it).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass
from multiprocessing.connection import Connection
from pathlib import Path
from typing import Any

import numpy as np

from gonio.errors import GonioError
from gonio.planner import Plan, parse_plan
from gonio.rig import Rig
from gonio.store import checks, readonly
from gonio.store.read import check_plan, check_targets, decode_meta, refusing
from gonio.types import FloatArray


@dataclass(frozen=True)
class PlanInfo:
    """What a live view needs of the stored plan, from its header alone (cheap even for
    a plan of a million targets): its name, rig, number of targets, predicted total
    (s), whether it is a fly plan or an adaptive plan's survey, its parametrization and
    whether it is isotropic (three coordinates, else four)."""

    name: str
    rig: Rig
    targets: int
    total_s: float
    fly: bool
    survey: bool
    parametrization: str = "rusinkiewicz"
    isotropic: bool = True

    @classmethod
    def of(
        cls, head: bytes, rig_text: str, where: str, alignment_text: str | None = None
    ) -> PlanInfo:
        """The header of a stored plan's first bytes ``head``; `checks.Bad` (or the rig
        file's `ConfigError`) when it is not one."""
        field_ = "meta.plan_file"
        header: dict[str, Any] = {}
        for raw in head.split(b"\n")[1:]:
            if not raw.startswith(b"#"):
                break
            try:
                line = raw.decode("utf-8")
            except UnicodeDecodeError:
                break
            key, _, value = line.removeprefix("#").strip().partition(":")
            if key in ("spec", "summary"):
                header[key] = checks.mapping(
                    checks.json_value(value, f"{field_}.{key}"), f"{field_}.{key}"
                )
        if "spec" not in header or "summary" not in header:
            raise checks.Bad(f"{field_}: expected a stored plan's header, found none")
        spec, summary = header["spec"], header["summary"]
        sampling = checks.mapping(spec.get("sampling", {}), f"{field_}.spec.sampling")
        targets = checks.integer(summary.get("kept"), f"{field_}.summary.kept")
        if targets < 0:
            raise checks.Bad(f"{field_}.summary.kept: expected a count, got {targets}")
        wanted = checks.optional(checks.integer)(sampling.get("target"), f"{field_}.target")
        travel = checks.number(summary.get("travel_s"), f"{field_}.summary.travel_s")
        dwell = checks.number(summary.get("dwell_s"), f"{field_}.summary.dwell_s")
        return cls(
            name=str(spec.get("name", "")),
            rig=Rig.from_yaml(  # ConfigError: one line
                where,
                raw=rig_text.encode("utf-8"),
                alignment_raw=None if alignment_text is None else alignment_text.encode("utf-8"),
            ),
            targets=targets,
            total_s=travel + dwell,
            fly=sampling.get("strategy") == "fly",
            survey=sampling.get("strategy") == "adaptive"
            and wanted is not None
            and targets < wanted,
            parametrization=checks.text(
                spec.get("parametrization", "rusinkiewicz"), f"{field_}.spec.parametrization"
            ),
            isotropic=checks.boolean(spec.get("isotropic", True), f"{field_}.spec.isotropic"),
        )


@dataclass(frozen=True)
class PlanArrays:
    """What a live view uses of the stored plan's targets: each one's predicted time
    (s: the move into it, the settle, the exposures), its (ωi, ωo) and its coordinates
    in the plan's parametrization (their names: ``coordinate_names``)."""

    per_target_s: FloatArray
    wi: FloatArray
    wo: FloatArray
    coords: FloatArray
    coordinate_names: tuple[str, ...]

    @classmethod
    def of(cls, plan: Plan) -> PlanArrays:
        each = plan.travel_s + plan.rig.spec.settle_s + plan.exposure_s * plan.averages
        return cls(
            np.asarray(each, np.float64),
            plan.wi,
            plan.wo,
            np.asarray(plan.coords, np.float64),
            tuple(plan.coordinate_names),
        )


def parse_in_background(path: Path, out: Connection) -> None:
    """Send a large run's `PlanArrays` and its measured targets through ``out`` (or the
    one line why the plan cannot be read): the work of another process."""
    os.nice(10)  # after the acquisition and the server
    result: tuple[PlanArrays, np.ndarray] | str
    try:
        with refusing(path):
            conn = readonly.connect(path)
            try:
                conn.execute("BEGIN")
                meta = decode_meta(conn.execute("SELECT key, value FROM meta").fetchall())
                raw = conn.execute("SELECT value FROM meta WHERE key = 'plan_file'").fetchone()[0]
                plan = parse_plan(bytes(raw), f"{path}#plan_file")
                check_plan(meta, plan)
                targets = np.array([r[0] for r in conn.execute("SELECT target FROM samples")])
                conn.execute("COMMIT")
            finally:
                conn.close()
            if targets.dtype != np.int64 and targets.size:
                raise checks.Bad("samples.target: expected whole numbers")
            check_targets(targets, len(plan))
        result = (PlanArrays.of(plan), targets.astype(np.int64))
    except GonioError as exc:
        result = str(exc)
    out.send(result)
    out.close()


__all__: Sequence[str] = ("PlanArrays", "PlanInfo", "parse_in_background")
