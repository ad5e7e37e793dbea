"""Per-sample random streams: counter-based, drawn in batches, identical in any order.

The design notes ask for "one seed per run and one stream per sample index, so a resumed
simulated run equals an uninterrupted one". The simulator also needs to draw the noise of
thousands of samples at once (no Python loop per sample). numpy has no vectorized,
per-element-keyed generator: a `numpy.random.Generator` per sample costs ~20 µs to create
and forces a loop, and one shared generator makes every number depend on how many were
drawn before it (batch size, order, resume point). So the streams here are *counter-based*:
every number is a pure function of its key

    (run seed, sample index, channel, draw number)  →  64 random bits,

computed with numpy ``uint64`` arithmetic (wrapping, no overflow checks, no warnings) over
whole arrays of keys. Drawing sample 7 alone, inside a batch of 10 000, in reverse order or
after resuming at sample 5 gives the same bits, by construction.

The hash is SplitMix64 used the way Java's ``SplittableRandom`` splits it (Steele, Lea &
Flood, "Fast splittable pseudorandom number generators", OOPSLA 2014), chosen because it is
published, tested (the paper reports DieHarder and TestU01 BigCrush on split streams),
cheap (a dozen vector operations) and has O(1) random access:

* the run's root stream has a seed ``s₀`` from ``numpy.random.SeedSequence(seed)`` and the
  golden gamma ``γ₀ = 0x9e3779b97f4a7c15``;
* the key ``j = index·2¹⁶ + channel`` names the (j+1)-th ``split()`` of the root, whose
  child stream has seed ``mix64(s₀ + (2j+1)·γ₀)`` and gamma ``mixGamma(s₀ + (2j+2)·γ₀)``
  (odd, with ≥ 24 bit transitions, exactly as ``SplittableRandom.mixGamma``);
* draw ``d`` of that stream is ``mix64(seed + (d+1)·gamma)``, its ``nextLong()`` number d.

So each (index, channel) pair owns a SplitMix64 stream of period 2⁶⁴ with its own gamma.
Distinct gammas matter: two streams that shared a gamma would be shifted copies of one
sequence whenever their seeds differ by a multiple of it, while streams with different
gammas never line up (a counter hash of the form ``mix(h ⊕ d)`` has the same weakness,
which is why it was not used). `tests/sim/test_streams.py` checks the numbers against a
plain sequential ``SplittableRandom`` written from the paper, and their statistics.

Bits become numbers by inversion, one 64-bit word per variate, so draw d of every
distribution is word d of the stream whatever the distribution's parameters:

* `Streams.uniform`: the top 53 bits, ``k·2⁻⁵³`` in [0, 1);
* `Streams.uniform_open`: the top 52 bits, ``(k + ½)·2⁻⁵²`` in (0, 1), symmetric about ½
  (``1 − u`` is exact, so both tails are equally resolved: |z| ≤ 8.3 for normals);
* `Streams.normal`: ``scipy.special.ndtri`` of an open uniform;
* `Streams.poisson`: the exact Poisson quantile of an open uniform (`poisson_ppf`): the
  smallest k with CDF(k) ≥ u, found from a Cornish–Fisher guess and corrected by evaluating
  the CDF, so it is exact for λ = 0, tiny λ and λ up to 1e12 (see `poisson_ppf` for the
  one place where scipy's CDF is not accurate enough and what replaces it;
  `sim.virtual.physics.poisson`).

Channels keep effects apart: the shot noise of sample 7 and its read noise come from
different streams. Add a channel constant below for every new use; never renumber or reuse
one, or every simulated run's numbers change. For rare, non-vectorized uses there is
`Streams.generator`, a `numpy.random.Generator` from
``SeedSequence(seed, spawn_key=(index, channel))``.
"""

from __future__ import annotations

from typing import Final

import numpy as np
import scipy.special as sc
from numpy.typing import ArrayLike, NDArray

from gonio.errors import DomainError
from sim.virtual.physics.poisson import (
    SMALL_BATCH,
    _check_lam,
    _poisson_ppf,
    _poisson_ppf_py,
    poisson_ppf,
)

__all__ = [
    "APERTURE",
    "CHANNELS",
    "DARK",
    "DRIFT",
    "FOOTPRINT",
    "LOCKIN_X",
    "LOCKIN_Y",
    "MAX_CHANNEL",
    "MAX_INDEX",
    "POSITION",
    "READ",
    "SHOT",
    "STRAY_LIGHT",
    "TIMING",
    "Streams",
    "poisson_ppf",
]

# -- channels -------------------------------------------------------------------------
# Grouped with gaps so related effects can be added next to each other. Never renumber.

