"""The scene file (YAML): what a simulation adds to the rig it runs on.

The rig file describes the instrument, real or simulated: its geometry and optical
sizes, the light's kind, the detector's aperture, exposure range and readout, the
reference standard. A scene adds only what the simulated world needs: the material
(any `gonio.brdf` model with its parameters), the source's power (irradiance for a
collimated light, intensity for a point source, as the rig's ``light.kind`` says), the
simulated sensor's noise model, the effects to model and the seed. A scene that repeats
a fact of the rig is refused with one line saying where it belongs (`RIG_FIELDS`).

With no effects a reading is the exact analytic value carried through the radiometric
chain (`gonio.radiometry`); each listed effect is computed, and only those. Angles in
the file are degrees (``_deg``), lengths millimetres (``_mm``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Literal

from pydantic import (
    Field,
    ValidationInfo,
    field_validator,
    model_validator,
)

from gonio.brdf import MaterialSpec
from gonio.config import ConfigError, Strict, excerpt, field_error, load
from gonio.rig import Rig
from gonio.scene.effects import MAX_SOURCE_POWER, EffectName, EffectsSpec
from gonio.scene.faults import FaultRule


class SourceSpec(Strict):
    """The source's power, of the kind the rig's light is (``light.kind``): the
    irradiance of a collimated beam (W/m², perpendicular to the beam) or the intensity
    of a point source (W/sr)."""

    irradiance_w_m2: float | None = Field(
        None,
        gt=0,
        le=MAX_SOURCE_POWER,
        description="A collimated light's irradiance, perpendicular to the beam (W/m²).",
    )
    intensity_w_sr: float | None = Field(
        None, gt=0, le=MAX_SOURCE_POWER, description="A point source's intensity (W/sr)."
    )

    @model_validator(mode="after")
    def _one_power(self) -> SourceSpec:
        if (self.irradiance_w_m2 is None) == (self.intensity_w_sr is None):
            raise ValueError(
                "expected one power: irradiance_w_m2 (a collimated light) or intensity_w_sr "
                "(a point source)"
            )
        return self

    @property
    def kind(self) -> Literal["collimated", "point"]:
        """The kind of light this power is for."""
        return "collimated" if self.irradiance_w_m2 is not None else "point"

    @property
    def power(self) -> float:
        """The irradiance (W/m²) or the intensity (W/sr)."""
        value = self.irradiance_w_m2 if self.irradiance_w_m2 is not None else self.intensity_w_sr
        assert value is not None  # one of the two, by validation
        return value


#: The most electrons a count of the simulated sensor may name (a full well, a dark current
#: per second, a read noise): 10¹⁸, a coulomb's tenth, far beyond any sensor, and counts
#: whose squares (variances) stay finite.
MAX_ELECTRONS = 1e18

#: The colour bands a detector may see an RGB material in.
Band = Literal["luminance", "r", "g", "b"]


class DetectorSpec(Strict):
    """The simulated sensor behind the rig's detector optics: how light becomes a
    reading, and which colour band an RGB material is seen in. ``kind: adc`` (the
    default): a photodiode's charge read by an ADC in counts (`sim.virtual.physics.sensor`);
    ``kind: lockin``: its current read by a lock-in amplifier behind a chopped source,
    in volts (`sim.virtual.physics.lockin`): the dark current is rejected, a reading waits the
    output filter's settle time, it overloads at ``sensitivity_v``."""

    kind: Literal["adc", "lockin"] = Field(
        "adc", description="adc: counts from an ADC; lockin: volts from a lock-in amplifier."
    )
    responsivity_a_w: float = Field(
        gt=0,
        le=1e8,
        description="Photocurrent per radiant power reaching the sensor (A/W; a photodiode's "
        "is below 1, a photomultiplier's up to 1e7).",
    )
    dark_current_e_s: float = Field(
        0.0,
        ge=0,
        le=MAX_ELECTRONS,
        description="Thermal electrons per second (the dark_current effect; a lock-in rejects "
        "it, its shot noise stays).",
    )
    read_noise_e: float = Field(
        0.0,
        ge=0,
        le=MAX_ELECTRONS,
        description="The amplifier's noise per reading (electrons rms; the read_noise effect).",
    )
    full_well_e: float | None = Field(
        None,
        ge=1,
        le=MAX_ELECTRONS,
        description="adc: electrons the sensor holds; it maps to the ADC's top code.",
    )
    adc_bits: int = Field(16, ge=1, le=32, description="adc: the ADC's resolution (bits).")
    band: Band = Field("luminance", description="The colour band an RGB material is seen in.")
    time_constant_s: float | None = Field(
        None,
        gt=0,
        description="lockin: the output filter's time constant (s; none: the longest whose "
        "settle time fits the exposure, as the PyMeasure driver sets it).",
    )
    slope_db_oct: Literal[6, 12, 18, 24] = Field(
        24, description="lockin: the output filter's slope (dB/octave)."
    )
    sensitivity_v: float | None = Field(
        None,
        gt=0,
        le=1e3,
        description="lockin: the full scale (V); a reading at or above overloads.",
    )
    transimpedance_v_a: float = Field(
        1e6,
        gt=0,
        le=1e13,
        description="lockin: the current amplifier's gain before the lock-in (V/A).",
    )
    duty: float = Field(0.5, gt=0, lt=1, description="lockin: the chopper's open fraction.")
    phase_drift_deg_per_hour: float = Field(
        0.0,
        ge=-3.6e6,
        le=3.6e6,
        description="lockin: how fast the reading's phase drifts (°/h; at most a turn a second).",
    )

    @model_validator(mode="after")
    def _of_its_kind(self) -> DetectorSpec:
        if self.kind == "adc" and self.full_well_e is None:
            raise field_error("full_well_e", "Field required for kind: adc")
        if self.kind == "lockin" and self.sensitivity_v is None:
            raise field_error("sensitivity_v", "Field required for kind: lockin")
        lockin_only = ("time_constant_s", "sensitivity_v")
        for name in lockin_only if self.kind == "adc" else ("full_well_e",):
            if getattr(self, name) is not None:
                other = "lockin" if self.kind == "adc" else "adc"
                raise field_error(name, f"only for kind: {other} (this detector is {self.kind})")
        return self

    @property
    def streams(self) -> bool:
        """Whether readings can be streamed while the axes move (fly plans): yes, unless a
        lock-in (each reading waits its output filter's settle time)."""
        return self.kind != "lockin"


