"""The MERL writer (`gonio.export.merl`), read back with a reader written here from the
layout in docs/reference/formats.md, and its bin convention checked against both inverse readings
of MERL's index (a bin's lower corner, a bin's centre)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from gonio import brdf, params
from gonio.analysis.measured import Measured
from gonio.cli import main
from gonio.export.merl import fill, representative_pairs, write
from gonio.output import reserve_output
from gonio.reconstruct.methods import reconstruction

HALF_PI = np.pi / 2
SCALES = np.array([1.0, 1.15, 1.66]) / 1500.0


class Synthetic:
    """An analytic RGB model whose 'measured support' is both directions above 20°."""

    def __init__(self, model: brdf.BRDF) -> None:
        self.model = model

    def eval(self, wi, wo):
        return self.model.eval(wi, wo)

    def supported(self, wi, wo):
        return (np.asarray(wi)[..., 2] > np.sin(0.35)) & (np.asarray(wo)[..., 2] > np.sin(0.35))


MODEL = Synthetic(brdf.create("cook_torrance", alpha=0.3, kd=(0.5, 0.3, 0.2), f0=0.04))


def read_merl(path: Path) -> np.ndarray:
    """(3, 90, 90, 180) stored values × scales, as BRDFRead.cpp reads them."""
    raw = path.read_bytes()
    assert len(raw) == 34_992_012
    dims = np.frombuffer(raw[:12], dtype="<i4")
    assert dims.tolist() == [90, 90, 180]
    values = np.frombuffer(raw[12:], dtype="<f8").reshape(3, 90, 90, 180)
    return values * SCALES[:, None, None, None]


def merl_index(theta_h, theta_d, phi_d):
    """BRDFRead.cpp's lookup: floor of √(θh/(π/2))·90, θd/(π/2)·90, φd/π·180 (φd < 0
    shifted by π), clipped."""
    i = np.floor(np.sqrt(np.maximum(theta_h, 0) / HALF_PI) * 90).astype(int)
    j = np.floor(theta_d / HALF_PI * 90).astype(int)
    k = np.floor(np.where(phi_d < 0, phi_d + np.pi, phi_d) / np.pi * 180).astype(int)
    return np.clip(i, 0, 89), np.clip(j, 0, 89), np.clip(k, 0, 179)


def centre_reading():
    n = np.arange(90) + 0.5
    return (n / 90) ** 2 * HALF_PI, n / 90 * HALF_PI, (np.arange(180) + 0.5) / 180 * np.pi


def edge_reading():
    n = np.arange(90)
    return (n / 90) ** 2 * HALF_PI, n / 90 * HALF_PI, np.arange(180) / 180 * np.pi


def pairs_at(theta_h, theta_d, phi_d):
    """Direction pairs (φh = 0) of the given angles (broadcast), and where they exist."""
    c = np.stack(np.broadcast_arrays(theta_h, 0.0, theta_d, phi_d), axis=-1)
    p = params.get("rusinkiewicz")
    ok = p.valid(c)
    wi, wo = p.inverse(c[ok])
    return wi, wo, ok


@pytest.fixture(scope="module")
def written(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("merl") / "model.binary"
    with reserve_output(path, "-o") as out:
        summary = write(out, MODEL)
    assert "34992012 bytes" in summary
    return path


@pytest.fixture(scope="module")
def table(written: Path) -> np.ndarray:
    return read_merl(written)


@pytest.fixture(scope="module")
def sample():
    """A fixed subset of bins (index arrays) to check, spread over the table."""
    rng = np.random.default_rng(11)
    n = 40_000
    return rng.integers(0, 90, n), rng.integers(0, 90, n), rng.integers(0, 180, n)


def test_bins_hold_the_model_at_their_centres_where_supported(table, sample):
    i, j, k = sample
    th, td, pd = (a[idx] for a, idx in zip(centre_reading(), sample, strict=True))
    wi, wo, ok = pairs_at(th, td, pd)
    values = table[:, i, j, k].T
    inside = MODEL.supported(wi, wo)
    np.testing.assert_allclose(values[ok][inside], MODEL.eval(wi, wo)[inside], rtol=1e-14)
    assert np.all(values[ok][~inside] < 0)  # outside the support: missing
    assert np.all(values[~ok] < 0)  # no pair (a direction below the horizon): missing
    assert inside.sum() > 5000 and (~inside).sum() > 5000 and (~ok).sum() > 1000


def test_the_representative_pairs_are_the_parametrizations_inverse_bit_for_bit(sample):
    wi, wo, ok = representative_pairs()
    th, td, pd = (a[idx] for a, idx in zip(centre_reading(), sample, strict=True))
    expected_wi, expected_wo, expected_ok = pairs_at(th, td, pd)
    np.testing.assert_array_equal(ok[sample], expected_ok)
    np.testing.assert_array_equal(wi[sample][expected_ok], expected_wi)
    np.testing.assert_array_equal(wo[sample][expected_ok], expected_wo)
    assert np.all(wi[~ok] == (0.0, 0.0, 1.0)) and np.all(wo[~ok] == (0.0, 0.0, 1.0))


def test_the_centre_reading_maps_back_to_its_own_bin_the_edge_reading_not_always():
    bins = np.meshgrid(np.arange(0, 90, 7), np.arange(0, 90, 7), np.arange(0, 180, 9))
    bins = [b.ravel() for b in bins]

    def misses(reading):
        wi, wo, ok = pairs_at(*(a[n] for a, n in zip(reading, bins, strict=True)))
        c = params.get("rusinkiewicz").forward_iso(wi, wo)
        back = merl_index(c[:, 0], c[:, 1], c[:, 2])
        return sum(np.count_nonzero(b != n[ok]) for b, n in zip(back, bins, strict=True))

    assert misses(centre_reading()) == 0
    assert misses(edge_reading()) > 0  # rounding puts some lower corners in the bin below


def test_the_edge_reading_sees_the_value_half_a_bin_away(table):
    """A reader taking bin (i, j, k) at its lower corner attributes the centre's value to
    the corner: off by the model's change over half a bin, not more."""
    i, j, k = np.meshgrid(np.arange(5, 60, 5), np.arange(5, 60, 5), np.arange(3, 180, 11))
    i, j, k = i.ravel(), j.ravel(), k.ravel()
    edge_pairs = pairs_at(*(a[n] for a, n in zip(edge_reading(), (i, j, k), strict=True)))
    centre_pairs = pairs_at(*(a[n] for a, n in zip(centre_reading(), (i, j, k), strict=True)))
    assert np.all(edge_pairs[2]) and np.all(centre_pairs[2])
    at_edge = MODEL.eval(*edge_pairs[:2])
    at_centre = MODEL.eval(*centre_pairs[:2])
    stored = table[:, i, j, k].T
    keep = np.all(stored > 0, axis=1)
    np.testing.assert_allclose(stored[keep], at_centre[keep], rtol=1e-14)
    assert np.any(np.abs(stored[keep] - at_edge[keep]) > 1e-6 * at_edge[keep])


