"""Fuzzed run files: a real small run (acquired once) with pages of its SQLite file
damaged — bits flipped, bytes replaced, a page zeroed, the file cut at a page boundary
— read by `open_run`, by a follower (`RunFollower`) and by every read command
in-process. Whatever the damage, a run file is read or refused with `JournalError` (one
line), a command exits 0 or 2 (one line), never another exception, within a bounded CPU
time and memory. Lean by default (``FUZZ_EXAMPLES=N`` for a longer search)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gonio.store import JournalError, open_run
from gonio.store.follow import RunFollower
from tests.conftest import CliResult
from tests.gonio.test_config_fuzz import bounded, examples
from tests.support.acquire import acquire, plan_file, scene_file

#: SQLite's page size in a run file (the default).
PAGE = 4096


@pytest.fixture(scope="module")
def pristine(tmp_path_factory: pytest.TempPathFactory) -> bytes:
    """The bytes of a small complete run (acquired once; the WAL checkpointed)."""
    folder = tmp_path_factory.mktemp("fuzz-run")
    out = folder / "run.sqlite"
    acquire(plan_file(folder, target=8), scene_file(folder), out)
    raw = out.read_bytes()
    assert len(raw) % PAGE == 0
    return raw


#: One damage: how, which page, and (for flip and bytes) which bytes of it.
DAMAGE = st.tuples(
    st.sampled_from(["flip", "bytes", "zero", "cut"]),
    st.integers(0, 10**6),
    st.lists(st.tuples(st.integers(0, PAGE - 1), st.integers(0, 255)), min_size=1, max_size=32),
)


def damaged(raw: bytes, damage: tuple[str, int, list[tuple[int, int]]]) -> bytes:
    """``raw`` with one page damaged (or cut short at the page's start)."""
    how, page, edits = damage
    start = (page % (len(raw) // PAGE)) * PAGE
    out = bytearray(raw)
    if how == "cut":
        return bytes(out[:start])
    if how == "zero":
        out[start : start + PAGE] = bytes(PAGE)
    for at, value in edits if how in ("flip", "bytes") else ():
        if how == "flip":
            out[start + at] ^= 1 << (value % 8)
        else:
            out[start + at] = value
    return bytes(out)


def written(folder: Path, raw: bytes) -> Path:
    path = folder / "fuzzed.sqlite"
    for suffix in ("-wal", "-shm"):
        Path(f"{path}{suffix}").unlink(missing_ok=True)
    path.write_bytes(raw)
    return path


def check_open(path: Path) -> bool:
    """Whether the run opens; a refusal must be one short line."""
    try:
        bounded(lambda: open_run(path))
    except JournalError as exc:
        message = str(exc)
        assert "\n" not in message and len(message) < 600, message[:2000]
        return False
    return True


def check_follow(path: Path) -> bool:
    """Whether a follower of the run (``gonio serve``, ``gonio watch``) opens it; a
    refusal must be one short line."""
    try:
        bounded(lambda: RunFollower(path).close())
    except JournalError as exc:
        message = str(exc)
        assert "\n" not in message and len(message) < 600, message[:2000]
        return False
    return True


@settings(max_examples=examples(40), suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(damage=DAMAGE)
def test_a_damaged_page_is_read_or_refused_in_one_line(
    pristine: bytes, tmp_path: Path, damage: tuple[str, int, list[tuple[int, int]]]
) -> None:
    check_open(written(tmp_path, damaged(pristine, damage)))


#: The read commands (the run file, a work folder → arguments).
COMMANDS: dict[str, Callable[[Path, Path], list[str]]] = {
    "info": lambda run, tmp: ["info", str(run)],
    "info --json": lambda run, tmp: ["info", str(run), "--json"],
    "evaluate": lambda run, tmp: ["evaluate", str(run)],
    "fit": lambda run, tmp: ["fit", str(run), "--model", "lambert"],
    "plot": lambda run, tmp: ["plot", str(run), "--kind", "coverage", "-o", str(tmp / "p.png")],
    "export csv": lambda run, tmp: ["export", str(run), "--format", "csv", "-o", str(tmp / "x")],
    "export hdf5": lambda run, tmp: ["export", str(run), "--format", "hdf5", "-o", str(tmp / "h")],
    "watch": lambda run, tmp: ["watch", str(run), "--once"],
}


@settings(max_examples=examples(12), suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(damage=DAMAGE, command=st.sampled_from(sorted(COMMANDS)))
def test_every_read_command_exits_0_or_2_in_one_line_on_a_damaged_run(
    pristine: bytes,
    tmp_path: Path,
    run_gonio: Callable[..., CliResult],
    damage: tuple[str, int, list[tuple[int, int]]],
    command: str,
) -> None:
    path = written(tmp_path, damaged(pristine, damage))
    result = bounded(lambda: run_gonio(*COMMANDS[command](path, tmp_path)))
    assert isinstance(result, CliResult)
    assert result.returncode in (0, 2), (command, result.stderr[-3000:])
    assert "Traceback" not in result.stderr
    if result.returncode == 2:
        assert len(result.stderr.strip().splitlines()) == 1, result.stderr[-2000:]


def test_every_page_zeroed_or_cut_is_read_or_refused(pristine: bytes, tmp_path: Path) -> None:
    """Each page in turn, zeroed, and the file cut at each page boundary: the pinned
    extremes of the search above (the first page's header, the schema, each table)."""
    outcomes = []
    for page in range(len(pristine) // PAGE):
        start = page * PAGE
        zeroed = pristine[:start] + bytes(PAGE) + pristine[start + PAGE :]
        outcomes.append(check_open(written(tmp_path, zeroed)))
        check_follow(written(tmp_path, zeroed))
        outcomes.append(check_open(written(tmp_path, pristine[:start])))
        check_follow(written(tmp_path, pristine[:start]))
    assert not all(outcomes)  # the damage reached what the reader reads


def test_the_pristine_copy_opens(pristine: bytes, tmp_path: Path) -> None:
    path = written(tmp_path, pristine)
    assert len(open_run(path)) == 8
