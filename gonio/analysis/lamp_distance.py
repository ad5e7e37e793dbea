"""A point source's distance, as the sample's height changes it, divided out of a run's
calibrated samples.

The calibration takes the lamp at its rig-file distance r from every lit point. A
sample surface h above the rotation centre (the rig's measured alignment,
``height_mm``) puts the lit point at r' = |r ℓ − h n| from the lamp (ℓ the lamp's
true direction, n the surface normal: `gonio.rig.Geometry.light_distance_mm`), and
the irradiance scales by (r / r')². The reference standard on the same stage is read
at its own pose, at r'_ref; the sample's calibrated value is then f·(r'_ref / r'_s)²,
so the correction multiplies by (r'_s / r'_ref)²: about 1 + 2h (cos θ_ref − cos θi)/r,
0.3 % at h = 0.5 mm and r = 300 mm, six times the sensor's noise.

Applies to a point-source rig whose alignment has a height; a collimated beam's
irradiance does not depend on it.
"""

from __future__ import annotations

import numpy as np

from gonio.store import Run
from gonio.types import FloatArray


def distance_ratio(run: Run) -> FloatArray | None:
    """(r'_s / r'_ref)² (N,) per sample of the run; None where the correction does not
    apply (the module). The reference's distance is that at its first calibration's
    read-back pose (every calibration reads the reference at the rig's one pose)."""
    rig = run.plan.rig
    if rig.spec.light.kind != "point" or float(rig.alignment.height_mm) == 0.0:
        return None
    calibrations = run.of_kind("calibration")
    if not calibrations or len(run) == 0:
        return None
    reference = np.array(calibrations[0].data["pose_rad"], dtype=np.float64)
    at_ref = rig.geometry(reference, rig.alignment).light_distance_mm
    at_samples = rig.geometry(run.angles(), rig.alignment).light_distance_mm
    assert at_ref is not None and at_samples is not None  # a point source has one
    return np.asarray((at_samples / at_ref) ** 2, dtype=np.float64)


def distance_corrected(run: Run, f: FloatArray, sigma: FloatArray) -> tuple[FloatArray, FloatArray]:
    """The run's calibrated (f, σ) (N,) with the lamp's distance divided out where it
    applies, else as they are."""
    ratio = distance_ratio(run)
    if ratio is None:
        return f, sigma
    return np.asarray(f * ratio, dtype=np.float64), np.asarray(sigma * ratio, dtype=np.float64)
