"""The UTIA anisotropic BRDF database (Filip & Vávra 2014, 150 materials,
btf.utia.cas.cz): its ``.bin`` layout, a tabulated BRDF read from such a file
(``create("utia", path=...)``) and a writer of the layout (`write`).

Layout (docs/reference/formats.md#utia, after Filip's reader as published in Dupuy's
``dj_brdf.h`` and Sztrajman's ``read_brdf.py``): no header; 3 × 6 × 48 × 6 × 48 =
248 832 float64, little-endian, C-ordered over (channel, θi, φi, θv, φv), φv varying
fastest: **1 990 656 bytes**. Channels red, green, blue; θ = 0°, 15°, …, 75°; φ = 0°,
7.5°, …, 352.5°, both azimuths in the sample frame (φ = atan2(y, x), x the sample's
reference mark), ``i`` the light, ``v`` the detector. Negative values occur in the
published files and read as 0 (as every reader in use clamps them); a NaN or infinite
value is refused.

Values: ``encoding="linear"`` (the default, what `write` produces) reads a stored value
as the BRDF in sr⁻¹. ``encoding="srgb"`` decodes the published files as ``dj_brdf.h``
does after Filip: f = 100 · sRGB⁻¹(v / 140) (v clamped at 0); here per node, before
interpolating (``dj_brdf`` decodes after interpolating). The database's own pages do not
state the units; see the formats reference.

The tabulated BRDF interpolates quadrilinearly in (θi, φi, θv, φv) between the nodes
(`scipy.ndimage.map_coordinates`, order 1), periodic in both azimuths (352.5° → 360° ≡
0°), anisotropic (a common rotation of φi and φv changes the value), not reciprocal.
Beyond θ = 75° it is **constant in θ** (clamped to the 75° nodes; the published reader
extrapolates the 60°–75° slope linearly up to 90°). At the nodes it returns the stored
values (to float64 rounding of the angles). Between nodes its error is that of linear
interpolation on a 15° × 7.5° grid, ≈ (h²/8)·Σ|∂²f/∂x²| at a lobe's peak: ≈ 0.021/α² of
the peak for GGX of roughness α. Measured (studies/utia.py, docs/results/utia.md; both
θ ≤ 75°, largest error over the peak): Lambert exact; GGX α 0.3: 0.22, α 0.5: 0.088,
α 0.8: 0.043 (stated bound 0.06, tested); anisotropic GGX αx 0.3, αy 0.6: 0.13 (stated
bound 0.15, tested). A lobe narrower than α ≈ 0.3 is not resolved by the grid.
"""

from __future__ import annotations

import functools
import math
from pathlib import Path

import numpy as np
from scipy import ndimage

from gonio.brdf.base import BRDF, beyond_bound, read_path
from gonio.brdf.geometry import Pair
from gonio.errors import GonioError
from gonio.output import reserve_output
from gonio.types import FloatArray

#: Nodes in θ (per direction) and φ (per direction).
N_THETA = 6
N_PHI = 48
#: Grid steps (degrees).
THETA_STEP_DEG = 15.0
PHI_STEP_DEG = 7.5
#: The array a file holds: (channel, θi, φi, θv, φv).
SHAPE = (3, N_THETA, N_PHI, N_THETA, N_PHI)
#: float64 values in a file.
VALUES = math.prod(SHAPE)
#: A file's size: no header, float64 values only.
FILE_SIZE = VALUES * 8
#: ``encoding`` values accepted.
ENCODINGS = ("linear", "srgb")
#: ``srgb``: the stored value divided by this is sRGB-encoded (Filip's constant in ``dj_brdf``).
SRGB_DIVISOR = 140.0
#: ``srgb``: the decoded value times this is the BRDF (sr⁻¹).
SRGB_SCALE = 100.0

THETA_STEP = math.radians(THETA_STEP_DEG)
PHI_STEP = math.radians(PHI_STEP_DEG)
TWO_PI = 2.0 * math.pi


def theta_nodes() -> FloatArray:
    """θ of the nodes (rad): 0, 15°, …, 75°."""
    return np.arange(N_THETA, dtype=np.float64) * THETA_STEP


