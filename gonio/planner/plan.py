"""`build`: from a plan file and a rig to an ordered, timed list of motor targets.

Points are placed uniformly in the parametrization's coordinate box (or its isotropic
reduction), kept where the coordinates are `valid` and the rig can reach the pair, mapped
to joint angles, ordered for the motors, and timed with each axis's trapezoidal profile
plus settle and exposure. Nothing here moves a motor.
"""

from __future__ import annotations

import csv
import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gonio import params
from gonio.config import ConfigError, line_of, load, read_yaml
from gonio.planner import poses, sampling
from gonio.planner.exposure import exposures
from gonio.planner.ordering import Method, Ordering, mst_lower_bound, order_targets
from gonio.planner.schema import PlanSpec
from gonio.rig.model import Reason, Rig, Solution
from gonio.types import FloatArray

#: Sequence strategies draw in batches of this many points (a power of two for Sobol).
BATCH = 4096
#: A plan asking for a target count stops drawing after this many points.
MAX_DRAWN = 4_000_000


@dataclass
class Summary:
    requested: int  # points placed in the coordinate box
    invalid: int  # outside the parametrization's domain
    refused: dict[str, int]  # unreachable, by reason
    kept: int
    travel_s: float  # ordered, moves only
    naive_travel_s: float  # in generation order
    lower_bound_travel_s: float  # the MST of the travel-time graph
    dwell_s: float  # settle + exposure × averages, summed
    ordering_s: float  # time spent ordering (wall clock)
    lower_bound_exact: bool = True  # False: memory forced a weaker bound than the MST
    grid_shape: tuple[int, ...] | None = None
    target: int | None = None  # the kept targets asked for, if the plan gave a number
    bound_wall_s: float = 0.0  # time spent on the lower bound (wall clock)
    converged: bool = True  # the local search ended with no improving move left

    @property
    def total_s(self) -> float:
        return self.travel_s + self.dwell_s

    @property
    def naive_total_s(self) -> float:
        return self.naive_travel_s + self.dwell_s

    @property
    def lower_bound_s(self) -> float:
        return self.lower_bound_travel_s + self.dwell_s


@dataclass
class Plan:
    """Targets in measuring order. Angles in radians, times in seconds."""

    spec: PlanSpec
    rig: Rig
    coordinate_names: tuple[str, ...]
    coords: FloatArray  # (N, d) the planned coordinates
    generated: np.ndarray  # (N,) each target's position among the points placed
    wi: FloatArray  # (N, 3) the pair measured (sample frame)
    wo: FloatArray
    angles: FloatArray  # (N, A) in rig.axes order
    exposure_s: FloatArray
    averages: np.ndarray
    travel_s: FloatArray  # move into each target
    arrival_s: FloatArray  # predicted time of arrival at each target
    summary: Summary
    ordering: Ordering | None = None  # the first ordering (on the solutions nearest home)

    def __len__(self) -> int:
        return len(self.coords)

    def write_csv(self, path: str | Path) -> None:
        """One row per target in measuring order: index, its position among the points
        placed (generation order), coordinates, ωi, ωo, joint angles (rad), exposure,
        averages, predicted arrival (s from the start). Floats are written exactly."""
        header = [
            "index",
            "generated",
            *self.coordinate_names,
            "wi_x", "wi_y", "wi_z", "wo_x", "wo_y", "wo_z",
            *(f"{a}_rad" for a in self.rig.axes),
            "exposure_s", "averages", "arrival_s",
        ]  # fmt: skip
        with Path(path).open("w", newline="", encoding="utf-8") as f:
            out = csv.writer(f)
            out.writerow(header)
            for i in range(len(self)):
                row = [*self.coords[i], *self.wi[i], *self.wo[i], *self.angles[i]]
                out.writerow(
                    [i, int(self.generated[i]), *(repr(float(v)) for v in row),
                     repr(float(self.exposure_s[i])), int(self.averages[i]),
                     repr(float(self.arrival_s[i]))]
                )  # fmt: skip


