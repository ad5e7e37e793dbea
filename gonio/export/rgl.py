"""``--format rgl``: a reconstruction as an isotropic RGL ``.bsdf`` file (Dupuy & Jakob
2018; Mitsuba 3's ``measured`` plugin; layout in `gonio.brdf.rgl` and
docs/reference/formats.md#rgl), written with ``jacobian`` = 1.

How the fields are computed from the reconstruction f:

1. ``ndf``: the normal distribution D(θm) retrieved from f's retro-reflection by power
   iteration (Dupuy et al. 2015, the acquisition's own first step): for a microfacet
   surface f(ω, ω) = F(0)·D(ω)/(4 cos θ σ(ω)) with σ(ω) = ∫ D(m) max(0, ω·m) dm, so
   D ← f(ω, ω)·cos θ·σ_D(ω), normalized to ∫ D(m) cos θm dm = 1, iterated
   `POWER_ITERATIONS` times from D = f(ω, ω)·cos θ on `NDF_NODES` nodes uniform in
   u(θ) = √(θ/(π/2)). Retro-reflection values below `FLOOR` × their maximum are raised
   to it, so D is positive everywhere and every direction can be sampled.
2. ``sigma``: σ(θ) = ∫ D(m) max(0, ω·m) dm of that D, by quadrature (the inner azimuthal
   integral in closed form).
3. ``vndf``: per incident node θi (`THETA_I` nodes from 0 to `THETA_MAX`), the visible
   normals' density max(0, ωi·m)·D(m)/σ(θi) times the Jacobian 2π²·u·sin θm of the
   (u(θm), u(φm)) square, on `VNDF_SHAPE` nodes (φm measured from φi), normalized
   to mean 1 and mixed with `UNIFORM` (a constant): the visible normals' density
   vanishes as u³ at the pole, which would leave the first column of the warped
   square a band of half vectors several degrees wide.
4. ``spectra`` / ``rgb``: at the `SAMPLES` × `SAMPLES` nodes s of the warped square,
   the value f(ωi, ωo)·cos θo·4σ(θi)/D(ωm) with ωm = V(s) (the reader's own warp, ndf and sigma
   interpolants, so reading back is exact at the nodes), ωo = ωm mirrored about ωi;
   below the horizon, the value at ωo lifted to 0.5° elevation (so interpolation does
   not pull the last samples above the horizon to 0). For a microfacet surface this
   value is F·G2(ωi, ωo)/G1(ωi), bounded by the Fresnel factor: smooth where f peaks.
5. ``luminance`` (the renderer's sampling guide only): the Rec. 709 luminance of that
   value, raised to `FLOOR` × its slice's maximum.

Colour: an RGB reconstruction is written as ``rgb`` (``color="rgb"``) or as a spectrum
(``color="spectral"``, the default: the three boxes of `gonio.brdf.rgl.upsampling`,
which read back to the same RGB); a one-band reconstruction is written grey (luminance
band) or in its channel (r, g, b) as RGB, and as a spectrum flat over the visible
(luminance band) or over its channel's box, scaled to read back the value in that
band. The reconstruction's extrapolation fills every pair outside the measured support
(the format has no missing values); the summary says how many there are.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from gonio.brdf import Marginal2D, Table, rgl, tensor_file
from gonio.errors import GonioError
from gonio.export.steps import evaluated, reconstructed, sparse_note, step
from gonio.output import PendingOutput
from gonio.radiometry import LUMINANCE
from gonio.store import Run
from gonio.types import FloatArray, Surface

if TYPE_CHECKING:
    from gonio.export import Options

#: Incident elevation nodes, uniform from 0 to THETA_MAX (rad).
THETA_I = 16
THETA_MAX = np.radians(89.0)
#: Nodes of the warped square per side (the ``spectra`` / ``rgb`` tables).
SAMPLES = 32
#: (φm rows, u(θm) columns) of the ``vndf`` table.
VNDF_SHAPE = (64, 64)
#: Nodes in u(θ) of ``ndf`` and ``sigma`` (2 rows in φ: isotropic).
NDF_NODES = 128
POWER_ITERATIONS = 8
FLOOR = 1e-3
#: Weight of the uniform density mixed into the warp (relative to the visible normals'
#: mean density on the square): samples near the pole, where the visible normals'
#: density vanishes as u³.
UNIFORM = 0.5
#: Wavelengths (nm) of a spectral file.
WAVELENGTHS = np.arange(360.0, 831.0, 10.0)
COLORS = ("spectral", "rgb")
BANDS = ("luminance", "r", "g", "b")
#: Elevation (rad) below-horizon outgoing directions are lifted to.
LIFT = np.radians(0.5)


def direction(theta: ArrayLike, phi: ArrayLike) -> FloatArray:
    """Unit vectors (..., 3) at elevations ``theta`` and azimuths ``phi`` (rad)."""
    st = np.sin(theta)
    return np.stack(np.broadcast_arrays(st * np.cos(phi), st * np.sin(phi), np.cos(theta)), -1)


def projected_area(d: FloatArray, theta_m: FloatArray, theta: FloatArray) -> FloatArray:
    """σ(θ) = ∫ D(m) max(0, ω·m) dm for an isotropic D given at ``theta_m`` (uniform in
    u(θm), from 0 to π/2), at elevations ``theta``; trapezoids in u, dθ = π u du."""
    u = rgl.theta_to_u(theta_m)
    a = np.cos(theta)[:, None] * np.cos(theta_m)[None]
    b = np.sin(theta)[:, None] * np.sin(theta_m)[None]
    # ∫₀^{2π} max(0, a + b cos φ) dφ in closed form.
    ratio = np.clip(-a / np.where(b > 0, b, 1.0), -1.0, 1.0)
    phi0 = np.arccos(ratio)
    ring = np.where(b > 0, 2.0 * (a * phi0 + b * np.sin(phi0)), 2 * np.pi * np.maximum(a, 0.0))
    integrand = ring * d[None] * np.sin(theta_m)[None] * np.pi * u[None]
    return np.asarray(np.trapezoid(integrand, u, axis=-1))


def power_iteration(retro: FloatArray, theta_m: FloatArray) -> FloatArray:
    """D at ``theta_m`` from the retro-reflection ``retro`` there (module docstring)."""
    u = rgl.theta_to_u(theta_m)
    f = np.maximum(retro, FLOOR * np.max(retro))
    d = f * np.cos(theta_m)
    for _ in range(POWER_ITERATIONS):
        d = d / np.trapezoid(2 * np.pi * d * np.cos(theta_m) * np.sin(theta_m) * np.pi * u, u)
        d = f * np.cos(theta_m) * projected_area(d, theta_m, theta_m)
    return d / np.trapezoid(2 * np.pi * d * np.cos(theta_m) * np.sin(theta_m) * np.pi * u, u)


class _Counter:
    """Evaluates the reconstruction as one channel or RGB, counting pairs outside its
    support and values that are not finite (written 0)."""

    def __init__(self, surface: Surface) -> None:
        self.surface, self.pairs, self.unsupported, self.bad = surface, 0, 0, 0

    def __call__(self, wi: FloatArray, wo: FloatArray, description: str) -> FloatArray:
        f, ok = evaluated(self.surface, wi, wo, description)
        self.pairs += wi[..., 0].size
        self.unsupported += 0 if ok is None else int(np.count_nonzero(~ok))
        finite = np.isfinite(f)
        self.bad += int(np.count_nonzero(~finite))
        return np.where(finite, np.maximum(f, 0.0), 0.0)


def _grey(f: FloatArray) -> FloatArray:
    return f @ np.asarray(LUMINANCE) if f.ndim > 1 and f.shape[-1] == 3 else f


def colour_matrix(channels: int, band: str, color: str) -> tuple[FloatArray, FloatArray | None]:
    """The matrix (channels, C) taking the reconstruction's values to the file's colour
    values (C = 3 for RGB, Λ for a spectrum), and the wavelengths (None for RGB)."""
    if band not in BANDS:
        raise GonioError(f"band {band!r}: expected one of {', '.join(BANDS)}")
    if color not in COLORS:
        raise GonioError(f"color {color!r}: expected one of {', '.join(COLORS)}")
    spectral = color == "spectral"
    if channels == 3:
        return (rgl.upsampling(WAVELENGTHS) if spectral else np.eye(3)), (
            WAVELENGTHS if spectral else None
        )
    if band == "luminance":
        row = np.ones((1, len(WAVELENGTHS) if spectral else 3))
        return row, (WAVELENGTHS if spectral else None)
    c = "rgb".index(band)
    if not spectral:
        return np.eye(3)[c : c + 1], None
    box = rgl.boxes(WAVELENGTHS)[c]
    return (box / (box @ rgl.reduction(WAVELENGTHS))[c])[None], WAVELENGTHS


def fields(
    surface: Surface,
    *,
    band: str = "luminance",
    color: str = "spectral",
    description: str = "",
    theta_nodes: int = THETA_I,
    samples: int = SAMPLES,
) -> tuple[dict[str, np.ndarray | str], _Counter]:
    """The file's fields for ``surface`` (one channel seen in ``band``, or RGB), with
    ``theta_nodes`` incident elevations and ``samples`` × ``samples`` values per
    elevation and colour, and the counter of the pairs evaluated."""
    f = _Counter(surface)
    # 1–2: NDF and projected area.
    u_fine = np.linspace(0.0, 1.0, NDF_NODES)
    theta_m = u_fine**2 * (np.pi / 2)
    w = direction(np.minimum(theta_m, np.radians(89.5)), 0.0)
    retro = _grey(f(w, w, "evaluating the retro-reflection"))
    if not np.max(retro) > 0:
        raise GonioError("the reconstruction's retro-reflection is 0 everywhere: no NDF")
    d = power_iteration(retro, theta_m)
    sigma = projected_area(d, theta_m, theta_m)
    ndf32 = np.tile(d.astype(np.float32), (2, 1))
    sigma32 = np.tile(sigma.astype(np.float32), (2, 1))
    ndf_t, sigma_t = Table(ndf32), Table(sigma32)
    # 3: the visible normals on the (u(θm), u(φm)) square, per incident node.
    theta_i = np.linspace(0.0, THETA_MAX, theta_nodes)
    h, wn = VNDF_SHAPE
    ux, uy = np.meshgrid(np.linspace(0, 1, wn), np.linspace(0, 1, h))
    u_grid = np.stack([ux, uy], axis=-1)
    tm, pm = ux**2 * (np.pi / 2), (2 * uy - 1) * np.pi
    m = direction(tm, pm)
    wi_nodes = direction(theta_i, 0.0)
    s_i = sigma_t.eval(np.stack([rgl.theta_to_u(theta_i), np.full(theta_nodes, 0.5)], -1))
    cosine = np.maximum(np.einsum("tk,hwk->thw", wi_nodes, m), 0.0)
    jac = 2 * np.pi**2 * ux * np.sin(tm)
    vndf = cosine * ndf_t.eval(u_grid)[None] / s_i[:, None, None] * jac[None]
    vndf = vndf / np.mean(vndf, axis=(1, 2), keepdims=True) + UNIFORM
    vndf32 = vndf[None].astype(np.float32)
    phi_nodes = np.zeros(1, dtype=np.float32)
    warp = Marginal2D(vndf32, (phi_nodes.astype(np.float64), theta_i.astype(np.float32)))
    # 4: the values at the warped square's nodes.
    sx, sy = np.meshgrid(np.linspace(0, 1, samples), np.linspace(0, 1, samples))
    s = np.broadcast_to(np.stack([sx, sy], -1), (theta_nodes, samples, samples, 2))
    t32 = theta_i.astype(np.float32).astype(np.float64)[:, None, None]
    u_m = warp.sample(s, (np.zeros(1), t32))
    wm = direction(u_m[..., 0] ** 2 * (np.pi / 2), (2 * u_m[..., 1] - 1) * np.pi)
    wi = np.broadcast_to(direction(t32, 0.0), wm.shape)
    wo = 2 * np.sum(wi * wm, axis=-1, keepdims=True) * wm - wi
    low = wo[..., 2] < np.sin(LIFT)
    # Straight down (no azimuth): lifted away from ωi.
    flat = np.where(
        np.hypot(wo[..., :1], wo[..., 1:2]) > 1e-9, wo[..., :2], -wi[..., :2] - [1e-3, 0]
    )
    flat = flat / np.linalg.norm(flat, axis=-1, keepdims=True)
    lifted = np.concatenate([flat * np.cos(LIFT), np.full_like(wo[..., 2:], np.sin(LIFT))], -1)
    wo = np.where(low[..., None], lifted, wo)
    half = (wi + wo) / np.linalg.norm(wi + wo, axis=-1, keepdims=True)
    th, ph = rgl.elevation(half), np.arctan2(half[..., 1], half[..., 0])
    uy_m = rgl.phi_to_u(ph)
    u_half = np.stack([rgl.theta_to_u(th), uy_m - np.floor(uy_m)], -1)
    u_wi = np.stack([rgl.theta_to_u(t32), np.full(t32.shape, 0.5)], -1)
    scale = wo[..., 2] * 4 * sigma_t.eval(u_wi) / np.maximum(ndf_t.eval(u_half), 1e-30)
    values = f(wi, wo, "evaluating the tabulated values")
    channels = 3 if values.ndim == 4 else 1
    if channels == 1:
        values = values[..., None]
    matrix, wavelengths = colour_matrix(channels, band, color)
    stored = values * scale[..., None] @ matrix  # (θ, n, n, C)
    stored = np.moveaxis(stored, -1, 1)[None].astype(np.float32)  # (1, θ, C, n, n)
    # 5: the sampling guide.
    rgb = (
        values
        * scale[..., None]
        @ (matrix @ rgl.reduction(wavelengths) if wavelengths is not None else matrix)
    )
    lum = np.maximum(rgb @ np.asarray(LUMINANCE), 0.0)
    lum = np.maximum(lum, FLOOR * np.max(lum, axis=(1, 2), keepdims=True) + 1e-30)
    out: dict[str, np.ndarray | str] = {
        "description": description,
        "jacobian": np.ones(1, dtype=np.uint8),
        "theta_i": theta_i.astype(np.float32),
        "phi_i": phi_nodes,
        "ndf": ndf32,
        "sigma": sigma32,
        "vndf": vndf32,
        "luminance": lum[None].astype(np.float32),
    }
    if wavelengths is not None:
        out["wavelengths"] = wavelengths.astype(np.float32)
        out["spectra"] = stored
    else:
        out["rgb"] = stored
    return out, f


def write(
    out: PendingOutput,
    surface: Surface,
    *,
    band: str = "luminance",
    color: str = "spectral",
    description: str = "",
    theta_nodes: int = THETA_I,
    samples: int = SAMPLES,
    allow_sparse: bool = False,
) -> str:
    """Compute the fields (`fields`) and write the file to ``out``; the one-line summary
    (and a warning line for a sparse run written with ``allow_sparse``; `sparse_note`)."""
    table, counter = fields(
        surface,
        band=band,
        color=color,
        description=description,
        theta_nodes=theta_nodes,
        samples=samples,
    )
    supported = counter.pairs - counter.unsupported
    note = sparse_note(supported, counter.pairs, "RGL pairs", allow=allow_sparse)
    with step("writing"):
        data = tensor_file.to_bytes(table)
        out.write_bytes(data)
    kind = f"{len(WAVELENGTHS)} wavelengths" if "spectra" in table else "RGB"
    n = np.shape(table["luminance"])
    return (
        f"wrote {out.path} (RGL .bsdf, {len(data)} bytes): isotropic, {n[1]} incident "
        f"elevations × {n[2]}×{n[3]} samples, {kind}; {counter.unsupported} of "
        f"{counter.pairs} pairs evaluated outside the measured support (extrapolated)"
        + (f", {counter.bad} non-finite values written 0" if counter.bad else "")
        + (f"\n{note}" if note else "")
    )


def export_run(run: Run, out: PendingOutput, options: Options) -> str:
    measured, surface = reconstructed(
        run, options.method, extrapolate="nearest", allow_sparse=options.allow_sparse
    )
    text = f"gonio export of {run.path.name}: {options.method} reconstruction, "
    text += f"{measured.band} band"
    return write(
        out,
        surface,
        band=measured.band,
        color=options.rgl_color,
        description=text,
        allow_sparse=options.allow_sparse,
    )
