"""A stop-and-go plan's predicted duration against a hand computation: on the serial
arch rig (Dynamixel servos) the moves at the rates the profile registers hold and the
bus's wire time of each step at the rig's baud rate; on the simulated arch rig the rig
file's rates and no bus. The stored plan keeps the figures and says which model."""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import numpy as np
import pytest

from gonio.cli.render import render_summary
from gonio.planner import build
from gonio.planner.model import Plan
from gonio.planner.schema import PlanSpec
from gonio.planner.stored import plan_bytes, read_plan, write_plan
from gonio.rig.model import Rig

RIGS = Path(__file__).resolve().parents[3] / "configs" / "rigs"
RPM = 2.0 * math.pi / 60.0  # rad/s in one rev/min
RPM2 = 2.0 * math.pi / 3600.0  # rad/s² in one rev/min²
#: The register steps configs/rigs/arch_serial.yaml's rates round to, and the gears:
#: 45 °/s = 32.75 → 33 × 0.229 rev/min, 90 °/s² = 4.19 → 4 × 214.577 rev/min²; the
#: azimuth's 40 °/s and 60 °/s² through its 2:1 belt, 58.2 → 58 and 5.59 → 6 steps; the
#: sample's 90 °/s and 180 °/s², 65.5 → 66 and 8.39 → 8.
STEPS = {
    "light_elevation": (33, 4, 1.0),
    "detector_azimuth": (58, 6, 2.0),
    "detector_elevation": (33, 4, 1.0),
    "sample_rotation": (66, 8, 1.0),
}


def tiny(rig: Rig) -> Plan:
    """Eight anisotropic Sobol targets on ``rig``."""
    spec = PlanSpec.model_validate(
        {
            "name": "tiny",
            "parametrization": "hybrid",
            "isotropic": False,
            "sampling": {"strategy": "sobol", "target": 8, "seed": 3},
            "exposure": {"seconds": 0.05, "averages": 2},
        }
    )
    return build(spec, rig)


def at_baud(baud: int) -> Rig:
    rig = Rig.from_yaml(RIGS / "arch_serial.yaml")
    bus = rig.spec.bus.model_copy(update={"baud": baud})
    return Rig(rig.spec.model_copy(update={"bus": bus}))


def moves_by_hand(plan: Plan, velocity: list[float], acceleration: list[float]) -> np.ndarray:
    """Each move's time, one axis and one move at a time: the slowest axis's trapezoid."""
    poses = [plan.rig.home.tolist(), *plan.angles.tolist()]
    out = []
    for p, q in itertools.pairwise(poses):
        times = []
        for x, y, v, a in zip(p, q, velocity, acceleration, strict=True):
            d = abs(y - x)
            times.append(2.0 * math.sqrt(d / a) if d < v * v / a else d / v + v / a)
        out.append(max(times))
    return np.array(out)


def bus_by_hand(moves: np.ndarray, baud: int) -> np.ndarray:
    """The goals' SYNC_WRITE (34 bytes for 4 motors), two polls of Moving … Present
    Position (18 bytes out, 4 × 25 back, 4 return delays of 500 µs), and half a poll
    period (a poll and the bus's 2 ms pause) after a motion's end."""
    goals = 34 * 10 / baud
    poll = 118 * 10 / baud + 4 * 500e-6
    return goals + 2 * poll + np.where(moves > 0, 0.5 * (poll + 0.002), 0.0)


@pytest.mark.parametrize("baud", [57_600, 1_000_000])
def test_a_dynamixel_plan_runs_the_registers_rates_and_counts_the_bus(baud: int) -> None:
    rig = at_baud(baud)
    plan = tiny(rig)
    names = list(rig.axes)
    velocity = [STEPS[n][0] * 0.229 * RPM / STEPS[n][2] for n in names]
    acceleration = [STEPS[n][1] * 214.577 * RPM2 / STEPS[n][2] for n in names]
    assert math.degrees(acceleration[names.index("light_elevation")]) == pytest.approx(
        85.83, abs=0.005
    )
    moves = moves_by_hand(plan, velocity, acceleration)
    np.testing.assert_allclose(plan.travel_s, moves, rtol=1e-12)
    bus = bus_by_hand(moves, baud)
    dwell = rig.spec.settle_s + 0.05 * 2
    s = plan.summary
    assert s.timing == "dynamixel"
    assert s.bus_s == pytest.approx(bus.sum(), rel=1e-12)
    assert s.total_s == pytest.approx(moves.sum() + len(plan) * dwell + bus.sum(), rel=1e-12)
    arrival = np.cumsum(moves) + np.concatenate([[0.0], np.cumsum(dwell + bus)[:-1]])
    np.testing.assert_allclose(plan.arrival_s, arrival, rtol=1e-12)
    # Against the rig file's rates (what the planner counted before): not the same moves.
    configured = moves_by_hand(plan, list(rig.velocity), list(rig.acceleration))
    assert np.abs(plan.travel_s - configured).max() > 1e-3
    text = render_summary(plan)
    assert f"the bus at {f'{baud:,}'.replace(',', ' ')} baud" in text
    assert f"{1e3 * bus.mean():.1f} ms a target" in text


def test_a_simulated_plan_runs_the_rig_files_rates_with_no_bus() -> None:
    rig = Rig.from_yaml(RIGS / "arch.yaml")
    plan = tiny(rig)
    moves = moves_by_hand(plan, list(rig.velocity), list(rig.acceleration))
    np.testing.assert_allclose(plan.travel_s, moves, rtol=1e-12)
    s = plan.summary
    assert s.timing == "rig" and s.bus_s == 0.0
    assert s.total_s == pytest.approx(moves.sum() + len(plan) * (rig.spec.settle_s + 0.1))
    assert "simulated motors, no bus" in render_summary(plan)
    stored = plan_bytes(plan).decode()
    assert '"bus_s"' not in stored and '"timing"' not in stored  # the bytes as before


def test_the_stored_plan_keeps_the_bus_and_the_model(tmp_path: Path) -> None:
    plan = tiny(at_baud(57_600))
    write_plan(plan, tmp_path / "plan.csv")
    back = read_plan(tmp_path / "plan.csv")
    assert back == plan
    assert back.summary.timing == "dynamixel" and back.summary.bus_s == plan.summary.bus_s
