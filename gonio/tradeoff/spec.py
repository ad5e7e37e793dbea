"""The sweep file (YAML), validated: the scenes, the rig and the axes a trade-off study
sweeps (docs/explanations/tradeoff.md).

Every combination of the axes' values (their Cartesian product, less the ``exclude``
patterns) is planned, acquired on the simulated backend, reconstructed and scored. The
file is checked whole when it is read — names, coordinates, effects, reconstruction
methods, and (in `gonio.tradeoff.grid.load_sweep`, with the rig and scenes) exposures
against the detector, the scaled rigs and the size of the grid — so a mistake is one line
``FILE:LINE: field: …`` before anything runs.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal, get_args

from pydantic import Field, ValidationInfo, field_validator, model_validator
from pydantic.config import JsonDict

from gonio import params
from gonio.config import Strict, excerpt, field_error
from gonio.config_schema import InSchema
from gonio.planner import (
    MAX_KICKS_GIVEN,
    MAX_MOVES,
    MAX_PLAN_MINUTES,
    MAX_TARGETS,
    MIN_BLUR_DEG,
    MIN_RATE_HZ,
    WHY_MAX_TARGETS,
    AcquisitionSpec,
    AdaptiveSpec,
    PlanSpec,
    Strategy,
    Warp,
)
from gonio.reconstruct import DEFAULT_FILL, DEFAULT_SEED, DEFAULT_SIZE, METRICS, methods
from gonio.scene import EffectsSpec

#: Strategies a sweep may name: the planner's own, and ``warped`` (Sobol with the
#: sweep's ``warps`` for the parametrization).
WARPED = "warped"
STRATEGIES: tuple[str, ...] = (*get_args(Strategy), WARPED)

#: ``motion`` values: stop-and-go, or readings streamed while an axis sweeps.
STOP: Literal["stop"] = "stop"
FLY: Literal["fly"] = "fly"
#: The axes that apply to stop-and-go combinations only, and to fly ones only (a
#: combination of the other motion takes None for them, and is run once).
STOP_AXES = ("sampling", "exposure_s", "averages")
FLY_AXES = ("blur_deg", "rate_hz", "segment")

#: The longest instrument-time budget (minutes) of a combination: `MAX_PLAN_MINUTES`;
#: every combination under it is planned, simulated and scored, so a longer budget is
#: hours of a sweep's CPU per combination.
MAX_MINUTES = MAX_PLAN_MINUTES
#: The range of ``velocity_scale``: a hundredth to a hundred times the rig's speeds
#: (slower, a simulated move of minutes per degree; faster, no servo of the kind).
VELOCITY_SCALES = (0.01, 100.0)
#: The most readings averaged per target a sweep may ask (each one is simulated).
MAX_AVERAGES = 1000
#: The bounds of the fly axes: those of a fly plan's fields (`gonio.planner.fly_spec.FlySpec`).
BLUR_RANGE = (MIN_BLUR_DEG, 30.0)
RATE_RANGE = (MIN_RATE_HZ, 10_000.0)
#: The longest exposure: a plan's (`gonio.planner.schema.ExposureSpec`).
MAX_EXPOSURE_S = 3600.0

#: The effects of a scene that a sweep may toggle: those `gonio.scene.EffectsSpec` models.
EFFECT_NAMES: tuple[str, ...] = tuple(EffectsSpec.model_fields)
#: ``effects`` values: the scene's own effects, or none at all.
SCENE, NONE = "scene", "none"

#: The warps of ``warped`` sampling when the sweep gives none for a parametrization:
#: u ↦ u² on the half-vector coordinate, denser toward the specular peak.
DEFAULT_WARPS: dict[str, dict[str, Warp]] = {
    "hybrid": {"hbar": Warp(power=2.0)},
    "orthographic": {"hbar": Warp(power=2.0)},
    "rusinkiewicz": {"theta_h": Warp(power=2.0)},
}


#: An effect's name, as the JSON Schema says it (`_check_effects` checks it).
EffectName = Annotated[str, InSchema(enum=list(EFFECT_NAMES))]


class Without(Strict):
    """The scene's effects less these."""

    without: list[EffectName] = Field(min_length=1, description="The effects left out.")


