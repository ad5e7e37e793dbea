"""The forward chain with optional effects, as the simulator runs it.

    detector_power(source, optics, brdf_eval, wi, wo)                 ideal: Φ = f · G
        footprint=True, sample_diameter_mm=S                          spatial integration
        aperture_integration=True                                     angular integration

* collimated beam: Φ = K · A · η, with A = `aperture_integral` (weight cos θ) or
  f · cos θo · Ω, and η = `footprint_fraction` or 1;
* point source, footprint: `point_source_power` (which integrates over the seen part of
  the sample), its f replaced by the aperture mean f̄ = A / Ω (weight 1) at every
  surface node when aperture integration is on too (nested quadratures: 768 × 288
  BRDF evaluations per pair at the default orders, ~40 ms a pair; orders (4, 6) × (4, 8)
  keep ≤ 1e-3 for GGX α = 0.02 at ~1.4 ms, see docs/explanations/radiometry.md); point source, no
  footprint: Φ = K · A (weight 1).

Approximation in the combinations: the seen region (η for the beam, the spatial
integral's domain for the point source) is the one seen from wo, not from each
direction of the cap; across the symmetric cap the first-order changes cancel, so the
error is second order in the cap's half-angle α.
"""

from __future__ import annotations

import numpy as np

from gonio.errors import DomainError
from gonio.radiometry._checks import direction_pair, positive, spread
from gonio.radiometry.aperture import DEFAULT_ORDER as APERTURE_ORDER
from gonio.radiometry.aperture import aperture_integral, weight_for
from gonio.radiometry.footprint import footprint_fraction
from gonio.radiometry.ideal import (
    CollimatedSource,
    DetectorOptics,
    Source,
    prefactor_checked,
    radiant_power_checked,
    view_weight_checked,
)
from gonio.radiometry.spatial import DEFAULT_ORDER as SPATIAL_ORDER
from gonio.radiometry.spatial import point_source_power
from gonio.types import ArrayLike, BrdfEval, FloatArray


def detector_power(
    source: Source,
    optics: DetectorOptics,
    brdf_eval: BrdfEval,
    wi: ArrayLike,
    wo: ArrayLike,
    *,
    footprint: bool = False,
    aperture_integration: bool = False,
    sample_diameter_mm: float | None = None,
    spatial_order: tuple[int, int] = SPATIAL_ORDER,
    aperture_order: int | tuple[int, int] = APERTURE_ORDER,
) -> FloatArray:
    """Φ (W) into the detector's aperture, with only the effects asked for (see module).

    ``brdf_eval(wi, wo)`` → f (sr⁻¹), shape (...) or (..., 3). ``sample_diameter_mm`` is
    required with ``footprint``; the orders go to `point_source_power` and
    `aperture_integral`. Result: shape broadcast(wi, wo)[:-1] (+ (3,) for RGB).
    """
    a, b = direction_pair(wi, wo)
    if footprint:
        if sample_diameter_mm is None:
            raise DomainError("the footprint effect needs sample_diameter_mm")
        sample = positive("sample_diameter_mm", sample_diameter_mm)
    if not footprint and not aperture_integration:
        return radiant_power_checked(source, optics, brdf_eval(a, b), a, b)
    omega = optics.aperture_sr

    def averaged(x: FloatArray, y: FloatArray) -> FloatArray:
        return (
            aperture_integral(brdf_eval, x, y, omega, weight_for(source), order=aperture_order)
            / omega
        )

    if isinstance(source, CollimatedSource):
        if aperture_integration:
            angular = aperture_integral(brdf_eval, a, b, omega, "cos", order=aperture_order)
        else:
            f = np.asarray(brdf_eval(a, b), dtype=np.float64)
            angular = f * spread(f, view_weight_checked(source, b) * omega)
        k = prefactor_checked(source, optics, a)
        if footprint:
            eta = footprint_fraction(source.beam_diameter_mm, optics.fov_diameter_mm, sample, a, b)
            k = k * eta
        return np.asarray(angular * spread(angular, k), dtype=np.float64)
    if footprint:
        f_eval = averaged if aperture_integration else brdf_eval
        return point_source_power(source, optics, sample, f_eval, a, b, order=spatial_order)
    angular = aperture_integral(brdf_eval, a, b, omega, "one", order=aperture_order)
    return np.asarray(
        angular * spread(angular, prefactor_checked(source, optics, a)), dtype=np.float64
    )
