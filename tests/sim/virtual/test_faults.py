"""Injected faults (`sim.virtual.faults`): where and when they fire, that they hold the motors
as the contract asks, and that a resumed run meets exactly the faults of a whole one."""

from __future__ import annotations

import pytest

from drivers.errors import CommError, DetectorError, MotionTimeout, MotorFault
from gonio.acquire.measure import measure_target
from gonio.config import ConfigError
from gonio.errors import GonioError
from gonio.rig.model import Rig
from gonio.scene import FaultRule, Scene, load_scene
from sim.virtual.devices.instrument import SimulatedInstrument
from sim.virtual.faults import FaultInjector
from sim.virtual.physics.streams import Streams
from tests.conftest import CONFIGS

MATTE = load_scene(CONFIGS / "scenes" / "matte.yaml")


def pose_of(rig: Rig, k: int) -> dict[str, float]:
    """A reachable pose that differs from sample to sample."""
    lo, hi = rig.limits[:, 0], rig.limits[:, 1]
    frac = 0.1 + 0.05 * (k % 7)
    return dict(zip(rig.axes, (lo + frac * (hi - lo)).tolist(), strict=True))


def attempt(inst: SimulatedInstrument, rig: Rig, k: int) -> str:
    """Measure sample k once: 'ok', or the name of the error it met."""
    try:
        m = measure_target(inst.devices(), k, pose_of(rig, k), 0.01, 1, settle_s=0.1)
    except (MotorFault, CommError, MotionTimeout, DetectorError) as exc:
        return type(exc).__name__
    return "saturated" if m.reading.saturated else "ok"


def test_faults_fire_at_their_samples_once_and_retries_succeed(rigs: dict[str, Rig]) -> None:
    rig = rigs["arch"]
    scene = MATTE.with_faults(
        {"kind": "comm_error", "at": 3},
        {"kind": "motion_timeout", "at": 5},
        {"kind": "detector_error", "at": 7},
        {"kind": "saturated", "at": [8, 9]},
        {"kind": "motor_fault", "at": 11, "axis": "detector_elevation", "flags": ["overheating"]},
    )
    with SimulatedInstrument(scene, rig) as inst:
        seen = [attempt(inst, rig, k) for k in range(11)]
        assert seen == ["ok"] * 3 + ["CommError", "ok", "MotionTimeout", "ok", "DetectorError",
                                     "saturated", "saturated", "ok"]  # fmt: skip
        for k in (3, 5, 7):  # the same samples again: transient faults are gone
            assert attempt(inst, rig, k) == "ok"
        assert attempt(inst, rig, 11) == "MotorFault"
        # A motor fault latches until the bus is rebooted, as on hardware.
        assert inst.bus.health()["detector_elevation"].error_flags == ("overheating",)
        assert attempt(inst, rig, 11) == "MotorFault"
        assert inst.bus.reboot() == ("detector_elevation",)
        assert attempt(inst, rig, 11) == "ok"


def test_a_saturated_fault_reads_the_sensor_full_scale(rigs: dict[str, Rig]) -> None:
    rig = rigs["arch"]
    with SimulatedInstrument(MATTE.with_faults({"kind": "saturated", "at": 0}), rig) as inst:
        m = measure_target(inst.devices(), 0, pose_of(rig, 0), 0.01, 2, settle_s=0.0)
    assert m.reading.saturated and m.reading.raw == (2.0**16 - 1,) * 2


def test_random_faults_are_a_pure_function_of_seed_and_sample() -> None:
    rule = FaultRule(kind="comm_error", rate=0.1)
    a = FaultInjector((rule,), Streams(3))
    b = FaultInjector((rule,), Streams(3))
    kinds = frozenset({"comm_error"})
    hits = [k for k in range(5000) if a.fired(k, 0, kinds)]
    assert 400 < len(hits) < 600  # 10 % of 5 000
    # Asked in another order, or only from sample 2 500 on (a resumed run): the same.
    assert [k for k in reversed(range(5000)) if b.fired(k, 0, kinds)] == hits[::-1]
    assert [k for k in range(2500, 5000) if b.fired(k, 0, kinds)] == [h for h in hits if h >= 2500]
    assert not any(a.fired(k, 1, kinds) for k in hits)  # a retry is not faulted again
    assert not any(a.fired(k, 0, frozenset({"detector_error"})) for k in hits)
    other = FaultInjector((rule,), Streams(4))
    assert [k for k in range(5000) if other.fired(k, 0, kinds)] != hits


@pytest.mark.parametrize(
    ("faults", "message"),
    [
        ("[{kind: comm_error}]", "faults.0.at: expected exactly one of at"),
        ("[{kind: comm_error, at: 1, rate: 0.1}]", "faults.0.at: expected exactly one of at"),
        ("[{kind: comm_error, rate: 1.5}]", "faults.0.rate: "),
        ("[{kind: comm_error, at: -2}]", "faults.0.at: expected sample indices ≥ 0"),
        ("[{kind: melt, at: 1}]", "faults.0.kind: "),
        ("[{kind: motor_fault, at: 1, flags: [sadness]}]", "faults.0.flags: expected some of"),
        ("[{kind: saturated, at: 1, axis: light_elevation}]", "faults.0.axis: only a motor_fault"),
    ],
)
def test_bad_fault_rules_are_one_line(tmp_path: object, faults: str, message: str) -> None:
    from pathlib import Path

    assert isinstance(tmp_path, Path)
    text = (CONFIGS / "scenes" / "matte.yaml").read_text(encoding="utf-8")
    path = tmp_path / "scene.yaml"
    path.write_text(text + f"faults: {faults}\n", encoding="utf-8")
    with pytest.raises(ConfigError) as info:
        load_scene(path)
    line = str(info.value)
    assert "\n" not in line and message in line and line.startswith(f"{path}:")


def test_a_fault_on_an_unknown_axis_is_refused_by_the_instrument(rigs: dict[str, Rig]) -> None:
    scene: Scene = MATTE.with_faults({"kind": "motor_fault", "at": 1, "axis": "elbow"})
    with pytest.raises(GonioError, match=r"faults\.0\.axis: 'elbow' is not an axis of rig"):
        SimulatedInstrument(scene, rigs["arch"])