#: ``scene``, ``none``, the effects named, or the scene's less some.
Effects = Annotated[str, InSchema(enum=[SCENE, NONE])] | list[EffectName] | Without
#: The JSON Schema of an axis: each value once (`Axes` checks it).
UNIQUE: JsonDict = {"uniqueItems": True}


def effects_label(effects: Effects) -> str:
    """The value as a results column shows it: ``scene``, ``none``, ``a+b`` (only those)
    or ``without:a+b`` (the scene's less those)."""
    if isinstance(effects, Without):
        return "without:" + "+".join(effects.without)
    if isinstance(effects, list):
        return "+".join(effects) if effects else NONE
    return effects


#: The plan file's fields, whose descriptions the sweep's fields of those names share.
_PLAN = PlanSpec.model_fields
#: A parametrization's name, in the JSON Schema.
_PARAMETRIZATION = {"enum": params.names()}


class Axes(Strict):
    """The values swept, each a list; a combination takes one value of each."""

    # The planner's default unless the sweep names them (one source of truth).
    parametrization: list[Annotated[str, InSchema(enum=params.names())]] = Field(
        default_factory=lambda: [PlanSpec.model_fields["parametrization"].default],
        min_length=1,
        description="Parametrizations the targets are placed in (default: the plan file's).",
        json_schema_extra=UNIQUE,
    )
    sampling: list[Annotated[str, InSchema(enum=list(STRATEGIES))]] = Field(
        ["sobol"],
        min_length=1,
        description="Strategies: the plan file's, or warped (Sobol with the sweep's warps).",
        json_schema_extra=UNIQUE,
    )
    samples: list[Annotated[int, InSchema(minimum=1, maximum=MAX_TARGETS)]] = Field(
        min_length=1,
        description="Kept targets asked for (a plan's sampling.target).",
        json_schema_extra=UNIQUE,
    )  # kept targets asked for (sampling.target)
    exposure_s: list[Annotated[float, InSchema(exclusiveMinimum=0, maximum=MAX_EXPOSURE_S)]] = (
        Field(
            [0.05],
            min_length=1,
            description="Exposures (s), within the rig's detector.exposure_range_s.",
            json_schema_extra=UNIQUE,
        )
    )
    averages: list[Annotated[int, InSchema(minimum=1, maximum=MAX_AVERAGES)]] = Field(
        [1],
        min_length=1,
        description="Readings averaged per target, at most the rig's detector.max_averages "
        f"and {MAX_AVERAGES} (each reading is simulated).",
        json_schema_extra=UNIQUE,
    )
    # Each axis's max velocity × v and max acceleration × v²: every move takes 1/v the time.
    velocity_scale: list[
        Annotated[float, InSchema(minimum=VELOCITY_SCALES[0], maximum=VELOCITY_SCALES[1])]
    ] = Field(
        [1.0],
        min_length=1,
        description="Factors v on every axis's max velocity (× v) and acceleration (× v²): "
        f"each move takes 1/v the time; {VELOCITY_SCALES[0]:g} to {VELOCITY_SCALES[1]:g} (a "
        "hundredth to a hundred times the rig's speeds).",
        json_schema_extra=UNIQUE,
    )
    method: list[Annotated[str, InSchema(enum=list(methods.names()))]] = Field(
        [methods.NAIVE],
        min_length=1,
        description="Reconstruction methods scored.",
        json_schema_extra=UNIQUE,
    )
    effects: list[Effects] = Field(
        [SCENE],
        min_length=1,
        description="Effects modelled: scene (the scene's own), none, a list of names (only "
        "those), or {without: [names]} (the scene's less those).",
        json_schema_extra=UNIQUE,
    )

    motion: list[Literal["stop", "fly"]] = Field(
        [STOP],
        min_length=1,
        description="How the rig measures: stop (move, settle, then read each target) or fly "
        "(readings streamed while one axis sweeps at constant velocity; sampling, "
        "exposure_s and averages then do not apply, the fly axes do).",
        json_schema_extra=UNIQUE,
    )
    minutes: list[Annotated[float, InSchema(exclusiveMinimum=0, maximum=MAX_MINUTES)] | None] = (
        Field(
            [None],
            min_length=1,
            description="Instrument-time budgets (minutes): the plan's target is fitted so its "
            "predicted duration fits the budget (samples then does not apply); none: the "
            "samples axis sets the target. At least one sample's time on the rig (its "
            "settle_s and the shortest exposure or integration), at most a day (1440: the "
            "longest acquisition one plan holds; each combination is simulated whole).",
            json_schema_extra=UNIQUE,
        )
    )
    blur_deg: list[Annotated[float, InSchema(minimum=BLUR_RANGE[0], maximum=BLUR_RANGE[1])]] = (
        Field(
            [0.5],
            min_length=1,
            description="Fly only: the most angular smear of one reading (degrees), which sets "
            "the sweep's velocity (a fly plan's sampling.fly.blur_deg, within its bounds).",
            json_schema_extra=UNIQUE,
        )
    )
    rate_hz: list[Annotated[float, InSchema(minimum=RATE_RANGE[0], maximum=RATE_RANGE[1])]] = Field(
        [100.0],
        min_length=1,
        description="Fly only: readings per second the detector streams, each integrating "
        "1 / rate_hz (a fly plan's sampling.fly.rate_hz).",
        json_schema_extra=UNIQUE,
    )
    segment: list[Literal["detector_arc", "light_arc", "theta_h_line"]] = Field(
        ["detector_arc"],
        min_length=1,
        description="Fly only: what sweeps, detector_arc, light_arc or theta_h_line (a fly "
        "plan's sampling.fly.segment).",
        json_schema_extra=UNIQUE,
    )

    @field_validator("samples", "averages")
    @classmethod
    def _positive_counts(cls, values: list[int], info: ValidationInfo) -> list[int]:
        for k, value in enumerate(values):
            if value < 1:
                raise field_error(str(k), f"expected a positive count, got {value}")
            if info.field_name == "averages" and value > MAX_AVERAGES:
                raise field_error(
                    str(k),
                    f"expected at most {MAX_AVERAGES} averages (each reading is "
                    f"simulated), got {value:,}",
                )
            if info.field_name == "samples" and value > MAX_TARGETS:
                raise field_error(
                    str(k),
                    f"expected at most {MAX_TARGETS:,} targets, got {value:,} ({WHY_MAX_TARGETS})",
                )
        return values

    @field_validator("exposure_s", "velocity_scale", "minutes", "blur_deg", "rate_hz")
    @classmethod
    def _positive_numbers(
        cls, values: list[float | None], info: ValidationInfo
    ) -> list[float | None]:
        least, most = _RANGES.get(str(info.field_name), (None, None))
        why = _WHY.get(str(info.field_name), "")
        for k, value in enumerate(values):
            if value is None and info.field_name == "minutes":
                continue
            if value is None or not value > 0:
                raise field_error(str(k), f"expected a positive number, got {value}")
            if least is not None and value < least:
                raise field_error(str(k), f"expected at least {least:g}{why}, got {value:g}")
            if most is not None and value > most:
                raise field_error(str(k), f"expected at most {most:g}{why}, got {value:g}")
        return values

    @model_validator(mode="after")
    def _known_values(self) -> Axes:
        for k, name in enumerate(self.parametrization):
            if name not in params.names():
                raise field_error(
                    f"parametrization.{k}",
                    f"unknown parametrization {excerpt(name)}; "
                    f"expected one of {', '.join(params.names())}",
                )
        for k, name in enumerate(self.sampling):
            if name not in STRATEGIES:
                raise field_error(
                    f"sampling.{k}",
                    f"unknown strategy {excerpt(name)}; expected one of {', '.join(STRATEGIES)}",
                )
        for k, method in enumerate(self.method):
            if method not in methods.names():
                raise field_error(
                    f"method.{k}",
                    f"unknown reconstruction method {excerpt(method)}; expected one of "
                    f"{', '.join(methods.names())}",
                )
        for k, effects in enumerate(self.effects):
            _check_effects(f"effects.{k}", effects)
        for name in type(self).model_fields:
            values = getattr(self, name)
            labels = [_label(v) for v in values]
            twice = next((i for i, v in enumerate(labels) if v in labels[:i]), None)
            if twice is not None:
                raise field_error(f"{name}.{twice}", f"{excerpt(values[twice])} is given twice")
        return self


