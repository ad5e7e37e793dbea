"""Counter-based per-sample streams: the same numbers in any batch, order or resume; the
construction against a sequential SplittableRandom; uniform, normal and exact Poisson
statistics; the Poisson quantile in the tails where scipy's CDF is not enough."""

from __future__ import annotations

import math

import mpmath
import numpy as np
import pytest
import scipy.special as sc
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import stats

from sim.virtual.physics import poisson as poisson_mod
from sim.virtual.physics import streams as streams_mod
from sim.virtual.physics.streams import (
    CHANNELS,
    DARK,
    MAX_CHANNEL,
    MAX_INDEX,
    READ,
    SHOT,
    Streams,
    poisson_ppf,
)

MASK = (1 << 64) - 1
FIVE_SIGMA = 5.0


# -- a sequential reference: java.util.SplittableRandom, from the paper --------------------


def _mix64(z: int) -> int:
    z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & MASK
    z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & MASK
    return z ^ (z >> 31)


def _mix_gamma(z: int) -> int:
    z = ((z ^ (z >> 33)) * 0xFF51AFD7ED558CCD) & MASK
    z = ((z ^ (z >> 33)) * 0xC4CEB9FE1A85EC53) & MASK
    z = (z ^ (z >> 33)) | 1
    n = bin(z ^ (z >> 1)).count("1")
    return z ^ 0xAAAAAAAAAAAAAAAA if n < 24 else z


class SplittableRandom:
    """Steele, Lea & Flood (2014), as in java.util.SplittableRandom (unsigned here)."""

    def __init__(self, seed: int, gamma: int = 0x9E3779B97F4A7C15) -> None:
        self.seed = seed & MASK
        self.gamma = gamma

    def next_seed(self) -> int:
        self.seed = (self.seed + self.gamma) & MASK
        return self.seed

    def next_long(self) -> int:
        return _mix64(self.next_seed())

    def split(self) -> SplittableRandom:
        return SplittableRandom(self.next_long(), _mix_gamma(self.next_seed()))


def root_seed(seed: int) -> int:
    return int(np.random.SeedSequence(seed).generate_state(1, np.uint64)[0])


def test_streams_are_splits_of_a_sequential_splittable_random() -> None:
    """Key j = index·2¹⁶ + channel is the (j+1)-th split of the run's root stream, and
    draw d is that child's (d+1)-th nextLong — checked by actually splitting in order,
    for both the Python-int path (few words) and the numpy path (many)."""
    seed = 20240917
    root = SplittableRandom(root_seed(seed))
    keys = {(0, c) for c in range(6)} | {(1, 0), (1, 1)}
    last = max(i << 16 | c for i, c in keys)
    expected: dict[tuple[int, int], list[int]] = {}
    for j in range(last + 1):
        child = root.split()
        key = (j >> 16, j & 0xFFFF)
        if key in keys:
            expected[key] = [child.next_long() for _ in range(40)]
    s = Streams(seed)
    for (index, channel), words in expected.items():
        few = s.bits(index, channel, 5)  # Python ints
        many = s.bits(np.full(3, index), channel, 40)  # numpy
        assert few.tolist() == words[:5]
        assert many.tolist() == [words] * 3
        assert s.bits(index, channel, 3, start=37).tolist() == words[37:]


def test_python_and_numpy_paths_agree_including_weak_gammas() -> None:
    """~3 % of stream gammas need SplittableRandom's bit-transition fix; both paths
    apply it identically (and the SWAR popcount equals numpy's)."""
    s = Streams(7)
    idx = np.arange(4000)
    vector = s.bits(idx, READ, 3)
    scalar = np.concatenate([s.bits(idx[i : i + 8], READ, 3) for i in range(0, idx.size, 8)])
    np.testing.assert_array_equal(vector, scalar)
    # The fix really happened for some of these keys.
    base = (
        s._root_seed_int + (2 * ((idx.astype(object) << 16) | READ) + 2) * 0x9E3779B97F4A7C15
    ) & MASK
    weak = 0
    for b in base.tolist():
        z = ((b ^ (b >> 33)) * 0xFF51AFD7ED558CCD) & MASK
        z = ((z ^ (z >> 33)) * 0xC4CEB9FE1A85EC53) & MASK
        z = (z ^ (z >> 33)) | 1
        weak += bin(z ^ (z >> 1)).count("1") < 24
    assert weak > 20
    words = np.random.default_rng(3).integers(0, 2**63, 5000, dtype=np.uint64) * np.uint64(3)
    counts = streams_mod._popcount_swar(words)
    assert counts.tolist() == [bin(w).count("1") for w in words.tolist()]


