"""The adaptive strategy's second pass (docs/explanations/adaptive.md): planned from an estimate of
the material made from the survey's measurements, and appended to the survey's plan.

`build` of an adaptive plan gives the first pass, a Sobol survey of ``survey`` kept
targets (`Plan.is_survey`). Once it is measured, the caller estimates the BRDF from its
samples (`gonio.workflows.adaptive.estimate`: the ``model`` family fitted to them, or
for ``survey`` their own reconstruction); `extend` takes the density of
`gonio.planner.adaptive` from that estimate and decides from the survey whether it pays
(`gonio.planner.choice`): if so it places the rest of the target with it (a share
``edge`` moved onto the edge of the rig's cap), if not it continues the survey's Sobol
sequence, so that the whole plan is the uniform one; the summary's ``second_pass`` says
which and why. It orders those targets from the survey's last pose, and returns the
whole plan: the survey's targets unchanged, first,
then the new ones. The engine stores that plan in the run in place of the survey's, so
a resumed run measures the stored second pass and never plans it again; the same
survey samples give the same second pass, bit for bit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from gonio import params
from gonio.planner import adaptive, choice
from gonio.planner.builder import build
from gonio.planner.model import Plan
from gonio.planner.placement import draw_kept
from gonio.planner.sampling import Sequence, to_box
from gonio.planner.schema import PlanSpec
from gonio.rig import Rig
from gonio.types import BrdfEval, FloatArray


@dataclass(frozen=True)
class Survey:
    """What the survey measured: ``drawn`` points placed (`Plan.summary.requested`, the
    invalid and unreachable ones too), the pairs ``wi``, ``wo`` (N, 3) and the BRDF
    values ``f`` (N,) or (N, C) in sr⁻¹ measured there."""

    drawn: int
    wi: FloatArray
    wo: FloatArray
    f: FloatArray


def extend(first: Plan, estimate: BrdfEval, survey: Survey, *, where: str = "plan") -> Plan:
    """The whole adaptive plan: ``first`` (the survey, as built) and the second pass
    planned from ``estimate`` (the BRDF estimated from the survey's samples, sr⁻¹) and
    the ``survey``'s measurements (see the module); the summary's ``second_pass`` says
    how it was placed and why."""
    spec, rig = first.spec, first.rig
    assert spec.sampling.target is not None and first.is_survey
    count = spec.sampling.target - len(first)
    coords, chosen = second_pass(spec, rig, estimate, survey, count, where)
    second = build(
        spec, rig, where=where, text=first.plan_text, placed=coords, start=first.angles[-1]
    )
    whole = joined(first, second)
    return replace(whole, summary=replace(whole.summary, second_pass=chosen.reason))


def second_pass(
    spec: PlanSpec,
    rig: Rig,
    estimate: BrdfEval,
    survey: Survey,
    count: int,
    where: str = "plan",
    *,
    margin: float = choice.MARGIN,
) -> tuple[FloatArray, choice.Choice]:
    """The second pass's points in the coordinate box (generation order: every point
    drawn, ``count`` of them kept) and the choice that placed them
    (`gonio.planner.choice`): the density (`adaptive.density`) of ``estimate`` (the BRDF
    estimated from the ``survey``, sr⁻¹), a share ``edge`` of the points moved onto the
    edge of the rig's cap; or, where that density is not predicted to pay, the survey's
    Sobol sequence continued (the uniform plan's points after the survey's).
    ``margin``: `choice.choose`'s."""
    options = spec.sampling.options()
    errors = adaptive.error_map(estimate, rig, spec.parametrization, spec.isotropic)
    q = choice.survey_misfit(np.asarray(estimate(survey.wi, survey.wo)), survey.f)
    assert spec.sampling.target is not None
    total = spec.sampling.target
    chosen = choice.choose(errors, q, total - count, total, options.floor, margin=margin)
    p = params.get(spec.parametrization)
    bounds = np.asarray(p.iso_bounds if spec.isotropic else p.bounds, dtype=np.float64)
    if chosen.kind == "uniform":
        return uniform_rest(spec, rig, bounds, survey.drawn, total, where), chosen
    density = errors.density(options.floor)

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
    return coords, chosen


def uniform_rest(
    spec: PlanSpec, rig: Rig, bounds: FloatArray, drawn: int, total: int, where: str
) -> FloatArray:
    """The points of the uniform Sobol plan of ``total`` kept targets (the survey's
    sequence, seeded alike) after its first ``drawn``: the survey's own points."""
    stream = Sequence("sobol", len(bounds), spec.sampling.seed)
    ones = np.ones(len(bounds))
    points = draw_kept(spec, rig, where, lambda n: to_box(stream.draw(n), bounds, ones), total)
    return points[drawn:]


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
    first's last dwell (and its bus time), its generation indices after the first's
    points, counts and times summed."""
    a, b = first.summary, second.summary
    dwell_last = first.rig.spec.settle_s + float(first.exposure_s[-1] * first.averages[-1])
    bus_last = float(first.rig.bus_time(first.travel_s[-1])) if a.timing == "dynamixel" else 0.0
    end = float(first.arrival_s[-1]) + dwell_last + bus_last
    summary = replace(
        b,
        requested=a.requested + b.requested,
        invalid=a.invalid + b.invalid,
        refused={k: a.refused.get(k, 0) + v for k, v in b.refused.items()},
        kept=a.kept + b.kept,
        travel_s=a.travel_s + b.travel_s,
        dwell_s=a.dwell_s + b.dwell_s,
        bus_s=a.bus_s + b.bus_s,
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
        ordering_s=None
        if first.ordering_s is None or second.ordering_s is None
        else first.ordering_s + second.ordering_s,
    )
