"""The choice of plan for a time budget and a material guess
(docs/explanations/tradeoff.md, "Which plan for a budget").

Every candidate (`CANDIDATES`: stop-and-go Sobol and warped targets in Rusinkiewicz's
coordinates at the plan's own exposure, fly detector arcs, fly lines along θh at two
blur budgets, a mixed plan of θh lines and 50 stop-and-go targets where they leave gaps;
and the plan as written when it is none of those) is fitted to the budget
of predicted instrument time (`runner.fit_to_budget`) and its error predicted by one
error model for all: the noise-free material guess sampled at the plan's pairs
(``plan.wi``, ``plan.wo``), reconstructed by linear interpolation in the plan's
coordinates with a support distance that spans every gap between the samples (the
diagonal of the unit box; the largest empty ball about a test pair, ``gap``, is
reported) and by rbf, the nearest sample's value outside their support, and scored by
log-RMSE over every pair of a seeded test set against the guess itself; the lower of
the two counts (a run is reconstructed the way that serves it best).

The rule (`pick`): the lowest predicted error, but a fly plan only when predicted at
least `MARGIN` times lower than the best stop-and-go one (never one predicted worse).

The prediction is the interpolation error of the guess alone: no noise, motion blur,
timing jitter or readings lost; it ranks plans, it does not forecast a run's score.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from gonio import progress
from gonio.analysis import Measured
from gonio.errors import GonioError
from gonio.planner import Plan, PlanSpec, Warp
from gonio.reconstruct import SCENE, TestSet, Truth, evaluate, reconstruct, testset, truth_from_spec
from gonio.rig import Rig
from gonio.tradeoff.grid import sampling_fields
from gonio.tradeoff.runner import fit_to_budget
from gonio.tradeoff.spec import DEFAULT_WARPS, FLY, STOP, WARPED

#: Test pairs the predictions are scored on by default (a few seconds at 15 minutes).
TEST_PAIRS = 5000
#: First guesses of a plan's size per second of budget (stop-and-go targets, fly
#: readings), from which `runner.fit_to_budget` fits it.
STOP_PER_S, FLY_PER_S = 1.0, 20.0
#: How many times lower than the best stop-and-go plan's a fly plan's predicted error
#: must be for it to be chosen. The prediction knows no noise, blur or jitter, which
#: weigh more the lower the error: on the matte scene at 15 minutes θh lines were
#: predicted 1.2× lower than warped stop-and-go and measured 1.3× higher; on the glossy
#: gold predicted 41× and measured 16× lower (studies/fly_trade.py).
MARGIN = 2.0
#: The reconstructions each candidate is predicted with (its lower error counts: a
#: run is reconstructed the way that serves it best; rbf refuses data on too few lines,
#: such as detector arcs), and the fill outside the support.
METHODS, EXTRAPOLATE = ("linear", "rbf"), "nearest"


@dataclass(frozen=True)
class Candidate:
    """One kind of plan the choice weighs: ``motion`` (`STOP` or `FLY`); stop-and-go:
    ``strategy`` (a planner strategy, or ``warped``: Sobol with ``warps``, by default
    `DEFAULT_WARPS` of the parametrization); fly: ``segment`` and ``blur_deg``;
    ``parametrization`` None: the plan's own. ``as_written``: the plan's own sampling,
    only its target fitted."""

    name: str
    motion: str
    strategy: str = "sobol"
    parametrization: str | None = "rusinkiewicz"
    warps: dict[str, Warp] | None = None
    segment: str | None = None
    blur_deg: float | None = None
    as_written: bool = False
    fill: int = 0  # stop-and-go targets after θh lines (a mixed plan)

    def spec(self, base: PlanSpec, target: int) -> PlanSpec:
        """``base`` with this candidate's parametrization and sampling of ``target``
        targets (its seed and ordering kept; a fly plan at the detector's rate of
        ``base`` if it is a fly plan, and without the stop-and-go exposure options)."""
        data: dict[str, Any] = base.model_dump(mode="json")
        if self.as_written:
            data["sampling"]["target"] = target
            data["sampling"]["counts"] = None
            return PlanSpec.model_validate(data)
        parametrization = self.parametrization or base.parametrization
        warps = self.warps
        if warps is None:
            warps = DEFAULT_WARPS.get(parametrization, {}) if self.strategy == WARPED else {}
        combination = {
            "motion": self.motion,
            "sampling": self.strategy,
            "segment": self.segment,
            "rate_hz": base.sampling.fly_options().rate_hz,
            "blur_deg": self.blur_deg,
        }
        data["parametrization"] = parametrization
        data["sampling"] = sampling_fields(
            combination, target=target, seed=base.sampling.seed, warps=warps, adaptive={}
        )
        if self.fill:
            data["sampling"]["fly"]["fill"] = self.fill  # measured at the plan's exposure
        elif self.motion == FLY:
            data.pop("exposure")  # a fly plan reads at the detector's rate
        return PlanSpec.model_validate(data)

    def first_guess(self, budget_s: float) -> int:
        """The target the fitting starts from for a budget of ``budget_s`` (s)."""
        return max(1, round(budget_s * (FLY_PER_S if self.motion == FLY else STOP_PER_S)))


#: The candidates of every choice (θh lines only for isotropic plans).
CANDIDATES: tuple[Candidate, ...] = (
    Candidate("sobol, rusinkiewicz", STOP),
    Candidate("warped, rusinkiewicz", STOP, strategy=WARPED),
    Candidate("detector arcs, 0.5°", FLY, segment="detector_arc", blur_deg=0.5),
    Candidate("θh lines, 0.5°", FLY, segment="theta_h_line", blur_deg=0.5),
    Candidate("θh lines, 1°", FLY, segment="theta_h_line", blur_deg=1.0),
    Candidate("θh lines, 1°, 50 filled", FLY, segment="theta_h_line", blur_deg=1.0, fill=50),
)


@dataclass(frozen=True)
class Fitted:
    """A candidate's plan fitted to the budget (None, with the reason in ``error``,
    when it has none), and the wall time its fitting took (s)."""

    candidate: Candidate
    plan: Plan | None
    error: str = ""
    wall_s: float = 0.0


@dataclass(frozen=True)
class Prediction:
    """A candidate's plan and its predicted figures: instrument time (s), samples,
    log-RMSE over every test pair, coverage (the share of test pairs inside the
    samples' hull: the rest take the nearest sample's value), gap (the largest distance
    from a test pair to its nearest sample, unit box of the plan's coordinates). None
    for a candidate without a plan (``error`` says why)."""

    name: str
    motion: str
    plan: Plan | None
    seconds: float | None
    samples: int
    log_rmse: float | None
    coverage: float | None
    gap: float | None
    error: str = ""
    wall_s: float = 0.0  # fitting and predicting
    method: str = ""  # the reconstruction of the prediction (`METHODS`)

    @property
    def is_fly(self) -> bool:
        return self.motion == FLY


@dataclass(frozen=True)
class Choice:
    """The candidates' predictions, the one chosen (`pick`) and the best stop-and-go
    one (None if no stop-and-go candidate has a prediction)."""

    budget_s: float
    material: str
    test_pairs: int
    test_seed: int
    predictions: tuple[Prediction, ...]
    chosen: Prediction
    best_stop: Prediction | None
    wall_s: float = field(default=0.0)
    margin: float = MARGIN  # the rule's (`pick`)

    @property
    def plan(self) -> Plan:
        assert self.chosen.plan is not None
        return self.chosen.plan


def material_guess(spec: str, *, parametrization: str, isotropic: bool, rig: Rig) -> Truth:
    """The material guess a SPEC names, seen in luminance: a material or scene YAML file
    or ``NAME:key=value,…`` (as ``gonio evaluate --truth`` reads them); `GonioError`, one
    line, for anything else."""
    path = Path(spec)
    if spec == SCENE or (path.suffix.lower() not in (".yaml", ".yml") and path.is_file()):
        raise GonioError(
            f"{spec}: expected a material guess: a material or scene YAML file, or a "
            "model NAME:key=value,… (e.g. cook_torrance:alpha=0.05,fresnel=conductor)"
        )
    empty = np.zeros((0, 3))
    stub = Measured(
        wi=empty,
        wo=empty,
        f=np.zeros(0),
        sigma=np.zeros(0),
        parametrization=parametrization,
        isotropic=isotropic,
        rig=rig,
        scene_text=None,
        band="luminance",
        source="the plan",
    )
    return truth_from_spec(spec, stub)


def fit(
    spec: PlanSpec,
    rig: Rig,
    budget_s: float,
    candidates: Sequence[Candidate] | None = None,
    *,
    where: str = "the plan",
) -> tuple[Fitted, ...]:
    """Every candidate's plan fitted to ``budget_s`` of predicted instrument time (s).

    ``candidates`` None: `CANDIDATES` (θh lines only for an isotropic ``spec``), then
    the plan as written when it is neither adaptive nor one of them. A candidate the
    planner refuses (nothing fits, nothing reachable) keeps the reason.
    """
    if not budget_s > 0.0 or not math.isfinite(budget_s):
        raise GonioError(f"a time budget must be a positive number of seconds, got {budget_s:g}")
    if candidates is None:
        candidates = _defaults(spec)
    out = []
    for candidate in candidates:
        started = time.perf_counter()
        try:
            candidate_spec = candidate.spec(spec, candidate.first_guess(budget_s))
            with progress.quiet():
                plan = fit_to_budget(candidate_spec, rig, budget_s, where=where)
            out.append(Fitted(candidate, plan, wall_s=time.perf_counter() - started))
        except GonioError as exc:
            reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            out.append(Fitted(candidate, None, reason, time.perf_counter() - started))
    return tuple(out)


def _defaults(spec: PlanSpec) -> tuple[Candidate, ...]:
    chosen = [c for c in CANDIDATES if spec.isotropic or c.segment != "theta_h_line"]
    if spec.sampling.strategy == "adaptive":
        return tuple(chosen)  # an adaptive plan's size is not fitted to a budget
    fly = spec.sampling.strategy == FLY
    kind = spec.sampling.fly_options().segment if fly else spec.sampling.strategy
    warped = "warped " if spec.sampling.warps else ""
    name = f"as written: {warped}{kind}, {spec.parametrization}"
    own = Candidate(name.replace("_", " "), FLY if fly else STOP, as_written=True)

    def key(s: PlanSpec) -> tuple[str, str]:
        sampling = s.sampling.model_dump(mode="json", exclude={"target", "counts", "seed"})
        return s.parametrization, repr(sampling)

    known = {key(c.spec(spec, 1)) for c in chosen}
    return tuple(chosen) if key(own.spec(spec, 1)) in known else (*chosen, own)


def predict(
    fitted: Sequence[Fitted],
    material: Truth,
    rig: Rig,
    *,
    budget_s: float,
    test_set: TestSet,
) -> Choice:
    """The predictions of the ``fitted`` plans for ``material`` on ``test_set`` (see
    the module docstring) and the choice among them (`pick`); `GonioError` when no
    candidate has a prediction."""
    started = time.perf_counter()
    predictions = []
    for one in fitted:
        begun = time.perf_counter()
        if one.plan is None:
            predictions.append(
                Prediction(one.candidate.name, one.candidate.motion, None, None, 0, None, None,
                           None, one.error, one.wall_s)
            )  # fmt: skip
            continue
        log_rmse, coverage, gap, method = _predicted(one.plan, material, rig, test_set)
        predictions.append(
            Prediction(
                name=one.candidate.name,
                motion=one.candidate.motion,
                plan=one.plan,
                seconds=one.plan.summary.total_s,
                samples=len(one.plan),
                log_rmse=log_rmse,
                coverage=coverage,
                gap=gap,
                wall_s=one.wall_s + time.perf_counter() - begun,
                method=method,
            )
        )
    errors = [p.log_rmse for p in predictions]
    motions = [p.motion for p in predictions]
    chosen = pick(errors, motions)
    if chosen is None:
        reasons = "; ".join(f"{p.name}: {p.error or 'no prediction'}" for p in predictions)
        raise GonioError(f"no candidate plan fits {budget_s:g} s ({reasons})")
    best = best_stop(errors, motions)
    return Choice(
        budget_s=budget_s,
        material=material.label,
        test_pairs=len(test_set.wi),
        test_seed=test_set.seed,
        predictions=tuple(predictions),
        chosen=predictions[chosen],
        best_stop=None if best is None else predictions[best],
        wall_s=sum(f.wall_s for f in fitted) + time.perf_counter() - started,
    )


def choose(
    spec: PlanSpec,
    rig: Rig,
    budget_s: float,
    material: Truth,
    *,
    candidates: Sequence[Candidate] | None = None,
    test_pairs: int = TEST_PAIRS,
    seed: int = testset.DEFAULT_SEED,
    where: str = "the plan",
) -> Choice:
    """The plan to measure in a time budget, for a material guess.

    Parameters
    ----------
    spec : PlanSpec
        The plan: its seed, exposure, ordering and acquisition options carry over to
        every candidate.
    rig : Rig
        The rig it is planned on.
    budget_s : float
        Predicted instrument time (s) each candidate's plan is fitted to.
    material : Truth
        The material guess (`material_guess`).
    candidates : sequence of Candidate, optional
        The plans weighed (default: `CANDIDATES` and the plan as written, `fit`).
    test_pairs, seed : int
        The test set's size and seed (`gonio.reconstruct.testset.draw`).
    where : str
        Names the plan in an error.

    Returns
    -------
    Choice
        Every candidate's prediction and the chosen one (`pick`). `GonioError` when no
        candidate fits the budget.
    """
    test_set = testset.draw(rig, isotropic=spec.isotropic, size=test_pairs, seed=seed)
    fitted = fit(spec, rig, budget_s, candidates, where=where)
    return predict(fitted, material, rig, budget_s=budget_s, test_set=test_set)


def _predicted(
    plan: Plan, material: Truth, rig: Rig, test_set: TestSet
) -> tuple[float | None, float | None, float | None, str]:
    """(log-RMSE, coverage, gap, method) of the plan's noise-free samples of
    ``material``, reconstructed by each of `METHODS` (the lower error counts)."""
    f = np.asarray(material.eval(plan.wi, plan.wo), dtype=np.float64)
    measured = Measured(
        wi=plan.wi,
        wo=plan.wo,
        f=f,
        sigma=np.zeros_like(f),
        parametrization=plan.spec.parametrization,
        isotropic=plan.spec.isotropic,
        rig=rig,
        scene_text=None,
        band="luminance",
        source=plan.spec.name,
    )
    # linear: the unit box's diagonal as the support distance, so that the interpolant
    # answers wherever it is defined (inside the samples' hull); rbf: its own support.
    dims = len(plan.spec.coordinates())
    best: tuple[float | None, float | None, float | None, str] = (None, None, None, "")
    for method in METHODS:
        try:
            candidate = reconstruct(
                measured,
                method=method,
                extrapolate=EXTRAPOLATE,
                max_distance=math.sqrt(dims) if method == "linear" else None,
            )
            every = evaluate(
                candidate, material, rig, isotropic=plan.spec.isotropic, test_set=test_set
            ).regions["all"]
        except GonioError:
            continue  # rbf on samples on too few lines or planes
        distance, _ = candidate.domain.nearest(
            candidate.space.scaled(test_set.wi, test_set.wo), bounded=False
        )
        error = every.scores.log_rmse
        if error is not None and (best[0] is None or error < best[0]):
            best = (error, every.coverage, float(distance.max()), method)
    return best


def best_stop(errors: Sequence[float | None], motions: Sequence[str]) -> int | None:
    """The index of the stop-and-go candidate of lowest predicted error (the first of
    equals), None if none has one."""
    stops = [k for k, m in enumerate(motions) if m == STOP]
    return pick([errors[k] for k in stops], [STOP] * len(stops), stops)


def pick(
    errors: Sequence[float | None], motions: Sequence[str], index: Sequence[int] | None = None
) -> int | None:
    """The candidate chosen from predicted errors (None or NaN: no prediction) and
    motions: the lowest error, a fly plan only when predicted at least `MARGIN` times
    lower than every stop-and-go one (stop-and-go before fly among equals, then the
    first). Its position (or ``index`` of it), None when no candidate has a prediction."""
    usable = {k: e for k, e in enumerate(errors) if e is not None and math.isfinite(e)}
    if not usable:
        return None
    stops = [e for k, e in usable.items() if motions[k] == STOP]
    floor = min(stops) / MARGIN if stops else math.inf
    allowed = {k: e for k, e in usable.items() if motions[k] == STOP or e <= floor}
    best = min(allowed, key=lambda k: (allowed[k], motions[k] != STOP, k))
    return best if index is None else index[best]
