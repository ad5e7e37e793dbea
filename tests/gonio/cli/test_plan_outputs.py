"""`gonio plan`'s outputs cannot fail late and are never left half written: each is
created (as a temporary file beside it) before any planning, written whole, flushed and
renamed into place; without -o the command says nothing was written."""

from __future__ import annotations

import errno
import os
import stat
import threading
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

import gonio.cli.plan as plan_command
from tests.conftest import CONFIGS, CliResult

Gonio = Callable[..., CliResult]
QUICK = str(CONFIGS / "plans" / "quick.yaml")
SMALL = str(CONFIGS / "plans" / "quickstart.yaml")


def _no_planning(monkeypatch: pytest.MonkeyPatch) -> None:
    def refuse(*args: object) -> None:
        raise AssertionError("planning started before the output was checked")

    monkeypatch.setattr(plan_command, "load_plan_source", refuse)


def _sys_refuses() -> bool:
    """/sys/kernel exists, `os.access` calls it writable, and creating a file fails."""
    folder = Path("/sys/kernel")
    if not folder.is_dir() or not os.access(folder, os.W_OK):
        return False
    try:
        (folder / "gonio-probe").open("x").close()
    except OSError:
        return True
    (folder / "gonio-probe").unlink()  # pragma: no cover
    return False  # pragma: no cover


@pytest.mark.skipif(not _sys_refuses(), reason="needs a /sys that os.access calls writable")
@pytest.mark.parametrize("option", ["-o", "--plot"])
def test_a_folder_the_kernel_refuses_is_refused_before_any_work(
    option: str, monkeypatch: pytest.MonkeyPatch, run_gonio: Gonio
) -> None:
    """Under /sys, `os.access` says writable (we run as root) but the kernel refuses to
    create a file: that used to come after the whole summary (a PermissionError
    traceback for --plot); now one line before anything is planned."""
    _no_planning(monkeypatch)
    name = "/sys/kernel/gonio-plan.csv" if option == "-o" else "/sys/kernel/coverage.png"
    r = run_gonio("plan", QUICK, option, name)
    assert r.returncode == 2
    assert r.stdout == ""
    assert r.stderr == (
        f"gonio: error: {option} {name}: cannot create a file in /sys/kernel: "
        f"{os.strerror(errno.EACCES)}\n"
    )


def test_a_figure_format_matplotlib_cannot_write_is_refused_before_any_work(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, run_gonio: Gonio
) -> None:
    _no_planning(monkeypatch)
    r = run_gonio("plan", QUICK, "--plot", str(tmp_path / "coverage.xyz"))
    assert r.returncode == 2
    assert r.stdout == ""
    assert len(r.stderr.splitlines()) == 1
    assert "matplotlib cannot write '.xyz' figures; name a file ending in one of" in r.stderr
    assert list(tmp_path.iterdir()) == []


def test_a_refused_figure_write_leaves_the_old_file_whole(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, run_gonio: Gonio
) -> None:
    """The disk fills half way through the figure: the previous figure is still there,
    byte for byte, no temporary file is left, and the error is one line."""
    old = tmp_path / "coverage.png"
    old.write_bytes(b"the previous figure")

    def half_then_full(plan: Any, path: str | Path, **kwargs: Any) -> None:
        Path(path).write_bytes(b"\x89PNG half")
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr("gonio.plots.plot_coverage", half_then_full)  # as gonio plan finds it
    r = run_gonio("plan", SMALL, "--plot", str(old))
    assert r.returncode == 2
    assert r.stderr == (
        f"gonio: error: --plot {old}: cannot write it: {os.strerror(errno.ENOSPC)}; "
        "nothing was written\n"
    )
    assert old.read_bytes() == b"the previous figure"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["coverage.png"]


def test_an_interrupted_plan_leaves_no_file_and_the_old_one_whole(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, run_gonio: Gonio
) -> None:
    old = tmp_path / "plan.csv"
    old.write_text("an older plan\n")

    def interrupted(*args: object) -> None:
        assert any(p.name.startswith(".plan.csv.") for p in tmp_path.iterdir())  # reserved
        raise KeyboardInterrupt

    monkeypatch.setattr(plan_command, "load_plan_source", interrupted)
    r = run_gonio("plan", QUICK, "-o", str(old), "--plot", str(tmp_path / "c.png"))
    assert r.returncode == 130
    assert old.read_text() == "an older plan\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["plan.csv"]


def test_outputs_replace_atomically_keep_modes_and_follow_links(
    tmp_path: Path, run_gonio: Gonio
) -> None:
    target = tmp_path / "real.csv"
    target.write_text("old\n")
    target.chmod(0o640)
    link = tmp_path / "plan.csv"
    link.symlink_to(target.name)
    r = run_gonio("plan", SMALL, "-o", str(link))
    assert r.returncode == 0, r.stderr
    assert link.is_symlink() and target.read_text().startswith("# gonio-plan v1\n")
    assert stat.S_IMODE(target.stat().st_mode) == 0o640
    assert sorted(p.name for p in tmp_path.iterdir()) == ["plan.csv", "real.csv"]
    fresh = tmp_path / "fresh.csv"
    r = run_gonio("plan", SMALL, "-o", str(fresh))
    mask = os.umask(0o022)
    os.umask(mask)
    assert stat.S_IMODE(fresh.stat().st_mode) == 0o666 & ~mask


def test_a_pipe_or_device_is_written_in_place(tmp_path: Path, run_gonio: Gonio) -> None:
    """An output that exists and is not a regular file (a named pipe here; /dev/null,
    /dev/stdout alike) is written in place: the old writer renamed a temporary file over
    it, which as root turned ``-o /dev/null`` into a regular file for the whole machine.
    (A named pipe in a temporary folder shows it without touching /dev.)"""
    fifo = tmp_path / "plan.fifo"
    os.mkfifo(fifo)
    received: list[bytes] = []
    reader = threading.Thread(target=lambda: received.append(fifo.read_bytes()), daemon=True)
    reader.start()
    r = run_gonio("plan", SMALL, "-o", str(fifo))
    reader.join(timeout=30)
    assert r.returncode == 0, r.stderr
    assert r.stdout.splitlines()[-1] == f"wrote 300 targets to {fifo}"
    assert stat.S_ISFIFO(fifo.stat().st_mode)
    assert received and received[0].startswith(b"# gonio-plan v1\n")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["plan.fifo"]


def test_without_o_the_plan_says_nothing_was_written(tmp_path: Path, run_gonio: Gonio) -> None:
    r = run_gonio("plan", SMALL)
    assert r.returncode == 0, r.stderr
    assert r.stdout.splitlines()[-1] == (
        "nothing written: give -o PLAN.csv to store the plan (gonio.planner.read_plan "
        "reads it back)"
    )
    figure = tmp_path / "coverage"  # no suffix: a PNG
    r = run_gonio("plan", SMALL, "--plot", str(figure))  # a figure alone: still not the plan
    assert r.returncode == 0, r.stderr
    assert figure.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert r.stdout.splitlines()[-2:] == [
        f"drew the coverage in {figure}",
        "nothing written: give -o PLAN.csv to store the plan (gonio.planner.read_plan "
        "reads it back)",
    ]
