"""`SimDetector`'s ``motion_blur`` and ``timestamp_jitter`` effects on a stream: a window
is the mean over Gauss–Legendre time nodes of the optics along the path, its stamps are
late and jittered from the sample's own random stream."""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
import yaml

from gonio.config import ConfigError
from gonio.rig.model import Rig
from gonio.scene import Scene, load_scene
from sim.clock import ManualClock
from sim.virtual.devices.detector import SimDetector
from sim.virtual.devices.windows import blur_nodes, gauss_legendre
from sim.virtual.physics.streams import Streams
from tests.conftest import CONFIGS

GLOSSY = load_scene(CONFIGS / "scenes" / "glossy_metal.yaml")


def narrow(effects: dict[str, object], alpha: float = 0.02) -> Scene:
    """The gold scene with a GGX α lobe and only ``effects`` (exact readings)."""
    data = GLOSSY.model_dump()
    data["material"] = {"name": "cook_torrance", **data["material"]["params"], "alpha": alpha}
    return Scene.model_validate({**data, "effects": effects})


def sweep(rig: Rig, start_deg: float, speed_deg_s: float) -> Callable[[float], dict[str, float]]:
    """The detector arc at ``speed_deg_s`` from ``start_deg`` at t = 0, the light at 30°."""

    def pose_at(t: float) -> dict[str, float]:
        theta_o = math.radians(start_deg + speed_deg_s * t)
        return dict(zip(rig.axes, (math.radians(30.0), 0.0, -theta_o, 0.0), strict=True))

    return pose_at


def stream(scene: Scene, rig: Rig, pose_at: Callable[[float], dict[str, float]], *,
           seconds: float = 0.1, rate: float = 100.0, integration: float = 0.008,
           sample: int = 0, seed: int = 0) -> tuple[SimDetector, list]:  # fmt: skip
    clock = ManualClock(0.0)
    det = SimDetector(
        scene, rig, lambda: pose_at(clock.now()), clock=clock, streams=Streams(seed),
        pose_at=pose_at,
    )  # fmt: skip
    with det:
        det.begin_sample(sample)
        det.start_stream(rate, integration)
        clock.advance(seconds)
        readings = det.stop_stream()
    return det, readings


def test_the_node_count_grows_with_the_smear(rigs: dict[str, Rig]) -> None:
    assert blur_nodes(np.array([0.0, 0.01, 0.05, 0.051, 1.0, 100.0]), 0.05, 64).tolist() == [
        1, 1, 1, 2, 20, 64,
    ]  # fmt: skip
    rig = rigs["arch"]
    counts = []
    for speed in (0.0, 10.0, 50.0, 200.0):  # smear 0, 0.08, 0.4, 1.6° in 8 ms
        det, _ = stream(narrow({"motion_blur": {}}), rig, sweep(rig, 20.0, speed))
        counts.append(set(det.stream_nodes))
    assert counts == [{1}, {2}, {8}, {32}]


def test_a_still_window_blurred_is_the_static_reading_exactly(rigs: dict[str, Rig]) -> None:
    rig = rigs["arch"]
    still = sweep(rig, 30.2, 0.0)
    _, blurred = stream(narrow({"motion_blur": {}, "shot_noise": {}}), rig, still)
    _, plain = stream(narrow({"shot_noise": {}}), rig, still)
    assert [r.value for r in blurred] == [r.value for r in plain]


def test_a_linear_in_time_signal_has_its_middle_as_mean(rigs: dict[str, Rig]) -> None:
    for n in (1, 2, 5, 33):
        x, w = gauss_legendre(n)
        assert w.sum() == pytest.approx(1.0, abs=1e-15)
        assert (w * x**3).sum() == pytest.approx(0.25, abs=1e-14) or n < 2
    rig = rigs["arch"]
    det, _ = stream(
        narrow({"motion_blur": {"max_step_deg": 0.01, "max_nodes": 1024}}),
        rig,
        sweep(rig, 20.0, 0.0),
    )
    # geometric power linear in the detector's angle, the angle linear in time
    det.chain.geometric_power = lambda wi, wo, target="sample": (
        1e-6
        * (  # type: ignore[method-assign]
            2.0 + np.arctan2(np.abs(wo[:, 0]), wo[:, 2])
        )
    )
    pose_at = sweep(rig, 20.0, 300.0)
    det.windows.pose_at = pose_at
    with det:
        det.start_stream(100.0, 0.008)
        det._clock.advance(0.05)  # type: ignore[attr-defined]
        readings = det.stop_stream()
    assert set(det.stream_nodes) == {240}
    for r in readings:
        wi, wo = rig.forward(np.array([[pose_at(r.middle_s)[a] for a in rig.axes]]))
        at_middle = det.chain.electrons(
            det.chain.power(det.chain.geometric_power(wi, wo), np.array([[r.middle_s]])),
            np.array([0.008]),
        )[0, 0] / (det.sensor.full_well_e / (2**det.sensor.adc_bits - 1))
        assert r.value == pytest.approx(at_middle, rel=1e-9)


