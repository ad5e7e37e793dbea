"""Control of a running acquisition from outside its process: pause, resume and stop
requests that the engine reads between targets (the process that acquires owns the
decision; whoever asks only appends a request).

Beside the run file ``RUN.sqlite`` lie two small files:

- ``RUN.sqlite.token``: the run's control token (`issue_token`), owner-only (0600),
  written by ``gonio acquire``; whoever holds it may post requests (``gonio serve``
  compares it in constant time);
- ``RUN.sqlite.requests``: the requests, one JSON line each (`post_request`,
  appended); a session reads only the lines appended after it started
  (`ControlRequests`), so an old request never acts on a later session.

A ``stop`` request acts exactly as a first Ctrl-C: the sample in flight finishes, the
session ends resumable (`StopRequested`). A ``pause`` holds the axes between targets
and waits, the process still running, until a ``resume`` (or a ``stop``, or Ctrl-C).
Each is journaled by the engine as a ``pause``, ``resume`` or ``stop`` event (the kind
is the action) whose ``reason`` is ``request``, with who asked and when
(`Request.data`).
"""

from __future__ import annotations

import json
import os
import secrets
import signal
import stat
import time
import uuid
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

from gonio.acquire.runtime import utc_now
from gonio.acquire.signals import RunInterrupted

Action = Literal["pause", "resume", "stop"]
ACTIONS: tuple[Action, ...] = ("pause", "resume", "stop")
#: The longest ``by`` a request keeps (characters).
BY_CHARS = 200


def token_path(run: Path) -> Path:
    """Where the run file ``run``'s control token lies."""
    return Path(f"{run}.token")


def requests_path(run: Path) -> Path:
    """Where the run file ``run``'s control requests are appended."""
    return Path(f"{run}.requests")


def _owner_only(st: os.stat_result) -> bool:
    return stat.S_ISREG(st.st_mode) and st.st_mode & 0o077 == 0 and st.st_uid == os.getuid()


def read_token(run: Path) -> str | None:
    """The run's control token, or None when there is none, it is unreadable or its file
    is readable by others than its owner (such a token is not trusted)."""
    path = token_path(run)
    try:
        fd = os.open(path, os.O_RDONLY | os.O_CLOEXEC | os.O_NOFOLLOW)
    except OSError:
        return None
    try:
        if not _owner_only(os.fstat(fd)):
            return None
        token = os.read(fd, 4096).decode("ascii", "replace").strip()
    finally:
        os.close(fd)
    return token or None


def issue_token(run: Path) -> str:
    """The run's control token: the one beside it when it is owner-only, else a new one
    (32 random bytes, URL-safe) written owner-only (mode 0600) in its place. `OSError`
    if the folder cannot be written."""
    token = read_token(run)
    if token is not None:
        return token
    token = secrets.token_urlsafe(32)
    path = token_path(run)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_CLOEXEC, 0o600)
    try:
        os.write(fd, f"{token}\n".encode("ascii"))
    finally:
        os.close(fd)
    os.replace(tmp, path)
    return token


@dataclass(frozen=True)
class Request:
    """One control request: the ``action``, who asked (``by``: free text, e.g. the
    client's address), when (``utc``, ISO 8601) and its ``id``."""

    action: Action
    by: str
    utc: str
    id: str

    def data(self) -> dict[str, Any]:
        """What the journal's pause/resume event records of it."""
        return {"action": self.action, "by": self.by, "requested_utc": self.utc, "id": self.id}

    @classmethod
    def parse(cls, line: str) -> Request | None:
        """The request of one line of the requests file (None if it is not one)."""
        try:
            value = json.loads(line)
        except ValueError:
            return None
        if not isinstance(value, Mapping) or value.get("action") not in ACTIONS:
            return None
        return cls(
            value["action"],
            str(value.get("by", ""))[:BY_CHARS],
            str(value.get("utc", "")),
            str(value.get("id", "")),
        )


def post_request(run: Path, action: Action, by: str) -> Request:
    """Append a request to the run's requests file (created owner-only); the request.
    One ``write`` of one line with ``O_APPEND``: concurrent posters never interleave."""
    if action not in ACTIONS:
        raise ValueError(f"unknown control action {action!r}")
    request = Request(action, by[:BY_CHARS], utc_now(), uuid.uuid4().hex[:12])
    line = json.dumps({**request.data(), "utc": request.utc}, ensure_ascii=True) + "\n"
    fd = os.open(requests_path(run), os.O_WRONLY | os.O_APPEND | os.O_CREAT | os.O_CLOEXEC, 0o600)
    try:
        os.write(fd, line.encode("ascii"))
    finally:
        os.close(fd)
    return request


class ControlRequests:
    """The engine's side: the requests appended to the run's requests file since this
    session started (``run`` None, an in-memory run: never any). `poll` costs one
    ``stat`` when nothing was posted."""

    def __init__(self, run: Path | None) -> None:
        self.path = None if run is None else requests_path(run)
        self._offset = self._size()
        self._partial = b""

    def _size(self) -> int:
        if self.path is None:
            return 0
        try:
            return os.stat(self.path).st_size
        except OSError:
            return 0

    def poll(self) -> list[Request]:
        """The requests posted since the last poll, in order."""
        size = self._size()
        if size <= self._offset:
            if size < self._offset:  # replaced by a shorter file: read it from its start
                self._offset, self._partial = 0, b""
            return []
        assert self.path is not None
        with open(self.path, "rb") as f:
            f.seek(self._offset)
            chunk = f.read(size - self._offset)
        self._offset += len(chunk)
        *lines, self._partial = (self._partial + chunk).split(b"\n")
        found = (Request.parse(line.decode("ascii", "replace")) for line in lines)
        return [r for r in found if r is not None]

    def wait(self, seconds: float) -> list[Request]:
        """Sleep ``seconds`` of wall time, then `poll` (a paused run's loop)."""
        time.sleep(seconds)
        return self.poll()


class StopRequested(RunInterrupted):
    """A ``stop`` request ended the session, as a first Ctrl-C does (nothing
    abandoned; the run resumable)."""

    def __init__(self, request: Request) -> None:
        KeyboardInterrupt.__init__(self, "stop request")
        self.signum = signal.SIGINT
        self.abandoned = False
        self.request = request
