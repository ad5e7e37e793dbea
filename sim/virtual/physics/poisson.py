"""The exact Poisson quantile `poisson_ppf`, by inversion of one uniform per count.

`sim.virtual.physics.streams` draws Poisson counts as the quantile of an open uniform (one
64-bit word per variate, so draw d is word d whatever λ). A Cornish–Fisher guess is corrected by
stepping until CDF(k − 1) < u ≤ CDF(k). scipy's ``pdtrc`` (behind
``scipy.stats.poisson.sf``) is wrong more than about 4.5 σ above the mean once λ ≳ 10⁶
(85–90 % low at 5–8 σ for λ = 10¹⁰, scipy 1.17.1), so that region uses a two-term Temme
expansion of the incomplete gamma function, checked against a direct tail sum in
tests/sim/test_streams.py.
"""

from __future__ import annotations

import math
from typing import Final

import numpy as np
import scipy.special as sc
from numpy.typing import ArrayLike, NDArray

from gonio.errors import DomainError

FloatArray = NDArray[np.float64]

#: Up to this many numbers at once, plain Python floats beat numpy's per-call overhead.
SMALL_BATCH: Final = 32

#: From this λ on, the upper-tail survival function comes from Temme's expansion (below).
_TEMME_MIN_LAM: Final = 1e5
#: ... for counts at least this many √(k+1) above λ (where scipy's series stops converging).
_TEMME_MIN_SIGMAS: Final = 4.0
#: Cornish–Fisher guesses are used from this λ on (below it the search starts at 0).
_GUESS_MIN_LAM: Final = 3.0
#: λ above this cannot be represented with integer resolution in float64.
_MAX_LAM: Final = 2.0**52
_MAX_STEPS: Final = 100_000


def poisson_ppf(u: ArrayLike, lam: ArrayLike) -> FloatArray:
    """The Poisson(λ) quantile of u ∈ (0, 1): the smallest integer k with CDF(k) ≥ u.

    Exact to the precision of the CDF, for any finite λ in [0, 2⁵²] (λ = 0 gives 0).
    A Cornish–Fisher guess ``λ + √λ z + (z² − 1)/6 + (z − z³)/(72√λ)`` (z = Φ⁻¹(u)) is
    corrected by stepping k until ``CDF(k − 1) < u ≤ CDF(k)``; it is right or one off for
    λ ≥ 3, so one or two CDF evaluations do. The comparison uses ``CDF(k) =
    scipy.special.pdtr`` for u ≤ ½ and the survival function ``1 − CDF(k) ≤ 1 − u`` (exact
    for u > ½) above, so both tails are resolved to the last bit of u.

    One exception: scipy's ``pdtrc`` (the regularized lower incomplete gamma; seen in
    scipy 1.17.1) is wrong beyond ~4.5 σ above the mean for λ ≳ 10⁶ — its series stops
    before converging; at λ = 10¹⁰ it is 85–90 % low at 5–8 σ. There the survival
    function comes from Temme's uniform asymptotic expansion (DLMF §8.12, two terms),
    accurate to ~1e-14 relative for λ ≥ 10⁵ (checked against a direct tail sum in the
    tests).
    """
    u_arr = np.asarray(u, dtype=np.float64)
    lam_arr = np.asarray(lam, dtype=np.float64)
    if u_arr.shape != lam_arr.shape:
        u_arr, lam_arr = np.broadcast_arrays(u_arr, lam_arr)
    if u_arr.size and not (u_arr.min() > 0.0 and u_arr.max() < 1.0):
        raise DomainError("Poisson quantiles need u in the open interval (0, 1)")
    _check_lam(lam_arr)
    return _poisson_ppf(u_arr, lam_arr)


def _check_lam(lam: FloatArray) -> None:
    if lam.size and not (lam.min() >= 0.0 and lam.max() <= _MAX_LAM):  # also catches NaN
        bad = lam[~((lam >= 0.0) & (lam <= _MAX_LAM))]
        raise DomainError(f"Poisson means must be finite and in [0, 2**52], got {bad[:3]}")