# -- the same numbers whatever the batch ---------------------------------------------------

indices = st.lists(st.integers(0, MAX_INDEX), min_size=1, max_size=40)


def _all_draws(s: Streams, index: np.ndarray, channel: int, size: int) -> list[np.ndarray]:
    lam = np.broadcast_to(np.array([0.0, 1e-3, 0.7, 40.0, 3e5, 1e10])[:size], (*index.shape, size))
    return [
        s.bits(index, channel, size),
        s.uniform(index, channel, size),
        s.uniform_open(index, channel, size),
        s.normal(index, channel, size),
        s.poisson(index, channel, np.ascontiguousarray(lam)),
    ]


@settings(max_examples=60)
@given(
    seed=st.integers(0, 2**64),
    index=indices,
    channel=st.sampled_from(sorted(CHANNELS.values())),
    size=st.integers(1, 6),
)
def test_batch_equals_one_by_one(seed: int, index: list[int], channel: int, size: int) -> None:
    s = Streams(seed)
    idx = np.array(index, dtype=np.uint64)
    batch = _all_draws(s, idx, channel, size)
    for n, i in enumerate(index):
        alone = _all_draws(s, np.array(i), channel, size)
        for b, a in zip(batch, alone, strict=True):
            np.testing.assert_array_equal(b[n], a)


@settings(max_examples=40)
@given(seed=st.integers(0, 2**32), n=st.integers(1, 200), data=st.data())
def test_order_does_not_matter(seed: int, n: int, data: st.DataObject) -> None:
    s = Streams(seed)
    idx = np.arange(n, dtype=np.int64) * 7919
    perm = np.array(data.draw(st.permutations(range(n))))
    for a, b in zip(_all_draws(s, idx, SHOT, 3), _all_draws(s, idx[perm], SHOT, 3), strict=True):
        np.testing.assert_array_equal(a[perm], b)


@pytest.mark.parametrize("k", [0, 1, 17, 30, 31, 150, 299])
def test_resume_equals_uninterrupted(k: int) -> None:
    """Samples k.. drawn after a 'resume' (a new Streams, same seed) equal the tail of an
    uninterrupted run 0..N−1, for every distribution."""
    n = 300
    full = _all_draws(Streams(99), np.arange(n), DARK, 4)
    resumed = _all_draws(Streams(99), np.arange(k, n), DARK, 4)
    for f, r in zip(full, resumed, strict=True):
        np.testing.assert_array_equal(f[k:], r)


def test_draws_are_positions_in_a_stream() -> None:
    s = Streams(5)
    idx = np.arange(50)
    whole = s.uniform(idx, SHOT, 10)
    np.testing.assert_array_equal(s.uniform(idx, SHOT, 4, start=6), whole[:, 6:])
    np.testing.assert_array_equal(s.uniform(idx, SHOT, 3), whole[:, :3])
    assert s.uniform(idx, SHOT, 0).shape == (50, 0)
    assert s.uniform(3, SHOT, 2).shape == (2,)
    assert s.normal(np.arange(0), SHOT, 2).shape == (0, 2)


def test_index_dtypes_and_extremes() -> None:
    s = Streams(1)
    ref = s.bits(np.array([0, 5, MAX_INDEX], dtype=np.uint64), MAX_CHANNEL, 2)
    for dtype in (np.int64, np.uint64, np.int32):
        idx = np.array([0, 5, MAX_INDEX if dtype != np.int32 else 0], dtype=dtype)
        got = s.bits(idx, MAX_CHANNEL, 2)
        np.testing.assert_array_equal(got[:2], ref[:2])
    np.testing.assert_array_equal(s.bits([0, 5, MAX_INDEX], MAX_CHANNEL, 2), ref)


# -- statistics -------------------------------------------------------------------------


def test_uniform_is_uniform() -> None:
    s = Streams(2024)
    u = s.uniform(np.arange(1000), SHOT, 100).ravel()  # 1e5 draws
    assert u.min() >= 0.0
    assert u.max() < 1.0
    assert stats.kstest(u, "uniform").pvalue > 1e-3
    across = s.uniform(np.arange(100_000), READ, 1).ravel()  # one draw per sample
    assert stats.kstest(across, "uniform").pvalue > 1e-3
    # 53 bits: the numbers are multiples of 2⁻⁵³ and use the low bits too.
    k = u * 2.0**53
    np.testing.assert_array_equal(k, np.floor(k))
    assert np.mean(k % 2) == pytest.approx(0.5, abs=0.01)