def test_the_blur_on_a_narrow_lobe_matches_a_fine_quadrature(rigs: dict[str, Rig]) -> None:
    rig = rigs["arch"]
    pose_at = sweep(rig, 28.0, 100.0)  # 0.8° per 8 ms window, across the peak at 30°
    det, blurred = stream(narrow({"motion_blur": {}}), rig, pose_at, seconds=0.05)
    _, mid = stream(narrow({}), rig, pose_at, seconds=0.05)
    bias = []
    for r, m in zip(blurred, mid, strict=True):
        t = np.linspace(r.started_s, r.ended_s, 4001)  # trapezoids on 4000 steps
        poses = np.array([[pose_at(x)[a] for a in rig.axes] for x in t])
        power = det.chain.geometric_power(*rig.forward(poses))
        fine = ((power[1:] + power[:-1]) / 2).mean()
        middle = np.array([[pose_at(r.middle_s)[a] for a in rig.axes]])
        at_middle = det.chain.geometric_power(*rig.forward(middle))[0]
        # the readings scale as the power: blurred / mid-time = fine mean / power at middle
        assert r.value / m.value == pytest.approx(fine / at_middle, rel=1e-6)
        bias.append(r.value / m.value - 1)
    assert min(bias) < -0.01  # the peak is lowered by the blur


def test_jittered_stamps_are_reproducible_per_seed_and_sample(rigs: dict[str, Rig]) -> None:
    rig = rigs["arch"]
    scene = narrow({"timestamp_jitter": {"sigma_s": 2e-4, "latency_s": 1e-3}})
    pose_at = sweep(rig, 20.0, 5.0)
    det, a = stream(scene, rig, pose_at, seconds=2.0, sample=7)
    _, b = stream(scene, rig, pose_at, seconds=2.0, sample=7)
    _, c = stream(scene, rig, pose_at, seconds=2.0, sample=8)
    _, d = stream(scene, rig, pose_at, seconds=2.0, sample=7, seed=1)
    assert [r.started_s for r in a] == [r.started_s for r in b]
    assert [r.started_s for r in a] != [r.started_s for r in c]
    assert [r.started_s for r in a] != [r.started_s for r in d]
    truth = np.array(det.stream_truth)
    shift = np.array([r.started_s for r in a]) - truth[:, 0]
    assert np.array([r.ended_s - r.started_s for r in a]) == pytest.approx(0.008)
    assert shift.mean() == pytest.approx(1e-3, abs=4 * 2e-4 / math.sqrt(len(a)))
    assert shift.std() == pytest.approx(2e-4, rel=0.2)
    # the values are those of the true windows: as without jitter
    _, plain = stream(narrow({}), rig, pose_at, seconds=2.0, sample=7)
    assert [r.value for r in a] == [r.value for r in plain]


@pytest.mark.parametrize(
    ("effect", "field"),
    [
        ({"motion_blur": {"max_step_deg": 0}}, "effects.motion_blur.max_step_deg"),
        ({"motion_blur": {"max_nodes": 0.5}}, "effects.motion_blur.max_nodes"),
        ({"timestamp_jitter": {"sigma_s": -1e-3}}, "effects.timestamp_jitter.sigma_s"),
        ({"timestamp_jitter": {"lag": 1}}, "effects.timestamp_jitter.lag"),
    ],
)
def test_bad_effect_parameters_are_one_line(
    tmp_path: Path, effect: dict[str, object], field: str
) -> None:
    path = tmp_path / "scene.yaml"
    data = GLOSSY.model_dump()
    data["material"] = {"name": "cook_torrance", **data["material"]["params"]}
    path.write_text(yaml.safe_dump({**data, "effects": effect}))
    with pytest.raises(ConfigError) as err:
        load_scene(path)
    message = str(err.value)
    assert "\n" not in message and field in message and str(path) in message