def phi_nodes() -> FloatArray:
    """φ of the nodes (rad): 0, 7.5°, …, 352.5°."""
    return np.arange(N_PHI, dtype=np.float64) * PHI_STEP


def _direction(theta: FloatArray, phi: FloatArray) -> FloatArray:
    s = np.sin(theta)
    return np.stack(np.broadcast_arrays(s * np.cos(phi), s * np.sin(phi), np.cos(theta)), -1)


def grid_directions() -> tuple[FloatArray, FloatArray]:
    """(wi, wo) of every node, each (6, 48, 6, 48, 3), axes (θi, φi, θv, φv)."""
    t, p = theta_nodes(), phi_nodes()
    wi = _direction(t[:, None, None, None], p[None, :, None, None])
    wo = _direction(t[None, None, :, None], p[None, None, None, :])
    wi, wo = np.broadcast_arrays(wi, wo)
    return np.array(wi), np.array(wo)


def tabulate(model: BRDF) -> FloatArray:
    """``model`` (any gonio BRDF) at every node: (3, 6, 48, 6, 48) in sr⁻¹, a grey model
    written as the same values in red, green and blue."""
    wi, wo = grid_directions()
    values = np.asarray(model.eval(wi, wo), dtype=np.float64)
    if not model.is_rgb:
        values = np.repeat(values[..., None], 3, axis=-1)
    return np.ascontiguousarray(np.moveaxis(values, -1, 0))


def to_bytes(values: FloatArray) -> bytes:
    """The file of ``values`` (3, 6, 48, 6, 48): little-endian float64, no header."""
    values = np.asarray(values, dtype=np.float64)
    if values.shape != SHAPE:
        raise GonioError(f"UTIA table of shape {values.shape}, expected {SHAPE}")
    return np.ascontiguousarray(values, dtype="<f8").tobytes()


def write(path: str | Path, model: BRDF) -> Path:
    """Write ``model`` tabulated on the UTIA grid (`tabulate`) to ``path`` (replaced
    whole or not at all, `gonio.output`); the path written."""
    data = to_bytes(tabulate(model))
    with reserve_output(path, "path") as out:
        out.write_bytes(data)
    return Path(path)


def read_table(path: str | Path, encoding: str = "linear") -> FloatArray:
    """The values (3, 6, 48, 6, 48) in sr⁻¹ of a UTIA file, decoded by ``encoding``,
    negatives as 0 (read-only; the last few files read are kept). `GonioError` (one
    line naming the file) for a file of another size or with a NaN or infinite value."""
    if encoding not in ENCODINGS:
        raise GonioError(f"encoding must be one of {', '.join(ENCODINGS)}, got {encoding!r}")
    path = Path(path)
    try:
        info = path.stat()
    except OSError as exc:
        raise GonioError(f"{path}: cannot read the UTIA file: {exc.strerror or exc}") from None
    return _read(str(path.resolve()), info.st_mtime_ns, info.st_size, encoding)


@functools.lru_cache(maxsize=4)
def _read(path: str, _mtime_ns: int, size: int, encoding: str) -> FloatArray:
    # The size is checked before anything is read: nothing is allocated that the byte
    # count does not justify.
    if size != FILE_SIZE:
        raise GonioError(
            f"{path}: not a UTIA BRDF file: {size} bytes, expected {FILE_SIZE} "
            "(3 × 6 × 48 × 6 × 48 float64, no header)"
        )
    try:
        with open(path, "rb") as stream:
            raw = np.fromfile(stream, dtype="<f8", count=VALUES)
    except OSError as exc:
        raise GonioError(f"{path}: cannot read the UTIA file: {exc.strerror or exc}") from None
    if raw.size != VALUES:  # the file shrank between stat and read
        raise GonioError(f"{path}: not a UTIA BRDF file: truncated while read")
    stored = raw.astype(np.float64).reshape(SHAPE)
    bad = ~np.isfinite(stored)
    if bad.any():
        c, ti, pi, tv, pv = (int(j[0]) for j in np.nonzero(bad))
        raise GonioError(
            f"{path}: UTIA value {stored[c, ti, pi, tv, pv]} at channel {'RGB'[c]}, "
            f"θi {ti * THETA_STEP_DEG:g}°, φi {pi * PHI_STEP_DEG:g}°, "
            f"θv {tv * THETA_STEP_DEG:g}°, φv {pv * PHI_STEP_DEG:g}° "
            f"({int(bad.sum())} such); expected finite numbers"
        )
    absurd = beyond_bound(stored)
    if absurd is not None:
        raise GonioError(f"{path}: UTIA {absurd}")
    table = np.maximum(stored, 0.0)
    if encoding == "srgb":
        table = SRGB_SCALE * srgb_decode(table / SRGB_DIVISOR)
    table.setflags(write=False)
    return table


