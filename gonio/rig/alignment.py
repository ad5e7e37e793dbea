"""`Alignment`: how a real rig differs from its rig file, as the forward kinematics
applies it (`gonio.rig.model.Rig.forward` and `Rig.geometry`).

Parameters (radians, millimetres; each broadcast over leading axes, so a batch of
alignments is one object):

zero_offset (..., A)
    Per axis, the true joint angle minus the rig file's: an axis the rig reads at q
    really stands at q + δ (a scalar: the same δ on every axis).
tilt, tilt_azimuth (...)
    The sample's true normal in the stage's frame (the frame the sample chain carries,
    z its nominal normal): tilted by ``tilt`` toward the azimuth ``tilt_azimuth`` from
    the stage's x, n = (sin α cos β, sin α sin β, cos α): a wedge, or a badly seated
    sample. The tilt turns with the sample stage. The true sample frame is the stage's
    turned by the smallest rotation taking z to n (its x stays the reference mark's
    direction where the tilt is 0).
height (...)
    How far (mm) the sample surface lies above the rotation centre, along the true
    normal (the point where every chain aims): the true sample frame's origin is the
    foot of the perpendicular from the rotation centre to the surface.
light_pointing, detector_pointing (..., 2)
    The light's and the detector's pointing vectors turned by the rotation vector
    (e_x, e_y, 0) of their chain's last frame (the pointing being its z): about x tilts
    it toward −y, about y toward +x. The turn is about the rotation centre: the axis
    still passes through it (a collimator turned in place would also shift its beam
    by its unknown distance times the angle; that shift is the height's kind of error).

The forward map (`Rig.geometry`): joint angles q → q + δ through every chain; the
sample frame is R_sample R_tilt (R_tilt the tilt's rotation), the pointing vectors
R_chain R_pointing p. Then the height: a distant detector and a collimated beam keep
their directions and shift their spot on the surface by h tan θ along their azimuth
(`Geometry.light_offset_mm`, `.view_offset_mm`); a point source at distance r from the
rotation centre sits at s = r ωi − h z from the surface's origin, so the true ωi is
s / |s| and its distance |s| (`Geometry.light_distance_mm`): a change of order h / r
rad in ωi and 2 h cos θi / r in the irradiance.

Every rotation is exact (Rodrigues), so the map holds at any size; what is a
small-error model is the physics of the parameters (the turn about the rotation centre,
the height along the normal). To first order every error moves ωi and ωo linearly: a
zero offset of an axis is commanding it shifted; a tilt α moves a mirror's specular
direction by 2α; a pointing error ε moves its direction by ε.

What a mirror scan can tell apart (for the fit that finds these): a light or detector
pointing error about its last axis (the y of both shipped rig types) is that axis's
zero offset (one parameter, not two); a common zero offset of the detector azimuth and
the sample rotation (arch) turns both directions about the normal (unseen on an
isotropic sample: the reference mark's orientation); the tilt, turning with the sample
stage, is told from the offsets by turning the stage; the height, with a collimated
beam and a distant detector, moves no direction at all (only spots: a camera or the
footprint tells it), and with a point source only by h / r.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from gonio.types import ArrayLike, FloatArray

#: cos θ below which a spot's shift (h tan θ) is taken at this floor: finite, and
#: beyond any sample at the horizon (h / 1e-9).
_COS_FLOOR = 1e-9


def _array(value: ArrayLike) -> FloatArray:
    out = np.array(value, dtype=np.float64)
    out.setflags(write=False)
    return out


def rotation_from_vector(v: FloatArray) -> FloatArray:
    """Rotation matrices (..., 3, 3) of rotation vectors ``v`` (..., 3) (angle |v|
    about v / |v|; Rodrigues, smooth through 0)."""
    v = np.asarray(v, dtype=np.float64)
    theta = np.linalg.norm(v, axis=-1)
    a = np.sinc(theta / np.pi)[..., None, None]  # sin θ / θ
    b = (0.5 * np.sinc(theta / (2.0 * np.pi)) ** 2)[..., None, None]  # (1 − cos θ) / θ²
    zero = np.zeros_like(theta)
    x, y, z = v[..., 0], v[..., 1], v[..., 2]
    k = np.stack(
        [
            np.stack([zero, -z, y], axis=-1),
            np.stack([z, zero, -x], axis=-1),
            np.stack([-y, x, zero], axis=-1),
        ],
        axis=-2,
    )
    return np.asarray(np.eye(3) + a * k + b * (k @ k), dtype=np.float64)


@dataclass(frozen=True, eq=False)
class Alignment:
    """A rig's misalignment (see the module): radians and millimetres, each field
    broadcast over leading axes (any array-like is taken as float64)."""

    zero_offset: FloatArray = field(default_factory=lambda: _array(0.0))
    tilt: FloatArray = field(default_factory=lambda: _array(0.0))
    tilt_azimuth: FloatArray = field(default_factory=lambda: _array(0.0))
    height_mm: FloatArray = field(default_factory=lambda: _array(0.0))
    light_pointing: FloatArray = field(default_factory=lambda: _array((0.0, 0.0)))
    detector_pointing: FloatArray = field(default_factory=lambda: _array((0.0, 0.0)))

    def __post_init__(self) -> None:
        for name in (
            "zero_offset",
            "tilt",
            "tilt_azimuth",
            "height_mm",
            "light_pointing",
            "detector_pointing",
        ):
            value = _array(getattr(self, name))
            if not np.all(np.isfinite(value)):
                raise ValueError(f"{name}: expected finite values")
            object.__setattr__(self, name, value)
        for name in ("light_pointing", "detector_pointing"):
            if getattr(self, name).shape[-1:] != (2,):
                raise ValueError(f"{name}: expected shape (..., 2), two angles (rad)")

    @classmethod
    def none(cls) -> Alignment:
        """The identity: the rig is as its file says."""
        return cls()

    @cached_property
    def is_none(self) -> bool:
        """True where every parameter is exactly 0 (the forward map is then the rig
        file's, bit for bit); computed once (the fields are read-only)."""
        return not any(
            np.any(getattr(self, n))
            for n in ("zero_offset", "tilt", "height_mm", "light_pointing", "detector_pointing")
        )

    @cached_property
    def batch_shape(self) -> tuple[int, ...]:
        """The leading axes the parameters broadcast to (() for one alignment); computed
        once."""
        return np.broadcast_shapes(
            self.zero_offset.shape[:-1],
            self.tilt.shape,
            self.tilt_azimuth.shape,
            self.height_mm.shape,
            self.light_pointing.shape[:-1],
            self.detector_pointing.shape[:-1],
        )

    def joints(self, angles: FloatArray) -> FloatArray:
        """True joint angles (..., A) of the rig file's ``angles`` (..., A): q + δ."""
        return np.asarray(np.asarray(angles, dtype=np.float64) + self.zero_offset)

    @property
    def normal(self) -> FloatArray:
        """The sample's true normal in the stage frame (..., 3)."""
        s = np.sin(self.tilt)
        return np.stack(
            [s * np.cos(self.tilt_azimuth), s * np.sin(self.tilt_azimuth), np.cos(self.tilt)],
            axis=-1,
        )

    def tilt_rotation(self) -> FloatArray:
        """R_tilt (..., 3, 3): the true sample frame's axes in the stage frame (the
        smallest rotation taking z to `normal`)."""
        c, s = np.cos(self.tilt_azimuth), np.sin(self.tilt_azimuth)
        axis = np.stack([-s, c, np.zeros_like(c)], axis=-1)
        return rotation_from_vector(self.tilt[..., None] * axis)

    def pointing_rotation(self, chain: str) -> FloatArray:
        """R_pointing (..., 3, 3) of the ``light`` or ``detector`` chain's last frame."""
        e = self.light_pointing if chain == "light" else self.detector_pointing
        return rotation_from_vector(np.concatenate([e, np.zeros_like(e[..., :1])], axis=-1))


@dataclass(frozen=True)
class Geometry:
    """What the optics really see at a pose: true sample-frame (ωi, ωo) (..., 3); the
    shift (mm, (..., 2), true sample frame) of the beam's and of the view's centre on the
    surface from its origin; a point source's true distance from it (mm, (...); None for
    a collimated beam)."""

    wi: FloatArray
    wo: FloatArray
    light_offset_mm: FloatArray
    view_offset_mm: FloatArray
    light_distance_mm: FloatArray | None


def at_height(
    aim_i: FloatArray, aim_o: FloatArray, height_mm: FloatArray, light_distance_mm: float | None
) -> Geometry:
    """The `Geometry` of a sample surface ``height_mm`` above the rotation centre, whose
    chains aim at the rotation centre along the true sample-frame unit vectors
    ``aim_i``, ``aim_o`` (..., 3); ``light_distance_mm``: a point source's distance from
    the rotation centre (None: a collimated beam). See the module."""
    h = np.asarray(height_mm, dtype=np.float64)

    def shift(aim: FloatArray) -> FloatArray:
        cos = np.maximum(aim[..., 2], _COS_FLOOR)
        return np.asarray(h[..., None] * aim[..., :2] / cos[..., None], dtype=np.float64)

    wi, distance = aim_i, None
    if light_distance_mm is not None:
        s = light_distance_mm * aim_i - h[..., None] * np.array([0.0, 0.0, 1.0])
        distance = np.linalg.norm(s, axis=-1)
        wi = s / distance[..., None]
    return Geometry(wi, aim_o, shift(aim_i), shift(aim_o), distance)
