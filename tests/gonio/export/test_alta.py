"""`gonio export --format alta`, read back as ALTA reads a text data file (a header of
``#KEY value`` lines, ``# `` comments, then whitespace-separated rows of x, y and the
``#VS 1`` half-width), with ALTA's coordinates computed here from its definitions
(``params.cpp``: V = ωo packed first, L = ωi; H = (L + V)/2, B = (L − V)/2)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from gonio.analysis.measured import Measured
from gonio.cli import main


def read_alta(path: Path) -> tuple[dict[str, str], np.ndarray]:
    header: dict[str, str] = {}
    rows = []
    for line in path.read_text(encoding="ascii").splitlines():
        if line.startswith("#"):
            if not line.startswith("# "):
                key, _, value = line[1:].partition(" ")
                header[key] = value.strip()
            continue
        rows.append([float(x) for x in line.split()])
    return header, np.array(rows)


@pytest.fixture(scope="module")
def files(run_file: Path, tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("alta")
    out = {}
    for param in ("stark_3d", "rusin_th_td_pd"):
        out[param] = folder / f"{param}.alta"
        args = ["export", str(run_file), "--format", "alta", "--alta-param", param]
        assert main([*args, "-o", str(out[param]), "-q"]) == 0
    return out


def _rotate_z(v: np.ndarray, angle: np.ndarray) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.stack([c * v[:, 0] - s * v[:, 1], s * v[:, 0] + c * v[:, 1], v[:, 2]], axis=1)


def _rotate_y(v: np.ndarray, angle: np.ndarray) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.stack([c * v[:, 0] + s * v[:, 2], v[:, 1], -s * v[:, 0] + c * v[:, 2]], axis=1)


def test_the_header_is_what_alta_parses(files):
    for param, name in (("stark_3d", "STARK_3D"), ("rusin_th_td_pd", "RUSIN_TH_TD_PD")):
        header, rows = read_alta(files[param])
        assert header == {
            "DIM": "3 1",
            "PARAM_IN": name,
            "PARAM_OUT": "INV_STERADIAN",
            "VS": "1",
        }
        assert rows.shape[1] == 3 + 1 + 1  # x, y and one half-width per row


def test_stark_3d_coordinates_values_and_intervals(files, run_file):
    measured = Measured.from_run(run_file)
    _, rows = read_alta(files["stark_3d"])
    V, L = measured.wo, measured.wi
    H, B = (L + V) / 2, (L - V) / 2
    expected = np.stack(
        [
            np.hypot(H[:, 0], H[:, 1]),
            np.linalg.norm(B, axis=1),
            np.mod(np.arctan2(B[:, 1], B[:, 0]) - np.arctan2(H[:, 1], H[:, 0]), 2 * np.pi),
        ],
        axis=1,
    )
    np.testing.assert_allclose(rows[:, :3], expected, rtol=0, atol=1e-12)
    assert np.all((rows[:, 2] >= 0) & (rows[:, 2] < 2 * np.pi))
    np.testing.assert_array_equal(rows[:, 3], measured.f)
    np.testing.assert_array_equal(rows[:, 4], measured.sigma)
    assert np.all(rows[:, 4] > 0)  # a noisy run: every interval has a width


def test_altas_own_inverse_of_stark_3d_gives_the_pair_swapped(files, run_file):
    """ALTA's to_cartesian of STARK_3D (H in the x-z plane, B of elevation
    atan2(−Hz, ‖h̄‖ cos Δφ)) takes the principal quadrant and so rebuilds −B: the pair
    up to a rotation about the normal, with light and view exchanged (docs/reference/formats.md).
    Immaterial for the reciprocal BRDFs ALTA fits; the file holds the forward values."""
    measured = Measured.from_run(run_file)
    _, rows = read_alta(files["stark_3d"])
    hbar, b, dphi = rows[:, 0], rows[:, 1], rows[:, 2]
    hz = np.sqrt(1 - hbar**2 - b**2)
    theta = np.arctan2(-hz, hbar * np.cos(dphi))
    B = b[:, None] * np.stack(
        [np.sin(theta) * np.cos(dphi), np.sin(theta) * np.sin(dphi), np.cos(theta)], axis=1
    )
    H = np.stack([hbar, np.zeros_like(hbar), hz], axis=1)
    V, L = H - B, H + B
    np.testing.assert_allclose(V[:, 2], measured.wi[:, 2], atol=1e-9)  # swapped
    np.testing.assert_allclose(L[:, 2], measured.wo[:, 2], atol=1e-9)
    np.testing.assert_allclose(
        np.sum(V * L, axis=1), np.sum(measured.wo * measured.wi, axis=1), atol=1e-9
    )
    assert not np.allclose(V[:, 2], measured.wo[:, 2], atol=1e-3)


def test_rusin_th_td_pd_is_the_view_rotated_into_the_halfway_frame(files, run_file):
    measured = Measured.from_run(run_file)
    _, rows = read_alta(files["rusin_th_td_pd"])
    V, L = measured.wo, measured.wi
    h = (V + L) / np.linalg.norm(V + L, axis=1, keepdims=True)
    theta_h = np.arccos(h[:, 2])
    diff = _rotate_y(_rotate_z(V, -np.arctan2(h[:, 1], h[:, 0])), -theta_h)
    expected = np.stack(
        [theta_h, np.arccos(diff[:, 2]), np.mod(np.arctan2(diff[:, 1], diff[:, 0]), 2 * np.pi)],
        axis=1,
    )
    np.testing.assert_allclose(rows[:, :3], expected, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(rows[:, 3], measured.f)


def test_an_unknown_parametrization_is_a_usage_error(run_file, tmp_path, capsys):
    args = ["export", str(run_file), "--format", "alta", "--alta-param", "spherical"]
    with pytest.raises(SystemExit) as stop:
        main([*args, "-o", str(tmp_path / "x.alta")])
    assert stop.value.code == 2
    assert "--alta-param" in capsys.readouterr().err
