"""Simulated runs: the vectorized `simulate` equals the target-by-target run through the
driver protocols, a resumed run equals an uninterrupted one, and with no effects the
readings carried back through the calibration give the model's BRDF to 1e-12."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from gonio import radiometry
from gonio.acquire.measure import measure_target
from gonio.acquire.reference import CALIBRATION_INDEX, reference_pose
from gonio.planner import build
from gonio.planner.files import load_plan_source
from gonio.planner.model import Plan
from gonio.planner.schema import PlanSpec
from gonio.rig.model import Rig
from gonio.scene import Scene, load_scene
from gonio.workflows.simulate import simulate_plan
from sim.clock import ManualClock
from sim.virtual.devices.instrument import SimulatedInstrument
from sim.virtual.physics.optics import SceneOptics
from sim.virtual.simulate import expected_rate, simulate, simulate_standard
from tests.conftest import CONFIGS
from tests.support.measure import measure_targets
from tests.support.rigs import with_point_source

SCENES = CONFIGS / "scenes"


def small_plan(rig: Rig, *, isotropic: bool = True, n: int = 120, seed: int = 0) -> Plan:
    spec = PlanSpec.model_validate(
        {
            "name": "t",
            "parametrization": "hybrid",
            "isotropic": isotropic,
            "sampling": {"strategy": "sobol", "target": n, "seed": seed},
            "exposure": {"seconds": 0.01, "averages": 1},
            "time_budget_s": 2,
        }
    )
    return build(spec, rig)


def varied(plan: Plan) -> Plan:
    """The plan with exposures and averages that differ from target to target."""
    n = len(plan)
    return dataclasses.replace(
        plan,
        exposure_s=np.where(np.arange(n) % 3 == 0, 0.002, 0.01),
        averages=(np.arange(n) % 4 + 1).astype(np.int64),
    )


@pytest.mark.parametrize(
    ("scene_name", "rig_name", "isotropic"),
    [
        ("matte", "arch", True),
        ("glossy_metal", "in_plane", True),
        ("brushed_metal", "in_plane", False),
        ("seed000_specular", "arch_point", False),
        ("matte_lockin", "arch", True),
    ],
)
def test_vectorized_equals_target_by_target(
    rigs: dict[str, Rig],
    arch_point: Rig,
    scene_name: str,
    rig_name: str,
    isotropic: bool,
) -> None:
    rig = {**rigs, "arch_point": arch_point}[rig_name]
    scene = load_scene(SCENES / f"{scene_name}.yaml", rig)
    plan = varied(small_plan(rig, isotropic=isotropic, n=60))
    fast = simulate(plan, scene)
    with SimulatedInstrument(scene, plan.rig) as inst:
        slow = measure_targets(inst, plan)
    # Bit for bit: the same motion, times, optics and random numbers.
    for field in ("read_back", "true", "wi", "wo", "settled_s", "end_s", "value", "std"):
        np.testing.assert_array_equal(getattr(fast, field), getattr(slow, field), err_msg=field)
    np.testing.assert_array_equal(fast.saturated, slow.saturated)
    assert fast.instrument_time_s == slow.instrument_time_s


def test_a_lockin_reading_waits_its_filter_and_reads_its_level(rigs: dict[str, Rig]) -> None:
    """A lock-in's reading of τ fixed by the scene waits its settle time (10.1 τ at 24
    dB/oct) when that is longer than the exposure; its value is a level (V), the same
    whatever the exposure, its noise that of the filter's bandwidth."""
    rig = rigs["arch"]
    scene = load_scene(SCENES / "matte_lockin.yaml", rig)
    fixed = scene.model_copy(
        update={"detector": scene.detector.model_copy(update={"time_constant_s": 0.003})}
    )
    plan = small_plan(rig, n=40)  # exposures of 10 ms
    following, slow = simulate(plan, scene), simulate(plan, fixed)
    assert following.instrument_time_s == pytest.approx(plan.summary.total_s, rel=1e-9)
    waited = (slow.end_s - slow.settled_s) / plan.averages
    np.testing.assert_allclose(waited, 10.1 * 0.003, rtol=1e-12)
    # τ 3 ms instead of 10 ms / 10.1: a narrower bandwidth, a smaller spread; the same level.
    ratio = np.abs(slow.value / following.value - 1.0)
    assert np.median(ratio) < 0.05 and np.median(following.value) > 1e-4
    exact = simulate(plan, scene.with_effects([]))
    noise = lambda run: np.std(run.value / exact.value - 1.0)  # noqa: E731
    assert noise(slow) < noise(following)


def test_instrument_time_matches_the_plan_prediction(rigs: dict[str, Rig]) -> None:
    scene = load_scene(SCENES / "matte.yaml")
    plan = small_plan(rigs["arch"])
    run = simulate(plan, scene)
    assert run.instrument_time_s == pytest.approx(plan.summary.total_s, rel=1e-9)
    np.testing.assert_allclose(run.settled_s - plan.rig.spec.settle_s, plan.arrival_s, atol=1e-6)


