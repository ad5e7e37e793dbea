"""Export a BRDF as the factored representation of Lawrence et al. 2004.

`factorize` tabulates y = f(ωi, ωo) cos θi on bin centres of (θo, φo) × (θh, φh)
(ωi = 2 (ωo·ĥ) ĥ − ωo; 0 where ωi is below the horizon), factors the intensity
(mean of the channels) by non-negative matrix factorization (scikit-learn's `NMF`,
coordinate descent, NNDSVDa start) into J outer terms Fⱼ(ωo) Gⱼ(ĥ), each Gⱼ (as a
θh × φh matrix) into K inner terms uⱼₖ(θh) vⱼₖ(φh), fits the colour factors, and builds
the CDFs. `export` writes the two files (`gonio.brdf.factored_file`) atomically.

Normalization (the file format leaves it free; the reader does not rely on it):
∫ Gⱼ dωh = 1 (the scale goes into Fⱼ), ∫ uⱼₖ dz = 1 (into vⱼₖ), so Fⱼ(ωo) is the energy
of outer term j at ωo and ∫ vⱼₖ dφ the share of inner term k in it.

Colour (RGB models): per channel c a single term Fc_c(ωo) Gc_c(ĥ) fitted by weighted
least squares, min Σ (y_c − Fc_c Gc_c Î)², Î = Σⱼ FⱼGⱼ the factored intensity, by
alternating closed-form updates (a rank-1 fit with weights; scikit-learn has no
weighted NMF). The seed fits the ratio y_c / Î unweighted, which lets pairs where the
BRDF is ~0 (and the ratio is noise) weigh as much as the lobe.
"""

from __future__ import annotations

import warnings
from contextlib import ExitStack
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from gonio.brdf import factored_file as ff
from gonio.errors import GonioError
from gonio.export.steps import evaluated, reconstructed, sparse_note, step
from gonio.output import PendingOutput, reserve_output
from gonio.params import direction
from gonio.store import Run
from gonio.types import Evaluable, FloatArray

if TYPE_CHECKING:
    from gonio.export import Options

#: Alternating updates of the colour fit: 5 already reach the fit's floor to 1e-12 in
#: the colour error (measured on gold-like Cook-Torrance and an RGB Lambert).
COLOUR_ITERATIONS = 10


@dataclass(frozen=True)
class Resolution:
    """Bin counts of the tables (equal bins; see `gonio.brdf.factored_file`)."""

    theta_out: int = 16
    phi_out: int = 32
    theta_p: int = 32
    phi_p: int = 64
    z: int = 1024


@dataclass(frozen=True)
class Factorization:
    """The tables and the relative Frobenius errors of the intensity matrix.

    ``outer_error`` = ‖Y − FG‖/‖Y‖, ``error`` = ‖Y − Σ F u v‖/‖Y‖ (what the sampler's
    terms hold), ``colour_error`` = ‖y_rgb − Fc Gc Î‖/‖y_rgb‖ (0 for grey models).
    """

    tables: ff.FactoredTables
    outer_error: float
    error: float
    colour_error: float


def table(model: Evaluable, res: Resolution) -> FloatArray:
    """y = f cos θi on the bin centres: (θo, φo, θh, φh), plus (3,) if f is RGB."""
    return supported_table(model, res)[0]


def supported_table(model: Evaluable, res: Resolution) -> tuple[FloatArray, int | None, int]:
    """`table`, the number of its lit bins (ωi above the horizon) the model's data
    supports (None when the model does not say) and the number of lit bins."""
    wo = _centres(res.theta_out, res.phi_out)[:, :, None, None, :]
    h = _centres(res.theta_p, res.phi_p)[None, None, :, :, :]
    d = np.sum(wo * h, axis=-1, keepdims=True)
    wi = 2.0 * d * h - wo
    wo = np.broadcast_to(wo, wi.shape)
    lit = wi[..., 2] > 0.0
    values, support = evaluated(model, wi[lit], wo[lit], "evaluating the table to factor")
    cos_i = wi[lit][:, 2]
    rgb = values.ndim == 2
    out = np.zeros(lit.shape + values.shape[1:], dtype=np.float64)
    out[lit] = values * (cos_i[:, None] if rgb else cos_i)
    supported = None if support is None else int(np.count_nonzero(support))
    return out, supported, int(np.count_nonzero(lit))


