"""The scene file: what a simulation adds to the rig it runs on (`Scene`: the material,
the source's power, the simulated sensor, the effects to model, injected faults, the
seed), one schema read by the simulator (`sim`) and by the analysis of a simulated run
(`gonio.analysis`) alike."""

from gonio.scene.effects import MAX_SOURCE_POWER, EffectName, EffectsSpec, PositionErrorSpec
from gonio.scene.faults import (
    MOTOR_FLAGS,
    MOTOR_KINDS,
    STREAM_GAP,
    STREAM_GAP_FROM,
    FaultKind,
    FaultRule,
)
from gonio.scene.schema import (
    RIG_FIELDS,
    Band,
    DetectorSpec,
    Scene,
    SourceSpec,
    load_scene,
)

__all__ = [
    "MAX_SOURCE_POWER",
    "MOTOR_FLAGS",
    "MOTOR_KINDS",
    "RIG_FIELDS",
    "STREAM_GAP",
    "STREAM_GAP_FROM",
    "Band",
    "DetectorSpec",
    "EffectName",
    "EffectsSpec",
    "FaultKind",
    "FaultRule",
    "PositionErrorSpec",
    "Scene",
    "SourceSpec",
    "load_scene",
]
