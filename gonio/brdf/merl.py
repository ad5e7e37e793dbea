"""The MERL BRDF table (Matusik, Pfister, Brand & McMillan 2003): its binary layout,
and a tabulated BRDF read from such a file (``create("merl", path=...)``).

Layout (docs/reference/formats.md#merl, after MERL's ``BRDFRead.cpp``): three int32 (90, 90, 180),
then the 1 458 000 red, the 1 458 000 green and the 1 458 000 blue float64 values, each
channel a C-ordered array over (θh, θd, φd) with φd varying fastest; 34 992 012 bytes,
little-endian. A channel's BRDF value (sr⁻¹) is the stored value times its scale
(`SCALES`); a negative (or NaN) stored value marks a missing bin. Bin (i, j, k) holds
θh ∈ [(i/90)², ((i+1)/90)²]·π/2 (the square-root mapping MERL's reader inverts),
θd ∈ [j, j+1]·π/180, φd ∈ [k, k+1]·π/180 (φd folded into [0, π) by reciprocity).

The tabulated BRDF interpolates trilinearly in the index coordinates (√(θh/(π/2))·90,
θd/(π/2)·90, φd/π·180), with the bin centres as nodes, periodic in φd, constant beyond
the outermost centres in θh and θd. Missing bins take no part: a value is the weighted
mean of the corners present, and 0 where none is (as MERL's readers give 0, or warn,
"below horizon").
"""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np
from scipy import ndimage

from gonio import params
from gonio.brdf.base import BRDF, beyond_bound, read_path
from gonio.brdf.geometry import Pair
from gonio.errors import GonioError
from gonio.types import FloatArray

#: Bins in θh, θd and φd (the header's three int32, in this order).
SHAPE = (90, 90, 180)
#: Values per channel.
BINS = SHAPE[0] * SHAPE[1] * SHAPE[2]
#: BRDF value (sr⁻¹) = stored value × scale, per channel (red, green, blue).
SCALES = (1.0 / 1500.0, 1.15 / 1500.0, 1.66 / 1500.0)
#: Header (12 bytes) and 3 channels of float64.
FILE_SIZE = 12 + 3 * BINS * 8
#: The stored value written for a missing bin (any negative value reads as missing).
MISSING = -1.0
#: Below this total weight of the corners present, an interpolated value is 0.
MIN_WEIGHT = 1e-9

HALF_PI = 0.5 * np.pi


