"""`SimDetector` effect by effect: each effect's signature in the readings, through
the instrument (virtual motors, forward kinematics, radiometric chain, sensor)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from drivers.errors import DetectorError
from gonio import radiometry
from gonio.rig.model import Rig
from gonio.scene import Scene, load_scene
from sim.virtual.devices.instrument import SimulatedInstrument
from tests.conftest import CONFIGS
from tests.support.rigs import rig_with

SCENES = CONFIGS / "scenes"
MATTE = load_scene(SCENES / "matte.yaml")


def scene_with(base: Scene = MATTE, *, effects: Any = (), **changes: Any) -> Scene:
    data = base.model_dump()
    for key, value in changes.items():
        merge = isinstance(value, dict) and key != "material"
        data[key] = {**data[key], **value} if merge else value
    data["effects"] = effects if isinstance(effects, dict) else list(effects)
    return Scene.model_validate(data)


def in_plane_pose(rig: Rig, theta_i_deg: float, theta_o_deg: float) -> list[float]:
    """Arch rig: light at θi in the x-z plane, the detector at θo on the far side."""
    assert rig.spec.type == "arch"
    return [math.radians(theta_i_deg), 0.0, math.radians(-theta_o_deg), 0.0]


def read(inst: SimulatedInstrument, pose: list[float], exposure: float, averages: int = 1) -> Any:
    inst.bus.move_to(dict(zip(inst.rig.axes, pose, strict=True)))
    inst.bus.wait_settled(600.0)
    return inst.detector.measure(exposure, averages)


@pytest.fixture(scope="module")
def arch(rigs: dict[str, Rig]) -> Rig:
    return rigs["arch"]


def test_exact_value_without_effects(arch: Rig) -> None:
    scene = scene_with(effects=[])
    with SimulatedInstrument(scene, arch) as inst:
        pose = in_plane_pose(arch, 30.0, 20.0)
        r = read(inst, pose, 0.05, averages=3)
        wi, wo = arch.forward(np.array(pose))
    f = scene.material.model().eval(wi, wo)
    source = radiometry.CollimatedSource(1.0, 6.0)
    optics = radiometry.DetectorOptics(1e-5, 25.0)
    electrons = radiometry.electrons(radiometry.radiant_power(source, optics, f, wi, wo), 0.05, 0.5)
    gain = scene.detector.full_well_e / (2**scene.detector.adc_bits - 1)
    assert r.value == pytest.approx(float(electrons) / gain, rel=1e-14)
    assert r.std == 0.0 and r.n == 3 and not r.saturated
    assert r.raw == (r.value,) * 3


def test_exposure_and_averages_are_checked(arch: Rig) -> None:
    with SimulatedInstrument(MATTE, arch) as inst:
        for bad in (0.0, 1e-6, 120.0, math.nan):
            with pytest.raises(DetectorError, match="outside the detector's range"):
                inst.detector.measure(bad)
        for averages in (0, -1, 1.5):
            with pytest.raises(DetectorError, match="averages must be a positive integer"):
                inst.detector.measure(0.01, averages)  # type: ignore[arg-type]


def test_the_exposure_range_is_the_rigs(arch: Rig) -> None:
    rig = rig_with(arch, detector={"exposure_range_s": [0.01, 1.0]})
    with SimulatedInstrument(MATTE, rig) as inst:
        with pytest.raises(DetectorError, match=r"range \[0.01, 1\] s"):
            inst.detector.measure(0.005)
        assert inst.detector.measure(1.0).n == 1


def test_measuring_takes_virtual_time(arch: Rig) -> None:
    rig = rig_with(arch, detector={"readout_s": 0.004})
    with SimulatedInstrument(MATTE, rig) as inst:
        t = inst.clock.now()
        r = inst.detector.measure(0.1, 5)
        assert inst.clock.now() - t == pytest.approx(5 * 0.104)
        assert (r.started_s, r.ended_s) == (t, inst.clock.now())


def test_dark_frames_with_the_light_off(arch: Rig) -> None:
    scene = scene_with(effects=["dark_current"])
    gain = scene.detector.full_well_e / (2**scene.detector.adc_bits - 1)
    with SimulatedInstrument(scene, arch) as inst:
        inst.light.off()
        for t in (0.01, 0.1, 1.0):
            r = inst.detector.measure(t)
            assert r.value == pytest.approx(scene.detector.dark_current_e_s * t / gain, rel=1e-12)
        inst.light.on()
        assert inst.detector.measure(0.1).value > 1.5 * scene.detector.dark_current_e_s * 0.1 / gain


def test_stray_light_adds_a_constant_floor(arch: Rig) -> None:
    floor = 1e-13  # W
    clean = scene_with(effects=[])
    stray = scene_with(effects={"stray_light": {"power_w": floor}})
    gain = clean.detector.full_well_e / (2**clean.detector.adc_bits - 1)
    expected = radiometry.electrons(floor, 0.05, clean.detector.responsivity_a_w) / gain
    for theta_o in (5.0, 40.0, 70.0):
        pose = in_plane_pose(arch, 20.0, theta_o)
        with SimulatedInstrument(clean, arch) as a, SimulatedInstrument(stray, arch) as b:
            diff = read(b, pose, 0.05).value - read(a, pose, 0.05).value
        assert diff == pytest.approx(float(expected), rel=1e-9)
    with SimulatedInstrument(stray, arch) as b:
        b.light.off()
        assert b.detector.measure(0.05).value == 0.0  # stray light comes from the source


def test_drift_correlates_with_time_and_the_reference_removes_it(arch: Rig) -> None:
    scene = scene_with(
        effects={"source_drift": {"rate_per_hour": 0.05, "amplitude": 0.01, "period_s": 1800}}
    )
    pose = in_plane_pose(arch, 25.0, 35.0)
    samples, ratios, times = [], [], []
    with SimulatedInstrument(scene, arch) as inst:
        for _ in range(40):
            inst.clock.advance(300.0)  # a target every five minutes for over three hours
            s = read(inst, pose, 0.05).value
            times.append(inst.clock.now())
            inst.show("reference")
            r = inst.detector.measure(0.05).value
            inst.show("sample")
            samples.append(s)
            ratios.append(s / r)
    samples_a, ratios_a = np.array(samples), np.array(ratios)
    assert np.corrcoef(times, samples_a)[0, 1] > 0.95
    assert np.ptp(samples_a) / samples_a.mean() > 0.1
    # Re-measuring the reference right after each sample removes the drift, up to what
    # the source drifts in the 0.05 s between the two readings (≈ 2e-6).
    assert np.ptp(ratios_a) / ratios_a.mean() < 1e-5


def test_aperture_integration_lowers_a_sharp_peak_and_converges(arch: Rig) -> None:
    ggx = {"name": "cook_torrance", "alpha": 0.02, "fresnel": "schlick", "f0": 0.9}
    pose = in_plane_pose(arch, 30.0, 30.0)  # the mirror configuration: the peak
    values = {}
    for aperture in (1e-3, 1e-4, 1e-5, 1e-6):
        rig = rig_with(arch, detector={"aperture_sr": aperture})
        for effects in ([], ["aperture_integration"]):
            scene = scene_with(material=ggx, effects=effects)
            with SimulatedInstrument(scene, rig) as inst:
                values[aperture, bool(effects)] = read(inst, pose, 1e-4).value
    ratio = {a: values[a, True] / values[a, False] for a in (1e-3, 1e-4, 1e-5, 1e-6)}
    assert ratio[1e-3] < 0.9
    assert ratio[1e-3] < ratio[1e-4] < ratio[1e-5] < ratio[1e-6] <= 1.0
    assert 1.0 - ratio[1e-6] < 1e-3


@pytest.mark.parametrize(
    ("fov_mm", "predicted_deg"),
    [
        # The beam spills off the 30 mm sample when 6 / cos θi > 30.
        (100.0, math.degrees(math.acos(6.0 / 30.0))),
        # The lit ellipse leaves a 25 mm view seen from θo = 10° (major axes aligned)
        # when 6 / cos θi > 25 / cos θo.
        (25.0, math.degrees(math.acos(6.0 * math.cos(math.radians(10.0)) / 25.0))),
    ],
    ids=["sample-limit", "field-of-view-limit"],
)
def test_footprint_kicks_in_at_the_predicted_grazing_angle(
    arch: Rig, fov_mm: float, predicted_deg: float
) -> None:
    clean = scene_with(effects=[])
    spill = scene_with(effects=["footprint"])
    rig = rig_with(arch, constraints={"detector_fov_mm": fov_mm})
    ratios = {}
    angles = (60.0, predicted_deg - 0.01, predicted_deg + 0.01, 82.0, 84.0)
    for theta in angles:
        pose = in_plane_pose(rig, theta, 10.0)
        with SimulatedInstrument(clean, rig) as a, SimulatedInstrument(spill, rig) as b:
            ratios[theta] = read(b, pose, 0.05).value / read(a, pose, 0.05).value
    assert ratios[60.0] == pytest.approx(1.0, rel=1e-14)
    assert ratios[angles[1]] == pytest.approx(1.0, rel=1e-14)
    assert ratios[angles[2]] < 1.0 - 1e-6
    assert ratios[angles[2]] > ratios[82.0] > ratios[84.0]


def test_saturation_flags_the_glossy_peak(arch: Rig) -> None:
    glossy = load_scene(SCENES / "glossy_metal.yaml")
    pose = in_plane_pose(arch, 30.0, 30.0)
    with SimulatedInstrument(glossy, arch) as inst:
        long = read(inst, pose, 1.0)
        short = read(inst, pose, 1e-4)
    assert long.saturated and long.value == 2**24 - 1  # its 24-bit ADC
    assert not short.saturated


def test_rgb_material_seen_through_the_detector_band(arch: Rig) -> None:
    glossy = load_scene(SCENES / "glossy_metal.yaml")
    pose = in_plane_pose(arch, 30.0, 45.0)
    values = {}
    for band in ("luminance", "r", "g", "b"):
        scene = scene_with(glossy, detector={"band": band}, effects=[])
        with SimulatedInstrument(scene, arch) as inst:
            values[band] = read(inst, pose, 0.01).value
    assert values["r"] > values["g"] > values["b"]  # gold
    weights = (0.2126, 0.7152, 0.0722)
    expected = sum(w * values[c] for w, c in zip(weights, "rgb", strict=True))
    assert values["luminance"] == pytest.approx(expected, rel=1e-12)