def _poisson_ppf(u: FloatArray, lam: FloatArray) -> FloatArray:
    """`poisson_ppf` for arrays of one shape, u in (0, 1) and λ checked."""
    if u.size == 0:
        return np.zeros(u.shape)
    lam_min, lam_max = lam.min(), lam.max()
    shape = u.shape
    if u.size <= SMALL_BATCH:
        return np.array(_poisson_ppf_py(u.ravel().tolist(), lam.ravel().tolist())).reshape(shape)
    u = u.reshape(-1)
    lam = lam.reshape(-1)
    if lam_min >= _GUESS_MIN_LAM:
        k = _cornish_fisher(u, lam)
    else:
        k = np.zeros(u.shape)
        if lam_max >= _GUESS_MIN_LAM:
            big = lam >= _GUESS_MIN_LAM
            k[big] = _cornish_fisher(u[big], lam[big])
    _correct(k, u, lam)
    return k.reshape(shape)


def _cornish_fisher(u: FloatArray, lam: FloatArray) -> FloatArray:
    z: FloatArray = np.asarray(sc.ndtri(u))
    root = np.sqrt(lam)
    x = lam + root * z + (z * z - 1.0) / 6.0 + (z - z * z * z) / (72.0 * root)
    return np.maximum(np.ceil(x - 0.5), 0.0)


def _at_or_above(k: FloatArray, u: FloatArray, lam: FloatArray) -> NDArray[np.bool_]:
    """Whether CDF(k) ≥ u, elementwise (k ≥ 0): CDF(k) ≥ u below ½, SF(k) ≤ 1 − u above."""
    upper = u > 0.5
    n_upper = np.count_nonzero(upper)
    if n_upper == 0:
        return np.asarray(sc.pdtr(k, lam) >= u)
    if n_upper == u.size:
        return _poisson_sf(k, lam) <= 1.0 - u
    out = np.empty(k.shape, dtype=bool)
    lower = ~upper
    out[lower] = sc.pdtr(k[lower], lam[lower]) >= u[lower]
    out[upper] = _poisson_sf(k[upper], lam[upper]) <= 1.0 - u[upper]
    return out


def _correct(k: FloatArray, u: FloatArray, lam: FloatArray) -> None:
    """Step k (in place) to the smallest integer ≥ 0 with CDF(k) ≥ u."""
    ok = _at_or_above(k, u, lam)
    if not ok.all():
        up = np.flatnonzero(~ok)
        steps = 0
        while up.size:
            k[up] += 1.0
            up = up[~_at_or_above(k[up], u[up], lam[up])]
            steps = _count(steps)
    # Those stepped up are done (CDF(k − 1) < u is known); the others may step down.
    down = ok & (k > 0.0)
    if not down.any():
        return
    if down.all():
        below = _at_or_above(k - 1.0, u, lam)
        if not below.any():
            return
        todo = np.flatnonzero(below)
    else:
        todo = np.flatnonzero(down)
        todo = todo[_at_or_above(k[todo] - 1.0, u[todo], lam[todo])]
    steps = 0
    while todo.size:
        k[todo] -= 1.0
        todo = todo[k[todo] > 0.0]
        todo = todo[_at_or_above(k[todo] - 1.0, u[todo], lam[todo])]
        steps = _count(steps)