def test_resumed_run_equals_an_uninterrupted_one(rigs: dict[str, Rig]) -> None:
    scene = load_scene(SCENES / "brushed_metal.yaml")  # backlash, repeatability, drift, noise
    plan = varied(small_plan(rigs["in_plane"], isotropic=False, n=40))
    with SimulatedInstrument(scene, plan.rig) as inst:
        full = measure_targets(inst, plan)
    k = 23
    with SimulatedInstrument(scene, plan.rig) as first:
        measure_targets(first, plan, stop=k)
        state = first.snapshot()
    with SimulatedInstrument(scene, plan.rig, clock=ManualClock()) as second:
        second.restore(state)
        tail = measure_targets(second, plan, start=k)
    np.testing.assert_array_equal(tail.index, full.index[k:])
    np.testing.assert_array_equal(tail.value, full.value[k:])
    np.testing.assert_array_equal(tail.true, full.true[k:])
    np.testing.assert_array_equal(tail.end_s, full.end_s[k:])
    # One sample alone: the same stream gives the same reading.
    with SimulatedInstrument(scene, plan.rig) as third:
        third.restore(full_state_before(scene, plan, 31))
        one = measure_targets(third, plan, start=31, stop=32)
    assert one.value[0] == full.value[31]


def full_state_before(scene: Scene, plan: Plan, k: int) -> object:
    with SimulatedInstrument(scene, plan.rig) as inst:
        measure_targets(inst, plan, stop=k)
        return inst.snapshot()


def test_different_seeds_differ_and_the_same_seed_repeats(rigs: dict[str, Rig]) -> None:
    scene = load_scene(SCENES / "matte.yaml")
    plan = small_plan(rigs["arch"], n=50)
    a, b = simulate(plan, scene), simulate(plan, scene)
    c = simulate(plan, scene, seed=scene.seed + 1)
    np.testing.assert_array_equal(a.value, b.value)
    # Integer ADC codes with a few counts of noise coincide now and then.
    assert np.mean(a.value != c.value) > 0.5


@pytest.mark.parametrize("rig_name", ["arch", "in_plane"])
@pytest.mark.parametrize("kind", ["collimated", "point"])
@pytest.mark.parametrize("isotropic", [True, False])
def test_no_effects_counts_to_brdf_recovers_the_model(
    rigs: dict[str, Rig], rig_name: str, kind: str, isotropic: bool
) -> None:
    """The acquisition path with no effects: readings of the sample and of the reference
    standard (at a fixed pose) turned into BRDF values through the calibration recover
    the model's value at the measured pair to 1e-12 relative, over the reachable domain
    of every shipped rig, for both source types."""
    base = load_scene(SCENES / "glossy_metal.yaml").with_effects([])
    rig, source = (
        (rigs[rig_name], {"irradiance_w_m2": 1.0})
        if kind == "collimated"
        else (with_point_source(rigs[rig_name]), {"intensity_w_sr": 0.01})
    )
    scene = Scene.model_validate({**base.model_dump(), "source": source})
    assert rig.source_kind == kind
    plan = small_plan(rig, isotropic=isotropic, n=300, seed=5)
    run = simulate(plan, scene)
    with SimulatedInstrument(scene, rig) as inst:
        reference_pose = plan.angles[0]
        inst.show("reference")
        pose = dict(zip(rig.axes, reference_pose.tolist(), strict=True))
        ref = measure_target(
            inst.devices(), CALIBRATION_INDEX, pose, 0.01, 1, settle_s=rig.spec.settle_s
        ).reading
        wi_ref, wo_ref = rig.forward(reference_pose)
    calibration = radiometry.ReferenceCalibration.from_counts(
        rig.spec.reference.albedo, ref.value, 0.01, wi_ref, wo_ref, rig.source_kind
    )
    measured = calibration.brdf_from_counts(run.value, run.exposure_s, run.wi, run.wo)
    expected = SceneOptics(scene, rig).models["sample"](run.wi, run.wo)
    assert np.all(expected > 0)
    np.testing.assert_allclose(measured, expected, rtol=1e-12)
    assert scene.material.model().is_rgb  # the detector's band reduced RGB to one value


