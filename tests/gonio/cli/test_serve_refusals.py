"""``gonio serve`` refuses what it cannot serve before it binds anything: a run file
that is not a readable run (truncated, another program's database, a link to a file
that is not one, a huge sparse file), a path that is neither a run file nor a folder,
a --host that is not an address (or is written with its port), a port in use. Each is
one line on stderr naming what was refused, exit code 2, nothing on stdout, the port
left free and the folder as it was. And a run or a folder served, then stopped, leaves
the folder as it was (a non-run file in the folder is listed as unreadable)."""

from __future__ import annotations

import json
import os
import shutil
import signal
import socket
import sqlite3
import subprocess
import sys
import time
import urllib.request
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import pytest
import uvicorn

from tests.conftest import CliResult
from tests.support.folders import listing
from tests.support.runs import plan_spec, scene_spec, simulated_run

ROOT = Path(__file__).resolve().parents[3]
Gonio = Callable[..., CliResult]
ENV = {**os.environ, "PYTHONPATH": str(ROOT)}


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def port_is_free(port: int) -> bool:
    with socket.socket() as s:
        try:
            s.bind(("127.0.0.1", port))
        except OSError:
            return False
    return True


def serve(*args: str, cwd: Path) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-m", "gonio", "serve", *args],
        cwd=cwd,
        env=ENV,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


@pytest.fixture(scope="module")
def folder(runs_dir: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A folder of a finished run and of files that are not runs."""
    made = simulated_run(runs_dir, plan_spec(300), scene_spec("matte", noise=False))
    folder = tmp_path_factory.mktemp("served")
    run = Path(shutil.copy(made, folder / "run.sqlite"))
    (folder / "trunc.sqlite").write_bytes(run.read_bytes()[:3000])
    with sqlite3.connect(folder / "other.sqlite") as conn:
        conn.execute("PRAGMA journal_mode=WAL")
        conn.execute("CREATE TABLE t (x)")
    conn.close()
    (folder / "link.sqlite").symlink_to("/etc/passwd")
    with open(folder / "sparse.sqlite", "wb") as f:
        f.truncate(100 << 30)
    return folder


#: Each refusal: the arguments after ``gonio serve`` and words of its one line.
REFUSALS: dict[str, tuple[list[str], tuple[str, ...]]] = {
    "truncated": (["trunc.sqlite"], ("trunc.sqlite", "not a readable run file")),
    "another-database": (["other.sqlite"], ("other.sqlite", "not a gonio run file")),
    "link-to-a-text": (["link.sqlite"], ("link.sqlite", "not a readable run file")),
    "sparse": (["sparse.sqlite"], ("sparse.sqlite", "not a readable run file")),
    "device": (["/dev/null"], ("/dev/null", "expected a run file (.sqlite) or a folder")),
    "missing": (["missing.sqlite"], ("missing.sqlite", "no such run file or folder")),
    "bad-address": (["run.sqlite", "--host", "999.1.1.1"], ("--host 999.1.1.1", "expected")),
    "host-with-port": (
        ["run.sqlite", "--host", "localhost:8765"],
        ("--host localhost:8765", "--host localhost --port 8765"),
    ),
    "unresolved": (["run.sqlite", "--host", "nothing.invalid"], ("--host nothing.invalid",)),
}


@dataclass(frozen=True)
class Refused:
    """What one refused ``gonio serve`` did: its exit code, output, error and port."""

    code: int
    out: str
    err: str
    port: int


#: The refusals also run as the real command, each a new interpreter (one of each kind:
#: a file, a path, an address; each costs the interpreter's start).
IN_CHILDREN = ("truncated", "device", "host-with-port")


@pytest.fixture(scope="module")
def refused(folder: Path) -> tuple[dict[str, Refused], dict[str, tuple[object, ...]]]:
    """The refusals of `IN_CHILDREN` by the real command, all started at once, and the
    folder's listing before them."""
    before = listing(folder)
    ports = {case: free_port() for case in IN_CHILDREN}
    children = {
        case: serve(*REFUSALS[case][0], "--port", str(ports[case]), cwd=folder)
        for case in IN_CHILDREN
    }
    done = {}
    for case, child in children.items():
        try:
            out, err = child.communicate(timeout=60)
        except subprocess.TimeoutExpired:
            child.kill()
            out, err = child.communicate()
        done[case] = Refused(child.returncode, out, err, ports[case])
    return done, before


@pytest.mark.parametrize("case", list(REFUSALS))
def test_serve_refuses_before_serving(
    folder: Path, run_gonio: Gonio, monkeypatch: pytest.MonkeyPatch, case: str
) -> None:
    """In-process (quick): a refusal never reaches the web server."""

    def served(*args: object, **kwargs: object) -> None:
        raise AssertionError(f"gonio serve served {case}")

    monkeypatch.setattr(uvicorn.Server, "run", served)
    monkeypatch.chdir(folder)
    args, words = REFUSALS[case]
    before = listing(folder)
    result = run_gonio("serve", *args)
    assert result.returncode == 2, result.stderr[-2000:]
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and all(w in lines[0] for w in words), result.stderr[-2000:]
    assert result.stdout == ""
    assert listing(folder) == before


@pytest.mark.parametrize("case", IN_CHILDREN)
def test_serve_refuses_before_binding(
    folder: Path, refused: tuple[dict[str, Refused], dict[str, tuple[object, ...]]], case: str
) -> None:
    results, before = refused
    result, (_, words) = results[case], REFUSALS[case]
    assert result.code == 2, result.err[-2000:]
    lines = result.err.strip().splitlines()
    assert len(lines) == 1 and all(w in lines[0] for w in words), result.err[-2000:]
    assert result.out == ""
    assert port_is_free(result.port)
    assert listing(folder) == before


def test_a_port_in_use_is_one_line(folder: Path) -> None:
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        child = serve("run.sqlite", "--port", str(port), cwd=folder)
        out, err = child.communicate(timeout=30)
    assert child.returncode == 2 and out == ""
    assert err.count("\n") == 1 and f"127.0.0.1:{port}" in err and "in use" in err, err


@pytest.mark.parametrize("what", ["run.sqlite", "."])
def test_serving_then_stopping_leaves_the_folder_as_it_was(folder: Path, what: str) -> None:
    port = free_port()
    before = listing(folder)
    child = serve(what, "--port", str(port), cwd=folder)
    try:
        assert child.stdout is not None
        assert child.stdout.readline().startswith(f"serving {what} at http://127.0.0.1:{port}/")
        give_up = time.monotonic() + 20
        while True:
            try:
                with urllib.request.urlopen(f"http://127.0.0.1:{port}/api/runs", timeout=5) as r:
                    runs = {run["name"]: run for run in json.load(r)["runs"]}
                break
            except OSError:
                assert time.monotonic() < give_up, "the server did not answer"
                time.sleep(0.1)
    finally:
        child.send_signal(signal.SIGINT)
        child.communicate(timeout=30)
    assert runs["run.sqlite"]["state"] == "completed"
    if what == ".":  # what is not a run is listed so; a link out of the folder is not
        assert set(runs) == {"run.sqlite", "trunc.sqlite", "other.sqlite", "sparse.sqlite"}
        assert all(runs[n]["state"] == "unreadable" for n in set(runs) - {"run.sqlite"})
    assert listing(folder) == before
