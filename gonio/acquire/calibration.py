"""Calibration with the reference standard, through the `drivers.base` contract.

The reference standard (a Lambertian target of known albedo, the rig file's
``reference`` section) is read at the rig's calibration geometry (0°/45° in the shipped
rigs: light at the normal, detector 45° away) with the plan's typical exposure, halved
until the reading does not saturate. The geometry is the rig file's or none: where the
standard would not fill what the ideal chain assumes (a collimated beam's lit spot on
the standard and in the detector's view; for a point source, the view on the standard),
`reference_geometry` refuses the rig rather than move the standard to a geometry its
albedo is not given for. A dark reading is taken with the light off at the same
exposure. Readings of the sample become BRDF values through
`gonio.radiometry.ReferenceCalibration` (dark subtracted, the geometry of each pair
accounted for, directions from the read-back angles), and a drifting source is divided
out by interpolating the reference's dark-subtracted signal linearly in time between
the first and the last reference reading (the readings' middles, `Reading.middle_s`).

Reading the reference needs a way to put it on the stage: a simulated backend does it
through `drivers.base.Simulated.show`; on hardware the engine (a later issue) asks the
user or a changer. Calibration readings use stream indices from `CALIBRATION_INDEX` on,
so they never share random numbers with the plan's samples.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from drivers.base import Reading
from gonio import radiometry
from gonio.acquire.devices import Devices
from gonio.acquire.measure import measure_target
from gonio.config import ConfigError, line_of, read_yaml
from gonio.errors import GonioError
from gonio.rig.model import Reason, Rig
from gonio.types import FloatArray

#: Sample indices of calibration readings start here, far above any plan's indices.
CALIBRATION_INDEX = 1 << 40


def reference_geometry(rig: Rig) -> tuple[FloatArray, FloatArray]:
    """(ωi, ωo), each (3,), at which the reference standard is read: the rig file's
    ``reference`` geometry, where the reading is the ideal chain's (the standard,
    ``Rig.reference_diameter_mm`` across, holds a collimated beam's whole lit spot inside
    the detector's view, or the whole view of a point-source rig's detector); else
    `ConfigError` naming the rig file's line and field. Never another geometry: the
    standard's albedo is given for this one."""
    wi, wo = rig.reference_directions()
    problem = _clipped(rig, wi, wo)
    if problem is not None:
        field, message = problem
        where = str(rig.source) if rig.source else f"rig {rig.spec.name!r}"
        if rig.source is not None:
            where += f":{line_of(read_yaml(rig.source, rig.text)[1], field.split('.'))}"
        raise ConfigError(f"{where}: {field}: {message}")
    return wi, wo


def _clipped(rig: Rig, wi: FloatArray, wo: FloatArray) -> tuple[str, str] | None:
    """(field, why) when the reference reading at (wi, wo) would be clipped, else None."""
    ref, c = rig.spec.reference, rig.spec.constraints
    size, fov = rig.reference_diameter_mm, c.detector_fov_mm
    seen = fov / float(wo[2])  # the view's length on the standard, along the x-z plane
    if rig.source_kind == "point":
        if radiometry.seen_fits_sample(fov, size, wo):
            return None
        widest = f"θo ≤ {_floor_deg(fov / size)}°" if fov <= size else "no θo"
        return "reference.theta_o_deg", (
            f"the detector's {fov:g} mm field of view spans {seen:.1f} mm of the {size:g} mm "
            f"reference standard at θo = {ref.theta_o_deg:g}°, past its edge (a point "
            f"source's calibration assumes the view lies on the standard); expected "
            f"{widest}, or a standard at least {seen:.1f} mm across (reference.diameter_mm)"
        )
    beam = c.beam_diameter_mm
    assert beam is not None  # required by the rig file for a collimated light
    eta = float(radiometry.footprint_fraction(beam, fov, size, wi, wo))
    if eta == 1.0:
        return None
    lit = beam / float(wi[2])  # the lit spot's length, along the x-z plane
    low = f"the reference would read {100 * (1 - eta):.1f} % low"
    if lit > size:
        return "reference.theta_i_deg", (
            f"the {beam:g} mm beam lights {lit:.1f} mm of the {size:g} mm reference standard "
            f"at θi = {ref.theta_i_deg:g}°, past its edge ({low}); expected "
            f"θi ≤ {_floor_deg(beam / size)}°, or a standard at least {lit:.1f} mm across "
            "(reference.diameter_mm)"
        )
    return "reference.theta_o_deg", (
        f"the detector's {fov:g} mm field of view ({seen:.1f} mm along the standard at "
        f"θo = {ref.theta_o_deg:g}°) misses part of the {lit:.1f} mm lit spot ({low}); "
        "expected a geometry whose view takes in the whole spot"
    )


def _floor_deg(cosine: float) -> str:
    """arccos(cosine) in degrees rounded down to 0.1° (so the quoted limit is valid)."""
    return f"{math.floor(math.degrees(math.acos(cosine)) * 10) / 10:g}"