def _centres(n_theta: int, n_phi: int) -> FloatArray:
    theta = (np.arange(n_theta, dtype=np.float64) + 0.5) * (ff.HALF_PI / n_theta)
    phi = (np.arange(n_phi, dtype=np.float64) + 0.5) * (ff.TWO_PI / n_phi)
    return direction(theta[:, None], phi[None, :])


def _nmf(a: FloatArray, rank: int, seed: int, max_iter: int) -> tuple[FloatArray, FloatArray]:
    """W (m, rank), H (rank, n) ≥ 0 with A ≈ W H (Frobenius)."""
    try:
        from sklearn.decomposition import NMF  # optional: the factored extra
        from sklearn.exceptions import ConvergenceWarning  # optional: the factored extra
    except ImportError:
        raise GonioError(
            "the factored export needs scikit-learn: pip install 'gonio[factored]'"
        ) from None
    if not np.any(a > 0.0):
        return np.zeros((a.shape[0], rank)), np.zeros((rank, a.shape[1]))
    nmf = NMF(rank, init="nndsvda", solver="cd", max_iter=max_iter, tol=1e-6, random_state=seed)
    with warnings.catch_warnings():
        # Stopping at max_iter is a choice of the caller; the error is measured and kept.
        warnings.simplefilter("ignore", ConvergenceWarning)
        w = nmf.fit_transform(a)
    return np.asarray(w, dtype=np.float64), np.asarray(nmf.components_, dtype=np.float64)


def _colour(y: FloatArray, approx: FloatArray) -> tuple[FloatArray, FloatArray]:
    """a (m, 3), b (n, 3) ≥ 0 minimizing Σ (y[..., c] − a_c b_c approx)² per channel."""
    m, n = approx.shape
    a, b = np.ones((m, 3)), np.ones((n, 3))
    w2 = (approx * approx)[..., None]
    yw = y * approx[..., None]
    for _ in range(COLOUR_ITERATIONS):
        num, den = np.einsum("msc,sc->mc", yw, b), np.einsum("msc,sc->mc", w2, b * b)
        a = np.where(den > 0.0, num / np.where(den > 0.0, den, 1.0), 1.0)
        num, den = np.einsum("msc,mc->sc", yw, a), np.einsum("msc,mc->sc", w2, a * a)
        b = np.where(den > 0.0, num / np.where(den > 0.0, den, 1.0), 1.0)
    scale = b.mean(axis=0)  # a Gc of mean 1 per channel: the scale sits in Fc
    scale = np.where(scale > 0.0, scale, 1.0)
    return a * scale, b / scale


def factorize(
    model: Evaluable,
    outer: int = 2,
    inner: int = 2,
    res: Resolution | None = None,
    *,
    seed: int = 0,
    max_iter: int = 500,
) -> Factorization:
    """The factored representation of ``model`` with J = ``outer``, K = ``inner``."""
    res = res or Resolution()
    check_terms(outer, inner, res)
    return factorize_table(table(model, res), outer, inner, res, seed=seed, max_iter=max_iter)


def check_terms(outer: int, inner: int, res: Resolution) -> None:
    """`GonioError` unless J ≥ 1 and 1 ≤ K ≤ the inner matrix's smaller side."""
    if outer < 1 or inner < 1 or inner > min(res.theta_p, res.phi_p):
        raise GonioError(f"factored: need J ≥ 1 and 1 ≤ K ≤ {min(res.theta_p, res.phi_p)}")