def srgb_decode(v: FloatArray) -> FloatArray:
    """The sRGB transfer function inverted (IEC 61966-2-1): encoded → linear."""
    return np.where(v <= 0.04045, v / 12.92, ((v + 0.055) / 1.055) ** 2.4)


def index_coordinates(
    theta_i: FloatArray, phi_i: FloatArray, theta_v: FloatArray, phi_v: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Continuous node coordinates of angles (rad): θ/15° clamped to [0, 5], φ/7.5°
    wrapped into [0, 48] (48 ≡ 0)."""
    return (
        np.clip(theta_i, 0.0, (N_THETA - 1) * THETA_STEP) / THETA_STEP,
        np.mod(phi_i, TWO_PI) / PHI_STEP,
        np.clip(theta_v, 0.0, (N_THETA - 1) * THETA_STEP) / THETA_STEP,
        np.mod(phi_v, TWO_PI) / PHI_STEP,
    )


class UtiaTable(BRDF):
    """A BRDF tabulated in a UTIA ``.bin`` file (RGB, anisotropic, not reciprocal),
    interpolated quadrilinearly (see the module docstring). ``path``: the file;
    ``encoding``: ``linear`` (stored values are sr⁻¹) or ``srgb`` (the published
    database's encoding as ``dj_brdf.h`` decodes it)."""

    name = "utia"
    reciprocal = False
    physically_based = False

    def __init__(self, path: object, encoding: object = "linear") -> None:
        if not isinstance(encoding, str) or encoding not in ENCODINGS:
            raise GonioError(
                f"parameter encoding must be one of {', '.join(ENCODINGS)}, got {encoding!r}"
            )
        name, table = read_path(path, lambda name: read_table(name, encoding))
        super().__init__({"path": name, "encoding": encoding})
        self.is_rgb = True
        # One more node in each azimuth: 360° ≡ 0°, so φ in [352.5°, 360°) interpolates
        # toward the 0° node.
        self._grids = tuple(
            np.pad(channel, ((0, 0), (0, 1), (0, 0), (0, 1)), mode="wrap") for channel in table
        )

    @property
    def isotropic(self) -> bool:
        return False

    def _eval(self, p: Pair) -> FloatArray:
        theta_i = np.arctan2(np.hypot(p.xi, p.yi), p.zi)
        theta_v = np.arctan2(np.hypot(p.xo, p.yo), p.zo)
        return self.at(theta_i, np.arctan2(p.yi, p.xi), theta_v, np.arctan2(p.yo, p.xo))

    def at(
        self, theta_i: FloatArray, phi_i: FloatArray, theta_v: FloatArray, phi_v: FloatArray
    ) -> FloatArray:
        """The interpolated (..., 3) values (sr⁻¹) at angles (rad) of the light (i) and
        the detector (v); any φ (periodic), θ beyond 75° taken as 75°."""
        coords = index_coordinates(
            *(np.asarray(a, dtype=np.float64) for a in (theta_i, phi_i, theta_v, phi_v))
        )
        shape = np.broadcast(*coords).shape
        nodes = np.stack([np.broadcast_to(c, shape).ravel() for c in coords])
        out = [ndimage.map_coordinates(g, nodes, order=1, mode="nearest") for g in self._grids]
        return np.stack(out, axis=-1).reshape((*shape, 3))
