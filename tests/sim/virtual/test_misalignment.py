"""The scene's ``misalignment`` effect: the simulated devices measure through the true
geometry while the engine records the rig file's angles and directions. A zero offset
moves a glossy metal's specular peak to where the true geometry puts it; the
vectorized run equals the target-by-target one; the journal holds the rig file's pairs
and analysis the true ones; the rehearsal's emulated detector measures through the true
geometry; listed with no parameters it changes nothing; an offset of an axis the rig
has not is refused."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import pytest

from gonio.acquire.measure import measure_target
from gonio.analysis.summary import measured_pairs
from gonio.config import ConfigError
from gonio.rig import AlignmentSpec
from gonio.rig.model import Rig
from gonio.scene import Scene, load_scene
from gonio.types import FloatArray
from gonio.workflows.rehearsal import rehearsal_devices
from gonio.workflows.simulate import simulate_plan
from sim.virtual.devices.instrument import SimulatedInstrument
from sim.virtual.simulate import simulate
from tests.conftest import CONFIGS
from tests.sim.virtual.test_simulate import small_plan
from tests.support.measure import measure_targets

SCENES = CONFIGS / "scenes"
GLOSSY = load_scene(SCENES / "glossy_metal.yaml")


@dataclasses.dataclass(frozen=True)
class Sweep:
    """Targets for `simulate`: joint angles (N, A), one exposure each."""

    rig: Rig
    angles: FloatArray

    @property
    def exposure_s(self) -> FloatArray:
        return np.full(len(self.angles), 1e-3)

    @property
    def averages(self) -> np.ndarray:
        return np.ones(len(self.angles), dtype=np.int64)

    def __len__(self) -> int:
        return len(self.angles)


def misaligned(base: Scene, effects: list[str] | None = None, **spec: Any) -> Scene:
    """``base`` with only ``effects`` and the misalignment ``spec``."""
    listed: dict[str, Any] = dict.fromkeys(effects or [])
    return base.with_effects({**listed, "misalignment": spec})


def specular_peak_deg(rig: Rig, scene: Scene, light_deg: float) -> float:
    """The commanded detector elevation (°) of the largest reading over a sweep through
    the rig file's specular pose (light at +x, detector toward −x), by a parabola
    through the top three readings."""
    elevation = np.radians(np.arange(-light_deg - 3.0, -light_deg + 3.0, 0.01))
    q = np.zeros((len(elevation), len(rig.axes)))
    q[:, rig.axes.index("light_elevation")] = np.radians(light_deg)
    q[:, rig.axes.index("detector_elevation")] = elevation
    value = np.log(simulate(Sweep(rig, q), scene).value)
    k = int(np.argmax(value))
    a, b, c = value[k - 1 : k + 2]
    step = elevation[1] - elevation[0]
    return float(np.degrees(elevation[k] + 0.5 * step * (a - c) / (a - 2.0 * b + c)))


@pytest.mark.parametrize(
    ("axis", "offset_deg"), [("detector_elevation", 0.5), ("light_elevation", -0.3)]
)
def test_a_zero_offset_moves_the_specular_peak_where_the_true_geometry_puts_it(
    rigs: dict[str, Rig], axis: str, offset_deg: float
) -> None:
    """The true angle is the rig file's + δ: a detector δ off peaks at −θ − δ commanded;
    a light δ off puts the mirror direction at −(θ + δ), commanded as such."""
    rig, light = rigs["arch"], 30.0
    plain = specular_peak_deg(rig, GLOSSY.with_effects([]), light)
    assert plain == pytest.approx(-light, abs=1e-3)
    peak = specular_peak_deg(rig, misaligned(GLOSSY, zero_offset_deg={axis: offset_deg}), light)
    assert peak == pytest.approx(-light - offset_deg, abs=2e-3)


def test_a_tilt_moves_the_peak_by_twice_its_angle(rigs: dict[str, Rig]) -> None:
    rig, light = rigs["arch"], 40.0
    peak = specular_peak_deg(rig, misaligned(GLOSSY, tilt_deg=0.25, tilt_azimuth_deg=0.0), light)
    assert peak == pytest.approx(-light + 0.5, abs=2e-3)


@pytest.mark.parametrize("rig_name", ["arch", "in_plane"])
def test_vectorized_equals_target_by_target_through_the_true_geometry(
    rigs: dict[str, Rig], rig_name: str
) -> None:
    rig = rigs[rig_name]
    scene = misaligned(
        GLOSSY, ["shot_noise", "read_noise", "position_error"],
        zero_offset_deg={rig.axes[0]: 0.4, rig.axes[-1]: -0.2}, tilt_deg=0.3,
        tilt_azimuth_deg=70, height_mm=0.5, light_pointing_deg=(0.1, -0.2),
        detector_pointing_deg=(-0.3, 0.1),
    )  # fmt: skip
    plan = small_plan(rig, n=40)
    fast = simulate(plan, scene)
    with SimulatedInstrument(scene, plan.rig) as inst:
        slow = measure_targets(inst, plan)
    for field in ("read_back", "true", "wi", "wo", "value", "std"):
        np.testing.assert_array_equal(getattr(fast, field), getattr(slow, field), err_msg=field)
    alignment = AlignmentSpec.model_validate(scene.effects.model_dump()["misalignment"]).alignment(
        rig.axes
    )
    true_wi, true_wo = rig.forward(fast.true, alignment)
    np.testing.assert_array_equal(fast.wi, true_wi)
    np.testing.assert_array_equal(fast.wo, true_wo)
    assert np.max(np.abs(fast.wi - rig.forward(fast.true)[0])) > 1e-3


def test_the_journal_holds_the_rig_files_pairs_and_analysis_the_true_ones(
    rigs: dict[str, Rig],
) -> None:
    rig = rigs["arch"]
    spec = {"zero_offset_deg": {"detector_azimuth": 0.5}, "tilt_deg": 0.2}
    scene = misaligned(GLOSSY, **spec)
    result = simulate_plan(small_plan(rig, n=30), scene)
    read_back = result.run.angles()
    wi, wo = rig.forward(read_back)
    np.testing.assert_array_equal(result.wi, wi)
    np.testing.assert_array_equal(result.wo, wo)
    true_wi, true_wo = measured_pairs(result.run)
    alignment = AlignmentSpec.model_validate(spec).alignment(rig.axes)
    np.testing.assert_allclose(true_wi, rig.forward(read_back, alignment)[0], atol=1e-12)
    np.testing.assert_allclose(true_wo, rig.forward(read_back, alignment)[1], atol=1e-12)
    assert np.max(np.abs(true_wo - wo)) > 1e-3


def test_the_rehearsals_detector_measures_through_the_true_geometry(rigs: dict[str, Rig]) -> None:
    """An offset δ on every axis: the emulated detector at read-back q reads what the
    aligned simulation reads at q + δ."""
    rig = rigs["arch"]
    offset = dict.fromkeys(rig.axes, 0.3)
    scene = misaligned(GLOSSY.with_effects([]), zero_offset_deg=offset)
    target = np.radians([30.0, 10.0, -25.0, 5.0])
    with (
        rehearsal_devices(rig, scene, None, 40.0) as (devices, _),
        devices,
        SimulatedInstrument(GLOSSY.with_effects([]), rig) as sim,
    ):
        devices.bus.move_to(dict(zip(rig.axes, target.tolist(), strict=True)))
        devices.bus.wait_settled(10.0)
        read_back = np.array(list(devices.bus.positions().values()))
        reading = devices.detector.measure(0.01)
        pose = dict(zip(rig.axes, (read_back + np.radians(0.3)).tolist(), strict=True))
        expected = measure_target(sim.devices(), 0, pose, 0.01, 1, settle_s=0.0).reading
        assert reading.value == pytest.approx(expected.value, rel=1e-9)


def test_listed_with_no_parameters_it_changes_nothing(rigs: dict[str, Rig]) -> None:
    rig = rigs["in_plane"]
    plan = small_plan(rig, n=30)
    base = GLOSSY.with_effects(["shot_noise"])
    listed = GLOSSY.with_effects(["shot_noise", "misalignment"])
    assert listed.effects.misalignment == AlignmentSpec()
    a, b = simulate(plan, base), simulate(plan, listed)
    for field in ("wi", "wo", "value"):
        np.testing.assert_array_equal(getattr(a, field), getattr(b, field))


def test_an_offset_of_an_axis_the_rig_has_not_is_refused(rigs: dict[str, Rig]) -> None:
    scene = misaligned(GLOSSY, zero_offset_deg={"light_arm": 0.1})
    with pytest.raises(ConfigError, match="zero_offset_deg: 'light_arm' is not an axis"):
        scene.check_rig(rigs["arch"])