#: Photon (shot) noise of the signal electrons.
SHOT: Final = 0
#: Dark-current electrons (their Poisson noise).
DARK: Final = 1
#: Read noise of the output amplifier.
READ: Final = 2
#: A lock-in's in-phase (X) and quadrature (Y) noise (`sim.virtual.physics.lockin`).
LOCKIN_X: Final = 3
LOCKIN_Y: Final = 4
#: Motor position errors (repeatability, backlash).
POSITION: Final = 16
#: A stream's timestamp jitter (`sim.virtual.devices.detector`).
TIMING: Final = 17
#: Slow source drift.
DRIFT: Final = 32
#: Aperture integration (points over the detector's solid angle).
APERTURE: Final = 48
#: Beam footprint against the sample.
FOOTPRINT: Final = 49
#: Stray light.
STRAY_LIGHT: Final = 64
#: Injected faults (`sim.virtual.faults`): one channel per fault rule, from here on.
FAULT: Final = 128

#: Every named channel, by name (a test checks that no two share a number).
CHANNELS: Final[dict[str, int]] = {
    "SHOT": SHOT,
    "DARK": DARK,
    "READ": READ,
    "LOCKIN_X": LOCKIN_X,
    "LOCKIN_Y": LOCKIN_Y,
    "POSITION": POSITION,
    "TIMING": TIMING,
    "DRIFT": DRIFT,
    "APERTURE": APERTURE,
    "FOOTPRINT": FOOTPRINT,
    "STRAY_LIGHT": STRAY_LIGHT,
    "FAULT": FAULT,
}

_CHANNEL_BITS: Final = 16
#: Channels are integers in [0, MAX_CHANNEL].
MAX_CHANNEL: Final = (1 << _CHANNEL_BITS) - 1
#: Sample indices are integers in [0, MAX_INDEX] (the key j = index·2¹⁶ + channel < 2⁶³).
MAX_INDEX: Final = (1 << (63 - _CHANNEL_BITS)) - 1

# -- SplitMix64 / SplittableRandom mixers, on uint64 arrays -----------------------------

_U64 = np.uint64
#: At most this many words are computed with Python ints instead of numpy (faster there).
_SMALL: Final = SMALL_BATCH
_GOLDEN_GAMMA: Final = _U64(0x9E3779B97F4A7C15)
_M1: Final = _U64(0xBF58476D1CE4E5B9)  # Stafford's Mix13 (SplitMix64's mix64)
_M2: Final = _U64(0x94D049BB133111EB)
_G1: Final = _U64(0xFF51AFD7ED558CCD)  # MurmurHash3 fmix64 (SplittableRandom.mixGamma)
_G2: Final = _U64(0xC4CEB9FE1A85EC53)
_ALTERNATING: Final = _U64(0xAAAAAAAAAAAAAAAA)
_S1, _S11, _S12, _S27, _S30, _S31, _S33 = (_U64(s) for s in (1, 11, 12, 27, 30, 31, 33))
_ONE: Final = _U64(1)
_CHANNEL_SHIFT: Final = _U64(_CHANNEL_BITS)
_POW2_M53: Final = 2.0**-53
_POW2_M52: Final = 2.0**-52

U64Array = NDArray[np.uint64]
FloatArray = NDArray[np.float64]


def _mix64(z: U64Array) -> U64Array:
    """SplitMix64's output function (Stafford Mix13) on a fresh array."""
    z = z ^ (z >> _S30)
    z *= _M1
    z ^= z >> _S27
    z *= _M2
    z ^= z >> _S31
    return z


def _popcount_swar(z: U64Array) -> NDArray[np.integer]:
    """Bits set in each word, for numpy < 2 (which has no ``bitwise_count``)."""
    z = z - ((z >> _S1) & _U64(0x5555555555555555))
    z = (z & _U64(0x3333333333333333)) + ((z >> _U64(2)) & _U64(0x3333333333333333))
    z = (z + (z >> _U64(4))) & _U64(0x0F0F0F0F0F0F0F0F)
    return (z * _U64(0x0101010101010101)) >> _U64(56)


_popcount = getattr(np, "bitwise_count", _popcount_swar)


def _mix_gamma(z: U64Array) -> U64Array:
    """``SplittableRandom.mixGamma``: an odd gamma with at least 24 bit transitions."""
    z = z ^ (z >> _S33)
    z *= _G1
    z ^= z >> _S33
    z *= _G2
    z ^= z >> _S33
    z |= _ONE
    weak = _popcount(z ^ (z >> _S1)) < 24
    if weak.any():
        z[weak] ^= _ALTERNATING
    return z


# -- streams --------------------------------------------------------------------------


