"""A point source's spot fall-off, divided out of a run's calibrated samples.

The reference calibration (`gonio.radiometry.series`) takes the ideal point-source
chain: the lamp's irradiance uniform over the seen spot and one incidence direction.
A lamp at r lights a point x of the sample with I cos θ(x)/|s − x|² from ωi(x), so what
the detector integrates over its F-wide view is Φ = R · f(wi, wo) · G with R the ratio
`gonio.radiometry.spot_ratio` (the same quadrature the simulator's `footprint` effect
runs). The sample's ratio and the reference standard's (Lambertian, so geometry only)
enter f as R_sample / R_ref; the correction divides it out:

    f = f_cal · R_ref / (R_geo · R_f),    R_sample = R_geo · R_f

* R_ref, R_geo: geometry only (a constant BRDF): exact to the quadrature's rounding;
* R_f: the BRDF's own variation over the ±F/(2r) of incidence across the spot, with f
  estimated from the run's own samples (`gonio.analysis.estimate`, of
  f_cal · R_ref / R_geo). Its error, from the interpolant's, enters σ as
  |R_f − 1|: on the quick plan with the specular test function the estimated R_f − 1
  is within that of the true one (docs/results/point_source.md).

Applies where the instrument has the fall-off: a point-source rig measured on hardware
(no stored scene), or simulated (or rehearsed) with the scene's ``footprint`` effect.
"""

from __future__ import annotations

import numpy as np

from gonio.analysis.estimate import Estimate
from gonio.analysis.scene import scene_effects
from gonio.radiometry import CalibrationSeries, DetectorOptics, PointSource, spot_ratio
from gonio.rig import Rig
from gonio.store import Run
from gonio.types import BoolArray, FloatArray

#: Spatial quadrature order of R_f (R_f − 1 is ≲ 1 %: this order's error is below 1e-12
#: of it at r/F ≥ 4).
BRDF_ORDER = (4, 6)


def has_falloff(run: Run) -> bool:
    """Whether the run's instrument has the fall-off: a point-source rig, on hardware or
    with the stored scene's ``footprint`` effect."""
    if run.plan.rig.spec.light.kind != "point":
        return False
    scene_text = run.meta.get("scene_text")
    return scene_text is None or "footprint" in scene_effects(str(scene_text))


def _instrument(rig: Rig) -> tuple[PointSource, DetectorOptics]:
    """The rig's lamp (unit intensity: it cancels in every ratio) and detector optics."""
    distance = rig.spec.light.distance_mm
    assert distance is not None  # required of a point source by the rig file
    optics = DetectorOptics(rig.spec.detector.aperture_sr, rig.spec.constraints.detector_fov_mm)
    return PointSource(1.0, distance), optics


def brdf_ratio(
    rig: Rig, wi: FloatArray, wo: FloatArray, f: FloatArray, *, isotropic: bool = True
) -> FloatArray:
    """R_f (N,): the spot's ratio with the BRDF interpolated through the samples' values
    ``f`` (N,) at pairs (N, 3) (finite), over the geometric ratio; 1 where the estimate
    is not positive at the pair, and everywhere for too few distinct pairs."""
    model = Estimate(wi, wo, f, isotropic=isotropic)
    if not model.usable:
        return np.ones(len(f))

    source, optics = _instrument(rig)
    diameter = rig.spec.constraints.sample_diameter_mm
    with_f = spot_ratio(source, optics, diameter, wi, wo, model.eval, order=BRDF_ORDER)
    geometry = spot_ratio(source, optics, diameter, wi, wo, order=BRDF_ORDER)
    ratio = with_f / geometry
    return np.asarray(np.where(np.isfinite(ratio) & (ratio > 0), ratio, 1.0), dtype=np.float64)


def corrected(
    rig: Rig,
    series: CalibrationSeries,
    wi: FloatArray,
    wo: FloatArray,
    f: FloatArray,
    sigma: FloatArray,
    *,
    isotropic: bool = True,
) -> tuple[FloatArray, FloatArray]:
    """(f, σ) (sr⁻¹, (N,)) with the fall-off divided out of calibrated values ``f`` at
    pairs (N, 3) and the correction's error added to ``sigma`` (see the module)."""
    source, optics = _instrument(rig)
    r_ref = float(spot_ratio(source, optics, rig.reference_diameter_mm, series.wi, series.wo))
    r_geo = spot_ratio(source, optics, rig.spec.constraints.sample_diameter_mm, wi, wo)
    geometric = f * (r_ref / r_geo)
    r_f = brdf_ratio(rig, wi, wo, geometric, isotropic=isotropic)
    scale = r_ref / (r_geo * r_f)
    value = f * scale
    error = np.abs(value * (r_f - 1.0))
    return (
        np.asarray(value, dtype=np.float64),
        np.asarray(np.hypot(sigma * scale, error), dtype=np.float64),
    )


def spot_corrected(
    run: Run, series: CalibrationSeries, f: FloatArray, sigma: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """The run's calibrated (f, σ) with the fall-off divided out where its instrument has
    it (`has_falloff`), else as they are."""
    if not has_falloff(run) or len(f) == 0:
        return f, sigma
    wi, wo = run.directions()
    usable: BoolArray = np.isfinite(f) & np.isfinite(sigma)
    out_f, out_sigma = f.copy(), sigma.copy()
    out_f[usable], out_sigma[usable] = corrected(
        run.plan.rig,
        series,
        wi[usable],
        wo[usable],
        f[usable],
        sigma[usable],
        isotropic=run.plan.spec.isotropic,
    )
    return out_f, out_sigma
