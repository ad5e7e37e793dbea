"""`AlignmentSpec`: a misalignment as a file gives it (degrees, millimetres, axes by
name), turned into the kinematics' `Alignment` for a rig's axes. A scene's
``misalignment`` effect is one (`gonio.scene`)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Annotated

import numpy as np
from pydantic import Field

from gonio.config import Strict, excerpt
from gonio.rig.alignment import Alignment

#: The largest angular error (°): beyond 5° an axis or a sample is mis-assembled rather
#: than misaligned, and no first-order reading of the errors holds.
MAX_ERROR_DEG = 5.0
#: The largest height (mm) of the sample surface from the rotation centre: 10 mm off,
#: the sample sits on another stage than the rig file's.
MAX_HEIGHT_MM = 10.0

ErrorDeg = Annotated[float, Field(ge=-MAX_ERROR_DEG, le=MAX_ERROR_DEG)]


class AlignmentSpec(Strict):
    """How the rig differs from its file (`gonio.rig.alignment`): zero offsets, the
    sample's tilt and height, the light's and the detector's pointing errors."""

    zero_offset_deg: dict[str, ErrorDeg] = Field(
        default_factory=dict,
        description="Per axis (by its rig-file name): the true joint angle minus the rig "
        "file's (°, at most 5 either way).",
    )
    tilt_deg: float = Field(
        0.0,
        ge=0,
        le=MAX_ERROR_DEG,
        description="The sample normal's tilt from the stage's axis (°, at most 5): a wedge "
        "or a badly seated sample.",
    )
    tilt_azimuth_deg: float = Field(
        0.0,
        ge=-360,
        le=360,
        description="The azimuth the normal tilts toward, from the stage's x (the reference "
        "mark) (°).",
    )
    height_mm: float = Field(
        0.0,
        ge=-MAX_HEIGHT_MM,
        le=MAX_HEIGHT_MM,
        description="The sample surface's height above the rotation centre, along its normal "
        "(mm, at most 10 either way).",
    )
    light_pointing_deg: tuple[ErrorDeg, ErrorDeg] = Field(
        (0.0, 0.0),
        description="The light's pointing error: turns about its last frame's x and y (°, at "
        "most 5 each).",
    )
    detector_pointing_deg: tuple[ErrorDeg, ErrorDeg] = Field(
        (0.0, 0.0),
        description="The detector's pointing error: turns about its last frame's x and y (°, "
        "at most 5 each).",
    )

    def unknown_axes(self, axes: Sequence[str]) -> list[str]:
        """The axes ``zero_offset_deg`` names that are not in ``axes``."""
        return [name for name in self.zero_offset_deg if name not in axes]

    def alignment(self, axes: Sequence[str]) -> Alignment:
        """The `Alignment` for a rig with these ``axes`` (in its order); `ValueError` if
        an offset names another axis."""
        unknown = self.unknown_axes(axes)
        if unknown:
            known = ", ".join(axes)
            raise ValueError(f"zero_offset_deg: no axis {excerpt(unknown[0])} (axes: {known})")
        return Alignment(
            zero_offset=np.radians([self.zero_offset_deg.get(a, 0.0) for a in axes]),
            tilt=np.radians(np.float64(self.tilt_deg)),
            tilt_azimuth=np.radians(np.float64(self.tilt_azimuth_deg)),
            height_mm=np.asarray(self.height_mm, dtype=np.float64),
            light_pointing=np.radians(self.light_pointing_deg),
            detector_pointing=np.radians(self.detector_pointing_deg),
        )
