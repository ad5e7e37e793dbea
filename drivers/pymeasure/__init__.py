"""A detector read through PyMeasure's instrument classes over PyVISA (a lock-in
amplifier, an optical power meter, an electrometer, a multimeter).

`drivers.pymeasure.config` is free of PyMeasure (the rig file is checked without it:
the property names of the presets' classes against `PROPERTIES`, read from those
classes by tools/pymeasure_properties.py; another class's when the detector opens);
`drivers.pymeasure.detector` and `drivers.pymeasure.boundary` import PyMeasure and
PyVISA (the ``instruments`` extra) and are loaded only when a rig names such a detector.
"""

from drivers.pymeasure.config import (
    PRESET_FIELDS,
    PRESETS,
    SETTLE_TAU,
    ExposureConfig,
    PyMeasureConfigError,
    PyMeasureDetectorConfig,
    settle_tau,
    unknown_property,
)
from drivers.pymeasure.properties import PROPERTIES

__all__ = [
    "PRESETS",
    "PRESET_FIELDS",
    "PROPERTIES",
    "SETTLE_TAU",
    "ExposureConfig",
    "PyMeasureConfigError",
    "PyMeasureDetectorConfig",
    "settle_tau",
    "unknown_property",
]