class Streams:
    """The random numbers of one simulated run, keyed by (sample index, channel, draw).

    Every method takes ``index``: a non-negative int or a 1-d int array of N sample
    indices (any order, repeats allowed), and a ``channel`` (one of the constants of this
    module). Draw methods return an array of shape ``np.shape(index) + (size,)`` whose
    column j is draw ``start + j`` of each sample's stream; the numbers depend only on
    (seed, index, channel, draw), never on the batch, its order or earlier calls.
    """

    def __init__(self, seed: int) -> None:
        if isinstance(seed, bool) or not isinstance(seed, int | np.integer):
            raise TypeError(f"seed must be an int, got {type(seed).__name__}")
        if seed < 0:
            raise DomainError(f"seed must be >= 0, got {seed}")
        self._seed = int(seed)
        state = np.random.SeedSequence(self._seed).generate_state(1, np.uint64)
        self._root_seed = np.asarray(state[:1], dtype=np.uint64)
        self._root_seed_int = int(state[0])

    @property
    def seed(self) -> int:
        """The run's seed."""
        return self._seed

    def __repr__(self) -> str:
        return f"Streams(seed={self._seed})"

    # -- raw bits ---------------------------------------------------------------------

    def bits(self, index: ArrayLike, channel: int, size: int, *, start: int = 0) -> U64Array:
        """Draws ``start .. start+size-1`` of each sample's stream as raw 64-bit words."""
        words, shape = self._words(index, channel, size, start)
        return np.asarray(words, dtype=np.uint64).reshape(shape)

    def _words(
        self, index: ArrayLike, channel: int, size: int, start: int
    ) -> tuple[list[int] | U64Array, tuple[int, ...]]:
        """The words of `bits`, flat, and the output shape. A few words (≤ 32) come as a
        list of Python ints: there they are ~10x faster than numpy's per-call overhead."""
        idx, shape = _indices(index)
        _check_count("size", size)
        _check_count("start", start)
        _check_channel(channel)
        out_shape = (*shape, int(size))
        if idx.size * size <= _SMALL:
            return _bits_py(self._root_seed_int, idx.tolist(), int(channel), size, start), out_shape
        seeds, gammas = self._stream_keys(idx.astype(np.uint64), channel)
        counters = np.arange(1, size + 1, dtype=np.uint64)
        if start:
            counters += _U64(start)
        z = gammas[:, None] * counters[None, :]
        z += seeds[:, None]
        return _mix64(z).reshape(-1), out_shape

    def _stream_keys(self, idx: U64Array, channel: int) -> tuple[U64Array, U64Array]:
        """Seed and gamma of each (index, channel) stream: the (j+1)-th split of the root."""
        two_j = (idx << _CHANNEL_SHIFT) | _U64(channel)
        two_j <<= _ONE
        z = two_j + _ONE
        z *= _GOLDEN_GAMMA
        z += self._root_seed
        seeds = _mix64(z)
        z += _GOLDEN_GAMMA
        return seeds, _mix_gamma(z)

    # -- distributions ----------------------------------------------------------------

    def uniform(self, index: ArrayLike, channel: int, size: int, *, start: int = 0) -> FloatArray:
        """Uniform numbers in [0, 1) with 53 random bits (multiples of 2⁻⁵³)."""
        words, shape = self._words(index, channel, size, start)
        if isinstance(words, list):
            return np.array([(w >> 11) * _POW2_M53 for w in words]).reshape(shape)
        return ((words >> _S11).astype(np.float64) * _POW2_M53).reshape(shape)

    def uniform_open(
        self, index: ArrayLike, channel: int, size: int, *, start: int = 0
    ) -> FloatArray:
        """Uniform numbers in the open interval (0, 1): ``(k + ½)·2⁻⁵²`` with 52 random
        bits, symmetric about ½ (``1 − u`` is exact), in [2⁻⁵³, 1 − 2⁻⁵³]."""
        words, shape = self._words(index, channel, size, start)
        return np.asarray(_open_uniforms(words)).reshape(shape)

    def normal(self, index: ArrayLike, channel: int, size: int, *, start: int = 0) -> FloatArray:
        """Standard normal numbers (inverse CDF of `uniform_open`; |z| ≤ 8.3)."""
        return np.asarray(sc.ndtri(self.uniform_open(index, channel, size, start=start)))

    def poisson(
        self, index: ArrayLike, channel: int, lam: ArrayLike, *, start: int = 0
    ) -> FloatArray:
        """Exact Poisson counts (float64) with means ``lam`` (see `poisson_ppf`).

        ``lam`` has shape ``np.shape(index) + (size,)``, finite, in [0, 2⁵²]; column j
        uses draw ``start + j``. One uniform per count, so which numbers a count uses does
        not depend on λ.
        """
        lam_arr = np.asarray(lam, dtype=np.float64)
        idx_shape = np.shape(index)
        if lam_arr.ndim != len(idx_shape) + 1 or lam_arr.shape[:-1] != idx_shape:
            raise DomainError(
                f"lam must have shape index.shape + (size,) = {idx_shape} + (size,), "
                f"got {lam_arr.shape}"
            )
        _check_lam(lam_arr)
        words, shape = self._words(index, channel, lam_arr.shape[-1], start)
        u = _open_uniforms(words)
        if isinstance(u, list):
            return np.array(_poisson_ppf_py(u, lam_arr.ravel().tolist())).reshape(shape)
        return _poisson_ppf(u.reshape(shape), lam_arr)

    def generator(self, index: int, channel: int) -> np.random.Generator:
        """A `numpy.random.Generator` for one (index, channel), for rare non-vectorized
        uses: ``SeedSequence(seed, spawn_key=(index, channel))``. Its numbers are not those
        of the vectorized methods (a different construction), but are just as
        reproducible."""
        idx, _ = _indices(index)
        if idx.shape != (1,):
            raise DomainError("generator() takes one sample index")
        _check_channel(channel)
        seq = np.random.SeedSequence(self._seed, spawn_key=(int(idx[0]), int(channel)))
        return np.random.Generator(np.random.PCG64(seq))


