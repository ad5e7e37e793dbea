"""A reader leaves the folder of a run file as it found it: reading a finished run (or
refusing a damaged one) makes no ``-wal`` or ``-shm`` file beside it and changes no
file, through the store's readers and through every command that reads a run; a
reader of a run being written still sees each commit, also one that began reading
before the writer came."""

from __future__ import annotations

import shutil
from collections.abc import Callable
from pathlib import Path

import pytest

from gonio.errors import GonioError
from gonio.store import Journal, open_run
from gonio.store.follow import RunFollower
from tests.conftest import CliResult
from tests.support.folders import listing
from tests.support.runs import plan_spec, scene_spec, simulated_run

Gonio = Callable[..., CliResult]


@pytest.fixture(scope="module")
def made(runs_dir: Path) -> Path:
    """A finished run (the reconstruction tests' run: one acquisition per worker)."""
    return simulated_run(runs_dir, plan_spec(300), scene_spec("matte", noise=False))


@pytest.fixture
def run(made: Path, tmp_path: Path) -> Path:
    """A copy of the finished run, alone in its folder."""
    folder = tmp_path / "runs"
    folder.mkdir()
    return Path(shutil.copy(made, folder / "run.sqlite"))


def test_the_store_readers_leave_nothing(run: Path) -> None:
    before = listing(run.parent)
    read = open_run(run)
    assert len(read) == 300
    follower = RunFollower(run)
    assert follower.measured == 300 and not follower.refresh()
    follower.close()
    assert listing(run.parent) == before


def test_a_refused_run_file_is_left_as_it_was(run: Path) -> None:
    truncated = run.with_name("trunc.sqlite")
    truncated.write_bytes(run.read_bytes()[:3000])
    before = listing(run.parent)
    for reader in (open_run, RunFollower):
        with pytest.raises(GonioError, match=r"trunc\.sqlite: not a readable run file"):
            reader(truncated)
    assert listing(run.parent) == before


@pytest.mark.parametrize(
    "args",
    [
        ["info", "{run}"],
        ["info", "{run}", "--json"],
        ["watch", "{run}", "--once"],
        ["export", "{run}", "--format", "csv", "-o", "{out}/x.csv"],
        ["evaluate", "{run}"],
        ["plot", "{run}", "--kind", "coverage", "-o", "{out}/p.png"],
        ["fit", "{run}", "--model", "lambert"],
    ],
    ids=lambda args: "-".join(a for a in args if not a.startswith("{")),
)
def test_the_reading_commands_leave_only_their_outputs(
    run: Path, tmp_path: Path, run_gonio: Gonio, args: list[str]
) -> None:
    out = tmp_path / "out"
    out.mkdir()
    before = listing(run.parent)
    result = run_gonio(*(a.format(run=run, out=out) for a in args))
    assert result.returncode == 0, result.stderr[-2000:]
    assert listing(run.parent) == before


def test_a_reader_sees_the_commits_of_a_writer_that_came_after_it(run: Path) -> None:
    follower = RunFollower(run)  # a finished run: read as it stands
    try:
        events = len(follower.events)
        with Journal.reopen(run, durable=False) as journal:  # a resume begins
            journal.start_session("2025-01-01T00:00:00+00:00", {})
            journal.event("note", 1.0, "2025-01-01T00:00:01+00:00", {"n": 1})
            assert follower.refresh() and follower.writing
            assert len(follower.events) == events + 1
            assert len(open_run(run).events) == events + 1  # a reader while it writes
            journal.event("note", 2.0, "2025-01-01T00:00:02+00:00", {"n": 2})
            assert follower.refresh() and len(follower.events) == events + 2
        assert follower.refresh() and not follower.writing
    finally:
        follower.close()
    assert len(open_run(run).events) == events + 2