def geometry_label(rig: Rig) -> str:
    """The rig's calibration geometry, e.g. ``0°/45°`` (θi/θo; `reference_geometry`)."""
    reference_geometry(rig)
    ref = rig.spec.reference
    return f"{ref.theta_i_deg:g}°/{ref.theta_o_deg:g}°"


def reference_pose(rig: Rig) -> FloatArray:
    """Joint angles (rad, rig.axes order) of the rig's calibration geometry
    (`reference_geometry`; 0°/45° in the shipped rigs)."""
    wi, wo = reference_geometry(rig)
    solution = rig.solve(wi, wo)
    if solution.reasons[0] not in (Reason.OK, Reason.BLIND_SPOT, Reason.FOOTPRINT):
        raise GonioError(
            f"rig {rig.spec.name!r} cannot reach its reference geometry "
            f"({geometry_label(rig)}; {Reason(solution.reasons[0]).label.replace('_', ' ')})"
        )
    return np.asarray(solution.angles[0], dtype=np.float64)


def _measure_reference(
    devices: Devices, rig: Rig, k: int, pose: FloatArray, exposure_s: float
) -> Reading:
    simulation = devices.simulation
    if simulation is None:
        raise GonioError("this backend cannot put the reference standard on the stage by itself")
    simulation.show("reference")
    try:
        angles = dict(zip(rig.axes, pose.tolist(), strict=True))
        return measure_target(
            devices, CALIBRATION_INDEX + k, angles, exposure_s, 1, settle_s=rig.spec.settle_s
        ).reading
    finally:
        simulation.show("sample")


def read_reference(
    devices: Devices, rig: Rig, k: int, pose: FloatArray, exposure_s: float
) -> tuple[Reading, float]:
    """Reading ``k`` of the reference standard and its exposure (s), halved from
    ``exposure_s`` until the reading does not saturate (`GonioError` if even the
    detector's shortest exposure saturates)."""
    shortest = devices.detector.exposure_range_s[0]
    while True:
        reading = _measure_reference(devices, rig, k, pose, exposure_s)
        if not reading.saturated:
            return reading, exposure_s
        if exposure_s <= shortest:
            raise GonioError(
                f"the reference standard saturates the detector even at {shortest:g} s: "
                "lower the source's power or the detector's aperture"
            )
        exposure_s = max(exposure_s / 2, shortest)


def read_dark(devices: Devices, rig: Rig, k: int, pose: FloatArray, exposure_s: float) -> Reading:
    """A reading with the light off (the detector's own dark signal), light on after."""
    light = devices.light
    if light is None:
        raise GonioError("the rig has no light switch: a dark reading needs the light off")
    light.off()
    try:
        return _measure_reference(devices, rig, k, pose, exposure_s)
    finally:
        light.on()


@dataclass(frozen=True)
class Calibration:
    """The reference readings of a run and what they give (counts, seconds)."""

    albedo: float
    exposure_s: float  # of every reference and dark reading
    first: Reading
    dark: Reading
    last: Reading
    reference: radiometry.ReferenceCalibration

    @classmethod
    def from_readings(
        cls,
        rig: Rig,
        pose: FloatArray,
        exposure_s: float,
        first: Reading,
        dark: Reading,
        last: Reading,
    ) -> Calibration:
        """The calibration from the reference readings taken at ``pose`` (the rig's
        reference standard and source kind)."""
        albedo = rig.spec.reference.albedo
        wi, wo = rig.forward(np.asarray(pose))
        reference = radiometry.ReferenceCalibration.from_counts(
            albedo, first.value, exposure_s, wi, wo, rig.source_kind, dark_counts=dark.value
        )
        return cls(albedo, exposure_s, first, dark, last, reference)

    @property
    def dark_rate(self) -> float:
        """Dark counts per second of exposure."""
        return self.dark.value / self.exposure_s

    @property
    def change(self) -> float:
        """The source's drift over the run: last / first dark-subtracted reference − 1."""
        return (self.last.value - self.dark.value) / (self.first.value - self.dark.value) - 1.0

    def brdf(
        self,
        counts: FloatArray,
        exposure_s: FloatArray,
        wi: FloatArray,
        wo: FloatArray,
        middle_s: FloatArray,
    ) -> FloatArray:
        """BRDF values (sr⁻¹) of readings ``counts`` taken with ``exposure_s`` at the
        pairs (``wi``, ``wo``) from the read-back angles, at times ``middle_s`` (the
        middle of each target's exposures): dark subtracted, drift divided out."""
        recovered = self.reference.brdf_from_counts(
            counts, exposure_s, wi, wo, dark_counts=self.dark_rate * exposure_s
        )
        t0, t1 = self.first.middle_s, self.last.middle_s
        when = (middle_s - t0) / (t1 - t0)
        return np.asarray(recovered / (1.0 + self.change * when), dtype=np.float64)