def _indices(index: ArrayLike) -> tuple[NDArray[np.integer], tuple[int, ...]]:
    """Sample indices as a flat, validated integer array, and the shape the caller gave."""
    arr = np.asarray(index)
    if arr.dtype.kind not in "iu":
        raise TypeError(f"sample indices must be integers, got dtype {arr.dtype}")
    if arr.ndim > 1:
        raise DomainError(f"sample indices must be a scalar or 1-d, got shape {arr.shape}")
    flat = arr.reshape(-1)
    if flat.size <= _SMALL:
        bad = [i for i in flat.tolist() if not 0 <= i <= MAX_INDEX]
    elif (arr.dtype.kind == "i" and flat.min() < 0) or flat.max() > MAX_INDEX:
        bad = [int(flat.min()), int(flat.max())]
    else:
        bad = []
    if bad:
        raise DomainError(f"sample indices must be in [0, {MAX_INDEX}], got {bad[:3]}")
    return flat, arr.shape


def _open_uniforms(words: list[int] | U64Array) -> list[float] | FloatArray:
    """``(k + ½)·2⁻⁵²`` for the top 52 bits k of each word (exact in both forms)."""
    if isinstance(words, list):
        return [((w >> 12) + 0.5) * _POW2_M52 for w in words]
    u = (words >> _S12).astype(np.float64)
    u += 0.5
    u *= _POW2_M52
    return u


def _check_count(name: str, value: int) -> None:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 0:
        raise DomainError(f"{name} must be an int >= 0, got {value!r}")


def _check_channel(channel: int) -> None:
    if isinstance(channel, bool) or not isinstance(channel, int | np.integer):
        raise TypeError(f"channel must be an int, got {type(channel).__name__}")
    if not 0 <= channel <= MAX_CHANNEL:
        raise DomainError(f"channel must be in [0, {MAX_CHANNEL}], got {channel}")


# -- the same construction in Python ints (for a few words at a time) -------------------

_MASK64: Final = (1 << 64) - 1
_GOLDEN_GAMMA_INT: Final = int(_GOLDEN_GAMMA)


def _mix64_py(z: int) -> int:
    z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & _MASK64
    z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & _MASK64
    return z ^ (z >> 31)


def _mix_gamma_py(z: int) -> int:
    z = ((z ^ (z >> 33)) * 0xFF51AFD7ED558CCD) & _MASK64
    z = ((z ^ (z >> 33)) * 0xC4CEB9FE1A85EC53) & _MASK64
    z = (z ^ (z >> 33)) | 1
    return z ^ 0xAAAAAAAAAAAAAAAA if (z ^ (z >> 1)).bit_count() < 24 else z


def _bits_py(root: int, indices: list[int], channel: int, size: int, start: int) -> list[int]:
    """`Streams.bits` for a few words, in Python ints (a flat list, row by row)."""
    out: list[int] = []
    for index in indices:
        base = (root + (2 * ((index << _CHANNEL_BITS) | channel) + 1) * _GOLDEN_GAMMA_INT) & (
            _MASK64
        )
        seed = _mix64_py(base)
        gamma = _mix_gamma_py((base + _GOLDEN_GAMMA_INT) & _MASK64)
        out.extend(
            _mix64_py((seed + d * gamma) & _MASK64) for d in range(start + 1, start + size + 1)
        )
    return out
