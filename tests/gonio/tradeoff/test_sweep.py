"""A small sweep end to end through `gonio tradeoff` (the session's reference run):
its results, report, figures and target plan; a reused output folder skips what is
finished; a sweep killed with SIGKILL in a real subprocess (on the local process pool)
keeps every row it finished, and resuming it gives the rows of an uninterrupted run."""

from __future__ import annotations

import csv
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from matplotlib import image

from gonio.cli import main
from gonio.planner.files import load_plan_source
from gonio.tradeoff import runner
from gonio.tradeoff.front import pareto_front
from gonio.tradeoff.grid import load_sweep
from gonio.tradeoff.sweep import COLUMNS
from tests.gonio.tradeoff.conftest import TARGET, Reference, rows_of, write_sweep

ROOT = Path(__file__).resolve().parents[3]


def test_results_csv_has_one_row_per_combination_with_every_column(reference: Reference) -> None:
    with open(reference.out / "results.csv", newline="", encoding="utf-8") as stream:
        table = list(csv.DictReader(stream))
    sweep = load_sweep(reference.sweep)
    assert tuple(table[0]) == COLUMNS
    assert [r["id"] for r in table] == [t.id for t in sweep.tasks]
    assert len(table) == 4 and {r["error"] for r in table} == {""}
    assert {(r["parametrization"], r["sampling"]) for r in table} == {
        (p, s) for p in ("hybrid", "rusinkiewicz") for s in ("sobol", "warped")
    }
    for r in table:
        assert int(r["measured"]) == int(r["targets"]) == 100
        assert 0 < float(r["log_rmse"]) < 0.1
        assert float(r["instrument_s"]) > float(r["predicted_s"]) > 0  # + calibration
    # The CSV holds the stored rows' figures exactly (floats written by repr).
    stored = rows_of(reference.out)
    assert all(float(r["log_rmse"]) == stored[r["id"]]["log_rmse"] for r in table)


def test_the_report_has_the_front_and_the_target(reference: Reference) -> None:
    text = (reference.out / "report.md").read_text(encoding="utf-8")
    rows = list(rows_of(reference.out).values())
    front = [rows[i] for i in pareto_front(rows, "log_rmse")]
    section = text.split("Pareto front")[1].split("Best of each")[0]
    assert [line.split("`")[1] for line in section.splitlines() if "`" in line] == [
        r["id"] for r in front
    ]
    assert f"Fastest meeting log_rmse ≤ {TARGET:g}" in text and "plans/matte.yaml" in text
    for png in ("matte-error-vs-time.png", "matte-error-vs-samples.png"):
        assert f"({png})" in text
        pixels = image.imread(reference.out / png)
        assert pixels.shape[:2] == (480, 700) and np.ptp(pixels[..., :3]) > 0.5


def test_the_target_plan_is_the_fastest_meeting_it_and_plans_the_same(
    reference: Reference,
) -> None:
    rows = rows_of(reference.out).values()
    meeting = [r for r in rows if r["log_rmse"] <= TARGET]
    fastest = min(meeting, key=lambda r: r["instrument_s"])
    source = load_plan_source(reference.out / "plans" / "matte.yaml")
    assert source.rig.text == (ROOT / "configs" / "rigs" / "arch.yaml").read_bytes()
    plan = source.build()
    assert len(plan) == fastest["targets"]
    assert plan.summary.total_s == fastest["predicted_s"]
    assert f"wrote {reference.out / 'plans' / 'matte.yaml'}" in reference.stdout


def test_a_reused_folder_skips_the_finished_combinations(
    reference: Reference, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    def refuse(task: object) -> None:
        raise AssertionError("a finished combination ran again")

    monkeypatch.setattr(runner, "run", refuse)
    before = (reference.out / "results.jsonl").read_bytes()
    assert main(["tradeoff", str(reference.sweep), "-o", str(reference.out), "-j", "1",
                 "-q", "--target-error", str(TARGET)]) == 0  # fmt: skip
    assert "ran 0 combinations" in capsys.readouterr().out
    assert (reference.out / "results.jsonl").read_bytes() == before


def test_a_killed_sweep_keeps_its_finished_rows_and_resumes(
    reference: Reference, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    sweep, out = write_sweep(tmp_path), tmp_path / "out"
    child = subprocess.Popen(
        [sys.executable, "-m", "gonio", "tradeoff", str(sweep), "-o", str(out), "-j", "2", "-q"],
        cwd=ROOT,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        start_new_session=True,
    )
    results = out / "results.jsonl"
    deadline = time.monotonic() + 60
    try:
        while not (results.is_file() and results.read_bytes().count(b"\n") >= 1):
            assert child.poll() is None, child.stderr.read() if child.stderr else ""
            assert time.monotonic() < deadline, "no combination finished in 60 s"
            time.sleep(0.02)
    finally:
        os.killpg(child.pid, signal.SIGKILL)  # the sweep and its pool's processes
        child.wait()
        if child.stderr:
            child.stderr.close()
    assert child.returncode == -signal.SIGKILL
    kept = rows_of(out)
    expected = rows_of(reference.out)
    assert 1 <= len(kept) < len(expected)  # killed with combinations in flight
    assert all(kept[k] == expected[k] for k in kept)

    capsys.readouterr()
    assert main(["tradeoff", str(sweep), "-o", str(out), "-j", "1", "-q"]) == 0
    printed = capsys.readouterr().out
    assert f"ran {len(expected) - len(kept)} combinations" in printed
    assert f"{len(kept)} were already in" in printed
    assert rows_of(out) == expected