def index_coordinates(
    theta_h: FloatArray, theta_d: FloatArray, phi_d: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Continuous bin coordinates (u, v, w) of angles (rad): bin (i, j, k) covers
    [i, i+1) × [j, j+1) × [k, k+1); φd is folded into [0, π) first."""
    u = np.sqrt(np.clip(theta_h, 0.0, HALF_PI) / HALF_PI) * SHAPE[0]
    v = np.clip(theta_d, 0.0, HALF_PI) / HALF_PI * SHAPE[1]
    w = np.mod(phi_d, np.pi) / np.pi * SHAPE[2]
    return u, v, w


def bin_index(
    theta_h: FloatArray, theta_d: FloatArray, phi_d: FloatArray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The bin (i, j, k) MERL's reader looks up for these angles (floor, clipped)."""
    return tuple(  # type: ignore[return-value]
        np.clip(np.floor(c).astype(np.int64), 0, n - 1)
        for c, n in zip(index_coordinates(theta_h, theta_d, phi_d), SHAPE, strict=True)
    )


def bin_centres() -> tuple[FloatArray, FloatArray, FloatArray]:
    """(θh, θd, φd) of every bin's centre in index coordinates, broadcastable to `SHAPE`
    as (90, 1, 1), (1, 90, 1), (1, 1, 180): θh = ((i + ½)/90)²·π/2, θd = (j + ½)·π/180,
    φd = (k + ½)·π/180."""
    i = (np.arange(SHAPE[0], dtype=np.float64) + 0.5) / SHAPE[0]
    j = (np.arange(SHAPE[1], dtype=np.float64) + 0.5) / SHAPE[1]
    k = (np.arange(SHAPE[2], dtype=np.float64) + 0.5) / SHAPE[2]
    return (i * i * HALF_PI)[:, None, None], (j * HALF_PI)[None, :, None], (k * np.pi)[None, None]


def to_bytes(values: FloatArray, missing: np.ndarray) -> bytes:
    """The file of ``values`` (3, 90, 90, 180) in sr⁻¹ (red, green, blue), with the bins
    where ``missing`` (90, 90, 180) is True written as `MISSING`."""
    scales = np.asarray(SCALES)[:, None, None, None]
    stored = np.where(missing[None], MISSING, values / scales)
    header = np.asarray(SHAPE, dtype="<i4").tobytes()
    return header + np.ascontiguousarray(stored, dtype="<f8").tobytes()


def read_table(path: str | Path) -> FloatArray:
    """The values (3, 90, 90, 180) in sr⁻¹ of a MERL file, NaN where missing (read-only;
    the last few files read are kept). `GonioError` (one line) for a file of another
    size or header."""
    path = Path(path)
    try:
        info = path.stat()
    except OSError as exc:
        raise GonioError(f"{path}: cannot read the MERL file: {exc.strerror or exc}") from None
    return _read(str(path.resolve()), info.st_mtime_ns, info.st_size)


@functools.lru_cache(maxsize=4)
def _read(path: str, _mtime_ns: int, size: int) -> FloatArray:
    if size != FILE_SIZE:
        raise GonioError(
            f"{path}: not a MERL BRDF file: {size} bytes, expected {FILE_SIZE} "
            "(three int32 90 90 180, then 3 × 1458000 float64)"
        )
    try:
        with open(path, "rb") as stream:
            dims = tuple(int(d) for d in np.fromfile(stream, dtype="<i4", count=3))
            raw = np.fromfile(stream, dtype="<f8", count=3 * BINS)
    except OSError as exc:
        raise GonioError(f"{path}: cannot read the MERL file: {exc.strerror or exc}") from None
    if dims != SHAPE:
        raise GonioError(f"{path}: MERL header {dims}, expected {SHAPE}")
    stored = raw.reshape((3, *SHAPE))
    scales = np.asarray(SCALES)[:, None, None, None]
    missing = np.any(~(stored >= 0.0), axis=0)  # negative, or NaN
    table = np.where(missing[None], np.nan, stored * scales)
    absurd = beyond_bound(table)
    if absurd is not None:
        raise GonioError(f"{path}: MERL {absurd}")
    table.setflags(write=False)
    return table


class MerlTable(BRDF):
    """A BRDF tabulated in a MERL binary file (RGB, isotropic, reciprocal), interpolated
    trilinearly between bin centres (see the module docstring); ``path``: the file."""

    name = "merl"
    physically_based = False

    def __init__(self, path: object) -> None:
        name, table = read_path(path, read_table)
        super().__init__({"path": name})
        self.is_rgb = True
        present = ~np.isnan(table[0])
        # One cell of padding: the neighbour across φd = 0 ≡ π, and the edge in θh, θd.
        self._weight = _pad(present.astype(np.float64))
        self._sums = tuple(_pad(np.where(present, channel, 0.0)) for channel in table)

    def _eval(self, p: Pair) -> FloatArray:
        # Pairs below the horizon are discarded by `eval`; the normal stands in for them.
        normal = np.array([0.0, 0.0, 1.0])
        above = p.above[..., None]
        wi = np.where(above, np.stack([p.xi, p.yi, p.zi], axis=-1), normal)
        wo = np.where(above, np.stack([p.xo, p.yo, p.zo], axis=-1), normal)
        theta_h, theta_d, phi_d = np.moveaxis(params.get("rusinkiewicz").forward_iso(wi, wo), -1, 0)
        return self.at(theta_h, theta_d, phi_d)

    def at(self, theta_h: FloatArray, theta_d: FloatArray, phi_d: FloatArray) -> FloatArray:
        """The interpolated (..., 3) values at Rusinkiewicz angles (rad)."""
        u, v, w = index_coordinates(theta_h, theta_d, phi_d)
        shape = np.broadcast(u, v, w).shape
        # Centres at integers, plus the one cell of padding.
        nodes = np.stack([np.broadcast_to(c + 0.5, shape).ravel() for c in (u, v, w)])
        weight = ndimage.map_coordinates(self._weight, nodes, order=1, mode="nearest")
        present = weight > MIN_WEIGHT
        safe = np.where(present, weight, 1.0)
        out = [
            np.where(present, ndimage.map_coordinates(s, nodes, order=1, mode="nearest"), 0.0)
            / safe
            for s in self._sums
        ]
        return np.stack(out, axis=-1).reshape((*shape, 3))


def _pad(grid: FloatArray) -> FloatArray:
    """``grid`` with one more cell on each side: edge values in θh and θd, wrapped in φd."""
    edged = np.pad(grid, ((1, 1), (1, 1), (0, 0)), mode="edge")
    return np.pad(edged, ((0, 0), (0, 0), (1, 1)), mode="wrap")