#: The bounds of the numeric axes (None: no bound there; minutes have the rig's floor
#: too, `gonio.tradeoff.grid.load_sweep`), and why.
_RANGES: dict[str, tuple[float | None, float | None]] = {
    "exposure_s": (None, MAX_EXPOSURE_S),
    "velocity_scale": VELOCITY_SCALES,
    "minutes": (None, MAX_MINUTES),
    "blur_deg": BLUR_RANGE,
    "rate_hz": RATE_RANGE,
}
_WHY = {
    "minutes": " (a day: the longest acquisition one plan holds)",
    "velocity_scale": " (a hundredth to a hundred times the rig's speeds)",
    "blur_deg": " (below, the encoders' quantization hides the smear)",
    "rate_hz": " (below one reading a second a sweep passes tens of degrees between two)",
}


def _label(value: Any) -> str:
    return effects_label(value) if isinstance(value, list | Without) else str(value)


def _check_effects(where: str, effects: Effects) -> None:
    if isinstance(effects, str):
        if effects not in (SCENE, NONE):
            raise field_error(
                where,
                f"expected {SCENE} (the scene's effects), {NONE}, a list of effect names or "
                f"{{without: [names]}}, got {excerpt(effects)}",
            )
        return
    names = effects.without if isinstance(effects, Without) else effects
    for k, name in enumerate(names):
        if name not in EFFECT_NAMES:
            path = f"{where}.without.{k}" if isinstance(effects, Without) else f"{where}.{k}"
            raise field_error(
                path, f"unknown effect {excerpt(name)}; expected one of {', '.join(EFFECT_NAMES)}"
            )


