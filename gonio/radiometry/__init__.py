"""The radiometric chain, forward (the simulator) and inverse (the acquisition engine).

Sources (`CollimatedSource`, `PointSource`) and `DetectorOptics` are validated frozen
dataclasses (mm, W/m², W/sr, sr). Directions are sample-frame unit vectors (..., 3),
z = normal, pointing away from the surface: wi toward the light, wo toward the detector.

* ideal chain (`chain`): `irradiance`, `prefactor` K, `view_weight` c,
  `geometric_factor` G = K c Ω, `radiant_power` Φ = f G, `brdf_from_power` f = Φ / G,
  `electrons` / `power_from_electrons`, `signal_rate`;
* calibration (`calibration`): `ReferenceCalibration` against a Lambertian standard;
* effects: `footprint_fraction` (collimated beam against sample and field of view),
  `point_source_power` (spatial integration for a proximal point source) and its
  ratio to the ideal chain `spot_ratio`,
  `aperture_integral` (angular integration over the aperture), combined in
  `detector_power`.

Formulas, assumptions and measured accuracies: docs/explanations/radiometry.md.
"""

from typing import TYPE_CHECKING

from gonio.faces import lazy_face
from gonio.radiometry.aperture import aperture_integral, cap_half_angle, weight_for
from gonio.radiometry.calibration import ReferenceCalibration, relative_geometry
from gonio.radiometry.footprint import footprint_fraction, seen_fits_sample
from gonio.radiometry.forward import detector_power
from gonio.radiometry.ideal import (
    ELEMENTARY_CHARGE,
    CollimatedSource,
    DetectorOptics,
    PointSource,
    Source,
    SourceKind,
    brdf_from_power,
    electrons,
    geometric_factor,
    irradiance,
    power_from_electrons,
    prefactor,
    radiant_power,
    signal_rate,
    source_kind,
    view_weight,
)
from gonio.radiometry.spatial import point_source_power, spot_ratio

if TYPE_CHECKING:  # the names for the type checker (`as`: re-exported)
    from gonio.radiometry.bands import LUMINANCE as LUMINANCE
    from gonio.radiometry.bands import band_eval as band_eval
    from gonio.radiometry.series import CalibrationSeries as CalibrationSeries
    from gonio.radiometry.series import rounding_var as rounding_var
    from gonio.radiometry.series import student_variance as student_variance

#: The names of the face that load with their module when first used
#: (`gonio.faces`), by module.
WHERE = {
    "CalibrationSeries": "series",
    "LUMINANCE": "bands",
    "band_eval": "bands",
    "rounding_var": "series",
    "student_variance": "series",
}
__all__ = [
    "CollimatedSource",
    "DetectorOptics",
    "ELEMENTARY_CHARGE",
    "PointSource",
    "ReferenceCalibration",
    "Source",
    "SourceKind",
    "aperture_integral",
    "brdf_from_power",
    "cap_half_angle",
    "detector_power",
    "electrons",
    "footprint_fraction",
    "geometric_factor",
    "irradiance",
    "point_source_power",
    "power_from_electrons",
    "prefactor",
    "radiant_power",
    "relative_geometry",
    "seen_fits_sample",
    "signal_rate",
    "source_kind",
    "spot_ratio",
    "view_weight",
    "weight_for",
    *WHERE,
]
if not TYPE_CHECKING:
    __getattr__, __dir__ = lazy_face(__name__, WHERE)
