"""A fly plan that asks more than physics, the rig or this machine allows is refused in
one line naming the file, the field and the bound, before anything is laid out: a blur
budget below what the encoders resolve, a tolerance below what noise lets anyone see, a
target that would not fit in memory or would plan for hours, a detector that cannot
stream."""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
import yaml

from gonio.config import ConfigError, load
from gonio.planner import build
from gonio.planner.fly import limits
from gonio.planner.schema import MAX_READINGS, PlanSpec
from gonio.rig.model import Rig
from tests.conftest import CONFIGS, CliResult

FLY = yaml.safe_load((CONFIGS / "plans" / "fly.yaml").read_text())
QUICK_FLY = yaml.safe_load((CONFIGS / "plans" / "quick_fly.yaml").read_text())
RIGS = CONFIGS / "rigs"
GONIO = Path(sys.executable).with_name("gonio")


def write(tmp_path: Path, base: dict[str, Any], **fly: Any) -> Path:
    """``base`` with its rig named by an absolute path and ``fly`` (a ``target`` among
    them: the sampling's) replacing its fly options (None: removed), as a file."""
    data = yaml.safe_load(yaml.safe_dump(base))
    data["rig"] = str(RIGS / "arch.yaml")
    if "target" in fly:
        data["sampling"]["target"] = fly.pop("target")
    options = {**data["sampling"]["fly"], **fly}
    data["sampling"]["fly"] = {k: v for k, v in options.items() if v is not None}
    path = tmp_path / "plan.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    return path


def line_of(path: Path, key: str) -> int:
    return next(i for i, line in enumerate(path.read_text().splitlines(), 1) if f"{key}:" in line)


# (base, changes, the field refused, the line's key, expected words)
LOADER_CASES = [
    (FLY, {"lobe_width_deg": 1e-9}, "sampling.fly.lobe_width_deg", "lobe_width_deg",
     "greater than or equal to 0.01"),
    (QUICK_FLY, {"blur_deg": 1e-9}, "sampling.fly.blur_deg", "blur_deg",
     "greater than or equal to 0.01"),
    (FLY, {"lobe_fraction": None, "blur_tolerance": 1e-12}, "sampling.fly.blur_tolerance",
     "blur_tolerance", "greater than or equal to 0.000001"),
    (FLY, {"lobe_fraction": None, "blur_tolerance": 1e-6}, "sampling.fly.blur_tolerance",
     "blur_tolerance", "expected a blur budget of at least 0.01°"),
    (FLY, {"lobe_width_deg": 0.02}, "sampling.fly.lobe_fraction", "lobe_fraction",
     "expected a blur budget of at least 0.01°"),
    (FLY, {"target": 10**9}, "sampling.target", "target",
     f"expected at most {MAX_READINGS:,} readings in a fly plan"),
    (FLY, {"rate_hz": 0.001}, "sampling.fly.rate_hz", "rate_hz", "greater than or equal to 1"),
]  # fmt: skip


@pytest.mark.parametrize(
    ("base", "changes", "field", "key", "expected"),
    LOADER_CASES,
    ids=[c[2].split(".")[-1] + f"-{i}" for i, c in enumerate(LOADER_CASES)],
)
def test_a_fly_option_out_of_its_bounds_is_one_line_naming_it(
    tmp_path: Path, base: dict[str, Any], changes: dict[str, Any], field: str, key: str,
    expected: str,
) -> None:  # fmt: skip
    path = write(tmp_path, base, **changes)
    with pytest.raises(ConfigError) as info:
        load(path, PlanSpec)
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(f"{path}:{line_of(path, key)}: {field}: "), message
    assert expected in message, message


# (base, changes, the field refused, expected words)
RIG_CASES = [
    (QUICK_FLY, {"blur_deg": 0.015}, "sampling.fly.blur_deg",
     "expected a blur budget of at least 0.0254° (the quantization of light_elevation's"),
    (FLY, {"lobe_fraction": 0.01}, "sampling.fly.lobe_width_deg",
     "expected a blur budget of at least 0.0254° (the quantization of detector_elevation's"),
    (FLY, {"rate_hz": 1, "target": MAX_READINGS}, "sampling.target",
     "min to plan; expected at most 10 min"),
    (QUICK_FLY, {"rate_hz": 1, "target": MAX_READINGS}, "sampling.target",
     "min to plan; expected at most 10 min"),
]  # fmt: skip