class PlanSettings(Strict):
    """What every combination's plan shares (the plan file's fields of those names)."""

    max_moves: int | None = Field(
        None, ge=0, le=MAX_MOVES, description=_PLAN["max_moves"].description
    )
    kicks: int | None = Field(
        None, ge=0, le=MAX_KICKS_GIVEN, description=_PLAN["kicks"].description
    )
    ordering: Literal["search", "lkh"] = Field("search", description=_PLAN["ordering"].description)
    # Generous: a cap that binds makes the order depend on the machine's load.
    time_budget_s: float = Field(600.0, gt=0, description=_PLAN["time_budget_s"].description)
    acquisition: AcquisitionSpec = Field(
        default_factory=AcquisitionSpec, description=_PLAN["acquisition"].description
    )


class EvaluationSettings(Strict):
    """The test set every combination is scored on (`gonio.reconstruct.testset`)."""

    pairs: int = Field(
        DEFAULT_SIZE, ge=1, le=1_000_000, description="Direction pairs in the test set."
    )
    seed: int = Field(DEFAULT_SEED, ge=0, description="The seed the test set is drawn with.")
    extrapolate: Literal["nearest"] = Field(
        DEFAULT_FILL,
        description="How a reconstruction answers a test pair outside its samples' support: "
        "nearest (the inverse-distance mean of the nearest samples in log(1 + f)). Every "
        "pair is scored, so plans of different layouts compare on the same pairs; the "
        "coverage columns give the share inside the support.",
    )
    only_supported: bool = Field(
        False,
        description="Score only the test pairs inside each reconstruction's support (no "
        "fill): plans of different layouts are then scored on different pairs.",
    )


AXIS_NAMES = tuple(Axes.model_fields)


