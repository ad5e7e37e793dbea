"""A factored BRDF read from its files (Lawrence et al. 2004): eval and sampling.

``create("factored", path=...)`` reads the factor file ``path`` and its CDF file
``path + ".cdf"`` (`gonio.brdf.factored_file`). Conventions as everywhere in gonio: ``wi``
toward the light, ``wo`` toward the detector (the view), unit vectors (..., 3), z = normal.

eval: f(wi, wo) = Σⱼ Fⱼ(θo, φo) Gⱼ(θh, φh) / cos θi' (sr⁻¹), looked up in the bins of
(wo, ĥ): the files hold f · cos θi, the cosine of the *sampled* direction (see
docs/reference/formats_factored.md for why not the seed's cos θo), tabulated at the bins'
centres, and θi' is the θi of those centres. 0 where cos θi = 0 or cos θi' ≤ 0. RGB
files multiply by Fc(ωo) Gc(ĥ) per channel.

Sampling, given the view ``wo``, draws the halfway vector ĥ from the mixture of the
L = J·K terms Fⱼ(ωo) uⱼₖ(θh) vⱼₖ(φh), term (j, k) chosen with probability ∝ its energy
Fⱼ(ωo) ∫∫ uⱼₖ vⱼₖ dz dφ; φh and z = 1 − cos θh by inverting the term's piecewise-linear
CDFs (dωh = dz dφ, so a density in (z, φ) is one per steradian); then
wi = 2 (wo·ĥ) ĥ − wo, with density p(ĥ) / (4 |wo·ĥ|). The map ĥ ↦ wi is one-to-one from
the upper hemisphere onto the whole sphere, so the density integrates to 1 over the
sphere: draws below the horizon (wi_z < 0) are returned as they are, with their
density, and carry f = 0. Over the upper hemisphere it integrates to
1 − P(wi_z < 0 | wo).
"""

from __future__ import annotations

from os import PathLike
from pathlib import Path

import numpy as np

from gonio.brdf import factored_file as ff
from gonio.brdf.base import BRDF
from gonio.brdf.geometry import Pair
from gonio.directions import as_direction_pair, in_upper_hemisphere
from gonio.errors import DomainError
from gonio.params import direction, polar
from gonio.types import ArrayLike, FloatArray


