"""The read model of a large run, made small: a run over `FULL_LIMIT` samples is read by
a share of its targets and counted whole, its plan parsed in another process from the
second refresh on; what the views show then equals what a whole read shows."""

from __future__ import annotations

import json
import time
from pathlib import Path

import pytest

from gonio.cli import main
from gonio.errors import GonioError
from gonio.live import server
from gonio.live.model import LiveRun
from gonio.live.views import overview, points
from gonio.store import follow as model
from tests.support.acquire import MATTE, plan_file


def test_a_large_run_is_read_in_part_and_its_plan_in_the_background(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    plan = plan_file(tmp_path, target=40)
    path = tmp_path / "run.sqlite"
    assert main(["acquire", str(plan), "--scene", str(MATTE), "-o", str(path), "-q"]) == 0
    whole = LiveRun(path)
    assert whole.plan is not None and len(whole.samples["target"]) == 40
    monkeypatch.setattr(model, "FULL_LIMIT", 10)
    monkeypatch.setattr(model, "KEPT", 8)
    monkeypatch.setattr(model, "LAZY_PLAN_BYTES", 100)
    part = LiveRun(path)
    assert part.plan is None and part.measured == 40
    assert set(part.samples["target"].tolist()) == set(range(0, 40, 5))
    first = overview(part)
    same = overview(whole)
    for key in ("state", "measured", "targets", "skipped", "missing", "progress", "plan"):
        assert first[key] == same[key], key
    assert points(part)["shown"] == 8 and points(part)["pending_phi_deg"] == []
    give_up = time.monotonic() + 60
    while part.plan is None:  # the loader starts at the second refresh
        assert time.monotonic() < give_up, "the plan was not parsed"
        part.refresh()
        time.sleep(0.1)
    missing = part.missing()
    assert missing is not None and missing.size == 0
    later = overview(part)
    assert later["predicted_done_s"] == pytest.approx(same["predicted_done_s"])


def test_a_run_started_again_over_the_file_is_followed_anew(tmp_path: Path) -> None:
    """``gonio acquire --overwrite`` replaces the file: the server reads the new one."""
    path = tmp_path / "runs" / "run.sqlite"
    path.parent.mkdir()
    for n in (12, 8):
        plan = plan_file(tmp_path, target=n, name=f"plan{n}")
        args = ["acquire", str(plan), "--scene", str(MATTE), "-o", str(path), "-q"]
        assert main([*args, "--overwrite"]) == 0
        if n == 12:
            served = server.Served(path.parent)
        assert json.loads(served.view(path, "overview"))["measured"] == n
    assert not served.entry(path).live.replaced()
    path.unlink()
    with pytest.raises(GonioError, match=r"run\.sqlite"):
        served.view(path, "overview")