def test_extrapolation_on_request_fills_the_bins_outside_the_support():
    grey = Synthetic(brdf.create("lambert", albedo=0.6))
    missing, extrapolated = fill(grey), fill(grey, extrapolate=True)
    assert extrapolated.extrapolated == missing.unsupported > 0
    gained = missing.missing & ~extrapolated.missing
    assert np.count_nonzero(gained) == missing.unsupported
    # One channel is written grey; the extrapolation is the model's own value.
    np.testing.assert_allclose(extrapolated.values[:, gained], 0.6 / np.pi, rtol=1e-15)
    # Bins without a pair stay missing either way.
    assert np.count_nonzero(extrapolated.missing) == extrapolated.no_pair


def test_a_run_is_written_from_its_reconstruction(run_file, tmp_path, sample):
    """`gonio export --format merl`: the run's linear reconstruction at the bin centres
    where it is supported, the rest missing (negative)."""
    out = tmp_path / "run.binary"
    assert main(["export", str(run_file), "--format", "merl", "-o", str(out), "-q"]) == 0
    stored = read_merl(out)
    surface = reconstruction(Measured.from_run(run_file), "linear", None)
    th, td, pd = (a[idx] for a, idx in zip(centre_reading(), sample, strict=True))
    wi, wo, ok = pairs_at(th, td, pd)
    i, j, k = (idx[ok] for idx in sample)
    got = stored[:, i, j, k]
    inside = surface.supported(wi, wo)
    assert 0.05 < inside.mean() < 0.95  # a 60-sample run supports part of the table
    np.testing.assert_allclose(got[0, inside], surface.eval(wi, wo)[inside], rtol=1e-12)
    assert np.all(got[:, ~inside] < 0)  # written missing (`--merl-fill extrapolate`
    # fills them: test_extrapolation_on_request_fills_the_bins_outside_the_support)


def test_gonios_reader_takes_gonios_file_back(written, sample):
    """The whole round trip: model → MERL file → `gonio.brdf.create("merl")`, equal at
    the supported bin centres."""
    th, td, pd = (a[idx] for a, idx in zip(centre_reading(), sample, strict=True))
    wi, wo, _ = pairs_at(th, td, pd)
    inside = MODEL.supported(wi, wo)
    table = brdf.create("merl", path=str(written))
    np.testing.assert_allclose(
        table.eval(wi[inside], wo[inside]), MODEL.eval(wi[inside], wo[inside]), rtol=1e-9
    )