def test_every_bit_is_balanced() -> None:
    words = Streams(11).bits(np.arange(20_000), SHOT, 5).ravel()
    ones = np.array([np.count_nonzero((words >> np.uint64(b)) & np.uint64(1)) for b in range(64)])
    n = words.size
    assert np.all(np.abs(ones - n / 2) < FIVE_SIGMA * math.sqrt(n) / 2)


def test_uniform_open_is_open_and_symmetric() -> None:
    u = Streams(3).uniform_open(np.arange(20_000), SHOT, 5)
    assert u.min() >= 2.0**-53
    assert u.max() <= 1.0 - 2.0**-53
    np.testing.assert_array_equal((1.0 - u) + u, 1.0)
    k = u * 2.0**52 - 0.5  # the 52-bit integer behind each number
    np.testing.assert_array_equal(k, np.round(k))


def _corr(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.corrcoef(a.ravel(), b.ravel())[0, 1])


def test_streams_are_uncorrelated() -> None:
    """Different seeds, channels, neighbouring indices and neighbouring draws."""
    n = 40_000
    idx = np.arange(n)
    a = Streams(1).uniform(idx, SHOT, 3)
    bound = FIVE_SIGMA / math.sqrt(a.size)
    assert abs(_corr(a, Streams(2).uniform(idx, SHOT, 3))) < bound  # seeds
    assert abs(_corr(a, Streams(1).uniform(idx, DARK, 3))) < bound  # channels
    assert abs(_corr(a, Streams(1).uniform(idx + 1, SHOT, 3))) < bound  # indices
    assert abs(_corr(a[:, :2], a[:, 1:])) < FIVE_SIGMA / math.sqrt(2 * n)  # draws
    # Seeds that differ in one bit, and channels next to each other.
    assert abs(_corr(a, Streams(1 ^ (1 << 40)).uniform(idx, SHOT, 3))) < bound
    assert abs(_corr(Streams(1).uniform(idx, 3, 3), Streams(1).uniform(idx, 4, 3))) < bound


@pytest.mark.parametrize("pairing", ["indices", "draws", "channels"])
def test_pairs_fill_the_unit_square(pairing: str) -> None:
    """A 2-d chi-square test (16 × 16 cells) on neighbouring pairs."""
    s = Streams(8)
    n = 50_000
    if pairing == "indices":
        u = s.uniform(np.arange(n + 1), SHOT, 1).ravel()
        x, y = u[:-1], u[1:]
    elif pairing == "draws":
        u = s.uniform(np.arange(n), SHOT, 2)
        x, y = u[:, 0], u[:, 1]
    else:
        x = s.uniform(np.arange(n), SHOT, 1).ravel()
        y = s.uniform(np.arange(n), DARK, 1).ravel()
    counts, _, _ = np.histogram2d(x, y, bins=16, range=[[0, 1], [0, 1]])
    assert stats.chisquare(counts.ravel()).pvalue > 1e-4


def test_normal_moments() -> None:
    z = Streams(31).normal(np.arange(50_000), READ, 4).ravel()  # 2e5 draws
    n = z.size
    assert abs(z.mean()) < FIVE_SIGMA / math.sqrt(n)
    assert abs(z.var() - 1.0) < FIVE_SIGMA * math.sqrt(2.0 / n)
    assert abs(stats.skew(z)) < FIVE_SIGMA * math.sqrt(6.0 / n)
    assert abs(stats.kurtosis(z)) < FIVE_SIGMA * math.sqrt(24.0 / n)
    assert stats.kstest(z, "norm").pvalue > 1e-3
    assert np.abs(z).max() < 8.3


POISSON_MEANS = [0.0, 1e-3, 0.5, 3.0, 50.0, 1e4, 1e8, 1e10]


@pytest.mark.parametrize("lam", POISSON_MEANS)
def test_poisson_mean_and_variance(lam: float) -> None:
    n = 100_000
    x = Streams(77).poisson(np.arange(n), SHOT, np.full((n, 1), lam)).ravel()
    np.testing.assert_array_equal(x, np.round(x))
    assert x.min() >= 0.0
    if lam == 0.0:
        assert not x.any()
        return
    assert abs(x.mean() - lam) < FIVE_SIGMA * math.sqrt(lam / n)
    # sd of the sample variance of a Poisson: √((λ + 2λ²)/n) (4th central moment λ + 3λ²)
    assert abs(x.var(ddof=1) - lam) < FIVE_SIGMA * math.sqrt((lam + 2 * lam * lam) / n)


