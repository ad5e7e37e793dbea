"""The motion axis (stop-and-go or fly), the fly axes and the time budget: which axes
apply to which combination, the target fitted to the budget, and rows of both motions."""

from __future__ import annotations

from pathlib import Path

import pytest

from gonio.config import ConfigError
from gonio.planner.builder import build
from gonio.rig.model import Rig
from gonio.tradeoff.grid import load_sweep
from gonio.tradeoff.runner import fit_to_budget, run
from gonio.tradeoff.sweep import COLUMNS
from tests.conftest import CONFIGS
from tests.gonio.tradeoff.conftest import SMALL, write_sweep

#: Stop-and-go and fly plans on the matte scene, each fitted to 30 s of instrument time.
MOTION = {
    "parametrization": ["rusinkiewicz"],
    "sampling": ["sobol"],
    "samples": [100],
    "exposure_s": [0.01, 0.05],
    "method": ["linear"],
    "effects": ["none"],
    "motion": ["stop", "fly"],
    "minutes": [0.5],
    "blur_deg": [1.0, 2.0],
}


def test_each_motion_takes_its_own_axes_once(tmp_path: Path) -> None:
    sweep = load_sweep(write_sweep(tmp_path, axes=MOTION))
    stops = [t.inputs for t in sweep.tasks if t.inputs["motion"] == "stop"]
    flies = [t.inputs for t in sweep.tasks if t.inputs["motion"] == "fly"]
    # two exposures stop-and-go (no fly axis), two blur budgets fly (no exposure)
    assert sorted(r["exposure_s"] for r in stops) == [0.01, 0.05]
    assert all(r["blur_deg"] is None and r["rate_hz"] is None for r in stops)
    assert sorted(r["blur_deg"] for r in flies) == [1.0, 2.0]
    assert all(r["exposure_s"] is None and r["sampling"] is None for r in flies)
    assert all(r["samples"] is None and r["minutes"] == 0.5 for r in stops + flies)
    (fly,) = [t for t in sweep.tasks if t.inputs["blur_deg"] == 1.0]
    assert fly.budget_s == pytest.approx(30.0)
    assert fly.plan["sampling"]["strategy"] == "fly"
    assert fly.plan["sampling"]["fly"] == {
        "segment": "detector_arc",
        "rate_hz": 100.0,
        "blur_deg": 1.0,
    }


def test_a_stop_and_go_sweep_keeps_its_ids(tmp_path: Path) -> None:
    """The new axes at their defaults are not in a combination's id."""
    before = load_sweep(write_sweep(tmp_path, "a")).tasks
    axes = {**SMALL["axes"], "motion": ["stop"], "minutes": [None], "blur_deg": [3.0]}
    after = load_sweep(write_sweep(tmp_path, "b", axes=axes)).tasks
    assert [t.id for t in before] == [t.id for t in after]


def test_every_pair_is_scored_by_default_and_supported_only_keeps_the_old_ids(
    tmp_path: Path,
) -> None:
    every = load_sweep(write_sweep(tmp_path, "a")).tasks
    named = load_sweep(
        write_sweep(tmp_path, "b", evaluation={"pairs": 2000, "extrapolate": "nearest"})
    ).tasks
    inside = load_sweep(
        write_sweep(tmp_path, "c", evaluation={"pairs": 2000, "only_supported": True})
    ).tasks
    assert {(t.extrapolate, t.only_supported) for t in every} == {("nearest", False)}
    assert [t.id for t in every] == [t.id for t in named]
    assert {(t.extrapolate, t.only_supported) for t in inside} == {(None, True)}
    assert not {t.id for t in every} & {t.id for t in inside}
    # A sweep scored on the supported pairs keeps the ids it had before the fill existed.
    assert inside[0].id == "83a5dc1dc4ce15ce"


@pytest.mark.parametrize(
    ("axes", "message"),
    [
        ({"motion": ["walk"]}, "axes.motion.0"),
        ({"minutes": [0]}, "expected a positive number"),
        ({"blur_deg": [45]}, "axes.blur_deg.0"),
        ({"sampling": ["adaptive"], "minutes": [5]}, "cannot be fitted to a time budget"),
    ],
)
def test_bad_motion_axes_are_refused_in_one_line(
    tmp_path: Path, axes: dict[str, list[object]], message: str
) -> None:
    with pytest.raises(ConfigError) as err:
        load_sweep(write_sweep(tmp_path, axes={**SMALL["axes"], **axes}))
    assert message in str(err.value) and "\n" not in str(err.value)


def test_the_target_is_the_largest_that_fits_the_budget() -> None:
    sweep_rig = Rig.from_yaml(CONFIGS / "rigs" / "arch.yaml")
    task = load_sweep(CONFIGS / "sweeps" / "fly_trade.yaml").tasks[0]
    spec = task.plan_spec()
    plan = fit_to_budget(spec, sweep_rig, 20.0, where="test")
    assert 0.9 * 20.0 <= plan.summary.total_s <= 20.0
    assert plan.spec.sampling.target is not None
    more = spec.sampling.model_copy(update={"target": plan.spec.sampling.target + 2})
    assert build(spec.model_copy(update={"sampling": more}), sweep_rig).summary.total_s > 20.0


def test_stop_and_go_and_fly_rows_at_equal_instrument_time(tmp_path: Path) -> None:
    axes = {**MOTION, "exposure_s": [0.01], "blur_deg": [2.0]}
    evaluation = {"pairs": 500, "extrapolate": "nearest"}
    sweep = load_sweep(write_sweep(tmp_path, axes=axes, evaluation=evaluation))
    rows = {t.inputs["motion"]: run(t) for t in sweep.tasks}
    for row in rows.values():
        assert tuple(row) == COLUMNS and row["error"] == ""
        # within the budget, to a sweep (a fly plan's grain: one line of ~8 s here)
        assert 0.5 * 30.0 <= row["predicted_s"] <= 30.0
        assert row["instrument_s"] > 0 and row["log_rmse"] > 0
        assert row["coverage"] <= 1.0
        assert row["measured"] == row["targets"] == row["asked"] or row["motion"] == "fly"
    # streamed while moving: many times the readings of stop-and-go in the same time
    assert rows["fly"]["measured"] > 10 * rows["stop"]["measured"]
