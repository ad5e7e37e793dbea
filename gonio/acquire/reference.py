"""Where the reference standard is read: the rig's calibration geometry and pose.

The reference standard (a Lambertian target of known albedo, the rig file's
``reference`` section) is read at the rig's calibration geometry (0°/45° in the shipped
rigs: light at the normal, detector 45° away). The geometry is the rig file's or none:
where the standard would not fill what the ideal chain assumes (a collimated beam's lit
spot on the standard and in the detector's view; for a point source, the view on the
standard), `reference_geometry` refuses the rig rather than move the standard to a
geometry its albedo is not given for. The engine (`gonio.acquire.engine`) reads the
standard and a dark reading there on the plan's schedule; `gonio.analysis.calibrated`
turns the journaled readings into BRDF values.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from drivers.base import StageTarget, reading_unit
from drivers.devices import Devices
from drivers.values import Reading
from gonio import radiometry
from gonio.acquire.measure import TargetReading, measure_target, reading_fields
from gonio.config import ConfigError, line_of, read_yaml
from gonio.errors import GonioError
from gonio.rig import Reason, Rig
from gonio.types import FloatArray


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
    # Refusals about the sample's size or the arms' shadow do not bind the standard,
    # which has its own size (`_clipped` checks its footprint or view).
    geometry_only = (Reason.BLIND_SPOT, Reason.FOOTPRINT, Reason.VIEW_OFF_SAMPLE)
    if solution.reasons[0] not in (Reason.OK, *geometry_only):
        raise GonioError(
            f"rig {rig.spec.name!r} cannot reach its reference geometry "
            f"({geometry_label(rig)}; {Reason(solution.reasons[0]).label.replace('_', ' ')})"
        )
    return np.asarray(solution.angles[0], dtype=np.float64)


class Stage(Protocol):
    """Puts the sample or the reference standard in view (a simulated stage, or an
    operator asked to swap them)."""

    def show(self, target: StageTarget) -> None: ...


#: Sample indices of calibration readings start here, far above any plan's indices
#: (reading ``k`` of the reference uses CALIBRATION_INDEX + 2k, its dark + 2k + 1).
CALIBRATION_INDEX = 1 << 40


@dataclass(frozen=True)
class StandardReadings:
    """Calibration ``k``: the reference standard measured at its pose (read-back angles
    included), the dark reading at the same pose and exposure (None if not taken), and
    that exposure (s, as asked)."""

    reference: TargetReading
    dark: Reading | None
    exposure_s: float


def read_standard(
    devices: Devices,
    stage: Stage,
    rig: Rig,
    k: int,
    exposure_s: float,
    averages: int,
    *,
    dark: bool,
    timeout_s: float,
) -> StandardReadings:
    """Put the reference standard in view, read it at the rig's calibration pose with
    ``exposure_s`` halved until it does not saturate, then (``dark``) with the light off;
    the sample back in view whatever happens."""
    pose = dict(zip(rig.axes, reference_pose(rig).tolist(), strict=True))
    shortest = devices.detector.exposure_range_s[0]

    def read(index: int) -> TargetReading:
        return measure_target(
            devices,
            index,
            pose,
            exposure_s,
            averages,
            settle_s=rig.spec.settle_s,
            timeout_s=timeout_s,
        )

    level = reading_unit(devices.detector) != "counts"
    stage.show("reference")
    try:
        reference = read(CALIBRATION_INDEX + 2 * k)
        if reference.reading.saturated and level:
            raise GonioError(
                "the reference standard saturates the detector, whose reading is a level "
                f"({reading_unit(devices.detector)}: a shorter exposure reads the same): "
                "raise its range or sensitivity, or lower the source's power"
            )
        while reference.reading.saturated and exposure_s > shortest:
            exposure_s = max(exposure_s / 2.0, shortest)
            reference = read(CALIBRATION_INDEX + 2 * k)
        if reference.reading.saturated:
            raise GonioError(
                f"the reference standard saturates the detector even at {shortest:g} s: "
                "lower the source's power or the detector's aperture"
            )
        dark_reading = None
        if dark:
            light = devices.light
            if light is None:
                raise GonioError(
                    "the rig's light cannot be switched: a dark reading needs it off; set "
                    "acquisition.calibration.dark: false in the plan (darks then count as 0)"
                )
            light.off()
            try:
                dark_reading = read(CALIBRATION_INDEX + 2 * k + 1).reading
            finally:
                light.on()
    finally:
        stage.show("sample")
    return StandardReadings(reference, dark_reading, exposure_s)


def reading_data(reading: Reading, exposure_s: float, offset_s: float) -> dict[str, Any]:
    """What a calibration event keeps of a reading: its value, count and saturation, the
    journal's fields (`reading_fields`) and a lock-in's phase."""
    fields = reading_fields(reading, exposure_s, offset_s)
    data = {"value": reading.value, "n": reading.n, "saturated": reading.saturated, **fields}
    if reading.phase_deg is not None:
        data["phase_deg"] = reading.phase_deg
    return data


def calibration_data(
    read: StandardReadings, rig: Rig, why: str, k: int, count: int, unit: str, offset_s: float
) -> dict[str, Any]:
    """The ``calibration`` event of ``read`` (calibration ``k``, after ``count`` samples,
    for ``why``): the pair the reference was read at (from its read-back angles), the
    reference and dark readings (`reading_data`), and why no dark was read."""
    back = [read.reference.read_back[a] for a in rig.axes]
    wi, wo = rig.forward(np.array(back), rig.alignment)
    data: dict[str, Any] = {
        "why": why,
        "k": k,
        "count": count,
        "albedo": rig.spec.reference.albedo,
        "source_kind": rig.source_kind,
        "wi": wi.tolist(),
        "wo": wo.tolist(),
        "pose_rad": back,
        "unit": unit,
        "reference": reading_data(read.reference.reading, read.exposure_s, offset_s),
        "dark": None if read.dark is None else reading_data(read.dark, read.exposure_s, offset_s),
    }
    return data
