"""`build`: from a plan file and a rig to an ordered, timed list of motor targets.

Points are placed uniformly in the parametrization's coordinate box (or its isotropic
reduction), kept where the coordinates are `valid` and the rig can reach the pair, mapped
to joint angles, ordered for the motors, and timed with each axis's trapezoidal profile
plus settle and exposure. Nothing here moves a motor.

A `Plan` is frozen (its arrays read-only) and is the same for a given plan file, rig
and seed on any machine unless the ordering's wall-clock safety cap binds (the summary
says so). It writes itself to a file and reads back bit for bit (`Plan.write`,
`gonio.planner.stored.read_plan`); `content_hash` names the texts it was built from.
"""

from __future__ import annotations

import hashlib
import time
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from gonio.config import ConfigError, line_of, load, read_bytes, read_yaml, spec_text
from gonio.planner import lkh, placement, poses, sampling
from gonio.planner.bounds import held_karp_bound
from gonio.planner.exposure import check_detector, exposures
from gonio.planner.ordering import (
    Method,
    Ordering,
    Stop,
    default_kicks,
    default_moves,
    order_jointly,
)
from gonio.planner.placement import directions, place, too_many
from gonio.planner.poses import Relaxed
from gonio.planner.schema import PlanSpec
from gonio.rig.model import Reason, Rig, Solution
from gonio.types import FloatArray

#: Framing of `content_hash` (the version names the framing, not gonio's).
_HASH_MAGIC = b"gonio content v1\n"


def content_hash(plan_text: bytes, rig_text: bytes, scene_text: bytes | None = None) -> str:
    """SHA-256 (hex) of a plan file's, a rig file's and optionally a scene file's bytes,
    for the run journal: what a run measured, named by what it was made from.

    Framing: the bytes ``gonio content v1\\n``, then for each of plan, rig, scene the
    part's name, a space, its length in bytes in decimal (``-`` for no scene), a newline
    and the bytes themselves. The lengths make the split unambiguous: ("ab", "c") and
    ("a", "bc") hash differently, and no scene differs from an empty one.
    """
    h = hashlib.sha256(_HASH_MAGIC)
    for name, text in (("plan", plan_text), ("rig", rig_text), ("scene", scene_text)):
        h.update(f"{name} {'-' if text is None else len(text)}\n".encode("ascii"))
        if text is not None:
            h.update(text)
    return h.hexdigest()


def sha256(text: bytes) -> str:
    """SHA-256 (hex) of one file's bytes."""
    return hashlib.sha256(text).hexdigest()


@dataclass(frozen=True)
class Summary:
    """Counts and times of a plan. Times in seconds; the generation-order and MST
    figures are None unless the plan was built with ``bounds=True``."""

    requested: int  # points placed in the coordinate box
    invalid: int  # outside the parametrization's domain
    refused: Mapping[str, int]  # unreachable, by reason (read-only)
    kept: int
    travel_s: float  # ordered, moves only
    dwell_s: float  # settle + exposure × averages, summed
    ordering_s: float  # time spent ordering (wall clock)
    moves: int = 0  # improving moves of the ordering's descents
    max_moves: int = 0  # the budget of improving moves
    kicks: int = 0  # kicks of the iterated local search tried
    kicks_kept: int = 0  # … that shortened the path
    max_kicks: int = 0  # the budget of kicks
    stopped: Stop = "converged"  # why the ordering stopped
    time_cap_s: float = 0.0  # the ordering's wall-clock safety cap
    grid_shape: tuple[int, ...] | None = None
    target: int | None = None  # the kept targets asked for, if the plan gave a number
    naive_travel_s: float | None = None  # in generation order (bounds only)
    # Lower bounds on the moves of any order with any choice of solutions (bounds only):
    lower_bound_travel_s: float | None = None  # Held–Karp 1-tree (`gonio.planner.bounds`)
    mst_travel_s: float | None = None  # the minimum spanning tree (cheaper, looser)
    lower_bound_exact: bool | None = None  # False: memory forced a weaker MST somewhere
    bound_wall_s: float | None = None  # time spent on the lower bounds (wall clock)

    def __post_init__(self) -> None:
        object.__setattr__(self, "refused", MappingProxyType(dict(self.refused)))

    @property
    def converged(self) -> bool:
        """The local search ended with no improving move left."""
        return self.stopped == "converged"

    @property
    def total_s(self) -> float:
        return self.travel_s + self.dwell_s

    @property
    def naive_total_s(self) -> float | None:
        return None if self.naive_travel_s is None else self.naive_travel_s + self.dwell_s

    @property
    def lower_bound_s(self) -> float | None:
        if self.lower_bound_travel_s is None:
            return None
        return self.lower_bound_travel_s + self.dwell_s


