"""What inverse kinematics gives for each pair (`Solution`): the joint angles, the pair
measured, every candidate and why a refused pair is refused (`Reason`)."""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum

import numpy as np

from gonio.types import BoolArray, FloatArray


class Reason(IntEnum):
    """Why a pair is refused (0: it is not). "limit" in the issue's words covers
    THETA_MAX and AXIS_LIMIT."""

    OK = 0
    THETA_MAX = 1  # beyond the usable polar angle of the light or the detector
    BLIND_SPOT = 2  # source and detector closer than the minimum separation
    FOOTPRINT = 3  # the lit area leaves the sample or the detector's view (collimated)
    VIEW_OFF_SAMPLE = 4  # the detector's view runs past the sample's edge (point source)
    AXIS_LIMIT = 5  # no inverse-kinematics solution inside the axes' limits
    COLLISION = 6  # every solution inside the limits hits a keep-out box

    @property
    def label(self) -> str:
        return self.name.lower()


#: `Solution`'s fields in order, as one block of pairs gives them (`Rig._solve`).
Solved = tuple[FloatArray, FloatArray, FloatArray, np.ndarray, FloatArray, BoolArray]


@dataclass(frozen=True)
class Solution:
    """Per pair: joint angles (N, A), the pair measured (N, 3) each, the refusal reason
    (N,) and every candidate (N, K, A) with its usability (N, K) for a later choice."""

    angles: FloatArray
    wi: FloatArray
    wo: FloatArray
    reasons: np.ndarray
    candidates: FloatArray
    usable: BoolArray

    @property
    def ok(self) -> BoolArray:
        return np.asarray(self.reasons == Reason.OK, dtype=np.bool_)