#: Scene fields that are facts of the instrument: where the rig file holds each.
RIG_FIELDS = {
    ("source", "kind"): "light.kind",
    ("source", "beam_diameter_mm"): "constraints.beam_diameter_mm",
    ("source", "distance_mm"): "light.distance_mm",
    ("detector", "aperture_sr"): "detector.aperture_sr",
    ("detector", "fov_diameter_mm"): "constraints.detector_fov_mm",
    ("detector", "exposure_range_s"): "detector.exposure_range_s",
    ("detector", "readout_s"): "detector.readout_s",
    ("detector", "max_averages"): "detector.max_averages",
    ("detector", "interface"): "detector.interface",
    ("sample",): "constraints.sample_diameter_mm",
    ("reference",): "reference",
}


def _rig_field_given(data: Any) -> tuple[str, str] | None:
    """(scene field, rig field) of the first instrument fact a scene's data repeats."""
    if not isinstance(data, dict):
        return None
    for path, rig_field in RIG_FIELDS.items():
        section = data.get(path[0]) if len(path) > 1 else data
        if isinstance(section, dict) and path[-1] in section:
            return ".".join(path), rig_field
    return None


def source_mismatch(source: SourceSpec, kind: str, rig: str) -> tuple[str, str] | None:
    """(field, what was expected) when a scene's source power is not of the light
    ``kind`` of the ``rig`` (its file or name); None when it is."""
    if source.kind == kind:
        return None
    given, wanted = (
        ("irradiance_w_m2", "intensity_w_sr (W/sr)")
        if kind == "point"
        else ("intensity_w_sr", "irradiance_w_m2 (W/m², perpendicular to the beam)")
    )
    return f"source.{given}", f"the light of {rig} is {kind} (light.kind); expected {wanted}"


