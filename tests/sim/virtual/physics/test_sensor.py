"""The sensor model, effect by effect, by its statistics: shot-noise variance ∝ signal,
read noise independent of it, dark counts ∝ exposure, uniform quantization error,
saturation clipping and flags; exact without effects; the same readings in any batch."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import stats

from drivers.values import Reading
from sim.virtual.physics.sensor import SensorEffects, SensorSpec, read_out, readings, summarize
from sim.virtual.physics.streams import DARK, READ, SHOT, Streams

SPEC = SensorSpec(full_well_e=1e5, adc_bits=16, read_noise_e=8.0, dark_current_e_s=200.0)
GAIN = SPEC.gain_e_per_count
FIVE_SIGMA = 5.0


def only(**flags: bool) -> SensorEffects:
    return SensorEffects(**flags)


def read(
    signal: np.ndarray,
    effects: SensorEffects,
    *,
    t: float | np.ndarray = 0.1,
    seed: int = 1,
    index: np.ndarray | None = None,
    spec: SensorSpec = SPEC,
):
    """read_out with indices 0..N−1 unless given."""
    n = signal.shape[0]
    idx = np.arange(n) if index is None else index
    return read_out(signal, np.broadcast_to(t, (n,)), spec, effects, Streams(seed), idx)


# -- the spec and the effect switches ------------------------------------------------------


def test_spec_derived_values() -> None:
    assert SPEC.max_count == 65535
    assert GAIN == 1e5 / 65535
    tiny = SensorSpec(full_well_e=3.0, adc_bits=1, read_noise_e=0.0, dark_current_e_s=0.0)
    assert tiny.max_count == 1
    assert tiny.gain_e_per_count == 3.0


@pytest.mark.parametrize(
    ("changes", "error"),
    [
        ({"full_well_e": 0.0}, ValueError),
        ({"full_well_e": -1.0}, ValueError),
        ({"full_well_e": math.inf}, ValueError),
        ({"full_well_e": math.nan}, ValueError),
        ({"adc_bits": 0}, ValueError),
        ({"adc_bits": 33}, ValueError),
        ({"adc_bits": 12.0}, TypeError),
        ({"adc_bits": True}, TypeError),
        ({"read_noise_e": -0.1}, ValueError),
        ({"read_noise_e": math.nan}, ValueError),
        ({"dark_current_e_s": -1.0}, ValueError),
        ({"dark_current_e_s": math.inf}, ValueError),
        ({"dark_current_e_s": "5"}, TypeError),
    ],
)
def test_spec_rejects_bad_values(changes: dict[str, object], error: type[Exception]) -> None:
    with pytest.raises(error):
        replace(SPEC, **changes)  # type: ignore[arg-type]


def test_effect_switches() -> None:
    assert SensorEffects.none() == SensorEffects()
    assert not any(vars(SensorEffects.none()).values())
    assert all(vars(SensorEffects.all()).values())
    assert SensorEffects.from_names(["shot_noise", "source_drift", "saturation"]) == only(
        shot_noise=True, saturation=True
    )
    assert SensorEffects.names() == (
        "shot_noise",
        "read_noise",
        "dark_current",
        "quantization",
        "saturation",
    )
    assert SensorEffects(read_noise=True).random
    assert not SensorEffects(quantization=True, saturation=True, dark_current=True).random


# -- no effects: exact, deterministic, no draws ------------------------------------------


class NoDraws(Streams):
    """Streams that fail the test if anything is drawn."""

    def _words(self, *args: object, **kwargs: object):  # type: ignore[no-untyped-def, override]
        raise AssertionError("no random numbers may be drawn")


def test_no_effects_is_exact_and_draws_nothing() -> None:
    rng = np.random.default_rng(0)
    signal = np.concatenate([rng.uniform(0, 3e5, (500, 3)), [[0.0, 1e-300, 1e12]]])
    counts, saturated = read_out(
        signal, np.full(501, 0.5), SPEC, SensorEffects.none(), NoDraws(0), np.arange(501)
    )
    np.testing.assert_array_equal(counts, signal / GAIN)  # beyond full scale too: no clip
    np.testing.assert_allclose(counts, signal * 65535 / 1e5, rtol=1e-15, atol=0)
    assert not saturated.any()
    again, _ = read_out(signal, 0.5, SPEC, SensorEffects.none(), NoDraws(9), np.arange(501))
    np.testing.assert_array_equal(again, counts)
    # Effects whose parameters are deterministic draw nothing either.
    det = only(dark_current=True, quantization=True, saturation=True)
    read_out(signal, 0.5, SPEC, det, NoDraws(0), np.arange(501))


# -- shot noise ---------------------------------------------------------------------------


def test_shot_noise_variance_is_proportional_to_the_signal() -> None:
    """Variance in electrons = mean (Poisson): a weighted line through (mean, variance)
    over five signal levels has slope 1 and intercept 0 (read noise, dark current off)."""
    levels = np.array([20.0, 200.0, 2e3, 2e4, 8e4])
    n, a = 4000, 5
    means, variances, sds = [], [], []
    for k, lam in enumerate(levels):
        counts, saturated = read(
            np.full((n, a), lam), only(shot_noise=True), index=np.arange(n) + k * n
        )
        electrons = counts * GAIN
        np.testing.assert_allclose(electrons, np.round(electrons), rtol=0, atol=1e-9 * lam)
        m = n * a
        assert abs(electrons.mean() - lam) < FIVE_SIGMA * math.sqrt(lam / m)
        means.append(electrons.mean())
        variances.append(electrons.var(ddof=1))
        sds.append(math.sqrt((lam + 2 * lam * lam) / m))  # sd of a Poisson sample variance
        assert not saturated.any()
    (slope, intercept), cov = np.polyfit(means, variances, 1, w=1 / np.array(sds), cov="unscaled")
    assert abs(slope - 1.0) < FIVE_SIGMA * math.sqrt(cov[0, 0])
    assert abs(slope - 1.0) < 0.03
    assert abs(intercept) < FIVE_SIGMA * math.sqrt(cov[1, 1])
    np.testing.assert_allclose(np.array(variances) / levels, 1.0, atol=0.05)


def test_shot_noise_of_signal_and_dark_use_separate_streams() -> None:
    """Turning dark current on adds Poisson(dark) electrons from their own stream; the
    signal's shot noise stays the same realization."""
    n = 2000
    signal = np.full((n, 2), 5e3)
    t = 0.5
    shot, _ = read(signal, only(shot_noise=True), t=t)
    both, _ = read(signal, only(shot_noise=True, dark_current=True), t=t)
    dark = Streams(1).poisson(np.arange(n), DARK, np.full((n, 2), SPEC.dark_current_e_s * t))
    np.testing.assert_allclose((both - shot) * GAIN, dark, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(
        shot * GAIN, Streams(1).poisson(np.arange(n), SHOT, signal), rtol=1e-15
    )
    variance = (both * GAIN).var()  # Poisson(S) + Poisson(D) = Poisson(S + D)
    expected = 5e3 + SPEC.dark_current_e_s * t
    assert abs(variance / expected - 1.0) < FIVE_SIGMA * math.sqrt(2 / both.size)


# -- read noise ---------------------------------------------------------------------------


def test_read_noise_variance_is_sigma_squared_whatever_the_signal() -> None:
    n, a = 10_000, 2
    sigma2 = SPEC.read_noise_e**2
    first = None
    for lam in (0.0, 1e2, 1e4, 9e4):
        counts, _ = read(np.full((n, a), lam), only(read_noise=True))
        noise = counts * GAIN - lam
        m = noise.size
        assert abs(noise.mean()) < FIVE_SIGMA * math.sqrt(sigma2 / m)
        assert abs(noise.var() / sigma2 - 1.0) < FIVE_SIGMA * math.sqrt(2 / m)
        assert abs(stats.kurtosis(noise.ravel())) < FIVE_SIGMA * math.sqrt(24 / m)
        if first is None:
            first = noise
        else:  # not just the same variance: the same noise, added to any signal
            np.testing.assert_allclose(noise, first, atol=1e-10 * max(lam, 1.0))
    assert first is not None
    assert (first < 0).any()  # read noise can take a dark pixel below zero (no ADC here)


def test_read_noise_adds_to_shot_noise_in_quadrature() -> None:
    n = 20_000
    lam = 400.0
    counts, _ = read(np.full((n, 1), lam), only(shot_noise=True, read_noise=True))
    expected = lam + SPEC.read_noise_e**2
    assert abs((counts * GAIN).var() / expected - 1.0) < FIVE_SIGMA * math.sqrt(2 / n)


# -- dark current -------------------------------------------------------------------------

EXPOSURES = np.array([0.0, 0.01, 0.1, 1.0, 5.0])


def test_dark_counts_are_proportional_to_exposure() -> None:
    n = 200
    t = np.repeat(EXPOSURES, n)
    counts, _ = read(np.zeros((t.size, 2)), only(dark_current=True), t=t)
    expected = (SPEC.dark_current_e_s * t)[:, None] / GAIN
    np.testing.assert_allclose(counts, np.broadcast_to(expected, counts.shape), rtol=1e-15)


def test_dark_counts_with_shot_noise_are_poisson_in_exposure() -> None:
    """Mean ∝ t (a line through the origin with slope = dark current) and variance =
    mean at each exposure."""
    n, a = 5000, 4
    means = []
    for k, t in enumerate(EXPOSURES):
        counts, _ = read(
            np.zeros((n, a)),
            only(dark_current=True, shot_noise=True),
            t=t,
            index=np.arange(n) + k * n,
        )
        e = counts * GAIN
        lam = SPEC.dark_current_e_s * t
        m = e.size
        if lam == 0:
            assert not e.any()
        else:
            assert abs(e.mean() - lam) < FIVE_SIGMA * math.sqrt(lam / m)
            assert abs(e.var(ddof=1) - lam) < FIVE_SIGMA * math.sqrt((lam + 2 * lam**2) / m)
        means.append(e.mean())
    slope, intercept = np.polyfit(EXPOSURES, means, 1)
    assert slope == pytest.approx(SPEC.dark_current_e_s, rel=0.005)
    assert abs(intercept) < 0.5


# -- quantization -------------------------------------------------------------------------


def test_quantization_error_is_uniform_within_half_a_count() -> None:
    rng = np.random.default_rng(42)
    signal = GAIN * rng.uniform(0.0, 3000.0, (50_000, 2))
    exact, _ = read(signal, SensorEffects.none())
    counts, saturated = read(signal, only(quantization=True))
    np.testing.assert_array_equal(counts, np.round(counts))
    error = (counts - exact).ravel()
    assert np.abs(error).max() <= 0.5
    n = error.size
    assert abs(error.mean()) < FIVE_SIGMA * math.sqrt(1 / 12 / n)
    assert abs(error.var() - 1 / 12) < FIVE_SIGMA * math.sqrt((1 / 80 - 1 / 144) / n)
    assert stats.kstest(error, "uniform", args=(-0.5, 1.0)).pvalue > 1e-3
    assert not saturated.any()


def test_adc_codes_are_integer_steps_in_range() -> None:
    """Codes are consecutive integers across a dense signal ramp, clipped at 0 (read
    noise below a dark pixel) and at max_count (beyond full scale, even without the
    saturation effect, which only adds the flag)."""
    ramp = np.linspace(0.0, 50 * GAIN, 2001)[:, None]
    codes, _ = read(ramp, only(quantization=True))
    steps = np.diff(codes[:, 0])
    assert set(np.unique(steps)) == {0.0, 1.0}
    assert codes.min() == 0.0
    assert codes.max() == 50.0
    np.testing.assert_allclose(np.unique(codes) * GAIN, np.arange(51) * GAIN)
    dark, _ = read(np.zeros((5000, 1)), only(quantization=True, read_noise=True))
    assert dark.min() == 0.0
    assert 0.4 < np.mean(dark == 0.0) < 0.8  # half the noise is negative, then round
    bright, flags = read(np.full((10, 1), 3e5), only(quantization=True))
    np.testing.assert_array_equal(bright, SPEC.max_count)
    assert not flags.any()


# -- saturation ---------------------------------------------------------------------------


def test_saturation_clips_at_full_well_and_flags_exactly_those() -> None:
    n = 4000
    full = SPEC.full_well_e
    signal = np.linspace(0.995 * full, 1.005 * full, n)[:, None]
    counts, saturated = read(signal, only(shot_noise=True, saturation=True))
    electrons = Streams(1).poisson(np.arange(n), SHOT, signal)  # the same draws
    np.testing.assert_array_equal(saturated, electrons >= full)
    np.testing.assert_allclose(counts * GAIN, np.minimum(electrons, full), rtol=1e-15)
    assert (counts * GAIN).max() == pytest.approx(full, rel=1e-15)
    # The fraction flagged follows P(Poisson(λ) ≥ full well).
    p = stats.poisson.sf(full - 1, signal[:, 0]).mean()
    assert abs(saturated.mean() - p) < FIVE_SIGMA * math.sqrt(p * (1 - p) / n)
    # Without the effect nothing is clipped or flagged.
    free, flags = read(signal, only(shot_noise=True))
    np.testing.assert_allclose(free * GAIN, electrons, rtol=1e-15)
    assert not flags.any()
    assert (free * GAIN > full).any()


def test_saturation_flags_the_top_adc_code_too() -> None:
    """With quantization, a code at max_count is flagged as well: read noise can push a
    not-quite-full well to the top code (or a full one below it, still flagged)."""
    n = 20_000
    full = SPEC.full_well_e
    signal = np.full((n, 1), full - 2 * GAIN)  # two codes below the top
    effects = only(read_noise=True, quantization=True, saturation=True)
    codes, saturated = read(signal, effects)
    noise = Streams(1).normal(np.arange(n), READ, 1)
    expected = np.clip(np.rint((signal + SPEC.read_noise_e * noise) / GAIN), 0, SPEC.max_count)
    np.testing.assert_array_equal(codes, expected)
    np.testing.assert_array_equal(saturated, codes == SPEC.max_count)
    assert 0 < saturated.mean() < 1
    over, flags = read(np.full((n, 1), full * 1.01), effects)
    assert flags.all()
    assert (over < SPEC.max_count).any()  # read noise after clipping; still flagged


def test_a_saturated_signal_may_be_astronomically_large() -> None:
    """With saturation on, means far beyond float64's integer range read as a full well
    (the Poisson mean is capped where it cannot change the clipped result)."""
    effects = SensorEffects.all()
    huge, flags = read(np.array([[1e20, 1e300], [1e9, 2e5]]), effects, t=1.0)
    assert flags.all()
    ref, _ = read(np.array([[1e9, 1e9], [1e9, 1e9]]), effects, t=1.0)
    np.testing.assert_array_equal(huge, ref)
    with pytest.raises(ValueError, match="Poisson means"):
        read(np.array([[1e20]]), only(shot_noise=True))


# -- reproducibility ------------------------------------------------------------------------


effect_sets = st.builds(SensorEffects, *([st.booleans()] * 5))


@settings(max_examples=40)
@given(
    effects=effect_sets,
    n=st.integers(1, 50),
    a=st.integers(1, 4),
    seed=st.integers(0, 2**32),
    data=st.data(),
)
def test_a_sample_reads_the_same_alone_or_in_a_batch(
    effects: SensorEffects, n: int, a: int, seed: int, data: st.DataObject
) -> None:
    rng = np.random.default_rng(seed)
    signal = rng.uniform(0.0, 1.2 * SPEC.full_well_e, (n, a))
    t = rng.uniform(0.0, 2.0, n)
    idx = rng.choice(10**9, n, replace=False)
    streams = Streams(seed)
    counts, saturated = read_out(signal, t, SPEC, effects, streams, idx)
    for i in range(n):
        c, s = read_out(signal[i : i + 1], t[i], SPEC, effects, Streams(seed), idx[i])
        np.testing.assert_array_equal(c[0], counts[i])
        np.testing.assert_array_equal(s[0], saturated[i])
    perm = np.array(data.draw(st.permutations(range(n))))
    c, s = read_out(signal[perm], t[perm], SPEC, effects, streams, idx[perm])
    np.testing.assert_array_equal(c, counts[perm])
    np.testing.assert_array_equal(s, saturated[perm])


def test_resumed_run_reads_the_same() -> None:
    n = 300
    signal = np.random.default_rng(3).uniform(0, 1e5, (n, 3))
    full, _ = read(signal, SensorEffects.all(), seed=5)
    for k in (1, 120, 299):
        tail, _ = read(signal[k:], SensorEffects.all(), seed=5, index=np.arange(k, n))
        np.testing.assert_array_equal(tail, full[k:])
    other, _ = read(signal, SensorEffects.all(), seed=6)
    assert not np.array_equal(other, full)


def test_averaged_exposures_use_independent_numbers() -> None:
    n = 20_000
    lam = 1e3
    counts, _ = read(np.full((n, 2), lam), only(shot_noise=True, read_noise=True))
    assert abs(np.corrcoef(counts[:, 0], counts[:, 1])[0, 1]) < FIVE_SIGMA / math.sqrt(n)
    summary = summarize(counts, np.zeros_like(counts, dtype=bool))
    # E[s²] over samples equals the per-exposure variance (λ + σ²) / gain².
    expected = (lam + SPEC.read_noise_e**2) / GAIN**2
    assert np.mean(summary.std**2) == pytest.approx(expected, rel=FIVE_SIGMA * math.sqrt(2 / n))


# -- summaries --------------------------------------------------------------------------


def test_summarize_matches_reading_fields() -> None:
    counts = np.array([[1.0, 2.0, 6.0], [4.0, 4.0, 4.0]])
    saturated = np.array([[False, True, False], [False, False, False]])
    s = summarize(counts, saturated)
    np.testing.assert_allclose(s.value, [3.0, 4.0])
    np.testing.assert_allclose(s.std, [math.sqrt(7.0), 0.0])
    np.testing.assert_array_equal(s.n, [3, 3])
    np.testing.assert_array_equal(s.saturated, [True, False])
    one = summarize(counts[:, :1], saturated[:, :1])
    np.testing.assert_array_equal(one.value, [1.0, 4.0])
    np.testing.assert_array_equal(one.std, [0.0, 0.0])
    assert readings(counts, saturated, [1.0, 2.0], [1.5, 2.5]) == [
        Reading(
            value=3.0,
            std=math.sqrt(7.0),
            n=3,
            saturated=True,
            started_s=1.0,
            ended_s=1.5,
            raw=(1.0, 2.0, 6.0),
        ),
        Reading(
            value=4.0,
            std=0.0,
            n=3,
            saturated=False,
            started_s=2.0,
            ended_s=2.5,
            raw=(4.0, 4.0, 4.0),
        ),
    ]
    r = readings(counts[:1, :1], saturated[:1, :1], 0.0, 0.1)[0]
    assert r.middle_s == 0.05
    assert type(r.value) is float
    assert type(r.n) is int
    assert type(r.saturated) is bool
    with pytest.raises(ValueError, match="at least one"):
        summarize(np.zeros((2, 0)), np.zeros((2, 0), dtype=bool))
    with pytest.raises(ValueError, match="both"):
        summarize(counts, saturated[:, :2])


# -- argument errors ------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("signal", "t", "index", "match"),
    [
        (np.ones(3), 0.1, np.arange(3), "shape"),
        (np.ones((3, 1)), 0.1, np.arange(2), "index"),
        (np.ones((3, 1)), np.ones(2), np.arange(3), "exposure_s"),
        (-np.ones((3, 1)), 0.1, np.arange(3), "signal_e"),
        (np.full((3, 1), np.nan), 0.1, np.arange(3), "signal_e"),
        (np.full((3, 1), np.inf), 0.1, np.arange(3), "signal_e"),
        (np.ones((3, 1)), -0.1, np.arange(3), "exposure_s"),
        (np.ones((3, 1)), np.nan, np.arange(3), "exposure_s"),
    ],
)
def test_read_out_rejects_bad_arguments(
    signal: np.ndarray, t: object, index: np.ndarray, match: str
) -> None:
    with pytest.raises(ValueError, match=match):
        read_out(signal, t, SPEC, SensorEffects.all(), Streams(0), index)  # type: ignore[arg-type]
