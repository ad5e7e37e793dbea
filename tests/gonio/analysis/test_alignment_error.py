"""The uncertainty of the rig's measured alignment in each calibrated sample's σ: first
order through the slope of the BRDF the run's own samples suggest; it agrees with the
slope of the scene's true BRDF where the samples are dense enough to show it, adds in
quadrature, and is absent without a fit record."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from gonio.analysis import calibrate
from gonio.analysis.alignment_error import alignment_error
from gonio.analysis.scene import scene_truth
from gonio.planner import build, load_plan
from gonio.rig import AlignmentSpec, Rig
from gonio.rig.alignment_file import AlignmentFile, FitRecord, text
from gonio.rig.sensitivity import alignment_brdf_sigma
from gonio.scene import load_scene
from gonio.store.read import Run
from gonio.workflows.simulate import simulate_plan
from tests.conftest import CONFIGS
from tests.support.alignment import fit_record

ERROR_DEG = 0.5  # large, so that it dominates the radiometric noise


def rig_with(tmp_path: Path, fit: FitRecord | None) -> Rig:
    spec = AlignmentSpec(zero_offset_deg={"detector_elevation": 0.2}, tilt_deg=0.3)
    (tmp_path / "align.yaml").write_text(text(AlignmentFile(alignment=spec, fit=fit)))
    path = tmp_path / "arch.yaml"
    path.write_text((CONFIGS / "rigs" / "arch.yaml").read_text() + "alignment: align.yaml\n")
    return Rig.from_yaml(path)


def record() -> FitRecord:
    return fit_record(
        {"zero_offset.detector_elevation": (0.2, ERROR_DEG), "tilt_x": (0.3, ERROR_DEG)},
        [[1.0, 0.3], [0.3, 1.0]],
    )


def simulated(rig: Rig, scene_name: str) -> Run:
    spec, _ = load_plan(CONFIGS / "plans" / "quick.yaml")
    spec = spec.model_copy(update={"kicks": 0})
    spec = spec.model_copy(update={"sampling": spec.sampling.model_copy(update={"target": 300})})
    scene = load_scene(CONFIGS / "scenes" / f"{scene_name}.yaml", rig)
    return simulate_plan(build(spec, rig), scene, seed=3).run


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> tuple[Run, Run]:
    """The glossy metal measured by the arch rig with a fitted alignment, and with the
    same alignment set by hand (no uncertainty stated)."""
    fitted = rig_with(tmp_path_factory.mktemp("fitted"), record())
    by_hand = rig_with(tmp_path_factory.mktemp("by_hand"), None)
    return simulated(fitted, "glossy_metal"), simulated(by_hand, "glossy_metal")


def test_the_alignment_error_follows_the_true_slope(runs: tuple[Run, Run]) -> None:
    """σ_align is about 5 % of f here: the slope matters."""
    run, _ = runs
    got = alignment_error(run, calibrate(run, falloff=False).brdf)
    truth = scene_truth(str(run.meta["scene_text"]), None)

    class Truth:
        is_rgb = False

        @staticmethod
        def eval(wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
            return np.asarray(truth(wi, wo), dtype=np.float64)

    expected = alignment_brdf_sigma(Truth(), run.plan.rig, run.angles())
    assert np.all(np.isfinite(got)) and np.all(got >= 0)
    ratio = got / expected
    assert np.median(ratio) == pytest.approx(1.0, abs=0.1)
    assert np.quantile(ratio, [0.1, 0.9]) == pytest.approx([1.0, 1.0], abs=0.3)


def test_it_adds_in_quadrature_and_only_with_a_fit_record(runs: tuple[Run, Run]) -> None:
    fitted, by_hand = runs
    assert np.array_equal(fitted.samples["counts"], by_hand.samples["counts"])
    with_error, without = calibrate(fitted), calibrate(by_hand)
    np.testing.assert_array_equal(with_error.brdf, without.brdf)
    added = alignment_error(fitted, with_error.brdf)
    np.testing.assert_allclose(with_error.sigma, np.hypot(without.sigma, added), rtol=1e-12)
    assert np.median(added / without.sigma) > 3.0  # 0.5° dominates the noise
    assert not np.any(alignment_error(by_hand, without.brdf))