def factorize_table(
    y: FloatArray, outer: int, inner: int, res: Resolution, *, seed: int = 0, max_iter: int = 500
) -> Factorization:
    """`factorize` of a `table` ``y`` already made."""
    rgb = y.ndim == 5
    rows, cols = res.theta_out * res.phi_out, res.theta_p * res.phi_p
    intensity = (y.mean(axis=-1) if rgb else y).reshape(rows, cols)
    with step(f"factorizing: {outer} outer terms, {inner} inner terms each"):
        F, G = _nmf(intensity, outer, seed, max_iter)
    dz = ff.cell_dz(res.theta_p)
    dphi = ff.TWO_PI / res.phi_p
    G3 = G.reshape(outer, res.theta_p, res.phi_p)
    mass = np.einsum("jab,a->j", G3, dz) * dphi
    scale = np.where(mass > 0.0, mass, 1.0)
    F, G3 = F * scale, G3 / scale[:, None, None]
    u, v = np.empty((outer, inner, res.theta_p)), np.empty((outer, inner, res.phi_p))
    for j in range(outer):  # J small factorizations, not a loop over samples
        with step(f"factorizing outer term {j + 1} of {outer}"):
            uj, vj = _nmf(G3[j], inner, seed, max_iter)
        norm = dz @ uj
        norm = np.where(norm > 0.0, norm, 1.0)
        u[j], v[j] = (uj / norm).T, vj * norm[:, None]
    approx = F @ G3.reshape(outer, cols)
    full = F @ np.einsum("jka,jkb->jab", u, v).reshape(outer, cols)
    size = max(float(np.linalg.norm(intensity)), np.finfo(np.float64).tiny)
    if rgb:
        a, b = _colour(y.reshape(rows, cols, 3), approx)
        fitted = a[:, None, :] * b[None, :, :] * approx[..., None]
        colour_error = float(np.linalg.norm(y.reshape(rows, cols, 3) - fitted))
        colour_error /= max(float(np.linalg.norm(y)), np.finfo(np.float64).tiny)
    else:
        a, b, colour_error = np.ones((rows, 3)), np.ones((cols, 3)), 0.0
    cdf_phi, cdf_z = ff.term_cdfs(u, v, res.z)
    tables = ff.FactoredTables(
        F=F.T.reshape(outer, res.theta_out, res.phi_out),
        G=G3,
        u=u,
        v=v,
        Fc=a.reshape(res.theta_out, res.phi_out, 3),
        Gc=b.reshape(res.theta_p, res.phi_p, 3),
        cdf_phi=cdf_phi,
        cdf_z=cdf_z,
    )
    return Factorization(
        tables=tables,
        outer_error=float(np.linalg.norm(intensity - approx)) / size,
        error=float(np.linalg.norm(intensity - full)) / size,
        colour_error=colour_error,
    )


def export(
    model: Evaluable,
    path: Path | str,
    outer: int = 2,
    inner: int = 2,
    res: Resolution | None = None,
    *,
    seed: int = 0,
) -> Factorization:
    """`factorize` ``model`` and `write` it; the outputs are reserved before the work."""
    p = Path(path)
    with ExitStack() as outputs:
        factors = outputs.enter_context(reserve_output(p, "factored file"))
        cdfs = outputs.enter_context(
            reserve_output(p.with_name(p.name + ff.CDF_SUFFIX), "factored CDF file")
        )
        result = factorize(model, outer, inner, res, seed=seed)
        factors.write_bytes(ff.format_factors(result.tables).encode("utf-8"))
        cdfs.write_bytes(ff.format_cdfs(result.tables).encode("utf-8"))
    return result


def export_run(run: Run, out: PendingOutput, options: Options) -> str:
    """`gonio export --format factored`: the run's reconstruction (filled by its nearest
    sample outside the measured support: the factorization needs every bin) factored
    into ``out`` and its CDF file beside it (``out`` + ``.cdf``)."""
    cdf_path = out.path.with_name(out.path.name + ff.CDF_SUFFIX)
    res = Resolution()
    check_terms(options.outer, options.inner, res)
    with reserve_output(cdf_path, "factored CDF file") as cdfs:
        _, surface = reconstructed(
            run, options.method, extrapolate="nearest", allow_sparse=options.allow_sparse
        )
        y, supported, lit = supported_table(surface, res)
        note = sparse_note(
            lit if supported is None else supported,
            lit,
            "factored table's bins",
            allow=options.allow_sparse,
        )
        result = factorize_table(y, options.outer, options.inner, res, seed=0)
        with step("writing"):
            out.write_bytes(ff.format_factors(result.tables).encode("utf-8"))
            cdfs.write_bytes(ff.format_cdfs(result.tables).encode("utf-8"))
    return (
        f"wrote {out.path} and {cdf_path} (factored, J = {options.outer}, K = "
        f"{options.inner}): relative error {result.error:.3g} of the {options.method} "
        "reconstruction" + (f"\n{note}" if note else "")
    )
