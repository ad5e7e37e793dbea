"""The effects a scene may model (`EffectsSpec`): each listed effect is computed, and only
those; the ones with parameters take them from their own spec."""

from __future__ import annotations

from typing import Any, Literal

from pydantic import (
    Field,
    SerializerFunctionWrapHandler,
    model_serializer,
    model_validator,
)

from gonio.config import Strict
from gonio.rig import AlignmentSpec

#: The most power a source may give (W/m² of a collimated beam, W/sr of a point source):
#: a megawatt a square centimetre, beyond any laboratory source.
MAX_SOURCE_POWER = 1e10


class NoParams(Strict):
    """An effect whose parameters live elsewhere (the detector's), or has none."""


class SourceDriftSpec(Strict):
    """Source power × (1 + rate · t/3600 + amplitude · sin(2π t / period + phase)),
    t the run's virtual time (s)."""

    rate_per_hour: float = Field(
        0.01,
        ge=-1,
        le=1,
        description="Relative change of the power per hour (1/h), in [-1, 1]: a source that "
        "loses all of its power within the hour is a broken one.",
    )
    amplitude: float = Field(
        0.0, ge=0, lt=1, description="Relative amplitude of the power's oscillation."
    )
    period_s: float = Field(600.0, gt=0, description="The oscillation's period (s).")
    phase_deg: float = Field(
        0.0, ge=-360, le=360, description="The oscillation's phase at t = 0 (°)."
    )


class ApertureSpec(Strict):
    """The detector averages the BRDF over its solid angle: a Gauss–Legendre × trapezoid
    quadrature of ``order`` × 2·order nodes over the cap (order 6 keeps a GGX α = 0.02
    peak to 1e-7 at 1e-3 sr and 1e-13 at 1e-4 sr; docs/explanations/simulator.md)."""

    order: int = Field(
        6,
        ge=2,
        le=64,
        description="The quadrature's order: order × 2·order nodes over the detector's cap.",
    )


class PositionErrorSpec(Strict):
    """Motor tick quantization (4096/rev through the gear), backlash (the joint lags by
    half of it behind the direction of the last move) and repeatability (Gaussian, per
    move, 1σ)."""

    ticks: bool = Field(
        True,
        description="Quantize each joint to its motor's ticks (4096 a turn, through the gear).",
    )
    backlash_deg: float = Field(
        0.0,
        ge=0,
        le=10,
        description="Each joint's backlash (°): it lags half of it behind its last move.",
    )
    repeatability_deg: float = Field(
        0.0, ge=0, le=10, description="A joint's error per move (°, Gaussian, 1σ)."
    )


class StrayLightSpec(Strict):
    """A constant floor of radiant power (W) reaching the detector while the source is on."""

    power_w: float = Field(
        ge=0, le=MAX_SOURCE_POWER, description="The stray radiant power on the detector (W)."
    )


class MotionBlurSpec(Strict):
    """A stream's window integrates the optics along the path the joints travel during
    it: the mean over Gauss–Legendre nodes in time of the power at the pose of each
    node, as many nodes as the window's smear (the largest joint's travel in it) over
    ``max_step_deg``, at most ``max_nodes``. Without it a window is read at the pose of
    its middle."""

    max_step_deg: float = Field(
        0.05,
        gt=0,
        le=10,
        description="The largest joint travel between two time nodes of a window (°).",
    )
    max_nodes: int = Field(
        64, ge=1, le=1024, description="The most time nodes a window's quadrature takes."
    )


class TimestampJitterSpec(Strict):
    """The stamps a streaming detector reports are its true window shifted by a constant
    latency and a Gaussian jitter (one draw per window, both ends alike), drawn from the
    sample's own random stream, so they are reproducible per sample index."""

    sigma_s: float = Field(
        1e-4, ge=0, le=1, description="The jitter of a window's stamps (s, Gaussian, 1σ)."
    )
    latency_s: float = Field(
        0.0,
        ge=-1,
        le=1,
        description="The constant offset of the reported stamps from the true window (s; "
        "positive: reported late).",
    )


def _given(schema: dict[str, Any]) -> None:
    """An effect with required parameters: a file gives them (``stray_light:`` with
    nothing is refused: no null in its schema)."""
    schema["anyOf"] = [s for s in schema.pop("anyOf") if s.get("type") != "null"]
    if len(schema["anyOf"]) == 1:
        schema.update(schema.pop("anyOf")[0])


class EffectsSpec(Strict):
    """The effects a simulation models, each computed only when listed (none: every
    reading the exact analytic value carried through the radiometric chain): a list of
    names, or a mapping of name to its parameters (nothing: the defaults)."""

    shot_noise: NoParams | None = Field(
        None, description="Signal and dark electrons are Poisson draws."
    )
    read_noise: NoParams | None = Field(
        None, description="The amplifier adds Gaussian noise (detector.read_noise_e)."
    )
    dark_current: NoParams | None = Field(
        None, description="Thermal electrons join the signal (detector.dark_current_e_s)."
    )
    quantization: NoParams | None = Field(
        None, description="The ADC rounds to whole counts (detector.adc_bits)."
    )
    saturation: NoParams | None = Field(
        None,
        description="The well holds at most detector.full_well_e; fuller readings are flagged.",
    )
    source_drift: SourceDriftSpec | None = Field(
        None, description="The source's power drifts and oscillates with the run's time."
    )
    aperture_integration: ApertureSpec | None = Field(
        None, description="The detector averages the BRDF over its solid angle."
    )
    footprint: NoParams | None = Field(
        None,
        description="Only the part of the lit spot on the sample and in the detector's view "
        "counts.",
    )
    position_error: PositionErrorSpec | None = Field(
        None, description="Motor ticks, backlash and repeatability move the joints."
    )
    stray_light: StrayLightSpec | None = Field(
        None,
        description="A constant power reaches the detector while the source is on.",
        json_schema_extra=_given,
    )
    motion_blur: MotionBlurSpec | None = Field(
        None,
        description="A stream's window integrates the optics along the path travelled during "
        "it (time quadrature).",
    )
    timestamp_jitter: TimestampJitterSpec | None = Field(
        None,
        description="A stream's reported stamps are late by a latency and jittered.",
    )
    misalignment: AlignmentSpec | None = Field(
        None,
        description="The rig is not as its file says (zero offsets, the sample's tilt and "
        "height, pointing errors): the optics see the true geometry, the engine records the "
        "rig file's.",
    )

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


#: The effects a list may name: those with no required parameters.
EffectName = Literal[
    "shot_noise",
    "read_noise",
    "dark_current",
    "quantization",
    "saturation",
    "source_drift",
    "aperture_integration",
    "footprint",
    "position_error",
    "motion_blur",
    "timestamp_jitter",
    "misalignment",
]
