"""The alignment a mirror scan measures (`gonio.rig.alignment_fit`): peaks made where a
misaligned rig's true reflection meets the detector, located with noise, fitted back;
every determined parameter within 3 of its standard errors and 0.03° of the truth, the
others reported undetermined with what would determine them."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import least_squares

from gonio.errors import GonioError
from gonio.rig.alignment import Alignment
from gonio.rig.alignment_fit import as_alignment, fit, miss, parameters
from gonio.rig.alignment_hints import hints
from gonio.rig.model import Rig
from tests.conftest import CONFIGS

RIG = Rig.from_yaml(CONFIGS / "rigs" / "arch.yaml")
D = math.radians
#: Where the peak of each pose is located to (rad).
SIGMA = D(0.01)


def peaks(truth: Alignment, rotations_deg: tuple[float, ...], rng: np.random.Generator):
    """Poses (M, A) at which the detector sees the mirror's peak under ``truth``, the
    detector's two joints located with `SIGMA` of noise."""
    theta = np.radians([10.0, 25.0, 40.0, 55.0, 70.0])[:, None]
    phi = np.radians(np.arange(0.0, 360.0, 60.0))[None, :]
    wi = np.stack(
        np.broadcast_arrays(
            np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)
        ),
        axis=-1,
    ).reshape(-1, 3)
    out = []
    for rotation in np.radians(rotations_deg):
        c, s = math.cos(rotation), math.sin(rotation)
        turn = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        solution = RIG.solve(wi @ turn.T, (wi * (-1.0, -1.0, 1.0)) @ turn.T)
        for q in solution.angles[solution.ok]:

            def off(x: np.ndarray, q: np.ndarray = q) -> np.ndarray:
                return miss(RIG, np.concatenate([q[:1], x, q[3:]])[None], truth)[0]

            x = least_squares(off, q[1:3], xtol=1e-15, ftol=1e-15, gtol=1e-15).x
            out.append(np.concatenate([q[:1], x + rng.normal(0.0, SIGMA, 2), q[3:]]))
    return np.array(out)


def draw(rng: np.random.Generator) -> Alignment:
    return Alignment(
        zero_offset=np.radians(rng.uniform(-1.0, 1.0, 4)),
        tilt=D(0.5),
        tilt_azimuth=rng.uniform(0.0, 2.0 * math.pi),
        height_mm=0.5,
        light_pointing=np.radians(rng.uniform(-0.3, 0.3, 2)),
        detector_pointing=np.radians(rng.uniform(-0.3, 0.3, 2)),
    )


def truth_vector(truth: Alignment) -> np.ndarray:
    """The parameters as a scan sees them: the tilt's azimuth from the stage's zero as
    the rig file reads it (the stage's own offset, which a mirror cannot see, turns it)."""
    azimuth = float(truth.tilt_azimuth + truth.zero_offset[RIG.axes.index("sample_rotation")])
    tilt = float(truth.tilt)
    return np.concatenate(
        [
            truth.zero_offset,
            [tilt * math.cos(azimuth), tilt * math.sin(azimuth)],
            [float(truth.height_mm)],
            truth.light_pointing,
            truth.detector_pointing,
        ]
    )


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_every_determined_parameter_is_recovered_within_its_errors(seed: int) -> None:
    rng = np.random.default_rng(seed)
    truth = draw(rng)
    result = fit(RIG, peaks(truth, (0.0, 120.0, 240.0), rng), SIGMA)
    assert result.names == parameters(RIG)
    expected = truth_vector(truth)
    ok = result.determined
    assert {"tilt_x", "tilt_y", "zero_offset.detector_azimuth"} <= {
        n for n, d in zip(result.names, ok, strict=True) if d
    }
    error = np.abs(result.values - expected)[ok]
    assert np.all(error <= 3.0 * result.errors[ok] + 1e-12), (result.names, error, result.errors)
    assert np.all(error <= D(0.03))
    assert result.reduced_chi2 < 1.5  # joint noise moves the directions by at most σ
    # what acts alike is fitted as one: the light's elevation offset with its pointing
    # about the same axis, the detector's likewise
    names = list(result.names)
    for axis, pointing in (
        ("light_elevation", "light_pointing_y"),
        ("detector_elevation", "detector_pointing_y"),
    ):
        i, j = names.index(f"zero_offset.{axis}"), names.index(pointing)
        assert not ok[i] and not ok[j]
        assert abs(result.values[i] + result.values[j] - expected[i] - expected[j]) < D(0.03)


def test_what_a_collimated_scan_cannot_see_is_said_not_set() -> None:
    rng = np.random.default_rng(4)
    result = fit(RIG, peaks(draw(rng), (0.0, 120.0, 240.0), rng), SIGMA)
    height = result.names.index("height_mm")
    assert not result.determined[height] and math.isnan(result.errors[height])
    assert result.hints["height_mm"] == "moves no direction this rig measures: nothing to correct"
    assert set(result.hints) == {
        n for n, d in zip(result.names, result.determined, strict=True) if not d
    }
    # aliases are named as such, whatever the scan; what a mirror cannot see, with what can
    assert result.hints["light_pointing_y"] == (
        "no scan separates it from zero_offset.light_elevation: it moves every measured "
        "direction as that does (what they do together is fitted, and is what the "
        "directions need)"
    )
    assert "anisotropic reference" in result.hints["zero_offset.sample_rotation"]


def test_a_point_sources_height_is_no_alias() -> None:
    """With a point source the height moves the light's direction by h sin θi / r: not
    as any other parameter does, so a scan over a wider range of incidences would
    determine it."""
    point = Rig.from_yaml(CONFIGS / "rigs" / "arch_point.yaml")
    names = parameters(point)
    said = hints(point, names, ["height_mm"], lambda p: as_alignment(point, p))
    assert said["height_mm"].startswith("needs peaks over a wider range of incidences")


def test_too_few_or_bad_peaks_are_one_line() -> None:
    rng = np.random.default_rng(5)
    few = peaks(Alignment.none(), (0.0,), rng)[:2]
    with pytest.raises(GonioError, match="expected more peaks"):
        fit(RIG, few, SIGMA)
    with pytest.raises(GonioError, match="finite peaks with positive uncertainties"):
        fit(RIG, np.full((10, 4), np.nan), SIGMA)
    with pytest.raises(GonioError, match=r"expected peaks \(M, 4\)"):
        fit(RIG, np.zeros((10, 3)), SIGMA)
