"""Why a rig refuses a direction pair or a pose (`Reason`): its axes' limits, its
keep-out boxes and the constraints of its rig file (the largest polar angle, the blind
spot between light and detector, a collimated beam's footprint, a point source's view
off the sample). Angles are radians, directions sample-frame unit vectors."""

from __future__ import annotations

import math
from typing import Literal

import numpy as np

from gonio.rig import constraints
from gonio.rig.schema import ConstraintSpec
from gonio.rig.solution import Reason
from gonio.types import BoolArray, FloatArray


class Refusals:
    """The checks of a rig with joint ``limits`` (A, 2) rad, the rig file's constraints
    ``spec``, its ``axes`` (names, in order, for the keep-out boxes) and its light's
    ``source_kind``."""

    def __init__(
        self,
        limits: FloatArray,
        spec: ConstraintSpec,
        axes: tuple[str, ...],
        source_kind: Literal["collimated", "point"],
    ) -> None:
        self.limits = limits
        self.spec = spec
        self.source_kind = source_kind
        self.theta_max = math.radians(spec.theta_max_deg)
        self.min_separation = math.radians(spec.min_separation_deg)
        #: Each keep-out box: its name and {axis index: (low, high) rad}.
        self.collisions = [
            (
                box.name,
                {
                    axes.index(n): (math.radians(lo), math.radians(hi))
                    for n, (lo, hi) in box.ranges_deg.items()
                },
            )
            for box in spec.collisions
        ]

    def inside_limits(self, columns: FloatArray) -> BoolArray:
        """True where every axis's angle is inside its limits, for angles given by axis
        (A, ...): ``columns[j]`` the angles of axis j."""
        ok = np.ones(np.shape(columns[0]), dtype=np.bool_)
        for j in range(len(self.limits)):
            ok &= columns[j] >= self.limits[j, 0]
            ok &= columns[j] <= self.limits[j, 1]
        return ok

    def collides(self, angles: FloatArray) -> BoolArray:
        """True where joint angles (..., A) are inside a keep-out box."""
        hit = np.zeros(angles.shape[:-1], dtype=np.bool_)
        for _, box in self.collisions:
            hit |= constraints.in_box(angles, box)
        return hit

    def reasons(
        self, wi: FloatArray, wo: FloatArray, limits_ok: BoolArray, usable: BoolArray
    ) -> np.ndarray:
        """Why each pair (N, 3) is refused (`Reason`; OK where it is not), given which of
        its candidates (K, N) are within the limits and which are also collision-free."""
        reasons = np.full(len(wi), Reason.OK, dtype=np.int8)
        theta_max = (wi[:, 2] < math.cos(self.theta_max)) | (wo[:, 2] < math.cos(self.theta_max))
        c = self.spec
        # A collimated beam's lit ellipse must fit the sample and the view; a point source
        # floods the sample plane, so the view itself must stay on the sample.
        no_pair = np.zeros(len(wi), dtype=np.bool_)
        footprint = (
            no_pair
            if c.beam_diameter_mm is None
            else ~constraints.footprint_ok(
                wi, wo, c.beam_diameter_mm, c.sample_diameter_mm, c.detector_fov_mm
            )
        )
        off_sample = (
            ~constraints.view_on_sample(wo, c.detector_fov_mm, c.sample_diameter_mm)
            if self.source_kind == "point"
            else no_pair
        )
        checks = [
            (Reason.THETA_MAX, theta_max),
            (Reason.BLIND_SPOT, constraints.separation(wi, wo) < self.min_separation),
            (Reason.FOOTPRINT, footprint),
            (Reason.VIEW_OFF_SAMPLE, off_sample),
            (Reason.AXIS_LIMIT, ~limits_ok.any(axis=0)),
            (Reason.COLLISION, ~usable.any(axis=0)),
        ]
        for reason, refused in reversed(checks):  # the first check that fails wins
            reasons[refused] = reason
        return reasons
