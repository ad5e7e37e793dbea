"""A detector read through PyMeasure's instrument classes over PyVISA (a lock-in
amplifier, an optical power meter, an electrometer, a multimeter).

`drivers.pymeasure.config` is free of PyMeasure (the rig file is checked without it;
where it is installed, the property names also against the class, by `boundary`);
`drivers.pymeasure.detector` and `drivers.pymeasure.boundary` import PyMeasure and
PyVISA (the ``instruments`` extra) and are loaded only when a rig names such a detector.
"""

from drivers.pymeasure.config import (
    PRESETS,
    SETTLE_TAU,
    ExposureConfig,
    PyMeasureConfigError,
    PyMeasureDetectorConfig,
)

__all__ = [
    "PRESETS",
    "SETTLE_TAU",
    "ExposureConfig",
    "PyMeasureConfigError",
    "PyMeasureDetectorConfig",
]
