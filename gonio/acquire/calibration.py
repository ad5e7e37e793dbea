"""Calibration with the reference standard, through the `drivers.base` contract.

The reference standard (a Lambertian target of known albedo, the rig file's
``reference`` section) is read at the rig's calibration geometry (0°/45° in the shipped
rigs: light at the normal, detector 45° away) with the plan's typical
exposure, halved until the reading does not saturate; a dark reading is taken with the
light off at the same exposure. Readings of the sample become BRDF values through
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

from dataclasses import dataclass

import numpy as np

from drivers.base import Reading
from gonio import radiometry
from gonio.acquire.devices import Devices
from gonio.acquire.measure import measure_target
from gonio.errors import GonioError
from gonio.rig.model import Reason, Rig
from gonio.types import FloatArray

#: Sample indices of calibration readings start here, far above any plan's indices.
CALIBRATION_INDEX = 1 << 40


def geometry_label(rig: Rig) -> str:
    """The rig's calibration geometry, e.g. ``0°/45°`` (θi/θo)."""
    ref = rig.spec.reference
    return f"{ref.theta_i_deg:g}°/{ref.theta_o_deg:g}°"


def reference_pose(rig: Rig) -> FloatArray:
    """Joint angles (rad, rig.axes order) of the rig's calibration geometry (its
    ``reference`` section; 0°/45° in the shipped rigs)."""
    wi, wo = rig.reference_directions()
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