class Scene(Strict):
    """What a simulation adds to the rig it runs on: the material, the source's power,
    the simulated sensor, the effects to model, injected faults and the seed. A fact of
    the instrument (the light's kind, sizes, the detector's aperture) belongs in the rig
    file."""

    name: str = Field(description="The scene's name, shown in summaries and stored in the run.")
    material: MaterialSpec = Field(
        description="The material: name (a gonio.brdf model) and its parameters beside it; a "
        "relative path (a tabulated material) is relative to the scene file."
    )
    source: SourceSpec = Field(
        description="The source's power, of the rig's light.kind: one of irradiance_w_m2 or "
        "intensity_w_sr."
    )
    detector: DetectorSpec = Field(description="The simulated sensor behind the rig's optics.")
    effects: EffectsSpec = Field(
        default_factory=EffectsSpec,
        description="The effects to model: a list of names, or name: parameters (none: exact "
        "readings).",
    )
    faults: tuple[FaultRule, ...] = Field(
        (), description="Faults injected into the simulated devices."
    )  # `gonio.scene.faults`
    seed: int = Field(0, ge=0, description="The seed of every random draw of the simulation.")

    @model_validator(mode="before")
    @classmethod
    def _no_rig_facts(cls, data: Any) -> Any:
        """A fact of the instrument given in the scene: one line saying where it goes."""
        repeated = _rig_field_given(data)
        if repeated is not None:
            field, rig_field = repeated
            raise field_error(
                field,
                f"belongs in the rig file ({rig_field}), not the scene; a scene holds only "
                "what a simulation adds",
            )
        return data

    @field_validator(
        "effects", mode="before", json_schema_input_type=list[EffectName] | EffectsSpec | None
    )
    @classmethod
    def _none_is_empty(cls, v: Any) -> Any:
        return {} if v is None else v

    @field_validator("faults", mode="before", json_schema_input_type=list[FaultRule] | None)
    @classmethod
    def _no_faults(cls, v: Any) -> Any:
        return () if v is None else v

    def with_faults(self, *rules: FaultRule | dict[str, Any]) -> Scene:
        """The same scene with these injected faults instead of its own."""
        faults = tuple(
            r if isinstance(r, FaultRule) else FaultRule.model_validate(r) for r in rules
        )
        return self.model_copy(update={"faults": faults})

    @model_validator(mode="after")
    def _source_of_the_rig(self, info: ValidationInfo) -> Scene:
        """Read with a rig (`load_scene`): the source's power is of the rig's kind."""
        context = info.context or {}
        kind = context.get("source_kind")
        mismatch = None if kind is None else source_mismatch(self.source, kind, context["rig"])
        if mismatch is not None:
            raise field_error(*mismatch)
        return self

    def check_rig(self, rig: Rig) -> None:
        """`ConfigError` (one line) unless this scene can be simulated on ``rig``."""
        mismatch = source_mismatch(self.source, rig.source_kind, _rig_label(rig))
        if mismatch is not None:
            field, expected = mismatch
            raise ConfigError(f"scene {excerpt(self.name)}: {field}: {expected}")
        misalignment = self.effects.misalignment
        unknown = [] if misalignment is None else misalignment.unknown_axes(rig.axes)
        if unknown:
            raise ConfigError(
                f"scene {self.name!r}: effects.misalignment.zero_offset_deg: {unknown[0]!r} is "
                f"not an axis of rig {rig.spec.name!r} ({', '.join(rig.axes)})"
            )
        for k, rule in enumerate(self.faults):
            if rule.axis is not None and rule.axis not in rig.axes:
                raise ConfigError(
                    f"scene {self.name!r}: faults.{k}.axis: {rule.axis!r} is not an axis of "
                    f"rig {rig.spec.name!r} ({', '.join(rig.axes)})"
                )

    def with_effects(self, effects: EffectsSpec | dict[str, Any] | list[str]) -> Scene:
        """The same scene with another set of effects."""
        spec = effects if isinstance(effects, EffectsSpec) else EffectsSpec.model_validate(effects)
        return self.model_copy(update={"effects": spec})


def load_scene(path: str | Path, rig: Rig | None = None, *, raw: bytes | None = None) -> Scene:
    """Read and validate a scene file (`gonio.config.ConfigError` on any mistake), for
    ``rig`` when given (its source power must then be of the rig's light kind);
    ``raw``: the file's bytes, already read (what is validated is what was hashed)."""
    context = None if rig is None else {"source_kind": rig.source_kind, "rig": _rig_label(rig)}
    return load(path, Scene, context, raw=raw)


def _rig_label(rig: Rig) -> str:
    return f"the rig file {rig.source}" if rig.source else f"rig {rig.spec.name!r}"
