"""studies/align.py's helpers: its random misalignments have the sizes its page
states, and its direction error sees what the optics see and nothing a mirror cannot
(the sample stage's zero offset, moved into the tilt's azimuth, turns the sample frame
about its normal and nothing else)."""

from __future__ import annotations

import importlib.util
import math
import sys
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest

from gonio.rig import Rig
from gonio.rig.alignment_spec import AlignmentSpec
from tests.conftest import CONFIGS

STUDY = Path(__file__).resolve().parents[3] / "studies" / "align.py"


@pytest.fixture(scope="module")
def bench() -> ModuleType:
    saved = list(sys.path)  # the study puts benchmarks/ (its `_report`) on the path
    sys.path.insert(0, str(STUDY.parent))  # as when run
    try:
        spec = importlib.util.spec_from_file_location("align_study", STUDY)
        assert spec is not None and spec.loader is not None
        module = importlib.util.module_from_spec(spec)
        sys.modules[spec.name] = module  # its dataclasses look their module up
        spec.loader.exec_module(module)
    finally:
        sys.path[:] = saved
    return module


@pytest.fixture(scope="module")
def rig() -> Rig:
    return Rig.from_yaml(CONFIGS / "rigs" / "arch.yaml")


@pytest.fixture(scope="module")
def poses(rig: Rig) -> np.ndarray:
    """Joint angles (200, A) the arch rig measures at."""
    rng = np.random.default_rng(4)
    q = np.radians(rng.uniform([0, -170, -70, -180], [75, 170, 70, 180], (400, 4)))
    return q[rig.pose_reasons(q)[1]][:200]


def test_the_draws_have_the_stated_sizes_and_random_directions(bench: ModuleType, rig: Rig) -> None:
    specs = [bench.draw(np.random.default_rng(seed), rig.axes) for seed in range(200)]
    zeros = np.array([[s.zero_offset_deg[a] for a in rig.axes] for s in specs])
    assert np.all(np.abs(zeros) <= 1.0) and np.abs(zeros).max() > 0.95
    assert all(s.tilt_deg == 0.5 and abs(s.height_mm) == 0.5 for s in specs)
    assert {np.sign(s.height_mm) for s in specs} == {-1.0, 1.0}
    for chain in ("light_pointing_deg", "detector_pointing_deg"):
        vectors = np.array([getattr(s, chain) for s in specs])
        assert np.allclose(np.hypot(*vectors.T), 0.3)
        assert np.ptp(np.arctan2(vectors[:, 1], vectors[:, 0])) > 0.9 * 2 * math.pi
    assert bench.draw(np.random.default_rng(7), rig.axes) == specs[7]


def test_the_stage_zero_moved_into_the_tilt_turns_the_sample_frame_and_nothing_else(
    bench: ModuleType, rig: Rig, poses: np.ndarray
) -> None:
    truth = bench.draw(np.random.default_rng(1), rig.axes)
    zero = math.radians(truth.zero_offset_deg["sample_rotation"])
    gauged = bench.gauged(truth, "sample_rotation")
    assert gauged.zero_offset_deg["sample_rotation"] == 0.0
    wi, wo = rig.forward(poses, truth.alignment(rig.axes))
    gi, go = rig.forward(poses, gauged.alignment(rig.axes))
    c, s = math.cos(zero), math.sin(zero)
    turn = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    assert np.allclose(wi @ turn.T, gi, atol=1e-14) and np.allclose(wo @ turn.T, go, atol=1e-14)
    assert not np.allclose(wi, gi, atol=1e-4)  # the raw frames do differ
    # any other stage zero, its difference in the tilt's azimuth, is the same optics ...
    same = bench.gauged(truth, "sample_rotation", -0.8)
    assert np.allclose(bench.direction_errors(rig, poses, same, truth), 0.0, atol=1e-9)
    # ... but not the stage zero alone: the tilt turns with the stage
    alone = truth.model_copy(update={"zero_offset_deg": same.zero_offset_deg})
    assert bench.direction_errors(rig, poses, alone, truth).max() > 0.005


def test_the_direction_error_is_each_directions_own_turn(
    bench: ModuleType, rig: Rig, poses: np.ndarray
) -> None:
    none = AlignmentSpec()
    detector = AlignmentSpec(zero_offset_deg={"detector_elevation": 0.2})
    errors = bench.direction_errors(rig, poses, none, detector)
    assert errors.shape == (len(poses), 2)
    assert np.allclose(errors[:, 0], 0.0, atol=1e-9)  # ωi untouched
    assert np.allclose(errors[:, 1], 0.2, atol=1e-9)  # ωo turned by the offset, everywhere
    # a light pointing error about its arm's axis acts as the arm's zero offset
    pointing = AlignmentSpec(light_pointing_deg=(0.0, 0.3))
    arm = AlignmentSpec(zero_offset_deg={"light_elevation": 0.3})
    assert np.allclose(bench.direction_errors(rig, poses, pointing, arm), 0.0, atol=1e-9)


def test_the_truth_is_compared_in_the_estimates_gauge(bench: ModuleType, rig: Rig) -> None:
    truth = AlignmentSpec(
        zero_offset_deg={"sample_rotation": 0.3, "detector_azimuth": -0.4},
        tilt_deg=0.5,
        tilt_azimuth_deg=40.0,
    )
    estimate = AlignmentSpec(zero_offset_deg={"sample_rotation": 0.1})
    values = dict(zip(bench.parameters(rig), bench.truth_vector(rig, truth, estimate), strict=True))
    assert math.degrees(values["zero_offset.sample_rotation"]) == pytest.approx(0.1)
    assert math.degrees(values["zero_offset.detector_azimuth"]) == pytest.approx(-0.4)
    assert math.degrees(values["tilt_x"]) == pytest.approx(0.5 * math.cos(math.radians(40.2)))
    assert math.degrees(values["tilt_y"]) == pytest.approx(0.5 * math.sin(math.radians(40.2)))


def test_the_peaks_offsets_are_where_the_detector_must_be_commanded(
    bench: ModuleType, rig: Rig
) -> None:
    none = bench.peak_offsets(rig, AlignmentSpec())
    assert none.shape[1] == 2 and len(none) >= 10 and np.allclose(none, 0.0, atol=1e-12)
    turned = bench.peak_offsets(rig, AlignmentSpec(zero_offset_deg={"detector_azimuth": 0.5}))
    assert np.allclose(turned, [0.0, -0.5], atol=1e-9)  # commanded back by the offset
    lifted = bench.peak_offsets(rig, AlignmentSpec(zero_offset_deg={"detector_elevation": 0.5}))
    assert np.allclose(lifted, [-0.5, 0.0], atol=1e-9)
    # a turn across the plane of incidence needs 1 / sin θo of azimuth
    tilted = bench.peak_offsets(rig, AlignmentSpec(detector_pointing_deg=(0.5, 0.0)))
    assert np.abs(tilted[:, 1]).max() > 0.5 / math.sin(math.radians(25.0))