@pytest.mark.parametrize("lam", [0.5, 3.0, 50.0, 1e4])
def test_poisson_frequencies_match_the_pmf(lam: float) -> None:
    """Chi-square of the counts against the pmf (cells with ≥ 5 expected, tails pooled)."""
    n = 100_000
    x = Streams(5).poisson(np.arange(n), DARK, np.full((n, 1), lam)).ravel().astype(int)
    lo, hi = stats.poisson.ppf([1e-4, 1 - 1e-4], lam).astype(int)
    edges = np.arange(lo, hi + 1)
    observed = np.array(
        [np.count_nonzero(x < lo + 1)]
        + [np.count_nonzero(x == k) for k in edges[1:-1]]
        + [np.count_nonzero(x >= hi)]
    )
    probs = np.concatenate(
        [
            [stats.poisson.cdf(lo, lam)],
            stats.poisson.pmf(edges[1:-1], lam),
            [stats.poisson.sf(hi - 1, lam)],
        ]
    )
    expected = probs / probs.sum() * n
    if lam >= 1e3:  # pool neighbouring counts to keep the cells populated
        width = int(math.sqrt(lam) / 4)
        cut = (observed.size // width) * width
        observed = observed[:cut].reshape(-1, width).sum(axis=1)
        expected = expected[:cut].reshape(-1, width).sum(axis=1)
        expected *= observed.sum() / expected.sum()
    assert stats.chisquare(observed, expected).pvalue > 1e-4


# -- the Poisson quantile, exactly --------------------------------------------------------

#: Uniforms at the ends of (0, 1) and around ½, where the quantile switches CDF branch.
EXTREME_U = np.array(
    [
        *(2.0**-53, 1e-300, 1e-12, 1e-6, 0.1),
        *(0.5 - 2.0**-53, 0.5, 0.5 + 2.0**-53),
        *(0.9, 1 - 1e-9, 1 - 2.0**-40, 1 - 2.0**-53),
    ]
)


@pytest.mark.parametrize("lam", [0.0, 1e-300, 1e-3, 0.5, 2.999, 3.0, 50.0, 1e5, 1e8, 1e10, 1e12])
def test_poisson_ppf_is_the_smallest_k_with_cdf_at_least_u(lam: float) -> None:
    u = np.concatenate([EXTREME_U, np.random.default_rng(0).random(2000)])
    lam_arr = np.full_like(u, lam)
    k = poisson_ppf(u, lam_arr)
    assert np.all(poisson_mod._at_or_above(k, u, lam_arr))
    positive = k > 0
    below = poisson_mod._at_or_above(k[positive] - 1.0, u[positive], lam_arr[positive])
    assert not below.any()
    # The same answer one number at a time (the small-batch path).
    np.testing.assert_array_equal([poisson_ppf(v, lam)[()] for v in u[:40]], k[:40])


@pytest.mark.parametrize("lam", [1e-3, 0.5, 7.0, 300.0])
def test_poisson_ppf_agrees_with_scipy_where_scipy_is_exact(lam: float) -> None:
    u = np.random.default_rng(1).random(5000)
    np.testing.assert_array_equal(poisson_ppf(u, lam), stats.poisson.ppf(u, lam))


def _poisson_sf_reference(k: int, lam: float) -> float:
    """P(X > k) by direct summation: pmf(k+1) (mpmath) × Σ_m Π_{i≤m} λ/(k+1+i)."""
    mpmath.mp.dps = 30
    log_pmf = (k + 1) * mpmath.log(lam) - lam - mpmath.loggamma(k + 2)
    terms = int(80 * math.sqrt(lam) / max((k - lam) / math.sqrt(lam), 1.0)) + 1000
    i = np.arange(2, terms, dtype=np.float64)
    ratios = np.cumsum(-np.log1p((k + i - lam) / lam))
    return float(mpmath.exp(log_pmf)) * float(1.0 + np.sum(np.exp(ratios)))


@pytest.mark.parametrize("lam", [1e5, 1e6, 1e8, 1e10])
@pytest.mark.parametrize("sigmas", [4.2, 5.0, 6.0, 8.0])
def test_far_upper_tail_is_exact_for_large_means(lam: float, sigmas: float) -> None:
    """Beyond ~4.5 σ above large means scipy's pdtrc is far off (85 % low at λ = 1e10);
    the survival function used instead matches a direct tail sum, and the quantile
    switches from k to k + 1 exactly where 1 − u crosses P(X > k)."""
    k = float(math.ceil(lam + sigmas * math.sqrt(lam)))
    ref = _poisson_sf_reference(int(k), lam)
    sf = poisson_mod._poisson_sf(np.array([k]), np.array([lam]))[0]
    assert sf == pytest.approx(ref, rel=1e-12)
    if ref < 1e-10:
        return  # near 1, neighbouring doubles are further apart than P(X = k)
    delta = 1e-5  # inside the SF's step to its neighbours, ≈ (k − λ)/λ ≥ 4e-5
    for rel, expected in ((1 + delta, k), (1 - delta, k + 1)):
        u = 1.0 - ref * rel
        assert poisson_ppf(u, lam)[()] == expected


def test_temme_matches_scipy_where_scipy_is_accurate() -> None:
    """Just above the switch (4 √a above λ), scipy's own asymptotic branch is still used
    and accurate: the two agree, so the survival function is continuous there."""
    for lam in (1e5, 1e7, 1e9, 1e11):
        a = np.array([math.ceil(lam + 4.1 * math.sqrt(lam))]) + np.arange(3)
        ours = poisson_mod._temme_lower_gamma(a, np.full(3, lam))
        np.testing.assert_allclose(ours, sc.gammainc(a, lam), rtol=1e-11)


# -- generators, channels, errors --------------------------------------------------------


def test_generator_is_seeded_from_the_key() -> None:
    s = Streams(12)
    a = s.generator(7, DARK).random(5)
    np.testing.assert_array_equal(a, Streams(12).generator(7, DARK).random(5))
    seq = np.random.SeedSequence(12, spawn_key=(7, DARK))
    np.testing.assert_array_equal(a, np.random.Generator(np.random.PCG64(seq)).random(5))
    assert not np.array_equal(a, s.generator(8, DARK).random(5))
    assert not np.array_equal(a, s.generator(7, SHOT).random(5))


def test_channels_are_distinct_and_in_range() -> None:
    values = list(CHANNELS.values())
    assert len(set(values)) == len(values)
    assert all(0 <= v <= MAX_CHANNEL for v in values)
    assert {SHOT, DARK, READ} <= set(values)


@pytest.mark.parametrize(
    ("call", "error"),
    [
        (lambda s: s.uniform(-1, SHOT, 1), ValueError),
        (lambda s: s.uniform(np.array([0, -3]), SHOT, 1), ValueError),
        (lambda s: s.uniform(np.arange(100) - 1, SHOT, 1), ValueError),
        (lambda s: s.uniform(MAX_INDEX + 1, SHOT, 1), ValueError),
        (lambda s: s.uniform(np.full(100, MAX_INDEX + 1, dtype=np.uint64), SHOT, 1), ValueError),
        (lambda s: s.uniform(1.5, SHOT, 1), TypeError),
        (lambda s: s.uniform(np.zeros((2, 2), dtype=int), SHOT, 1), ValueError),
        (lambda s: s.uniform(0, MAX_CHANNEL + 1, 1), ValueError),
        (lambda s: s.uniform(0, -1, 1), ValueError),
        (lambda s: s.uniform(0, 1.0, 1), TypeError),
        (lambda s: s.uniform(0, SHOT, -1), ValueError),
        (lambda s: s.uniform(0, SHOT, 1, start=-1), ValueError),
        (lambda s: s.poisson(np.arange(2), SHOT, np.array([[1.0], [-1.0]])), ValueError),
        (lambda s: s.poisson(np.arange(2), SHOT, np.array([[1.0], [np.nan]])), ValueError),
        (lambda s: s.poisson(np.arange(2), SHOT, np.array([[1.0], [np.inf]])), ValueError),
        (lambda s: s.poisson(np.arange(2), SHOT, np.array([[1.0], [2.0**53]])), ValueError),
        (lambda s: s.poisson(np.arange(2), SHOT, np.ones((3, 1))), ValueError),
        (lambda s: s.poisson(np.arange(2), SHOT, np.ones(2)), ValueError),
        (lambda s: s.generator(np.arange(2), SHOT), ValueError),
    ],
)
def test_bad_arguments_raise(call: object, error: type[Exception]) -> None:
    with pytest.raises(error):
        call(Streams(0))  # type: ignore[operator]


@pytest.mark.parametrize("seed", [-1, 1.5, True, "3"])
def test_bad_seeds_raise(seed: object) -> None:
    with pytest.raises((TypeError, ValueError)):
        Streams(seed)  # type: ignore[arg-type]


def test_poisson_ppf_rejects_u_outside_the_open_interval() -> None:
    for u in (0.0, 1.0, -0.5, np.nan):
        with pytest.raises(ValueError, match="open interval"):
            poisson_ppf(u, 1.0)


def test_large_seeds_and_repr() -> None:
    s = Streams(2**200 + 1)
    assert s.seed == 2**200 + 1
    assert "Streams(seed=" in repr(s)
    assert not np.array_equal(s.bits(0, SHOT, 4), Streams(1).bits(0, SHOT, 4))