def load_plan(path: str | Path, rig_path: str | Path | None = None) -> tuple[PlanSpec, Rig]:
    """The plan file and its rig (``rig_path`` overrides the plan's ``rig`` field)."""
    path = Path(path)
    spec = load(path, PlanSpec)
    if rig_path is None:
        if spec.rig is None:
            raise ConfigError(f"{path}: rig: no rig file named; give one here or with --rig")
        rig_path = path.parent / spec.rig
        if Path(rig_path).is_dir():
            line = line_of(read_yaml(path)[1], ("rig",))
            raise ConfigError(f"{path}:{line}: rig: {rig_path} is a folder; expected a rig file")
    return spec, Rig.from_yaml(rig_path)


def _place(spec: PlanSpec, rig: Rig, where: str) -> tuple[FloatArray, tuple[int, ...] | None]:
    """The points placed in the coordinate box, in generation order, and the grid shape."""
    p = params.get(spec.parametrization)
    names = spec.coordinates()
    bounds = np.asarray(p.iso_bounds if spec.isotropic else p.bounds, dtype=np.float64)
    powers = np.array(
        [spec.sampling.warps[n].power if n in spec.sampling.warps else 1.0 for n in names]
    )
    s = spec.sampling
    if s.target is not None and s.target > MAX_DRAWN:
        raise ConfigError(
            f"{where}: sampling.target: expected at most {MAX_DRAWN:,} targets, got {s.target:,}"
        )
    if s.strategy in ("grid", "stratified"):
        if s.counts is not None:
            shape = tuple(s.counts[n] for n in names)
            field = "sampling.counts"
        else:
            assert s.target is not None
            pilot = sampling.to_box(
                sampling.Sequence("sobol", len(names), s.seed).draw(BATCH), bounds, powers
            )
            rate = max(_kept(spec, rig, pilot).mean(), 1.0 / BATCH)
            shape = sampling.grid_shape_for((s.target / rate) ** (1.0 / len(names)), len(names))
            field = "sampling.target"
        cells = math.prod(shape)
        if cells > MAX_DRAWN:
            raise ConfigError(
                f"{where}: {field}: a {'×'.join(map(str, shape))} grid is {cells:,} points; "
                f"expected at most {MAX_DRAWN:,}"
            )
        jitter = np.random.default_rng(s.seed) if s.strategy == "stratified" else None
        unit = sampling.grid(shape, jitter=jitter)
        return sampling.to_box(unit, bounds, powers), shape
    assert s.target is not None
    stream = sampling.Sequence(s.strategy, len(names), s.seed)
    drawn: list[FloatArray] = []
    usable: list[np.ndarray] = []
    kept = 0
    while kept < s.target:
        if sum(len(d) for d in drawn) >= MAX_DRAWN:
            raise ConfigError(
                f"{where}: sampling.target: only {kept} of {s.target} targets are reachable "
                f"after {MAX_DRAWN} points; lower the target or relax the rig's constraints"
            )
        batch = sampling.to_box(stream.draw(BATCH), bounds, powers)
        usable.append(_kept(spec, rig, batch))
        kept += int(usable[-1].sum())
        drawn.append(batch)
    points = np.concatenate(drawn)
    keep = np.cumsum(np.concatenate(usable))
    last = int(np.searchsorted(keep, s.target)) + 1  # the point that completes the target
    return points[:last], None


def _directions(spec: PlanSpec, coords: FloatArray) -> tuple[np.ndarray, FloatArray, FloatArray]:
    """(valid mask, ωi, ωo of the valid points)."""
    p = params.get(spec.parametrization)
    if spec.isotropic:
        valid = p.valid_iso(coords)
        wi, wo = p.inverse_iso(coords[valid])
    else:
        valid = p.valid(coords)
        wi, wo = p.inverse(coords[valid])
    return valid, wi, wo