@pytest.mark.parametrize(
    ("base", "changes", "field", "expected"),
    RIG_CASES,
    ids=["blur-line", "lobe-arc", "time-arc", "time-line"],
)
def test_a_fly_plan_beyond_the_rig_or_the_planning_time_is_refused_before_laying_out(
    tmp_path: Path, rigs: dict[str, Rig], base: dict[str, Any], changes: dict[str, Any],
    field: str, expected: str,
) -> None:  # fmt: skip
    path = write(tmp_path, base, **changes)
    with pytest.raises(ConfigError) as info:
        build(load(path, PlanSpec), rigs["arch"], where=str(path))
    message = str(info.value)
    assert "\n" not in message and message.startswith(f"{path}: {field}: "), message
    assert expected in message, message


def test_a_target_beyond_the_memory_available_is_refused_saying_both(
    tmp_path: Path, rigs: dict[str, Rig], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(limits, "available_bytes", lambda: 64 << 20)
    path = write(tmp_path, FLY, target=100_000)
    with pytest.raises(ConfigError) as info:
        build(load(path, PlanSpec), rigs["arch"], where=str(path))
    assert str(info.value) == (
        f"{path}: sampling.target: 100,000 readings need about 195.3 MiB of memory to plan; "
        "this machine has 64.0 MiB available (expected at most 32,768 readings)"
    )


def test_the_memory_available_is_read_from_the_machine() -> None:
    assert 0 < limits.available_bytes() < 1 << 50


def test_the_shipped_fly_plans_are_within_every_bound(rigs: dict[str, Rig]) -> None:
    for name in ("fly", "quick_fly", "fly_rehearsal"):
        spec = load(CONFIGS / "plans" / f"{name}.yaml", PlanSpec)
        cost = limits.planning_estimate(spec, rigs["arch"])
        assert cost.seconds < 0.1 * limits.MAX_PLANNING_S, (name, cost)
        floor, _ = limits.blur_floor_deg(rigs["arch"], spec.sampling.fly_options())
        assert spec.sampling.fly_options().blur > 10 * floor


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        (
            ["plan", str(CONFIGS / "plans" / "fly.yaml"), "--rig", str(RIGS / "arch_lockin.yaml")],
            "detector.interface: plan 'fly' is a fly plan and this pymeasure detector cannot "
            "stream",
        ),
        (
            [
                "simulate",
                str(CONFIGS / "plans" / "fly.yaml"),
                "--rig",
                str(RIGS / "arch.yaml"),
                "--scene",
                str(CONFIGS / "scenes" / "matte_lockin.yaml"),
            ],
            "matte_lockin.yaml: detector.kind: plan 'fly' is a fly plan and the simulated lockin "
            "detector cannot stream",
        ),
        (
            [
                "acquire",
                str(CONFIGS / "plans" / "fly.yaml"),
                "--rig",
                str(RIGS / "arch_lockin.yaml"),
                "--rehearse",
                "--scene",
                str(CONFIGS / "scenes" / "matte_lockin.yaml"),
            ],
            "detector.kind: plan 'fly' is a fly plan and the simulated lockin detector cannot",
        ),
    ],
    ids=["plan", "simulate", "acquire"],
)
def test_a_fly_plan_on_a_detector_that_cannot_stream_is_refused_before_planning(
    tmp_path: Path, run_gonio: Callable[..., CliResult], args: list[str], expected: str
) -> None:
    out = tmp_path / "run.sqlite"
    extra = ["-o", str(out)] if args[0] in ("acquire", "simulate") else []
    result = run_gonio(*args, *extra)
    assert result.returncode == 2 and result.stdout == "", result.stdout
    assert result.stderr.count("\n") == 1 and expected in result.stderr, result.stderr
    assert list(tmp_path.iterdir()) == []  # no run file, no control token


def test_a_real_process_refuses_a_blur_the_encoders_cannot_see_at_once(tmp_path: Path) -> None:
    path = write(tmp_path, FLY, lobe_width_deg=None, lobe_fraction=None, blur_deg=1e-9)
    out = tmp_path / "out"
    out.mkdir()
    r = subprocess.run(
        [str(GONIO), "plan", str(path), "-o", str(out / "plan.csv")],
        capture_output=True, text=True, timeout=120, stdin=subprocess.DEVNULL,
    )  # fmt: skip
    assert r.returncode == 2 and r.stdout == "" and "Traceback" not in r.stderr
    assert r.stderr.count("\n") == 1
    assert f"{path}:{line_of(path, 'blur_deg')}: sampling.fly.blur_deg: " in r.stderr
    assert list(out.iterdir()) == []
