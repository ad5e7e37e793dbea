"""The ``gonio`` processes a soak spawns (a new interpreter, or a fork for tests) and
SIGKILLs at a chosen moment."""

from __future__ import annotations

import contextlib
import os
import signal
import sqlite3
import subprocess
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Protocol

from tests.soak.journal import connect, progress
from tests.soak.scenario import ROOT
from tests.soak.schedule import Kill


class Child(Protocol):
    """A started ``gonio`` process: `PopenChild` or a fork (`ForkLauncher`)."""

    pid: int

    def poll(self) -> int | None: ...
    def kill(self) -> None: ...
    def finish(self, timeout_s: float) -> tuple[int, str]:
        """Wait for the end: (return code, −9 when SIGKILLed; its stderr)."""


class PopenChild:
    """``python -m gonio ARGV`` in a new interpreter (what a user runs)."""

    def __init__(self, argv: Sequence[str], preexec: Callable[[], None] | None) -> None:
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "gonio", *argv],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            cwd=ROOT,
            preexec_fn=preexec,
        )
        self.pid = self.proc.pid

    def poll(self) -> int | None:
        return self.proc.poll()

    def kill(self) -> None:
        self.proc.send_signal(signal.SIGKILL)

    def finish(self, timeout_s: float) -> tuple[int, str]:
        try:
            _, err = self.proc.communicate(timeout=timeout_s)
        except BaseException:
            self.proc.kill()
            self.proc.wait()
            raise
        return self.proc.returncode, err.decode(errors="replace")


class ForkLauncher:
    """Children forked from this process that run ``main(ARGV)`` (the CLI's entry
    point, passed in: everything already imported, so a session starts in
    milliseconds; for tests)."""

    def __init__(self, main: Callable[[list[str]], int]) -> None:
        self.main = main

    def __call__(self, argv: Sequence[str], preexec: Callable[[], None] | None) -> Child:
        return ForkChild(self.main, list(argv), preexec)


class ForkChild:
    def __init__(
        self, main: Callable[[list[str]], int], argv: list[str], preexec: Callable[[], None] | None
    ) -> None:
        read, write = os.pipe()
        pid = os.fork()
        if pid == 0:  # the child: never returns
            code = 70
            try:
                os.close(read)
                null = os.open(os.devnull, os.O_WRONLY)
                os.dup2(null, 1)
                os.dup2(write, 2)
                sys.stdout = open(1, "w", closefd=False)  # noqa: SIM115
                sys.stderr = open(2, "w", closefd=False)  # noqa: SIM115
                if preexec is not None:
                    preexec()
                code = int(main(argv))
            except SystemExit as exc:
                code = exc.code if isinstance(exc.code, int) else 1
            except BaseException as exc:
                with contextlib.suppress(BaseException):
                    os.write(2, f"{type(exc).__name__}: {exc}\n".encode())
            finally:
                with contextlib.suppress(BaseException):
                    sys.stderr.flush()
                os._exit(code)
        os.close(write)
        self.pid = pid
        self._read = read
        self._status: int | None = None

    def poll(self) -> int | None:
        if self._status is None:
            pid, status = os.waitpid(self.pid, os.WNOHANG)
            if pid == 0:
                return None
            self._status = os.waitstatus_to_exitcode(status)
        return self._status

    def kill(self) -> None:
        os.kill(self.pid, signal.SIGKILL)

    def finish(self, timeout_s: float) -> tuple[int, str]:
        chunks = []
        while chunk := os.read(self._read, 65536):
            chunks.append(chunk)
        os.close(self._read)
        if self._status is None:
            _, status = os.waitpid(self.pid, 0)
            self._status = os.waitstatus_to_exitcode(status)
        return self._status, b"".join(chunks).decode(errors="replace")


Launcher = Callable[[Sequence[str], Callable[[], None] | None], Child]


def spawn(
    launch: Launcher,
    argv: Sequence[str],
    run: Path,
    kill: Kill | None,
    *,
    preexec: Callable[[], None] | None = None,
    timeout_s: float = 3600.0,
) -> tuple[int, int, bool, str, float]:
    """Run ``gonio`` with ``argv``; SIGKILL it as ``kill`` says (None: never).
    (pid, return code, killed, stderr, wall seconds)."""
    started = time.monotonic()
    child = launch(argv, preexec)
    killed = False
    try:
        if kill is not None:
            killed = kill_when(child, run, kill, started + timeout_s)
        rc, err = child.finish(max(started + timeout_s - time.monotonic(), 1.0))
    except BaseException:  # the soak itself interrupted: leave no child behind
        if child.poll() is None:
            child.kill()
        with contextlib.suppress(BaseException):
            child.finish(5.0)
        raise
    return child.pid, rc, killed and rc == -signal.SIGKILL, err, time.monotonic() - started


def kill_when(child: Child, run: Path, kill: Kill, deadline: float) -> bool:
    """SIGKILL ``child`` when ``kill`` says; whether it was still running then."""
    if kill.after > 0:
        conn: sqlite3.Connection | None = None
        start = None
        try:
            while child.poll() is None and time.monotonic() < deadline:
                if conn is None and run.exists():
                    conn = connect(run)
                if conn is not None:
                    now = progress(conn)
                    start = now if start is None else start
                    if now - start >= kill.after:
                        break
                time.sleep(0.002)
        finally:
            if conn is not None:
                conn.close()
    end = time.monotonic() + kill.delay_s
    while child.poll() is None and time.monotonic() < end:
        time.sleep(0.001)
    if child.poll() is not None:
        return False
    child.kill()
    return True