class SweepSpec(Strict):
    """A trade-off study: every combination of the axes' values (less the ``exclude``
    patterns), for every scene, is planned, acquired on the simulated rig, reconstructed
    and scored."""

    name: str = Field(min_length=1, description="The sweep's name, in its plans' names.")
    rig: str = Field(description="The rig file, relative to the sweep file.")
    scenes: list[str] = Field(
        min_length=1, description="The scene files, relative to the sweep file."
    )
    isotropic: bool = Field(True, description=_PLAN["isotropic"].description)
    axes: Axes = Field(description="The values swept; a combination takes one of each.")
    # Leave out every combination that matches all the fields of one pattern (a value,
    # or a list of values).
    exclude: list[
        Annotated[
            dict[str, Any], InSchema(minProperties=1, propertyNames={"enum": list(AXIS_NAMES)})
        ]
    ] = Field(
        default_factory=list,
        description="Patterns of axis: value (or a list of values); a combination matching "
        "every field of one is left out.",
    )
    warps: Annotated[dict[str, dict[str, Warp]], InSchema(propertyNames=_PARAMETRIZATION)] = Field(
        default_factory=dict,
        description="Per parametrization, per coordinate: the warps of warped sampling "
        "(default: u ↦ u² on the half-vector coordinate).",
    )
    adaptive: AdaptiveSpec = Field(
        default_factory=AdaptiveSpec, description="The options of adaptive sampling."
    )
    replicates: int = Field(
        1, ge=1, le=1000, description="Runs of each combination, each with other seeds."
    )
    seed: int = Field(
        0, ge=0, description="Mixed into every combination's id, and so into its seeds."
    )
    plan: PlanSettings = Field(
        default_factory=PlanSettings, description="What every combination's plan shares."
    )
    evaluation: EvaluationSettings = Field(
        default_factory=EvaluationSettings,
        description="The test set every combination is scored on.",
    )
    metric: str = Field(
        "log_rmse",
        description="The error the report, the front and --target-error use.",
        json_schema_extra={"enum": [*METRICS]},
    )

    @model_validator(mode="after")
    def _consistent(self) -> SweepSpec:
        if self.metric not in METRICS:
            raise field_error(
                "metric",
                f"unknown metric {excerpt(self.metric)}; expected one of {', '.join(METRICS)}",
            )
        for k, pattern in enumerate(self.exclude):
            if not pattern:
                raise field_error(f"exclude.{k}", "expected at least one axis: value")
            unknown = sorted(set(pattern) - set(AXIS_NAMES))
            if unknown:
                raise field_error(
                    f"exclude.{k}.{unknown[0]}",
                    f"not an axis; expected one of {', '.join(AXIS_NAMES)}",
                )
        for name, table in self.warps.items():
            if name not in params.names():
                raise field_error(
                    f"warps.{name}",
                    f"unknown parametrization; expected one of {', '.join(params.names())}",
                )
            p = params.get(name)
            coords = p.iso_names if self.isotropic else p.names
            unknown = sorted(set(table) - set(coords))
            if unknown:
                raise field_error(
                    f"warps.{name}.{unknown[0]}",
                    f"not a coordinate of {'isotropic ' if self.isotropic else ''}{name}; "
                    f"expected one of {', '.join(coords)}",
                )
        return self

    def warps_of(self, parametrization: str) -> dict[str, Warp]:
        """The warps of ``warped`` sampling in ``parametrization`` (the sweep's, else
        `DEFAULT_WARPS`; coordinates of the anisotropic form do not apply isotropically)."""
        if parametrization in self.warps:
            return self.warps[parametrization]
        p = params.get(parametrization)
        coords = p.iso_names if self.isotropic else p.names
        table = DEFAULT_WARPS.get(parametrization, {})
        return {c: w for c, w in table.items() if c in coords}

    def excluded(self, combination: dict[str, Any]) -> bool:
        """Whether a combination (axis → value) matches an ``exclude`` pattern: every
        axis the pattern names has the value given there, or one of the values listed
        (effects written as their label: ``scene``, ``none``, ``a+b``, ``without:a``)."""
        return any(
            all(_matches(combination[name], wanted) for name, wanted in pattern.items())
            for pattern in self.exclude
        )


def _matches(value: Any, wanted: Any) -> bool:
    for option in wanted if isinstance(wanted, list) else [wanted]:
        numbers = (int, float)
        if isinstance(value, numbers) and isinstance(option, numbers):
            if not isinstance(option, bool) and value == option:
                return True
        elif _label(value) == str(option):
            return True
    return False