class Factored(BRDF):
    """A tabulated BRDF in the factored representation; ``path`` names the factor file."""

    name = "factored"
    reciprocal = False
    physically_based = False

    def __init__(self, path: str | PathLike[str]) -> None:
        if not isinstance(path, str | PathLike):
            raise DomainError(f"parameter path must be a file name, got {path!r}")
        super().__init__({"path": str(path)})
        t = ff.read(Path(path))
        self.tables = t
        self.is_rgb = bool(np.ptp(t.Fc, axis=-1).any() or np.ptp(t.Gc, axis=-1).any())
        n_phi, n_z = t.cdf_phi.shape[1], t.z_count
        #: Per-term densities in φ (per radian) and in z, piecewise constant per bin.
        self._density_phi = np.diff(t.cdf_phi, axis=1, prepend=0.0) * (n_phi / ff.TWO_PI)
        self._density_z = np.diff(t.cdf_z, axis=1, prepend=0.0) * n_z
        dz = ff.cell_dz(t.G.shape[1])
        dphi = ff.TWO_PI / n_phi
        #: ∫∫ uⱼₖ vⱼₖ dz dφ, shape (J, K): the term's energy per unit of Fⱼ.
        self._energy = (t.u @ dz) * (t.v.sum(axis=-1) * dphi)

    @property
    def isotropic(self) -> bool:
        return False

    # -- evaluation ----------------------------------------------------------------------

    def _view_bins(
        self, x: FloatArray, y: FloatArray, z: FloatArray
    ) -> tuple[ff.IntArray, ff.IntArray]:
        theta, phi = polar(x, y, np.maximum(z, 0.0))
        n_theta, n_phi = self.tables.F.shape[1:]
        return ff.bin_index(theta, ff.HALF_PI, n_theta), ff.bin_index(phi, ff.TWO_PI, n_phi)

    def _halfway_bins(self, theta: FloatArray, phi: FloatArray) -> tuple[ff.IntArray, ff.IntArray]:
        n_theta, n_phi = self.tables.G.shape[1:]
        return ff.bin_index(theta, ff.HALF_PI, n_theta), ff.bin_index(phi, ff.TWO_PI, n_phi)

    def _eval(self, p: Pair) -> FloatArray:
        t = self.tables
        # 1-d components: the angle helpers work in place on arrays, not numpy scalars.
        xo, yo, zo, ci = (np.ravel(a) for a in (p.xo, p.yo, p.zo, p.ci))
        hx, hy, hz = (np.ravel(a) for a in p.halfway())
        io, jo = self._view_bins(xo, yo, zo)
        norm = np.sqrt(hx * hx + hy * hy + hz * hz)
        norm = np.where(norm > 0.0, norm, 1.0)
        ih, jh = self._halfway_bins(*polar(hx / norm, hy / norm, np.maximum(hz, 0.0) / norm))
        intensity = np.sum(t.F[:, io, jo] * t.G[:, ih, jh], axis=0)
        # cos θi of the pair of bin centres the table was sampled at: f is looked up
        # bin by bin, and f cos θi → 0 at the horizon (dividing by the pair's own
        # cos θi would turn a bin's value into a 1/cos θi spike there).
        c = self._centre_cos_i(io, jo, ih, jh)
        f = np.where((c > 0.0) & (ci > 0.0), intensity / np.where(c > 0.0, c, 1.0), 0.0)
        if not self.is_rgb:
            return np.asarray(f.reshape(p.shape), dtype=np.float64)
        rgb = f[:, None] * t.Fc[io, jo] * t.Gc[ih, jh]
        return np.asarray(rgb.reshape(*p.shape, 3), dtype=np.float64)

    def _centre_cos_i(
        self, io: ff.IntArray, jo: ff.IntArray, ih: ff.IntArray, jh: ff.IntArray
    ) -> FloatArray:
        """cos θi of wi = 2 (wo·ĥ) ĥ − wo for wo, ĥ at the centres of their bins."""
        (n_to, n_po), (n_th, n_ph) = self.tables.F.shape[1:], self.tables.G.shape[1:]
        wo = direction((io + 0.5) * (ff.HALF_PI / n_to), (jo + 0.5) * (ff.TWO_PI / n_po))
        h = direction((ih + 0.5) * (ff.HALF_PI / n_th), (jh + 0.5) * (ff.TWO_PI / n_ph))
        return np.asarray(2.0 * np.sum(wo * h, axis=-1) * h[:, 2] - wo[:, 2], dtype=np.float64)

    # -- sampling ------------------------------------------------------------------------

    def term_probabilities(self, wo: FloatArray) -> FloatArray:
        """P(term j·K + k | wo), shape (N, L) for wo (N, 3).

        ∝ Fⱼ(wo) ∫∫ uⱼₖ vⱼₖ; where every Fⱼ(wo) is 0, ∝ the energies alone; where
        those are 0 too (an all-zero file), uniform.
        """
        io, jo = self._view_bins(wo[:, 0], wo[:, 1], wo[:, 2])
        energy = self._energy.reshape(-1)
        w = (self.tables.F[:, io, jo].T[:, :, None] * self._energy[None]).reshape(len(wo), -1)
        fallback = energy if energy.sum() > 0.0 else np.ones_like(energy)
        total = w.sum(axis=1, keepdims=True)
        w = np.where(total > 0.0, w, fallback[None, :])
        return np.asarray(w / w.sum(axis=1, keepdims=True), dtype=np.float64)

    def _halfway_density(self, weights: FloatArray, z: FloatArray, phi: FloatArray) -> FloatArray:
        """p(ĥ) per steradian: Σ_terms P(term) p(z | term) p(φ | term)."""
        iz = ff.bin_index(z, 1.0, self._density_z.shape[1])
        ip = ff.bin_index(phi, ff.TWO_PI, self._density_phi.shape[1])
        terms = weights.T * self._density_z[:, iz] * self._density_phi[:, ip]
        return np.asarray(terms.sum(axis=0), dtype=np.float64)

    def sample(self, wo: ArrayLike, u: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """(wi, pdf) drawn given the view ``wo`` from uniforms ``u`` in [0, 1), shape (..., 3).

        u[..., 0] picks the term, u[..., 1] φh, u[..., 2] z. pdf is per steradian of wi;
        wi may lie below the horizon (see the module docstring). Shapes broadcast.
        """
        w, r = as_direction_pair(wo, u)
        if not np.all(in_upper_hemisphere(w[..., 0], w[..., 1], w[..., 2])):
            raise DomainError("sample: wo must be unit vectors in the upper hemisphere")
        if np.any(~np.isfinite(r)) or np.any(r < 0.0) or np.any(r >= 1.0):
            raise DomainError("sample: u must lie in [0, 1)")
        lead = w.shape[:-1]
        w, r = w.reshape(-1, 3), r.reshape(-1, 3)
        weights = self.term_probabilities(w)
        cum = np.cumsum(weights, axis=1)
        term = np.minimum((cum < r[:, :1] * cum[:, -1:]).sum(axis=1), cum.shape[1] - 1)
        phi = _invert(self.tables.cdf_phi, term, r[:, 1]) * (ff.TWO_PI / self._density_phi.shape[1])
        z = _invert(self.tables.cdf_z, term, r[:, 2]) / self._density_z.shape[1]
        theta = 2.0 * np.arcsin(np.sqrt(0.5 * z))  # acos(1 − z), accurate for small z
        h = direction(theta, phi)
        d = np.sum(w * h, axis=1)
        wi = 2.0 * d[:, None] * h - w
        p_h = self._halfway_density(weights, z, phi)
        pdf = np.where(d != 0.0, p_h / np.where(d != 0.0, 4.0 * np.abs(d), 1.0), 0.0)
        return wi.reshape(*lead, 3), pdf.reshape(lead)

    def pdf(self, wo: ArrayLike, wi: ArrayLike) -> FloatArray:
        """The density per steradian with which `sample` draws ``wi`` given ``wo``.

        Defined on the whole sphere of wi; 0 where wi = −wo or wo·ĥ = 0 (measure zero).
        """
        w, i = as_direction_pair(wo, wi)
        lead = w.shape[:-1]
        w, i = w.reshape(-1, 3), i.reshape(-1, 3)
        s = w + i
        norm = np.linalg.norm(s, axis=1)
        sign = np.where(s[:, 2] < 0.0, -1.0, 1.0)
        h = s * (sign / np.where(norm > 0.0, norm, 1.0))[:, None]
        theta, phi = polar(h[:, 0], h[:, 1], h[:, 2])
        z = 2.0 * np.sin(0.5 * theta) ** 2  # 1 − cos θh without cancellation
        d = np.abs(np.sum(w * h, axis=1))
        p_h = self._halfway_density(self.term_probabilities(w), z, phi)
        ok = (norm > 0.0) & (d > 0.0)
        return np.where(ok, p_h / np.where(ok, 4.0 * d, 1.0), 0.0).reshape(lead)


def _invert(cdf: FloatArray, term: ff.IntArray, x: FloatArray) -> FloatArray:
    """The position in bins, in [0, n], where row ``term`` of ``cdf`` (L, n) reaches ``x``.

    One binary search over all rows at once: row t is offset by t, so the rows laid end
    to end stay non-decreasing. Linear inside the bin (a piecewise-constant density).
    """
    n = cdf.shape[1]
    flat = (cdf + np.arange(cdf.shape[0], dtype=np.float64)[:, None]).ravel()
    b = np.clip(np.searchsorted(flat, term + x, side="right") - term * n, 0, n - 1)
    hi = cdf[term, b]
    lo = np.where(b > 0, cdf[term, np.maximum(b - 1, 0)], 0.0)
    width = hi - lo
    frac = np.where(width > 0.0, (x - lo) / np.where(width > 0.0, width, 1.0), 0.5)
    return np.asarray(b + np.clip(frac, 0.0, 1.0), dtype=np.float64)
