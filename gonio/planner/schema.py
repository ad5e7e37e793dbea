"""The plan file (YAML), validated.

A plan names the parametrization to sample uniformly (default ``rusinkiewicz``: its
uniform plans reach a given error with the fewest samples on every shipped scene,
docs/explanations/tradeoff.md "The study"), whether the material is isotropic (three coordinates:
the pair's azimuth is rotated out and the reciprocity fold applies) or anisotropic
(four; the sample rotation stage is used), how to place points, and how long to expose
each target. How `gonio acquire` runs the plan (its ``acquisition`` section) is
validated by `gonio.planner.policies`.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import Field, model_validator

from gonio import brdf, params
from gonio.brdf import family
from gonio.config import Strict, excerpt, field_error
from gonio.config_schema import InSchema
from gonio.errors import GonioError
from gonio.planner.fly_spec import FlySpec
from gonio.planner.material import flat_material, material_model
from gonio.planner.policies import AcquisitionSpec

Strategy = Literal["grid", "stratified", "sobol", "halton", "random", "adaptive"]
#: The most improving moves a plan may allow its ordering: far more than a descent from
#: 10⁶ targets applies (the default gives 10 a target), and still a count an int64 holds
#: with room.
MAX_MOVES = 10**9
#: The most kicks a plan may ask for: at some 10⁵ kicks a second, about two minutes, the
#: wall-time cap's default (time_budget_s).
MAX_KICKS_GIVEN = 10**7
#: The longest instrument time one plan is made for (minutes): a day; a longer campaign
#: is several plans (and runs), each resumable on its own.
MAX_PLAN_MINUTES = 1440.0
#: The most targets a plan may keep, and why (benchmarks/planner.py, table ``memory``).
MAX_TARGETS = 1_000_000
WHY_MAX_TARGETS = (
    "planning needs about 4 KB of memory and 0.2 ms of CPU per target, and a million "
    "targets are days of instrument time: split the acquisition into several plans"
)
#: A plan's strategies: the stop-and-go ones, and fly (readings taken while the axes move).
PlanStrategy = Literal["grid", "stratified", "sobol", "halton", "random", "adaptive", "fly"]


class Warp(Strict):
    """u ↦ u^power on one coordinate's unit interval before scaling to its bounds:
    power > 1 puts more points near the lower bound (e.g. ‖h̄‖ = 0, the specular peak)."""

    power: float = Field(
        ge=0.1,
        le=10,
        description="The exponent, in [0.1, 10]: > 1 denser near the lower bound, 1 uniform, "
        "< 1 sparser (beyond 10 a quarter of the points fall within 1e-6 of the bound and "
        "repeat each other).",
    )


class AdaptiveSpec(Strict):
    """The adaptive strategy (docs/explanations/adaptive.md): a Sobol survey of ``survey`` kept
    targets is measured first; a model of family ``model`` (a `gonio fit` spec) fitted
    to it (``survey``: the survey's own reconstruction, no model) estimates where a
    reconstruction errs; the rest of the target is then placed
    with the density of `gonio.planner.adaptive`, a share ``floor`` of it uniform and a
    share ``edge`` moved onto the edge of the rig's cap."""

    survey: int = Field(
        128,
        ge=16,
        description="Kept targets of the first pass, a Sobol survey (fewer than sampling.target).",
    )
    model: str = Field(
        "lambert+beckmann",
        description="The model family fitted to the survey to steer the rest, as `gonio fit "
        "--model` takes it (e.g. lambert+ggx); or survey: steer by the survey's own rbf "
        "reconstruction, no model.",
    )
    floor: float = Field(
        0.2, ge=0.0, le=1.0, description="Share of the rest of the target placed uniformly."
    )
    edge: float = Field(
        0.0,
        ge=0.0,
        lt=1.0,
        description="Share of the rest of the target moved onto the edge of the rig's cap "
        "(constraints.theta_max_deg).",
    )

    @model_validator(mode="after")
    def _known_model(self) -> AdaptiveSpec:
        if self.model != "survey":  # refused when the file is read, not after the survey
            try:
                family.parse(self.model)
            except GonioError as exc:
                raise field_error("model", f"{exc} (or survey: no model)") from None
        return self


#: The most readings a fly plan may ask for (``sampling.target``), and why.
MAX_READINGS = 1_000_000
WHY_MAX_READINGS = (
    "planning takes about 0.25 ms and 1 KB per reading, and a million readings are hours "
    "of instrument time at 100 Hz: split the acquisition into several plans"
)


class SamplingSpec(Strict):
    """Where the targets go: points placed in the parametrization's coordinate box (or its
    isotropic reduction), kept where the coordinates are valid and the rig reaches them;
    either ``counts`` per coordinate (a grid) or a ``target`` number of kept targets."""

    strategy: PlanStrategy = Field(
        "sobol",
        description="grid (cell centres), stratified (one uniform point per cell), sobol, "
        "halton (scrambled), random, adaptive (a Sobol survey first, then the rest of the "
        "target where a reconstruction errs), or fly (readings while an axis sweeps; "
        "stop-and-go otherwise).",
    )
    counts: dict[str, Annotated[int, InSchema(minimum=1)]] | None = Field(
        None,
        description="Points per coordinate, a count for every coordinate of the "
        "parametrization (grid and stratified only; instead of target).",
    )
    target: int | None = Field(
        None,
        gt=0,
        description="Kept targets wanted, any strategy (instead of counts); with strategy fly, "
        f"the readings wanted, at most {MAX_READINGS:,} ({WHY_MAX_READINGS}).",
    )
    seed: int = Field(
        0,
        ge=0,
        description="Seed of the point sequence or the stratified jitter, and of the ordering's "
        "kicks.",
    )
    warps: dict[str, Warp] = Field(
        default_factory=dict,
        description="Per coordinate: u ↦ u^power on its unit interval before scaling to its "
        "bounds (none: uniform; not with the adaptive strategy).",
    )
    adaptive: AdaptiveSpec | None = Field(
        None, description="The adaptive strategy's options (only with strategy: adaptive)."
    )
    fly: FlySpec | None = Field(
        None, description="The fly strategy's options (only with strategy: fly)."
    )

    @model_validator(mode="after")
    def _counts_or_target(self) -> SamplingSpec:
        if (self.counts is None) == (self.target is None):
            raise ValueError("give exactly one of counts (per coordinate) or target (a total)")
        if self.adaptive is not None and self.strategy != "adaptive":
            raise field_error("adaptive", f"options of the adaptive strategy, not {self.strategy}")
        if self.fly is not None and self.strategy != "fly":
            raise field_error("fly", f"options of the fly strategy, not {self.strategy}")
        if self.strategy == "fly" and self.target is not None and self.target > MAX_READINGS:
            raise field_error(
                "target",
                f"expected at most {MAX_READINGS:,} readings in a fly plan, got {self.target:,} "
                f"({WHY_MAX_READINGS})",
            )
        if self.strategy == "fly" and self.warps:
            raise field_error("warps", "the fly strategy lays out uniform sweeps (no warps)")
        if self.strategy == "adaptive":
            if self.warps:
                raise field_error("warps", "the adaptive strategy places its own density")
            survey = self.options().survey
            if self.target is not None and self.target <= survey:
                raise field_error(
                    "target", f"expected more targets than the survey's {survey}, got {self.target}"
                )
        if self.counts is not None:
            for name, count in self.counts.items():
                if count < 1:
                    raise field_error(
                        f"counts.{name}", f"expected a positive number of points, got {count}"
                    )
        if self.counts is not None and self.strategy not in ("grid", "stratified"):
            raise field_error(
                "counts", f"counts apply to grid and stratified sampling, not {self.strategy}"
            )
        return self

    def options(self) -> AdaptiveSpec:
        """The adaptive strategy's options (the defaults unless given)."""
        return self.adaptive or AdaptiveSpec()

    def fly_options(self) -> FlySpec:
        """The fly strategy's options (the defaults unless given)."""
        return self.fly or FlySpec()


class AdaptSpec(Strict):
    """Exposure and averaging scaled by 1/expected signal: s = f(ωi, ωo) · g of the
    expected material (g = cos θo for a collimated light, cos θi for a point source:
    `gonio.planner.exposure`); exposure = base × s_ref / s clipped to [min_s, max_s],
    with s_ref the median over the plan's targets."""

    material: dict[str, Any] = Field(
        min_length=1,
        description="The expected material: name (a gonio.brdf model) and its parameters "
        "beside it, e.g. {name: cook_torrance, alpha: 0.2, kd: 0.3}.",
        json_schema_extra=flat_material,
    )  # checked by gonio.brdf.material
    min_s: float = Field(gt=0, description="The shortest exposure (s).")
    max_s: float = Field(gt=0, description="The longest exposure (s), at least min_s.")
    max_averages: int = Field(
        1,
        ge=1,
        description="The most averages, which grow as the exposure would beyond max_s.",
    )

    @model_validator(mode="after")
    def _range(self) -> AdaptSpec:
        if self.min_s > self.max_s:
            raise field_error("min_s", f"expected at most max_s ({self.max_s}), got {self.min_s}")
        self.model()  # refuse an unknown model or bad parameters when the file is read
        return self

    def model(self) -> brdf.BRDF:
        """The expected material as a `gonio.brdf` model."""
        return material_model(self.material)


class ExposureSpec(Strict):
    """How long each target is exposed, and how many readings are averaged."""

    seconds: float = Field(
        0.1, gt=0, le=3600, description="Exposure of each reading (s); with adapt, the base."
    )
    averages: int = Field(1, ge=1, description="Readings averaged per target.")
    adapt: AdaptSpec | None = Field(
        None,
        description="Scale exposure and averages by 1/expected signal (none: the same for all).",
    )


class PlanSpec(Strict):
    """What to measure: the parametrization and how targets are placed in it, the
    exposure of each, how they are ordered for the motors, and how `gonio acquire` runs
    them, on the rig the ``rig`` field names."""

    name: str = Field(description="The plan's name, shown in summaries and stored in the run.")
    rig: str | None = Field(
        None,
        description="The rig file, relative to the plan file (none: give it with --rig).",
    )
    parametrization: str = Field(
        "rusinkiewicz",
        description="The coordinates targets are placed uniformly in (rusinkiewicz: the "
        "recommended plan).",
        json_schema_extra={"enum": [*params.names()]},
    )
    isotropic: bool = Field(
        True,
        description="true: the three isotropic coordinates, the sample rotation stage home; "
        "false: all four, the rotation stage in use (an anisotropic material).",
    )
    sampling: SamplingSpec = Field(description="Where the targets go.")
    exposure: ExposureSpec = Field(
        default_factory=ExposureSpec, description="Exposure and averages of each target."
    )
    # Improving moves the ordering may apply (both passes together); None: 10 per kept
    # target + 100 (`gonio.planner.ordering.default_moves`). A count, not a time, so the
    # same plan file orders the same on any machine.
    max_moves: int | None = Field(
        None,
        ge=0,
        le=MAX_MOVES,
        description="Improving moves the ordering may apply, both passes together (none: 10 "
        "per kept target + 100), at most 1e9. A count, so the file orders the same on any "
        "machine.",
    )
    # Kicks of the iterated local search after the descents; None: 3 per 2 kept targets,
    # at most 15 000 (`gonio.planner.ordering.default_kicks`). A count too: the kicks
    # are drawn from `sampling.seed`, so the same file orders the same on any machine.
    kicks: int | None = Field(
        None,
        ge=0,
        le=MAX_KICKS_GIVEN,
        description="Kicks of the iterated local search after the descents (none: 3 per 2 "
        "kept targets, at most 15 000), drawn from sampling.seed; at most 1e7.",
    )
    # "search": the iterated local search (seconds); "lkh": then LKH-3 on the chosen
    # poses through the optional `elkai` package (minutes, gigabytes past ~10 000
    # targets), kept where it is shorter.
    ordering: Literal["search", "lkh"] = Field(
        "search",
        description="search: the iterated local search (seconds); lkh: then LKH-3 on the "
        "chosen poses, kept where shorter (the optional elkai package; minutes).",
    )
    # A safety cap on the wall time of improving the order; when it binds the summary
    # says so (the order then depends on the machine).
    time_budget_s: float = Field(
        120.0,
        gt=0,
        description="A cap on the wall time of improving the order (s); the summary says "
        "when it binds (the order then depends on the machine).",
    )
    acquisition: AcquisitionSpec = Field(
        default_factory=AcquisitionSpec, description="How `gonio acquire` runs the plan."
    )

    @model_validator(mode="after")
    def _known_names(self) -> PlanSpec:
        if self.parametrization not in params.names():
            raise field_error(
                "parametrization",
                f"unknown parametrization {excerpt(self.parametrization)}; "
                f"expected one of {', '.join(params.names())}",
            )
        p = params.get(self.parametrization)
        coords = p.iso_names if self.isotropic else p.names
        for field in ("counts", "warps"):
            given = getattr(self.sampling, field) or {}
            unknown = sorted(set(given) - set(coords))
            if unknown:
                raise field_error(
                    f"sampling.{field}.{unknown[0]}",
                    f"not a coordinate; the coordinates of "
                    f"{'isotropic ' if self.isotropic else ''}{self.parametrization} are "
                    f"{', '.join(coords)}",
                )
        if self.sampling.strategy == "fly" and self.exposure.adapt is not None:
            raise field_error(
                "exposure.adapt", "a fly plan reads at a fixed rate (sampling.fly.integration_s)"
            )
        if self.sampling.counts is not None and set(self.sampling.counts) != set(coords):
            missing = ", ".join(c for c in coords if c not in self.sampling.counts)
            raise field_error("sampling.counts", f"expected a count for {missing} as well")
        return self

    def coordinates(self) -> tuple[str, ...]:
        p = params.get(self.parametrization)
        return tuple(p.iso_names if self.isotropic else p.names)
