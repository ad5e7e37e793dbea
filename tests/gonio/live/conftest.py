"""A `gonio serve` application served by uvicorn in a thread on a free loopback port,
and a `gonio acquire` child paced slow enough to watch."""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest
import uvicorn

from gonio.acquire import observer
from gonio.cli import main
from gonio.live import server
from tests.gonio.live.paced import Paced

ROOT = Path(__file__).resolve().parents[3]


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@contextmanager
def serving(served: server.Served) -> Iterator[str]:
    """``served`` on http://127.0.0.1:PORT (the base URL) for the length of the block."""
    port = free_port()
    config = uvicorn.Config(
        server.app(served), host="127.0.0.1", port=port, log_level="warning", lifespan="off"
    )
    srv = uvicorn.Server(config)
    thread = threading.Thread(target=srv.run, daemon=True)
    thread.start()
    give_up = time.monotonic() + 10
    while not srv.started:
        assert time.monotonic() < give_up, "the server did not start"
        time.sleep(0.01)
    try:
        yield f"http://127.0.0.1:{port}"
    finally:
        srv.should_exit = True
        thread.join(5)


@pytest.fixture
def serve() -> Callable[[server.Served], Iterator[str]]:
    return serving  # type: ignore[return-value]


def paced_acquire(args: list[str], seconds_per_target: float) -> subprocess.Popen[str]:
    """``gonio acquire ARGS`` in a child process whose every target takes at least
    ``seconds_per_target`` of wall time (tests/gonio/live/paced.py); stdout piped."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.Popen(
        [sys.executable, "-m", "tests.gonio.live.paced", str(seconds_per_target), *args],
        cwd=ROOT,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def printed_url(child: subprocess.Popen[str]) -> str:
    """The URL with the token that the acquiring ``child`` printed (its stdout read up
    to that line)."""
    assert child.stdout is not None
    for text in child.stdout:
        if text.startswith("watch and control: "):
            return text.rsplit(" ", 1)[-1].strip()
    raise AssertionError(f"gonio acquire printed no URL: {child.stderr and child.stderr.read()}")


def forked_acquire(args: list[str], seconds_per_target: float) -> int:
    """``gonio acquire ARGS`` (quiet) in a forked child paced as `paced_acquire` (no new
    interpreter to start); its pid, its exit status the command's exit code."""
    pid = os.fork()
    if pid == 0:  # pragma: no cover - the child
        code = 1
        try:
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, 1)
            os.dup2(devnull, 2)
            sys.stdout = sys.stderr = open(os.devnull, "w")  # noqa: SIM115 (until _exit)
            observer.for_stream = lambda quiet, stream=None: Paced(seconds_per_target)  # type: ignore[assignment]
            code = main(args)
        finally:
            os._exit(code)
    return pid