#: The array fields of a `Plan` and their dtypes.
ARRAYS: dict[str, type[np.generic]] = {
    "coords": np.float64,
    "generated": np.int64,
    "wi": np.float64,
    "wo": np.float64,
    "angles": np.float64,
    "exposure_s": np.float64,
    "averages": np.int64,
    "travel_s": np.float64,
    "arrival_s": np.float64,
}


def same_bits(a: np.ndarray, b: np.ndarray) -> bool:
    """Equal dtype, shape and every byte (so −0.0 ≠ 0.0: identical, not just equal)."""
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


@dataclass(frozen=True, eq=False)
class Plan:
    """Targets in measuring order. Angles in radians, times in seconds.

    Frozen: every array is a private read-only copy (change a plan with
    `dataclasses.replace`, which makes a new one). ``==`` is "the same stored plan":
    spec, plan and rig texts, coordinate names and summary equal, every array identical
    bit for bit; ``ordering`` (the search's diagnostics, not stored) is left out.
    """

    spec: PlanSpec
    rig: Rig
    coordinate_names: tuple[str, ...]
    coords: FloatArray  # (N, d) the planned coordinates
    generated: np.ndarray  # (N,) int64, each target's position among the points placed
    wi: FloatArray  # (N, 3) the pair measured (sample frame)
    wo: FloatArray
    angles: FloatArray  # (N, A) in rig.axes order
    exposure_s: FloatArray
    averages: np.ndarray  # (N,) int64
    travel_s: FloatArray  # move into each target
    arrival_s: FloatArray  # predicted time of arrival at each target
    summary: Summary
    plan_text: bytes  # the plan file's bytes (for a spec made in code: `spec_text`)
    ordering: Ordering | None = None  # the search's figures (constructed length, …)

    def __post_init__(self) -> None:
        n = len(self.coords)
        for name, dtype in ARRAYS.items():
            value = np.array(getattr(self, name), dtype=dtype)  # a copy nobody else holds
            if value.shape[:1] != (n,):
                raise ValueError(f"Plan.{name}: expected {n} rows, got shape {value.shape}")
            value.setflags(write=False)
            object.__setattr__(self, name, value)

    def __len__(self) -> int:
        return len(self.coords)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Plan):
            return NotImplemented
        return (
            self.spec == other.spec
            and self.plan_text == other.plan_text
            and self.rig.text == other.rig.text
            and self.coordinate_names == other.coordinate_names
            and self.summary == other.summary
            and all(same_bits(getattr(self, n), getattr(other, n)) for n in ARRAYS)
        )

    __hash__ = None  # type: ignore[assignment]

    def content_hash(self, scene_text: bytes | None = None) -> str:
        """`content_hash` of the texts this plan was built from (and a scene's)."""
        return content_hash(self.plan_text, self.rig.text, scene_text)

    def write(self, path: str | Path) -> None:
        """Store the plan (`gonio.planner.stored`: a ``# gonio-plan v1`` header, then one
        CSV row per target); `read_plan` reads it back bit for bit."""
        from gonio.planner.stored import write_plan

        write_plan(self, path)

    write_csv = write  # the name of `write` before plans were stored with a header


@dataclass(frozen=True)
class PlanSource:
    """A plan file as read: its path and bytes, the validated spec and the rig (which
    keeps its own bytes, `Rig.text`)."""

    path: Path
    text: bytes
    spec: PlanSpec
    rig: Rig

    def content_hash(self, scene_text: bytes | None = None) -> str:
        return content_hash(self.text, self.rig.text, scene_text)

    def build(self, *, bounds: bool = False) -> Plan:
        """`build` with this file's text (so the plan carries its hash)."""
        return build(self.spec, self.rig, where=str(self.path), bounds=bounds, text=self.text)


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