def _kept(spec: PlanSpec, rig: Rig, coords: FloatArray) -> np.ndarray:
    valid, wi, wo = _directions(spec, coords)
    ok = np.zeros(len(coords), dtype=np.bool_)
    ok[valid] = rig.solve(wi, wo, isotropic=spec.isotropic).ok
    return ok


def build(spec: PlanSpec, rig: Rig, *, where: str = "plan") -> Plan:
    """The ordered, timed plan (`ConfigError` if the rig can reach none of it)."""
    names = spec.coordinates()
    coords, shape = _place(spec, rig, where)
    valid, wi, wo = _directions(spec, coords)
    solution: Solution = rig.solve(wi, wo, isotropic=spec.isotropic)
    reasons = np.full(len(coords), -1, dtype=np.int8)  # -1: outside the domain
    reasons[valid] = solution.reasons
    refused = {r.label: int(np.count_nonzero(reasons == r)) for r in Reason if r != Reason.OK}
    kept_idx = np.flatnonzero(reasons == Reason.OK)
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
    # Order on each target's solution nearest home, then let every target take the
    # solution that suits its neighbours (`poses.choose`), improve the order on those
    # poses with what is left of the budget, and choose again.
    started = time.perf_counter()
    result = order_targets(
        rig.travel, targets, rig.home, method=method, time_budget_s=spec.time_budget_s,
        lower_bound=False,
    )  # fmt: skip
    chosen = sel[given[result.order]]
    angles, _ = poses.choose(
        solution.candidates[chosen], solution.usable[chosen], rig.home, rig.travel_time
    )
    left = max(spec.time_budget_s - (time.perf_counter() - started), 0.0)
    again = order_targets(
        rig.travel, angles, rig.home, method="given", time_budget_s=left, lower_bound=False
    )
    chosen = chosen[again.order]
    angles, travel = poses.choose(
        solution.candidates[chosen], solution.usable[chosen], rig.home, rig.travel_time
    )
    ordering_s = time.perf_counter() - started
    # The bound: the MST over the poses measured (any order of these poses is at least
    # this long). Generation order gets the same choice of solutions, for a fair ratio.
    bound, exact = mst_lower_bound(rig.travel, np.vstack([angles, rig.home[None, :]]))
    bound_wall_s = time.perf_counter() - started - ordering_s
    _, naive = poses.choose(
        solution.candidates[sel], solution.usable[sel], rig.home, rig.travel_time
    )
    order = np.searchsorted(sel, chosen)  # positions in generation order
    mwi, mwo = rig.forward(angles)  # the pair the chosen pose measures
    exposure, averages = exposures(spec.exposure, mwi, mwo)
    dwell = rig.spec.settle_s + exposure * averages
    arrival = np.cumsum(travel) + np.concatenate([[0.0], np.cumsum(dwell)[:-1]])
    summary = Summary(
        requested=len(coords),
        invalid=int(np.count_nonzero(~valid)),
        refused=refused,
        kept=int(kept_idx.size),
        travel_s=float(travel.sum()),
        naive_travel_s=float(naive.sum()),
        lower_bound_travel_s=bound,
        dwell_s=float(dwell.sum()),
        ordering_s=ordering_s,
        lower_bound_exact=exact,
        grid_shape=shape,
        target=spec.sampling.target,
        bound_wall_s=bound_wall_s,
        converged=result.converged and again.converged,
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
        "",
        f"  {'predicted duration':<26}{hms(s.total_s):>9}   (moves {hms(s.travel_s)}, "
        f"settle + exposure {hms(s.dwell_s)})",
        f"  {'in generation order':<26}{hms(s.naive_total_s):>9}   "
        f"({s.naive_total_s / s.total_s:.2f}× the ordered plan)",
        f"  {'lower bound (MST)':<26}{hms(s.lower_bound_s):>9}   "
        f"(ordered moves = {s.travel_s / max(s.lower_bound_travel_s, 1e-12):.2f}× the MST)",
        f"  {'ordering took':<26}{s.ordering_s:>8.1f}s",
    ]
    return "\n".join(lines)
