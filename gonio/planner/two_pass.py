"""The adaptive strategy's second pass (docs/adaptive.md): planned from the survey's
measurements and appended to the survey's plan.

`build` of an adaptive plan gives the first pass, a Sobol survey of ``survey`` kept
targets. Once it is measured, `extend` fits the ``model`` family to its samples (or,
for ``survey``, reconstructs them), takes the density of `gonio.planner.adaptive` from
that estimate, places the rest of the
target with it (a share ``edge`` moved onto the edge of the rig's cap), orders those
targets from the survey's last pose, and returns the whole plan: the survey's targets
unchanged, first, then the new ones. The engine stores that plan in the run in place
of the survey's, so a resumed run measures the stored second pass and never plans it
again; the same survey samples give the same second pass, bit for bit.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from gonio import params
from gonio.planner import adaptive
from gonio.planner.placement import draw_kept
from gonio.planner.plan import Plan, build
from gonio.planner.schema import PlanSpec
from gonio.rig.model import Rig
from gonio.types import BrdfEval, FloatArray

if TYPE_CHECKING:
    from gonio.analysis.measured import Measured

#: The ``model`` that steers by the survey's own reconstruction instead of a fit.
SURVEY = "survey"


def is_survey(plan: Plan) -> bool:
    """The plan is the first pass of an adaptive plan, its second still to be planned."""
    s = plan.spec.sampling
    return s.strategy == "adaptive" and s.target is not None and len(plan) < s.target


def extend(first: Plan, measured: Measured, *, where: str = "plan") -> Plan:
    """The whole adaptive plan: ``first`` (the survey, as built) and the second pass
    planned from ``measured`` (the survey's samples; see the module)."""
    spec, rig = first.spec, first.rig
    assert spec.sampling.target is not None and is_survey(first)
    coords = second_pass_points(spec, rig, measured, spec.sampling.target - len(first), where)
    second = build(
        spec, rig, where=where, text=first.plan_text, placed=coords, start=first.angles[-1]
    )
    return joined(first, second)


def second_pass_points(
    spec: PlanSpec, rig: Rig, measured: Measured, count: int, where: str = "plan"
) -> FloatArray:
    """The second pass's points in the coordinate box (generation order: every point
    drawn, ``count`` of them kept): the density (`adaptive.density`) of the estimate
    from ``measured`` (`estimate`), a share ``edge`` of the points moved onto the edge
    of the rig's cap."""
    options = spec.sampling.options()
    density = adaptive.density(
        estimate(measured, options.model), rig, spec.parametrization, spec.isotropic,
        floor=options.floor,
    )  # fmt: skip
    p = params.get(spec.parametrization)
    bounds = np.asarray(p.iso_bounds if spec.isotropic else p.bounds, dtype=np.float64)

    def inside(stream: adaptive.Stream, n: int, edge: bool) -> FloatArray:
        return draw_points(stream, n, bounds, rig, spec.parametrization, spec.isotropic, edge)

    on_edge = math.floor(options.edge * count)
    seed = spec.sampling.seed
    shaped = adaptive.Stream(density, seed + 1)
    coords = draw_kept(spec, rig, where, lambda n: inside(shaped, n, False), count - on_edge)
    if on_edge:
        edged = adaptive.Stream(density, seed + 2)
        edge = draw_kept(spec, rig, where, lambda n: inside(edged, n, True), on_edge)
        coords = np.concatenate([coords, edge])
    return coords


def estimate(measured: Measured, model: str) -> BrdfEval:
    """The BRDF the density is taken from: the ``model`` family fitted to the survey, or
    for ``survey`` the survey's own rbf reconstruction (no model at all)."""
    if model == SURVEY:
        from gonio.reconstruct.build import reconstruct

        return reconstruct(measured, method="rbf", extrapolate="nearest").eval
    from gonio.reconstruct.fit import fit

    return fit(measured, model).model.eval


def draw_points(
    stream: adaptive.Stream,
    n: int,
    bounds: FloatArray,
    rig: Rig,
    parametrization: str,
    isotropic: bool,
    edge: bool,
) -> FloatArray:
    """``n`` points from ``stream`` in the coordinate box; ``edge``: moved onto the edge
    of the rig's cap (`adaptive.onto_edge`; those outside the domain stay and are
    dropped as invalid)."""
    points = bounds[:, 0] + stream.draw(n) * (bounds[:, 1] - bounds[:, 0])
    if edge:
        points, _ = adaptive.onto_edge(points, rig, parametrization, isotropic)
    return np.asarray(points, dtype=np.float64)


def joined(first: Plan, second: Plan) -> Plan:
    """One plan measuring ``first``'s targets, then ``second``'s (planned to leave from
    the first's last pose): arrays concatenated, the second's arrival times after the
    first's last dwell, its generation indices after the first's points, counts and
    times summed."""
    a, b = first.summary, second.summary
    dwell_last = first.rig.spec.settle_s + float(first.exposure_s[-1] * first.averages[-1])
    end = float(first.arrival_s[-1]) + dwell_last
    summary = replace(
        b,
        requested=a.requested + b.requested,
        invalid=a.invalid + b.invalid,
        refused={k: a.refused.get(k, 0) + v for k, v in b.refused.items()},
        kept=a.kept + b.kept,
        travel_s=a.travel_s + b.travel_s,
        dwell_s=a.dwell_s + b.dwell_s,
        ordering_s=a.ordering_s + b.ordering_s,
        moves=a.moves + b.moves,
        max_moves=a.max_moves + b.max_moves,
        kicks=a.kicks + b.kicks,
        kicks_kept=a.kicks_kept + b.kicks_kept,
        max_kicks=a.max_kicks + b.max_kicks,
        stopped=a.stopped if a.stopped != "converged" else b.stopped,
    )
    return replace(
        second,
        coords=np.concatenate([first.coords, second.coords]),
        generated=np.concatenate([first.generated, second.generated + a.requested]),
        wi=np.concatenate([first.wi, second.wi]),
        wo=np.concatenate([first.wo, second.wo]),
        angles=np.concatenate([first.angles, second.angles]),
        exposure_s=np.concatenate([first.exposure_s, second.exposure_s]),
        averages=np.concatenate([first.averages, second.averages]),
        travel_s=np.concatenate([first.travel_s, second.travel_s]),
        arrival_s=np.concatenate([first.arrival_s, second.arrival_s + end]),
        summary=summary,
        ordering=None,
    )