def build(
    spec: PlanSpec,
    rig: Rig,
    *,
    where: str = "plan",
    bounds: bool = False,
    text: bytes | None = None,
    placed: FloatArray | None = None,
    start: FloatArray | None = None,
) -> Plan:
    """The ordered, timed plan (`ConfigError` if the rig can reach none of it).

    ``bounds``: also compute the figures the benchmarks compare against, the
    generation-order duration (a second choice of solutions) and the MST lower bound
    (otherwise None in the summary). ``text``: the plan file's bytes, for the content
    hash (`load_plan_source` gives them; default: the spec as YAML, `spec_text`).
    ``placed``: points already placed (generation order; the adaptive strategy's second
    pass, `gonio.planner.two_pass`) instead of the spec's; ``start``: the pose the
    motors leave from (default the rig's home)."""
    check_detector(spec, rig, where, text)
    names = spec.coordinates()
    coords, shape = place(spec, rig, where) if placed is None else (placed, None)
    home = rig.home if start is None else np.asarray(start, dtype=np.float64)
    valid, wi, wo = directions(spec, coords)
    solution: Solution = rig.solve(wi, wo, isotropic=spec.isotropic)
    reasons = np.full(len(coords), -1, dtype=np.int8)  # -1: outside the domain
    reasons[valid] = solution.reasons
    refused = {r.label: int(np.count_nonzero(reasons == r)) for r in Reason if r != Reason.OK}
    kept_idx = np.flatnonzero(reasons == Reason.OK)
    if kept_idx.size > placement.MAX_TARGETS:
        raise too_many(
            where, "sampling.counts" if spec.sampling.counts else "sampling", kept_idx.size
        )
    if kept_idx.size == 0:
        detail = ", ".join(f"{k} {v}" for k, v in refused.items() if v)
        raise ConfigError(
            f"{where}: the rig's constraints leave none of the {len(coords)} points reachable "
            f"({np.count_nonzero(~valid)} outside the domain; refused: {detail or 'none'})"
        )
    in_valid = np.cumsum(valid) - 1  # index into the valid subset
    sel = in_valid[kept_idx]

    if shape is not None:  # grids: serpentine over the full grid, refused cells skipped
        rank = np.empty(int(np.prod(shape)), dtype=np.int64)
        rank[sampling.serpentine(shape)] = np.arange(rank.size)
        given = np.argsort(rank[kept_idx], kind="stable")
        targets = solution.angles[sel][given]
        method: Method = "given"
    else:
        given, targets = np.arange(sel.size), solution.angles[sel]
        method = "auto"
    # Order on the relaxed any-branch time from each target's solution nearest home,
    # then choose solutions along the order and improve on them (`order_jointly`).
    budget = default_moves(sel.size) if spec.max_moves is None else spec.max_moves
    kicks = default_kicks(sel.size) if spec.kicks is None else spec.kicks
    started = time.perf_counter()
    cand, usable = solution.candidates[sel][given], solution.usable[sel][given]
    joint = order_jointly(
        rig.travel, cand, usable, targets, home, method=method, max_moves=budget,
        kicks=kicks, seed=spec.sampling.seed, time_budget_s=spec.time_budget_s,
    )  # fmt: skip
    result = joint.ordering
    order, angles, travel = joint.order, joint.angles, joint.travel
    if spec.ordering == "lkh":
        if not lkh.available():
            raise ConfigError(f"{where}: ordering: lkh needs elkai: pip install 'gonio[lkh]'")
        order, angles, travel = lkh.improve(rig.travel, home, cand, usable, order, angles, travel)
    chosen = sel[given[order]]
    ordering_s = time.perf_counter() - started
    stopped: Stop = result.stopped
    figures: dict[str, Any] = {}
    if bounds:
        # Bounds on every order with every choice of solutions (the relaxed time), and
        # generation order with the exact choice of solutions along it.
        relaxed = Relaxed.of(rig.travel, cand, usable, home)
        b = held_karp_bound(relaxed, float(travel.sum()))
        figures["bound_wall_s"] = time.perf_counter() - started - ordering_s
        _, naive = poses.choose(
            solution.candidates[sel], solution.usable[sel], home, rig.travel_time
        )
        figures.update(
            naive_travel_s=float(naive.sum()),
            lower_bound_travel_s=b.held_karp_s,
            mst_travel_s=b.mst_s,
            lower_bound_exact=b.exact,
        )
    order = np.searchsorted(sel, chosen)  # positions in generation order
    mwi, mwo = rig.forward(angles)  # the pair the chosen pose measures
    exposure, averages = exposures(spec.exposure, mwi, mwo, rig.source_kind)
    dwell = rig.spec.settle_s + exposure * averages
    arrival = np.cumsum(travel) + np.concatenate([[0.0], np.cumsum(dwell)[:-1]])
    summary = Summary(
        requested=len(coords),
        invalid=int(np.count_nonzero(~valid)),
        refused=refused,
        kept=int(kept_idx.size),
        travel_s=float(travel.sum()),
        dwell_s=float(dwell.sum()),
        ordering_s=ordering_s,
        moves=result.moves,
        max_moves=budget,
        kicks=result.kicks,
        kicks_kept=result.kicks_kept,
        max_kicks=kicks,
        stopped=stopped,
        time_cap_s=spec.time_budget_s,
        grid_shape=shape,
        target=spec.sampling.target,
        **figures,
    )
    return Plan(
        spec=spec,
        rig=rig,
        coordinate_names=names,
        coords=coords[kept_idx][order],
        generated=kept_idx[order],
        wi=mwi,
        wo=mwo,
        angles=angles,
        exposure_s=exposure,
        averages=averages,
        travel_s=travel,
        arrival_s=arrival,
        summary=summary,
        plan_text=spec_text(spec) if text is None else text,
        ordering=result,
    )


