"""The RGL material database's ``.bsdf`` files (Dupuy & Jakob 2018, "An Adaptive
Parameterization for Efficient Material Acquisition and Rendering"; Mitsuba 3's
``measured`` plugin): their fields, their evaluation, and a tabulated BRDF read from
one (``create("rgl", path=...)``).

A file is a ``tensor_file`` (`gonio.brdf.tensor_file`) with the float32 fields
``theta_i`` (Nθ) and ``phi_i`` (Nφ) (rad: the incident directions' nodes), ``ndf``
and ``sigma`` (2-D), ``vndf`` (Nφ, Nθ, H, W), ``luminance`` (Nφ, Nθ, n, n) and
``spectra`` (Nφ, Nθ, Λ, n, n) with ``wavelengths`` (Λ, nm), or ``rgb``
(Nφ, Nθ, 3, n, n) without; the uint8 fields ``description`` (text) and ``jacobian``
(one flag). Angles map to the unit square as u(θ) = √(θ/(π/2)), u(φ) = (φ + π)/(2π).
The file is isotropic when Nφ ≤ 2 (then φ of the half vector is measured from φi).

f(ωi, ωo)·cos θo for ωm the half vector (docs/reference/formats.md#rgl): s =
V⁻¹(u(θm), u(φm)) with V the warp (`gonio.brdf.marginal.Marginal2D`) of the table
``vndf`` at (φi, θi); the value is the table ``spectra`` (or ``rgb``) at s, (φi, θi)
and each wavelength, times ndf(u(θm), u(φm)) / (4 sigma(u(θi), u(φi))) when
``jacobian`` is 1. The files hold the BRDF times the cosine of ωo (Mitsuba's BSDF
``eval`` returns the foreshortened value; its ``measured`` plugin reads the file's
value as it is, with ωi the direction towards the camera), so this reader divides by
cos θo (by `MIN_COSINE` at most). ``ndf``, ``sigma`` and ``spectra`` are plain
bilinear tables (`gonio.brdf.marginal.Table`); ``luminance`` only guides a renderer's
sampling and is not read here.

Spectra are reduced to RGB through the CIE 1931 colour-matching functions (the fit of
Wyman, Sloan & Shirley 2013) over 360–830 nm, the spectrum linear between its
wavelengths and constant beyond them (as Mitsuba interpolates it), the XYZ → linear
sRGB (Rec. 709 primaries) matrix, and a white balance that makes a flat spectrum grey:
a flat spectrum of value v reads (v, v, v). A detector's band then sees the RGB as
for any RGB material (`gonio.radiometry.bands`).

Interpolation error: a smooth model written by `gonio.export.rgl` at its default
resolution reads back within a few per cent of its peak (docs/results/rgl.md gives
the measured figures); the reader itself adds nothing beyond float64 rounding to the
evaluation that the file's tables define.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gonio.brdf import tensor_file
from gonio.brdf.base import BRDF, beyond_bound, read_path
from gonio.brdf.geometry import Pair
from gonio.brdf.marginal import Marginal2D, Table
from gonio.errors import GonioError
from gonio.types import FloatArray

#: The wavelengths (nm) a spectrum is reduced over.
VISIBLE = (360.0, 830.0)
#: XYZ → linear sRGB (IEC 61966-2-1, Rec. 709 primaries, D65 white).
XYZ_TO_RGB = np.array(
    [[3.2406, -1.5372, -0.4986], [-0.9689, 1.8758, 0.0415], [0.0557, -0.2040, 1.0570]]
)
#: Upper wavelengths (nm) of the blue and green boxes of `upsampling` (red beyond).
BOXES = (490.0, 580.0)
#: The stored values are f·cos θo; below this cos θo they are divided by it instead.
MIN_COSINE = 1e-6
FLOAT_FIELDS = ("theta_i", "phi_i", "ndf", "sigma", "vndf", "luminance")


def _lobe(lam: FloatArray, mu: float, low: float, high: float) -> FloatArray:
    t = (lam - mu) / np.where(lam < mu, low, high)
    return np.asarray(np.exp(-0.5 * t * t))


def cie1931(lam: FloatArray) -> FloatArray:
    """x̄, ȳ, z̄ (..., 3) at wavelengths ``lam`` (nm): the multi-lobe fit of Wyman,
    Sloan & Shirley 2013 to the CIE 1931 2° observer."""
    x = (
        1.056 * _lobe(lam, 599.8, 37.9, 31.0)
        + 0.362 * _lobe(lam, 442.0, 16.0, 26.7)
        - 0.065 * _lobe(lam, 501.1, 20.4, 26.2)
    )
    y = 0.821 * _lobe(lam, 568.8, 46.9, 40.5) + 0.286 * _lobe(lam, 530.9, 16.3, 31.1)
    z = 1.217 * _lobe(lam, 437.0, 11.8, 36.0) + 0.681 * _lobe(lam, 459.0, 26.0, 13.8)
    return np.stack([x, y, z], axis=-1)


@functools.lru_cache(maxsize=8)
def _reduction(wavelengths: tuple[float, ...]) -> FloatArray:
    lam = np.linspace(*VISIBLE, 941)  # 0.5 nm
    nodes = np.asarray(wavelengths)
    # Each node's hat function (constant beyond the outermost nodes), on the fine grid.
    hats = np.stack([np.interp(lam, nodes, e) for e in np.eye(len(nodes))], axis=-1)
    cmf = cie1931(lam)
    xyz = np.trapezoid(hats[:, :, None] * cmf[:, None, :], lam, axis=0)
    xyz /= np.trapezoid(cmf[:, 1], lam)
    rgb = xyz @ XYZ_TO_RGB.T
    out = np.asarray(rgb / rgb.sum(axis=0))  # white balance: a flat spectrum → (1, 1, 1)
    out.setflags(write=False)
    return out


def reduction(wavelengths: FloatArray) -> FloatArray:
    """The matrix (Λ, 3) taking a spectrum's values at ``wavelengths`` (nm, increasing)
    to linear RGB, as the module docstring says."""
    return _reduction(tuple(float(w) for w in np.asarray(wavelengths, dtype=np.float64)))


def boxes(wavelengths: FloatArray) -> FloatArray:
    """(3, Λ): 1 at the wavelengths of the red (> 580 nm), green (490–580 nm) and blue
    (≤ 490 nm) boxes, 0 elsewhere; they add up to a flat spectrum."""
    lam = np.asarray(wavelengths, dtype=np.float64)
    blue = lam <= BOXES[0]
    green = (lam > BOXES[0]) & (lam <= BOXES[1])
    return np.stack([~(blue | green), green, blue]).astype(np.float64)


def upsampling(wavelengths: FloatArray) -> FloatArray:
    """The matrix (3, Λ) taking linear RGB to a spectrum at ``wavelengths`` that
    `reduction` takes back to the same RGB: a combination of the three `boxes` (grey
    stays flat; a saturated colour may need a negative box)."""
    basis = boxes(wavelengths)
    seen = basis @ reduction(wavelengths)  # (3 boxes, 3 channels)
    return np.asarray(np.linalg.solve(seen.T, np.eye(3)).T @ basis)


@dataclass(frozen=True)
class Material:
    """A read ``.bsdf`` file: its interpolants and what the file says of itself."""

    description: str
    isotropic: bool
    jacobian: bool
    reduction: int
    wavelengths: FloatArray | None
    ndf: Table
    sigma: Table
    vndf: Marginal2D
    rgb: Table


def read_material(path: str | Path) -> Material:
    """The material of the ``.bsdf`` file at ``path`` (the last few read are kept);
    `GonioError` (one line naming the file and the field) for a file Mitsuba's
    ``measured`` plugin would refuse, or with values that are not finite."""
    path = Path(path)
    try:
        info = path.stat()
    except OSError as exc:
        raise GonioError(f"{path}: cannot read the RGL file: {exc.strerror or exc}") from None
    return _read(str(path.resolve()), info.st_mtime_ns, info.st_size)


def _need(path: str, ok: bool, field: str, expected: str) -> None:
    if not ok:
        raise GonioError(f"{path}: RGL field {field}: expected {expected}")


@functools.lru_cache(maxsize=4)
def _read(path: str, _mtime_ns: int, _size: int) -> Material:
    fields = tensor_file.read(path)
    spectral = "wavelengths" in fields
    colour = "spectra" if spectral else "rgb"
    for name in (*FLOAT_FIELDS, "description", "jacobian", colour):
        _need(path, name in fields, name, "a field of that name (not in the file)")
    f32, u8 = np.dtype("<f4"), np.dtype("u1")
    for name in (*FLOAT_FIELDS, colour, *(("wavelengths",) if spectral else ())):
        _need(path, fields[name].dtype == f32, name, f"float32, got {fields[name].dtype}")
        _need(path, bool(np.all(np.isfinite(fields[name]))), name, "finite values (NaN or inf)")
        absurd = beyond_bound(fields[name].astype(np.float64))
        if absurd is not None:
            raise GonioError(f"{path}: RGL field {name}: {absurd}")
    for name in ("description", "jacobian"):
        _need(path, fields[name].dtype == u8, name, f"uint8, got {fields[name].dtype}")
    theta, phi = fields["theta_i"], fields["phi_i"]
    ndf, sigma, vndf, lum, values = (
        fields[k] for k in ("ndf", "sigma", "vndf", "luminance", colour)
    )
    lam = fields.get("wavelengths")
    channels = len(lam) if lam is not None and lam.ndim == 1 else 3
    for name, a in (("theta_i", theta), ("phi_i", phi), ("wavelengths", lam)):
        if a is not None:
            _need(path, a.ndim == 1 and len(a) >= 1, name, "one dimension")
            _need(path, bool(np.all(np.diff(a) > 0)), name, "increasing values")
    _need(path, fields["description"].ndim == 1, "description", "one dimension")
    _need(path, fields["jacobian"].shape == (1,), "jacobian", "shape [1]")
    for name, a in (("ndf", ndf), ("sigma", sigma)):
        _need(path, a.ndim == 2 and min(a.shape) >= 2, name, "two dimensions of at least 2")
    grid = (len(phi), len(theta))
    _need(path, vndf.ndim == 4 and vndf.shape[:2] == grid, "vndf", f"shape {list(grid)} + [H, W]")
    _need(path, min(vndf.shape[2:]) >= 2, "vndf", "H, W of at least 2")
    n = values.shape[-1] if values.ndim == 5 else 0
    shape = (*grid, channels, n, n)
    _need(path, values.shape == shape and n >= 2, colour, f"shape [Nφ, Nθ, {channels}, n, n]")
    _need(path, lum.shape == (*grid, n, n), "luminance", f"shape {[*grid, n, n]}")
    for name, a in (("ndf", ndf), ("vndf", vndf)):
        _need(path, bool(np.all(a >= 0)), name, "non-negative values")
    _need(path, bool(np.all(sigma > 0)), "sigma", "positive values")
    isotropic = len(phi) <= 2
    reduce_by = 1
    if not isotropic:
        reduce_by = int(np.rint(2 * np.pi / (float(phi[-1]) - float(phi[0]))))
        _need(path, reduce_by in (1, 2, 4), "phi_i", "a span of 2π, π or π/2")
    params = (phi.astype(np.float64), theta.astype(np.float64))
    try:
        warp = Marginal2D(vndf, params)
    except ValueError:
        raise GonioError(f"{path}: RGL field vndf: expected no slice of zero density") from None
    if lam is not None:
        values = np.einsum("pqlhw,lc->pqchw", values.astype(np.float64), reduction(lam))
    return Material(
        description=bytes(fields["description"]).decode("utf-8", "replace"),
        isotropic=isotropic,
        jacobian=bool(fields["jacobian"][0]),
        reduction=reduce_by,
        wavelengths=None if lam is None else lam.astype(np.float64),
        ndf=Table(ndf),
        sigma=Table(sigma),
        vndf=warp,
        rgb=Table(values, (*params, np.arange(3.0))),
    )


def elevation(d: FloatArray) -> FloatArray:
    """θ (rad) of unit vectors (..., 3), accurate near the pole: 2·asin(|d − n|/2)."""
    dz = d[..., 2] - 1.0
    chord = np.sqrt(d[..., 0] ** 2 + d[..., 1] ** 2 + dz * dz)
    return np.asarray(2.0 * np.arcsin(np.minimum(0.5 * chord, 1.0)))


def theta_to_u(theta: FloatArray) -> FloatArray:
    return np.asarray(np.sqrt(np.maximum(theta, 0.0) * (2.0 / np.pi)))


def phi_to_u(phi: FloatArray) -> FloatArray:
    return np.asarray((phi + np.pi) / (2.0 * np.pi))


def evaluate(material: Material, wi: FloatArray, wo: FloatArray) -> FloatArray:
    """f (..., 3) in sr⁻¹ of ``material`` at pairs (..., 3) above the surface."""
    wi, wo = np.broadcast_arrays(np.asarray(wi, np.float64), np.asarray(wo, np.float64))
    if material.reduction >= 2:
        sy = np.copysign(1.0, wi[..., 1])
        sx = np.copysign(1.0, wi[..., 0]) if material.reduction == 4 else sy
        flip = np.stack([-sx, -sy, np.ones_like(sx)], axis=-1)
        wi, wo = wi * flip, wo * flip
    wm = wi + wo
    wm = wm / np.linalg.norm(wm, axis=-1, keepdims=True)
    theta_i, phi_i = elevation(wi), np.arctan2(wi[..., 1], wi[..., 0])
    theta_m, phi_m = elevation(wm), np.arctan2(wm[..., 1], wm[..., 0])
    u_wi = np.stack([theta_to_u(theta_i), phi_to_u(phi_i)], axis=-1)
    um_y = phi_to_u(phi_m - phi_i if material.isotropic else phi_m)
    u_m = np.stack([theta_to_u(theta_m), um_y - np.floor(um_y)], axis=-1)
    s = material.vndf.invert(u_m, (phi_i, theta_i))
    channel = np.arange(3.0)
    f = material.rgb.eval(s[..., None, :], (phi_i[..., None], theta_i[..., None], channel))
    if material.jacobian:
        f = f * (material.ndf.eval(u_m) / (4.0 * material.sigma.eval(u_wi)))[..., None]
    return np.asarray(f / np.maximum(wo[..., 2], MIN_COSINE)[..., None])


class RglTable(BRDF):
    """A BRDF read from an RGL ``.bsdf`` file (spectral or RGB; isotropic or not),
    evaluated as the module docstring says; ``path``: the file."""

    name = "rgl"
    physically_based = False

    def __init__(self, path: object) -> None:
        name, self.material = read_path(path, read_material)
        super().__init__({"path": name})
        self.is_rgb = True

    def _eval(self, p: Pair) -> FloatArray:
        # Pairs below the horizon are discarded by `eval`; the normal stands in for them.
        normal = np.array([0.0, 0.0, 1.0])
        above = p.above[..., None]
        wi = np.where(above, np.stack([p.xi, p.yi, p.zi], axis=-1), normal)
        wo = np.where(above, np.stack([p.xo, p.yo, p.zo], axis=-1), normal)
        return evaluate(self.material, wi, wo)
