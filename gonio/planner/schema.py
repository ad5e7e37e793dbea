"""The plan file (YAML), validated.

A plan names the parametrization to sample uniformly (default ``hybrid``), whether the
material is isotropic (three coordinates: the pair's azimuth is rotated out and the
reciprocity fold applies) or anisotropic (four; the sample rotation stage is used),
how to place points, and how long to expose each target.
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from gonio import brdf, params
from gonio.config import Strict, field_error
from gonio.errors import GonioError

Strategy = Literal["grid", "stratified", "sobol", "halton", "random"]


class Warp(Strict):
    """u ↦ u^power on one coordinate's unit interval before scaling to its bounds:
    power > 1 puts more points near the lower bound (e.g. ‖h̄‖ = 0, the specular peak)."""

    power: float = Field(gt=0)


class SamplingSpec(Strict):
    strategy: Strategy = "sobol"
    counts: dict[str, int] | None = None  # per coordinate (grid, stratified)
    target: int | None = Field(None, gt=0)  # kept targets wanted (all strategies)
    seed: int = 0
    warps: dict[str, Warp] = Field(default_factory=dict)

    @model_validator(mode="after")
    def _counts_or_target(self) -> SamplingSpec:
        if (self.counts is None) == (self.target is None):
            raise ValueError("give exactly one of counts (per coordinate) or target (a total)")
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


class AdaptSpec(Strict):
    """Exposure and averaging scaled by 1/expected signal: s = f(ωi, ωo) cos θi of the
    expected material; exposure = base × s_ref / s clipped to [min_s, max_s], with s_ref
    the median over the plan's targets."""

    material: dict[str, float | str | list[float]] = Field(min_length=1)
    min_s: float = Field(gt=0)
    max_s: float = Field(gt=0)
    max_averages: int = Field(1, ge=1)

    @model_validator(mode="after")
    def _range(self) -> AdaptSpec:
        if self.min_s > self.max_s:
            raise field_error("min_s", f"expected at most max_s ({self.max_s}), got {self.min_s}")
        if "name" not in self.material:
            raise field_error("material", "expected a name (a gonio.brdf model) and its parameters")
        self.model()  # refuse an unknown model or bad parameters when the file is read
        return self

    def model(self) -> brdf.BRDF:
        """The expected material as a `gonio.brdf` model."""
        material = dict(self.material)
        name = str(material.pop("name"))
        try:
            return brdf.create(name, **material)
        except GonioError as exc:
            raise field_error("material", str(exc)) from None


class ExposureSpec(Strict):
    seconds: float = Field(0.1, gt=0)
    averages: int = Field(1, ge=1)
    adapt: AdaptSpec | None = None


class PlanSpec(Strict):
    name: str
    rig: str | None = None  # a rig file, relative to the plan file
    parametrization: str = "hybrid"
    isotropic: bool = True
    sampling: SamplingSpec
    exposure: ExposureSpec = Field(default_factory=ExposureSpec)
    # Improving moves the ordering may apply (both passes together); None: 10 per kept
    # target + 100 (`gonio.planner.ordering.default_moves`). A count, not a time, so the
    # same plan file orders the same on any machine.
    max_moves: int | None = Field(None, ge=0)
    # Kicks of the iterated local search after the descents; None: 3 per 2 kept targets,
    # at most 15 000 (`gonio.planner.ordering.default_kicks`). A count too: the kicks
    # are drawn from `sampling.seed`, so the same file orders the same on any machine.
    kicks: int | None = Field(None, ge=0)
    # "search": the iterated local search (seconds); "lkh": then LKH-3 on the chosen
    # poses through the optional `elkai` package (minutes, gigabytes past ~10 000
    # targets), kept where it is shorter.
    ordering: Literal["search", "lkh"] = "search"
    # A safety cap on the wall time of improving the order; when it binds the summary
    # says so (the order then depends on the machine).
    time_budget_s: float = Field(120.0, gt=0)

    @model_validator(mode="after")
    def _known_names(self) -> PlanSpec:
        if self.parametrization not in params.names():
            raise field_error(
                "parametrization",
                f"unknown parametrization {self.parametrization!r}; "
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
        if self.sampling.counts is not None and set(self.sampling.counts) != set(coords):
            missing = ", ".join(c for c in coords if c not in self.sampling.counts)
            raise field_error("sampling.counts", f"expected a count for {missing} as well")
        return self

    def coordinates(self) -> tuple[str, ...]:
        p = params.get(self.parametrization)
        return tuple(p.iso_names if self.isotropic else p.names)