def _poisson_ppf_py(u: list[float], lam: list[float]) -> list[float]:
    """`_poisson_ppf` for a few numbers, one by one in Python floats (the per-call
    overhead of numpy dominates there). The answer is defined by the CDF comparisons
    alone, which call the same scipy functions as the vector path, so both agree; the
    guess only decides where the search starts."""
    out: list[float] = []
    for ui, li in zip(u, lam, strict=True):
        k = 0.0
        if li >= _GUESS_MIN_LAM:
            z = float(sc.ndtri(ui))
            root = math.sqrt(li)
            x = li + root * z + (z * z - 1.0) / 6.0 + (z - z * z * z) / (72.0 * root)
            k = float(max(math.ceil(x - 0.5), 0))
        steps = 0
        if _at_or_above_py(k, ui, li):
            while k > 0.0 and _at_or_above_py(k - 1.0, ui, li):
                k -= 1.0
                steps = _count(steps)
        else:
            k += 1.0
            while not _at_or_above_py(k, ui, li):
                k += 1.0
                steps = _count(steps)
        out.append(k)
    return out


def _at_or_above_py(k: float, u: float, lam: float) -> bool:
    """`_at_or_above` for one number."""
    if u <= 0.5:
        return bool(sc.pdtr(k, lam) >= u)
    a = k + 1.0
    if lam >= _TEMME_MIN_LAM and a - lam >= _TEMME_MIN_SIGMAS * math.sqrt(a):
        sf = float(_temme_lower_gamma(np.array([a]), np.array([lam]))[0])
    else:
        sf = float(sc.pdtrc(k, lam))
    return sf <= 1.0 - u


def _count(steps: int) -> int:
    if steps >= _MAX_STEPS:  # pragma: no cover - the guess is never this far off
        raise RuntimeError("the Poisson quantile search did not converge")
    return steps + 1


def _poisson_sf(k: FloatArray, lam: FloatArray) -> FloatArray:
    """P(X > k) for X ~ Poisson(λ): scipy's pdtrc, or Temme's expansion in the far upper
    tail of large λ (where pdtrc is inaccurate)."""
    a = k + 1.0
    temme = (lam >= _TEMME_MIN_LAM) & (a - lam >= _TEMME_MIN_SIGMAS * np.sqrt(a))
    if not temme.any():
        return np.asarray(sc.pdtrc(k, lam))
    out = np.asarray(sc.pdtrc(k, lam))
    out[temme] = _temme_lower_gamma(a[temme], lam[temme])
    return out


#: Coefficients of μ − log(1 + μ) = Σ_{n≥2} (−1)ⁿ μⁿ / n, highest first (|μ| < 0.1).
_LOG1PMX_TERMS: Final = 18
_LOG1PMX_COEFFS: Final = np.array(
    [(-1.0) ** n / n for n in range(_LOG1PMX_TERMS + 1, 1, -1)], dtype=np.float64
)


def _mu_minus_log1p(mu: FloatArray) -> FloatArray:
    """μ − log(1 + μ) without cancellation (a power series for |μ| < 0.1)."""
    small = np.abs(mu) < 0.1
    out = np.empty_like(mu)
    if small.any():
        m = mu[small]
        acc = np.zeros_like(m)
        for c in _LOG1PMX_COEFFS:
            acc = acc * m + c
        out[small] = acc * m * m
    if not small.all():
        m = mu[~small]
        out[~small] = m - np.log1p(m)
    return out


def _temme_lower_gamma(a: FloatArray, x: FloatArray) -> FloatArray:
    """Regularized lower incomplete gamma P(a, x) for large a and x < a (not x ≈ a):
    Temme's uniform expansion with its first two terms (DLMF §8.12)."""
    mu = (x - a) / a  # λ' − 1 in DLMF's notation, negative here
    eta = -np.sqrt(2.0 * _mu_minus_log1p(mu))
    c0 = 1.0 / mu - 1.0 / eta
    c1 = 1.0 / eta**3 - 1.0 / mu**3 - 1.0 / mu**2 - 1.0 / (12.0 * mu)
    r = np.exp(-0.5 * a * eta * eta) / np.sqrt(2.0 * math.pi * a) * (c0 + c1 / a)
    return np.asarray(0.5 * sc.erfc(-eta * np.sqrt(0.5 * a)) - r)