def hms(seconds: float) -> str:
    """Seconds as h:mm:ss."""
    s = round(seconds)
    return f"{s // 3600}:{s % 3600 // 60:02d}:{s % 60:02d}"


def render_summary(plan: Plan) -> str:
    """The summary table `gonio plan` prints."""
    s = plan.summary
    spec = plan.spec
    kind = "isotropic" if spec.isotropic else "anisotropic"
    lines = [
        f"plan {spec.name!r}: {kind} {spec.parametrization}, {spec.sampling.strategy}"
        + (f" {'×'.join(map(str, s.grid_shape))}" if s.grid_shape else "")
        + f", rig {plan.rig.spec.name!r}",
        f"  {'requested':<26}{s.requested:>9}",
        f"  {'outside the domain':<26}{s.invalid:>9}",
    ]
    for label, count in s.refused.items():
        lines.append(f"  {'refused: ' + label.replace('_', ' '):<26}{count:>9}")
    lines += [
        f"  {'kept':<26}{s.kept:>9}"
        + (
            f"   (target {s.target}: a grid keeps the cells that fall in the domain)"
            if s.target is not None and s.grid_shape is not None and s.kept != s.target
            else ""
        ),
    ]
    if spec.sampling.strategy == "adaptive" and s.target is not None and s.kept < s.target:
        lines.append(
            f"  {'':<26}{'':>9}   (the survey: the other {s.target - s.kept} targets are "
            "planned from its measurements during the run, docs/adaptive.md)"
        )
    lines += [
        "",
        f"  {'predicted duration':<26}{hms(s.total_s):>9}   (moves {hms(s.travel_s)}, "
        f"settle + exposure {hms(s.dwell_s)})",
    ]
    if s.naive_total_s is not None:
        lines.append(
            f"  {'in generation order':<26}{hms(s.naive_total_s):>9}   "
            f"({s.naive_total_s / s.total_s:.2f}× the ordered plan)"
        )
    if s.lower_bound_s is not None and s.lower_bound_travel_s is not None:
        weak = "" if s.lower_bound_exact else "; memory forced a weaker bound"
        lines.append(
            f"  {'lower bound (Held–Karp)':<26}{hms(s.lower_bound_s):>9}   "
            f"(ordered / bound = {s.travel_s / max(s.lower_bound_travel_s, 1e-12):.3f}"
            f" in moves, any order and solutions{weak})"
        )
    if s.mst_travel_s is not None:
        lines.append(
            f"  {'lower bound (MST)':<26}{hms(s.mst_travel_s + s.dwell_s):>9}   "
            f"(ordered / bound = {s.travel_s / max(s.mst_travel_s, 1e-12):.3f} in moves)"
        )
    lines += [
        f"  {'ordering':<26}{ordering_line(s)}",
        f"  {'ordering took':<26}{s.ordering_s:>8.1f}s",
    ]
    return "\n".join(lines)


def ordering_line(s: Summary) -> str:
    """How the ordering ended, for the summary table."""
    kicks = f"{s.kicks:,} kicks ({s.kicks_kept:,} kept)"
    if s.stopped == "converged":
        return (
            f"converged after {s.moves:,} moves, then {kicks}; budgets {s.max_moves:,} "
            f"and {s.max_kicks:,}"
        )
    if s.stopped == "move budget":
        return f"stopped at the move budget ({s.max_moves:,} moves): not converged"
    return (
        f"stopped at the time cap ({s.time_cap_s:g} s, after {s.moves:,} of {s.max_moves:,} "
        f"moves, {s.kicks:,} of {s.max_kicks:,} kicks): not converged, and this order "
        "depends on the machine's speed"
    )