def test_repeated_measurements_continue_the_sample_streams(rigs: dict[str, Rig]) -> None:
    """Measuring one sample again (a retry, a longer exposure) draws new numbers from
    that sample's streams, never the next sample's; calibration readings have their own
    indices. Each is reproducible on a fresh instrument."""
    scene = load_scene(SCENES / "matte.yaml")
    rig = rigs["arch"]

    home = dict(zip(rig.axes, rig.home.tolist(), strict=True))

    def target(inst: SimulatedInstrument, index: int) -> float:
        m = measure_target(inst.devices(), index, home, 0.01, 1, settle_s=rig.spec.settle_s)
        return m.reading.value

    def readings() -> list[float]:
        with SimulatedInstrument(scene, rig) as inst:
            first = target(inst, 5)
            again = inst.detector.measure(0.01, 2)  # sample 5 again, two exposures
            inst.show("reference")
            ref = measure_target(
                inst.devices(), CALIBRATION_INDEX, home, 0.01, 1, settle_s=rig.spec.settle_s
            ).reading
            inst.show("sample")
            six = target(inst, 6)
            return [first, *again.raw, ref.value, six]

    a, b = readings(), readings()
    assert a == b
    assert len(set(a[:3])) == 3  # three exposures of sample 5: three draws
    # The readings of sample 6 do not depend on how often sample 5 was measured, nor
    # on the calibration reading taken in between.
    with SimulatedInstrument(scene, rig) as inst:
        assert target(inst, 6) == a[-1]


@pytest.fixture(scope="module")
def shipped_plans(arch_point: Rig) -> dict[tuple[str, str], Plan]:
    """Each shipped plan on its own rig and on the point-source rig, ordered with no move
    budget (which poses and exposures a plan holds does not depend on their order). Fly
    plans are planned, not acquired: left out."""
    plans = {}
    for path in sorted((CONFIGS / "plans").glob("*.yaml")):
        source = load_plan_source(path)
        if source.spec.sampling.strategy == "fly":
            continue
        spec = source.spec.model_copy(update={"max_moves": 0})
        plans[path.stem, "collimated"] = build(spec, source.rig)
        plans[path.stem, "point"] = build(spec, arch_point)
    return plans


@pytest.mark.parametrize("scene_name", sorted(p.stem for p in SCENES.glob("*.yaml")))
def test_no_shipped_plan_saturates_a_shipped_scene(
    shipped_plans: dict[tuple[str, str], Plan], scene_name: str
) -> None:
    """Every shipped scene models saturation and none of the shipped plans (quick,
    quickstart, isotropic_hybrid, anisotropic, rehearsal) puts a reading at the top of
    its ADC (the quick plan put 67 and 74 glossy and brushed-metal readings
    there, up to 48× full well, and 194 point-source readings above full well with
    saturation unmodelled)."""
    scene = load_scene(SCENES / f"{scene_name}.yaml")
    assert scene.effects.saturation is not None
    assert {name for name, _ in shipped_plans} == {
        "quick",
        "quickstart",
        "isotropic_hybrid",
        "anisotropic",
        "rehearsal",
    }
    for (name, kind), plan in shipped_plans.items():
        if kind == scene.source.kind:
            run = simulate(plan, scene)
            assert not run.saturated.any(), (name, int(run.saturated.sum()))


@pytest.mark.parametrize("scene_name", ["matte", "glossy_metal"])
def test_standard_readings_equal_the_engines_calibrations(
    rigs: dict[str, Rig], scene_name: str
) -> None:
    """`simulate_standard` reads the reference standard (and the dark) as the engine's
    calibrations do, bit for bit: the fast path of the calibration tests is the real one."""
    rig = rigs["arch"]
    scene = load_scene(SCENES / f"{scene_name}.yaml", rig)
    scene = scene.with_effects({**scene.effects.model_dump(), "source_drift": {"amplitude": 0.01}})
    spec = PlanSpec.model_validate(
        {
            "name": "t",
            "parametrization": "hybrid",
            "isotropic": True,
            "sampling": {"strategy": "sobol", "target": 6, "seed": 0},
            "exposure": {"seconds": 0.01, "averages": 1},
            "time_budget_s": 2,
            "max_moves": 0,
            "kicks": 0,
            "acquisition": {"calibration": {"every_samples": 3, "averages": 5}},
        }
    )
    run = simulate_plan(build(spec, rig), scene, seed=7).run
    events = run.of_kind("calibration")
    assert len(events) >= 3
    pose = reference_pose(rig)
    for light_on, key, offset in ((True, "reference", 0), (False, "dark", 1)):
        readings = [e.data[key] for e in events]
        k = np.array([e.data["k"] for e in events])
        got = simulate_standard(
            rig, scene, pose, np.array([r["started_s"] for r in readings]),
            readings[0]["exposure_s"], readings[0]["n"], CALIBRATION_INDEX + 2 * k + offset,
            seed=7, light_on=light_on,
        )  # fmt: skip
        assert got.value.tolist() == [r["value"] for r in readings]
        assert got.std.tolist() == [r["std"] for r in readings]


def test_expected_rate_is_the_noise_free_reading(rigs: dict[str, Rig]) -> None:
    rig = rigs["arch"]
    scene = load_scene(SCENES / "matte.yaml", rig).with_effects(["source_drift"])
    pose = reference_pose(rig)
    got = simulate_standard(rig, scene, pose, np.array([0.0, 100.0]), 0.02, 1, np.arange(2))
    t_mid = np.array([0.01, 100.01])
    np.testing.assert_allclose(got.value / 0.02, expected_rate(rig, scene, pose, t_mid), rtol=1e-13)
