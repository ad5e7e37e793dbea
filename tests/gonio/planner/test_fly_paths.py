"""Path lines of fly plans: the line's pairs are the line's coordinates, the chosen poses
measure them, the trajectories pass the rig's checks from rest to rest within the blur
budget, the readings keep their step along θh, and a plan of them reads back bit for bit
with a duration an independent sum predicts."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
from hypothesis import assume, example, given
from hypothesis import strategies as st
from scipy.spatial import cKDTree

from drivers.trajectory import check_trajectory
from gonio import params
from gonio.config import ConfigError
from gonio.planner import build, plan_bytes, read_plan, write_plan
from gonio.planner.fly.path_plan import line_density
from gonio.planner.fly.paths import (
    FINE_STEP,
    PathSegment,
    checked_trajectory,
    line_pairs,
    line_segments,
    path_readings,
    rig_setpoint_period,
    time_law,
)
from gonio.planner.schema import PlanSpec
from gonio.rig.constraints import separation
from gonio.rig.model import Rig
from gonio.rig.solution import Reason
from tests.conftest import RIG_FILES

RUS = params.get("rusinkiewicz")


def arch() -> Rig:
    return Rig.from_yaml(RIG_FILES["arch"])


def path_spec(target: int = 600, isotropic: bool = True, **fly: Any) -> PlanSpec:
    options = {"segment": "theta_h_line", "rate_hz": 100.0, "integration_s": 0.01,
               "blur_deg": 0.5, **fly}  # fmt: skip
    return PlanSpec.model_validate(
        {
            "name": "paths-test",
            "parametrization": "rusinkiewicz",
            "isotropic": isotropic,
            "sampling": {"strategy": "fly", "target": target, "seed": 3, "fly": options},
            "kicks": 10,
        }
    )


@given(
    st.floats(0.05, 1.5), st.floats(0.0, math.pi - 1e-3), st.floats(0.0, 1.5)
)  # fmt: skip
@example(0.5, 1.0, 3.6e-16)
def test_line_pairs_are_the_lines_coordinates(theta_d: float, phi_d: float, theta_h: float) -> None:
    wi, wo = line_pairs(theta_d, phi_d, np.array([theta_h]))
    assume(wi[0, 2] > 1e-6 and wo[0, 2] > 1e-6)  # a pair above the horizon
    assert np.allclose(np.linalg.norm(wi, axis=1), 1.0) and np.allclose(
        np.linalg.norm(wo, axis=1), 1.0
    )
    got = RUS.forward_iso(wi, wo)[0]
    assert got[0] == pytest.approx(theta_h, abs=1e-9)
    assert got[1] == pytest.approx(theta_d, abs=1e-9)
    if theta_h < 1e-6:
        return  # h at the normal: φh, hence the frame φd is measured in, is undefined
    # φd folded to [0, π) by reciprocity: either the line's or its reciprocal's
    assert min(abs(got[2] - phi_d), abs(got[2] - (phi_d + math.pi) % math.pi)) < 1e-7


@pytest.mark.parametrize(
    ("theta_d", "phi_d"), [(10, 0), (30, 45), (30, 90), (45, 135), (60, 20), (20, 179)]
)
def test_segments_measure_their_line_and_are_continuous(theta_d: float, phi_d: float) -> None:
    rig = arch()
    refused: dict[str, int] = {}
    segments = line_segments(rig, math.radians(theta_d), math.radians(phi_d), 0, True, refused)
    assert segments
    for seg in segments:
        reasons, commandable = rig.pose_reasons(seg.poses)
        assert np.all(reasons == Reason.OK) and commandable.all()
        wi, wo = rig.forward(seg.poses)
        got = RUS.forward_iso(wi, wo)
        assert np.allclose(got[:, 0], seg.theta_h, atol=1e-7)
        assert np.allclose(got[:, 1], math.radians(theta_d), atol=1e-7)
        assert np.all(np.diff(seg.theta_h) == pytest.approx(FINE_STEP))
        assert np.abs(np.diff(seg.poses, axis=0)).max() <= 10 * FINE_STEP + 1e-12


@pytest.mark.parametrize("backward", [False, True])
def test_trajectories_pass_the_rigs_checks_within_the_blur(backward: bool) -> None:
    rig = arch()
    period = rig_setpoint_period(rig)
    blur, t_int = math.radians(0.5), 0.01
    limits = {n: (float(lo), float(hi)) for n, (lo, hi) in zip(rig.axes, rig.limits, strict=True)}
    top_v = dict(zip(rig.axes, rig.velocity.tolist(), strict=True))
    top_a = dict(zip(rig.axes, rig.acceleration.tolist(), strict=True))
    for theta_d, phi_d in [(10, 0), (30, 90), (45, 135)]:
        seg = line_segments(rig, math.radians(theta_d), math.radians(phi_d), 0, True, {})[0]
        out = checked_trajectory(rig, seg, blur, t_int, period, backward)
        assert out is not None
        trajectory, t, theta = out
        check_trajectory(trajectory, limits, top_v, top_a)
        assert trajectory.period_s == period
        ends = (seg.poses[-1], seg.poses[0]) if backward else (seg.poses[0], seg.poses[-1])
        assert np.array_equal(trajectory.goals[0], ends[0])
        assert np.allclose(trajectory.goals[-1], ends[1], atol=1e-12)
        v = trajectory.velocities()
        assert np.abs(v[0]).max() < np.abs(v).max() and np.abs(v[-1]).max() < np.abs(v).max()
        # the measured directions' smear over one integration stays within the budget
        wi, wo = rig.forward(trajectory.goals)
        step = np.maximum(separation(wi[1:], wi[:-1]), separation(wo[1:], wo[:-1]))
        assert step.max() / period * t_int <= blur * (1 + 1e-6)
        assert float(t[-1]) <= trajectory.duration_s < float(t[-1]) + period
        assert np.all(np.diff(theta) <= 1e-12) if backward else np.all(np.diff(theta) >= -1e-12)


def test_readings_keep_their_step_along_theta_h() -> None:
    rig = arch()
    seg = line_segments(rig, math.radians(30), math.radians(60), 0, True, {})[0]
    trajectory, _, theta = checked_trajectory(rig, seg, math.radians(0.5), 0.01,
                                              rig_setpoint_period(rig), False)  # type: ignore[misc]  # fmt: skip
    step = math.radians(0.25)
    got = path_readings(trajectory, theta, 100.0, 0.01, step)
    assert np.all(np.diff(got.slots) > 0) and got.slots[0] == 0
    assert got.streamed == math.floor((trajectory.duration_s - 0.01) * 100 + 1e-9) + 1
    wi, wo = rig.forward(got.mids)
    along = RUS.forward_iso(wi, wo)[:, 0]
    assert np.all(np.diff(along) > 0.5 * step)
    assert np.allclose(got.mids, trajectory.at(got.slots / 100.0 + 0.005))


def test_a_plan_of_lines_reads_back_and_times_as_predicted(tmp_path: Any) -> None:
    rig = arch()
    plan = build(path_spec(), rig)
    sweeps = plan.sweeps
    assert sweeps is not None and sweeps.has_paths and len(plan) >= 600
    assert np.all(sweeps.path_count >= 2)
    # every target inside its sweep's trajectory, in order, at its slot
    for k in range(len(sweeps)):
        first, count = int(sweeps.first[k]), int(sweeps.count[k])
        since = plan.arrival_s[first : first + count] - sweeps.cruise_at_s[k]
        duration = (int(sweeps.path_count[k]) - 1) * sweeps.path_period_s
        assert np.all(since >= -1e-9) and np.all(since + sweeps.integration_s <= duration + 1e-9)
        goals = sweeps.set_points(k)
        assert np.array_equal(goals[0], sweeps.start[k]) and np.array_equal(
            goals[-1], sweeps.stop[k]
        )
    # the duration: moves from one sweep's end to the next one's start, settles, trajectories
    ends = np.vstack([rig.home[None, :], sweeps.stop[:-1]])
    moves = rig.travel.time(ends, sweeps.start).sum() + len(sweeps) * rig.spec.settle_s
    trajectories = ((sweeps.path_count - 1) * sweeps.path_period_s).sum()
    assert plan.summary.total_s == pytest.approx(moves + trajectories, rel=1e-9)
    write_plan(plan, tmp_path / "p.csv")
    back = read_plan(tmp_path / "p.csv")
    assert back == plan and plan_bytes(back) == plan_bytes(plan)


def test_path_lines_need_an_isotropic_plan() -> None:
    with pytest.raises(ConfigError, match="theta_h_line lines need an isotropic plan"):
        build(path_spec(isotropic=False), arch())


def test_lines_follow_their_density() -> None:
    rig = arch()
    plain = line_density(path_spec(), rig)
    p = plain.p.reshape(plain.shape)
    assert p.sum() == pytest.approx(1.0) and np.all(p >= 0)
    by_theta_d = p.sum(axis=1)
    reached = by_theta_d > 0
    # no material: denser toward grazing θd, where the test measure reaches
    assert np.all(np.diff(by_theta_d[reached][: int(reached.sum() * 0.8)]) > 0)
    gold = {"name": "cook_torrance", "alpha": 0.05, "fresnel": "conductor",
            "ior": [0.18, 0.42, 1.37], "k": [3.42, 2.35, 1.77]}  # fmt: skip
    guessed = line_density(path_spec(material=gold), rig).p
    assert guessed.sum() == pytest.approx(1.0) and not np.allclose(guessed, plain.p)
    assert np.array_equal(guessed > 0, plain.p > 0)  # the floor keeps every reached cell


def test_a_material_is_for_theta_h_lines_only() -> None:
    with pytest.raises(ValueError, match="only theta_h_line lines take a material"):
        path_spec(segment="detector_arc", material={"name": "lambert"})
    with pytest.raises(ValueError, match="material"):
        path_spec(material={"alpha": 0.1})


def test_a_short_segment_takes_a_finite_time() -> None:
    rig = arch()
    seg = line_segments(rig, math.radians(30), math.radians(60), 0, True, {})[0]
    two = PathSegment(seg.line, seg.theta_d, seg.phi_d, seg.theta_h[:2], seg.poses[:2])
    t = time_law(rig, two, math.radians(1.0), 0.01)
    assert np.all(np.isfinite(t)) and 0 < t[-1] < 1.0


def test_a_mixed_plan_fills_the_gaps_the_lines_leave(tmp_path: Any) -> None:
    rig = arch()
    lines_only = build(path_spec(target=300), rig)
    mixed = build(path_spec(target=300, fill=40), rig)
    sweeps = mixed.sweeps
    assert sweeps is not None and sweeps.swept == len(lines_only) == len(mixed) - 40
    np.testing.assert_array_equal(mixed.angles[: sweeps.swept], lines_only.angles)
    fill = slice(sweeps.swept, None)
    assert np.all(mixed.exposure_s[fill] == mixed.spec.exposure.seconds)
    assert np.all(np.diff(mixed.arrival_s) > 0)
    # each fill target is farther from the lines' readings than the lines' own spacing
    bounds = np.array(RUS.iso_bounds)
    unit = (mixed.coords - bounds[:, 0]) / (bounds[:, 1] - bounds[:, 0])
    tree = cKDTree(unit[: sweeps.swept])
    assert np.all(
        tree.query(unit[fill])[0] > np.median(tree.query(unit[: sweeps.swept], k=2)[0][:, 1])
    )
    assert mixed.summary.total_s > lines_only.summary.total_s
    write_plan(mixed, tmp_path / "m.csv")
    assert read_plan(tmp_path / "m.csv") == mixed


def test_fill_is_for_theta_h_lines_only() -> None:
    with pytest.raises(ValueError, match="only theta_h_line lines are filled"):
        path_spec(segment="detector_arc", fill=10)
