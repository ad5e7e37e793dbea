"""`gonio acquire` and `gonio info` as a user runs them (in-process): the dry run, the
progress display, one-line refusals before anything moves."""

from __future__ import annotations

import io
import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from gonio.acquire.observer import Shown, for_stream
from gonio.cli import main
from gonio.planner import Plan
from gonio.progress import Bar, Lines
from gonio.workflows import backends
from tests.conftest import CONFIGS, CliResult
from tests.support.acquire import plan_file, scene_file

Gonio = Callable[..., CliResult]


def test_a_dry_run_checks_everything_and_writes_nothing(run_gonio: Gonio, tmp_path: Path) -> None:
    out = tmp_path / "run.sqlite"
    r = run_gonio(
        "acquire",
        str(plan_file(tmp_path, target=20)),
        "--scene",
        str(scene_file(tmp_path)),
        "-o",
        str(out),
        "--dry-run",
    )
    assert r.returncode == 0, r.stderr
    assert "predicted duration" in r.stdout
    assert "  ok: targets: 20 within the axis limits" in r.stdout
    assert f"  ok: output: {out} writable" in r.stdout
    assert "  ok: motors: 4 axes answer" in r.stdout
    assert "  ok: detector: answers" in r.stdout
    assert r.stdout.rstrip().endswith("dry run: nothing moved, nothing written")
    assert not out.exists() and sorted(p.name for p in tmp_path.iterdir()) == [
        "scene.yaml",
        "small.yaml",
    ]


def test_a_dry_run_with_an_operator_and_no_terminal_says_the_run_will_need_one(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """A dry run moves nothing and asks nothing: where the run would ask an operator to
    place the reference standard and there is no terminal, it reports that, and the run
    itself refuses (in-process, a backend whose stage is the operator's)."""
    built = backends.build

    def operated(*args: object, **kwargs: object) -> backends.Backend:
        backend = built(*args, **kwargs)  # type: ignore[arg-type]
        backend.stage = backends.OperatorStage()
        return backend

    monkeypatch.setattr(backends, "build", operated)
    monkeypatch.setattr(sys, "stdin", io.StringIO(""))  # no terminal
    args = [
        "acquire",
        str(plan_file(tmp_path, target=20)),
        "--scene",
        str(scene_file(tmp_path)),
        "-o",
        str(tmp_path / "run.sqlite"),
    ]
    assert main([*args, "--dry-run"]) == 0
    assert "operator: the run will ask for the reference standard" in capsys.readouterr().out
    assert main(args) == 2
    assert "no one can be asked (no terminal)" in capsys.readouterr().err
    assert not (tmp_path / "run.sqlite").exists()


def test_a_hardware_rig_whose_port_is_missing_is_one_line_before_anything(
    run_gonio: Gonio, tmp_path: Path
) -> None:
    rig_text = (CONFIGS / "rigs" / "arch.yaml").read_text(encoding="utf-8")
    rig_text = rig_text.replace(
        "bus:\n  port: /dev/ttyUSB0", f"bus:\n  kind: dynamixel\n  port: {tmp_path}/ttyNOPE"
    )
    rig = tmp_path / "rig.yaml"
    rig.write_text(rig_text, encoding="utf-8")
    out = tmp_path / "run.sqlite"
    plan = plan_file(tmp_path, target=5, acquisition="acquisition: {calibration: {dark: false}}\n")
    r = run_gonio(
        "acquire",
        str(plan),
        "--rig",
        str(rig),
        "--scene",
        str(scene_file(tmp_path)),
        "-o",
        str(out),
    )
    assert r.returncode == 2, r.stderr
    assert r.stderr.count("\n") == 1 and "Traceback" not in r.stderr
    assert "ttyNOPE" in r.stderr, r.stderr
    assert not out.exists()


def test_without_an_output_the_run_is_refused(run_gonio: Gonio, tmp_path: Path) -> None:
    r = run_gonio(
        "acquire", str(plan_file(tmp_path, target=5)), "--scene", str(scene_file(tmp_path))
    )
    assert r.returncode == 2
    assert r.stderr == (
        "gonio: error: -o RUN: expected the run file to write (e.g. runs/my-run.sqlite)\n"
    )


def test_progress_lines_when_not_a_terminal_and_a_bar_on_one(quick_plan: Plan) -> None:
    plan = quick_plan
    todo = np.arange(len(plan))
    out = io.StringIO()
    lines = Shown(Lines(out, every_s=0.0, done_word="acquired"))
    lines.start(plan, todo)
    for done in (100, 250, 500):
        lines.advance(done)
    lines.close()
    text = out.getvalue().splitlines()
    assert text[0].startswith("acquired 100/500 targets, 0:00:00 elapsed, about ")
    assert text[-1].startswith("acquired 500/500 targets") and text[-1].endswith(
        "about 0:00:00 left"
    )

    class Tty(io.StringIO):
        def isatty(self) -> bool:
            return True

    assert isinstance(for_stream(False, Tty()).display, Bar)
    assert isinstance(for_stream(False, io.StringIO()).display, Lines)
    bar_out = Tty()
    bar = Shown(Bar(bar_out))
    bar.start(plan, todo)
    bar.advance(250)
    bar.close()
    assert "250/500" in bar_out.getvalue() and "left" in bar_out.getvalue()


def test_the_time_left_follows_the_measured_pace(quick_plan: Plan) -> None:
    from gonio.acquire.observer import Pace

    plan = quick_plan
    pace = Pace(plan, np.arange(len(plan)))
    assert (
        pace.left_s(0) == plan.summary.total_s
        or abs(pace.left_s(0) - plan.summary.total_s) < 1e-6 * plan.summary.total_s
    )
    pace.started -= 10.0  # ten wall seconds for the first half of the predicted time
    half = int(np.searchsorted(pace.cumulative, pace.cumulative[-1] / 2))
    assert abs(pace.left_s(half) - 10.0) < 0.5


def test_a_speedup_out_of_its_range_is_one_line(run_gonio: Gonio, tmp_path: Path) -> None:
    plan = plan_file(tmp_path, target=5)
    for bad in ("-1", "0", "nan", "inf", "fast", "1e-300", "0.5", "1e300"):
        r = run_gonio(
            "acquire",
            str(plan),
            "--scene",
            str(scene_file(tmp_path)),
            "-o",
            str(tmp_path / "r.sqlite"),
            "--rehearse",
            "--speedup",
            bad,
        )
        assert r.returncode == 2, (bad, r.stderr)
        assert r.stderr.count("\n") == 1 and "--speedup" in r.stderr and "Traceback" not in r.stderr
        assert not (tmp_path / "r.sqlite").exists()


def test_a_refusal_that_needs_no_plan_comes_before_planning(
    run_gonio: Gonio, tmp_path: Path
) -> None:
    """No scene for a simulated detector, or a negative seed: the one line is all that is
    printed (the plan summary used to come first)."""
    plan = str(plan_file(tmp_path, target=5))
    out = str(tmp_path / "r.sqlite")
    for args in (
        ("acquire", plan, "-o", out),
        ("acquire", plan, "--scene", str(scene_file(tmp_path)), "-o", out, "--seed", "-3"),
        ("simulate", plan, "--scene", str(scene_file(tmp_path)), "--seed", "-3"),
        ("fit", out, "--model", "lambert", "--seed", "-1"),
    ):
        r = run_gonio(*args)
        assert r.returncode == 2, (args, r.stderr)
        assert r.stdout == "" and r.stderr.count("\n") == 1, (args, r.stdout, r.stderr)
    assert "give --scene" in run_gonio("acquire", plan, "-o", out).stderr
