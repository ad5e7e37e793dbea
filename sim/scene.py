"""The scene file (YAML): what the simulated instrument measures and which effects it
models.

A scene names a material (any `gonio.brdf` model with its parameters), a light source
(a distant collimated beam or a proximal point source), a detector (aperture, field of
view, responsivity, sensor), the sample's size, a Lambertian reference target, and the
effects to model. With no effects a reading is the exact analytic value carried
through the radiometric chain (`gonio.radiometry`); each listed effect is computed, and
only those. Angles in the file are degrees (``_deg``), lengths millimetres (``_mm``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import (
    Field,
    SerializerFunctionWrapHandler,
    field_validator,
    model_serializer,
    model_validator,
)

from gonio import brdf
from gonio.config import Strict, field_error, load
from gonio.errors import GonioError
from sim.faults import FaultRule

#: Rec. 709 luminance weights: how a grey detector sees an RGB material.
LUMINANCE = (0.2126, 0.7152, 0.0722)


class MaterialSpec(Strict):
    """A `gonio.brdf` model: ``name`` and its parameters (numbers, strings, RGB lists)."""

    name: str
    params: dict[str, float | str | list[float]] = Field(default_factory=dict)

    @model_validator(mode="before")
    @classmethod
    def _flat(cls, data: Any) -> Any:
        """Accept ``{name: ggx, alpha: 0.1}`` as well as ``{name: ggx, params: {...}}``."""
        if isinstance(data, dict) and "params" not in data:
            rest = {k: v for k, v in data.items() if k != "name"}
            return {"name": data.get("name"), "params": rest}
        return data

    @model_validator(mode="after")
    def _buildable(self) -> MaterialSpec:
        self.model()
        return self

    def model(self) -> brdf.BRDF:
        try:
            return brdf.create(self.name, **self.params)
        except GonioError as exc:
            raise field_error("name", str(exc)) from None


class CollimatedSpec(Strict):
    kind: Literal["collimated"]
    irradiance_w_m2: float = Field(gt=0)  # perpendicular to the beam
    beam_diameter_mm: float = Field(gt=0)


class PointSpec(Strict):
    kind: Literal["point"]
    intensity_w_sr: float = Field(gt=0)
    distance_mm: float = Field(gt=0)


class DetectorSpec(Strict):
    aperture_sr: float = Field(gt=0, lt=6.2832)
    fov_diameter_mm: float = Field(gt=0)
    responsivity_a_w: float = Field(gt=0)
    dark_current_e_s: float = Field(0.0, ge=0)
    read_noise_e: float = Field(0.0, ge=0)
    full_well_e: float = Field(gt=0)
    adc_bits: int = Field(16, ge=1, le=32)
    exposure_range_s: tuple[float, float] = (1e-4, 60.0)
    readout_s: float = Field(0.0, ge=0)  # dead time after each exposure
    band: Literal["luminance", "r", "g", "b"] = "luminance"  # for RGB materials

    @model_validator(mode="after")
    def _range(self) -> DetectorSpec:
        lo, hi = self.exposure_range_s
        if not 0 < lo <= hi:
            raise field_error(
                "exposure_range_s", f"expected [min, max] with 0 < min ≤ max, got [{lo}, {hi}]"
            )
        return self


class SampleSpec(Strict):
    diameter_mm: float = Field(gt=0)


class ReferenceSpec(Strict):
    """The Lambertian standard measured for calibration (e.g. a 99 % diffuse target)."""

    albedo: float = Field(0.99, gt=0, le=1)


# -- effects ---------------------------------------------------------------------------


class NoParams(Strict):
    """An effect whose parameters live elsewhere (the detector's), or has none."""


class SourceDriftSpec(Strict):
    """Source power × (1 + rate · t/3600 + amplitude · sin(2π t / period + phase)),
    t the run's virtual time (s)."""

    rate_per_hour: float = 0.01
    amplitude: float = Field(0.0, ge=0, lt=1)
    period_s: float = Field(600.0, gt=0)
    phase_deg: float = 0.0


class ApertureSpec(Strict):
    """The detector averages the BRDF over its solid angle: a Gauss–Legendre × trapezoid
    quadrature of ``order`` × 2·order nodes over the cap (order 6 keeps a GGX α = 0.02
    peak to 1e-7 at 1e-3 sr and 1e-13 at 1e-4 sr; docs/simulator.md)."""

    order: int = Field(6, ge=2, le=64)


class PositionErrorSpec(Strict):
    """Motor tick quantization (4096/rev through the gear), backlash (the joint lags by
    half of it behind the direction of the last move) and repeatability (Gaussian, per
    move, 1σ)."""

    ticks: bool = True
    backlash_deg: float = Field(0.0, ge=0)
    repeatability_deg: float = Field(0.0, ge=0)


class StrayLightSpec(Strict):
    """A constant floor of radiant power (W) reaching the detector while the source is on."""

    power_w: float = Field(ge=0)


class EffectsSpec(Strict):
    shot_noise: NoParams | None = None
    read_noise: NoParams | None = None
    dark_current: NoParams | None = None
    quantization: NoParams | None = None
    saturation: NoParams | None = None
    source_drift: SourceDriftSpec | None = None
    aperture_integration: ApertureSpec | None = None
    footprint: NoParams | None = None
    position_error: PositionErrorSpec | None = None
    stray_light: StrayLightSpec | None = None

    @model_validator(mode="before")
    @classmethod
    def _names(cls, data: Any) -> Any:
        """A list of names (``[shot_noise, read_noise]``) means each with defaults; a
        name mapped to nothing (``shot_noise:``) likewise."""
        if isinstance(data, list):
            if not all(isinstance(x, str) for x in data):
                raise ValueError("expected effect names, or a mapping of effect: parameters")
            data = {name: {} for name in data}
        if isinstance(data, dict):
            return {k: ({} if v is None else v) for k, v in data.items()}
        return data

    @model_serializer(mode="wrap")
    def _listed_only(self, handler: SerializerFunctionWrapHandler) -> dict[str, Any]:
        """Dump only the effects listed, so a dump reads back as the same effects."""
        return {k: v for k, v in handler(self).items() if v is not None}

    def names(self) -> tuple[str, ...]:
        """The effects listed, in declaration order."""
        return tuple(n for n in type(self).model_fields if getattr(self, n) is not None)


# -- the scene ---------------------------------------------------------------------------


class Scene(Strict):
    name: str
    material: MaterialSpec
    source: Annotated[CollimatedSpec | PointSpec, Field(discriminator="kind")]
    detector: DetectorSpec
    sample: SampleSpec
    reference: ReferenceSpec = Field(default_factory=ReferenceSpec)
    effects: EffectsSpec = Field(default_factory=EffectsSpec)
    faults: tuple[FaultRule, ...] = ()  # injected faults (`sim.faults`)
    seed: int = Field(0, ge=0)

    @field_validator("effects", mode="before")
    @classmethod
    def _none_is_empty(cls, v: Any) -> Any:
        return {} if v is None else v

    @field_validator("faults", mode="before")
    @classmethod
    def _no_faults(cls, v: Any) -> Any:
        return () if v is None else v

    def with_faults(self, *rules: FaultRule | dict[str, Any]) -> Scene:
        """The same scene with these injected faults instead of its own."""
        faults = tuple(
            r if isinstance(r, FaultRule) else FaultRule.model_validate(r) for r in rules
        )
        return self.model_copy(update={"faults": faults})

    def with_effects(self, effects: EffectsSpec | dict[str, Any] | list[str]) -> Scene:
        """The same scene with another set of effects."""
        spec = effects if isinstance(effects, EffectsSpec) else EffectsSpec.model_validate(effects)
        return self.model_copy(update={"effects": spec})


def load_scene(path: str | Path) -> Scene:
    """Read and validate a scene file (`gonio.config.ConfigError` on any mistake)."""
    return load(path, Scene)
