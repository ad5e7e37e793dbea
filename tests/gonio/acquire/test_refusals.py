"""What `gonio acquire` refuses before anything moves: an existing or
unwritable output, a missing or busy port, a run file another `gonio acquire` writes.
Each is one line on stderr and exit code 2, and leaves no run file behind (or the one
there untouched)."""

from __future__ import annotations

import contextlib
import fcntl
import os
import sqlite3
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from gonio.store.journal import Journal
from gonio.store.read import open_run
from tests.conftest import CONFIGS, CliResult
from tests.support.acquire import ARCH, RunFiles


def one_line(result: CliResult) -> str:
    assert result.returncode == 2, result
    assert "Traceback" not in result.stderr
    (line,) = result.stderr.splitlines()
    assert line.startswith("gonio: error: ")
    return line


def unwritable_folder(tmp_path: Path) -> Path:
    """A folder this process cannot create files in (root ignores permission bits:
    then /sys, where nobody can)."""
    folder = tmp_path / "read-only"
    folder.mkdir(mode=0o500)
    for candidate in (folder, Path("/sys")):
        try:
            (candidate / "probe").touch()
        except OSError:
            return candidate
        (candidate / "probe").unlink()
    pytest.skip("no unwritable folder on this machine")


def test_an_existing_output_is_refused(
    tmp_path: Path, run_files: Callable[..., RunFiles], run_gonio: Callable[..., CliResult]
) -> None:
    files = run_files(20)
    path = tmp_path / "run.sqlite"
    path.write_bytes(b"not mine")
    line = one_line(run_gonio(*files.cli(path)))
    assert str(path) in line and "already exists" in line and "--resume" in line
    assert path.read_bytes() == b"not mine"


@pytest.mark.parametrize("where", ["unwritable", "no folder", "a folder"])
def test_an_output_that_cannot_be_written_is_refused(
    where: str,
    tmp_path: Path,
    run_files: Callable[..., RunFiles],
    run_gonio: Callable[..., CliResult],
) -> None:
    files = run_files(20)
    path = {
        "unwritable": lambda: unwritable_folder(tmp_path) / "run.sqlite",
        "no folder": lambda: tmp_path / "missing" / "run.sqlite",
        "a folder": lambda: tmp_path,
    }[where]()
    line = one_line(run_gonio(*files.cli(path)))
    assert str(path) in line
    assert not list(path.parent.glob("*.sqlite*")) or where == "a folder"


def hardware_rig(tmp_path: Path, port: str) -> Path:
    """The arch rig on a Dynamixel bus at ``port`` (the detector stays simulated)."""
    rig = tmp_path / "hardware.yaml"
    text = ARCH.read_text().replace(
        "  port: /dev/ttyUSB0\n", f"  kind: dynamixel\n  port: {port}\n"
    )
    assert "kind: dynamixel" in text
    rig.write_text(text)
    return rig


def test_a_missing_port_is_refused_before_the_first_move(
    tmp_path: Path, run_files: Callable[..., RunFiles], run_gonio: Callable[..., CliResult]
) -> None:
    port = "/dev/gonio-no-such-port"
    files = run_files(20, rig=hardware_rig(tmp_path, port))
    path = tmp_path / "run.sqlite"
    line = one_line(run_gonio(*files.cli(path)))
    assert port in line
    assert not path.exists()  # nothing moved, nothing measured: no run file
    assert not list(tmp_path.glob(".run.sqlite*"))


def test_a_dry_run_refuses_what_the_run_refuses_before_any_port(
    tmp_path: Path, run_files: Callable[..., RunFiles], run_gonio: Callable[..., CliResult]
) -> None:
    """A dark reading on the serial rig with its light switch taken away (light.switch:
    none): the run and its dry run both refuse it in one line, before a port is opened
    (the ports here answer nothing, which a dry run that opened them would report)."""
    text = (CONFIGS / "rigs" / "arch_serial.yaml").read_text(encoding="utf-8")
    start = text.index("  switch:                    # a relay board")
    text = text[:start] + "  switch: none" + text[text.index("\ndetector:", start) :]
    ptys = [os.openpty() for _ in range(2)]
    try:
        for (_, device), old in zip(ptys, ("/dev/ttyUSB0", "/dev/ttyACM0"), strict=True):
            text = text.replace(f"port: {old}\n", f"port: {os.ttyname(device)}\n")
        rig = tmp_path / "serial.yaml"
        rig.write_text(text, encoding="utf-8")
        files = run_files(5, rig=rig)
        path = tmp_path / "run.sqlite"
        for extra in ((), ("--dry-run",)):
            line = one_line(run_gonio(*files.cli(path), *extra))
            assert "acquisition.calibration.dark" in line and "no dark reading" in line, extra
        assert not path.exists()
    finally:
        for fds in ptys:
            for fd in fds:
                os.close(fd)


@pytest.fixture
def held_pty() -> Iterator[str]:
    """A pseudo-terminal another program holds (an exclusive flock, as `DynamixelLink`
    takes on its port)."""
    controller, device = os.openpty()
    path = os.ttyname(device)
    holder = os.open(path, os.O_RDWR | os.O_NOCTTY)
    fcntl.flock(holder, fcntl.LOCK_EX | fcntl.LOCK_NB)
    yield path
    for fd in (holder, device, controller):
        os.close(fd)


@pytest.mark.pty
def test_a_busy_port_is_refused_before_the_first_move(
    tmp_path: Path,
    held_pty: str,
    run_files: Callable[..., RunFiles],
    run_gonio: Callable[..., CliResult],
) -> None:
    files = run_files(20, rig=hardware_rig(tmp_path, held_pty))
    path = tmp_path / "run.sqlite"
    line = one_line(run_gonio(*files.cli(path)))
    assert held_pty in line and "busy" in line
    assert not path.exists()


def test_a_run_file_being_written_is_refused(
    tmp_path: Path, run_files: Callable[..., RunFiles], run_gonio: Callable[..., CliResult]
) -> None:
    files = run_files(20)
    path = tmp_path / "run.sqlite"
    assert files.start(path).report.outcome == "completed"
    before = open_run(path)
    with Journal.reopen(path, durable=False):  # another gonio acquire, writing
        for args in (
            ("acquire", "--resume", str(path), "-q"),
            (*files.cli(path), "--overwrite"),
        ):
            line = one_line(run_gonio(*args))
            assert str(path) in line and "another gonio acquire is writing this run" in line
    after = open_run(path)
    assert len(after.sessions) == len(before.sessions) and len(after) == len(before)


@pytest.mark.parametrize("table", ["samples", "events", "meta"])
def test_resuming_a_run_file_with_a_table_gone_is_one_line(
    tmp_path: Path,
    run_files: Callable[..., RunFiles],
    run_gonio: Callable[..., CliResult],
    table: str,
) -> None:
    files = run_files(5)
    path = tmp_path / "run.sqlite"
    assert files.start(path).report.outcome == "completed"
    with contextlib.closing(sqlite3.connect(path)) as conn:
        conn.execute(f"DROP TABLE {table}")
        conn.commit()
    line = one_line(run_gonio("acquire", "--resume", str(path), "-q"))
    assert str(path) in line and f"no such table: {table}" in line
