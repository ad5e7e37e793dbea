"""`gonio watch RUN.sqlite`: a run live in the terminal (progress, ETA, the last samples,
health, events), redrawn in place; ``q`` or Ctrl-C quits without touching the run. When
stdout is not a terminal: a plain line whenever something changed (at most every
``--every`` seconds), until the run is no longer being acquired."""

from __future__ import annotations

import argparse
import contextlib
import os
import select
import shutil
import sys
import termios
import time
import tty
from collections.abc import Iterator
from pathlib import Path

from gonio.cli.arguments import positive_seconds
from gonio.errors import GonioError
from gonio.live import LiveRun, line, overview, screen


def add_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser], help_: str) -> None:
    p = sub.add_parser(
        "watch",
        help=help_,
        description="Show a run live in the terminal: progress, instrument time, rate, "
        "ETA, the last samples, the motors' health and the events, redrawn in place; q or "
        "Ctrl-C quits and leaves the run alone. When stdout is not a terminal, print a "
        "plain line whenever something changed, until the run is no longer acquired.",
    )
    p.add_argument("run", type=Path, help="the run file (SQLite), being acquired or not")
    p.add_argument(
        "--every",
        type=positive_seconds,
        default=1.0,
        help="seconds between reads of the run file (default 1)",
    )
    p.add_argument("--once", action="store_true", help="show the run once and exit")
    p.set_defaults(func=cmd_watch)


def cmd_watch(args: argparse.Namespace) -> int:
    live = LiveRun(args.run)  # JournalError: one line naming the file and the field
    try:
        if args.once or not sys.stdout.isatty():
            return _plain(live, args.every, once=args.once)
        return _live(live, args.every)
    except GonioError as exc:  # what the views cannot show (a value out of its domain)
        if args.run.name in str(exc):
            raise
        raise GonioError(f"{args.run}: {exc}") from None
    finally:
        live.close()


def _plain(live: LiveRun, every: float, *, once: bool) -> int:
    shown = None
    while True:
        text = line(overview(live))
        if text != shown:
            print(text, flush=True)
            shown = text
        if once or not live.writing:
            return 0
        time.sleep(every)
        live.refresh()


@contextlib.contextmanager
def _keys() -> Iterator[int | None]:
    """Standard input in cbreak mode (keys without Enter, no echo) while inside; its
    descriptor, or None when it is not a terminal."""
    fd = sys.stdin.fileno() if sys.stdin.isatty() else None
    if fd is None:
        yield None
        return
    saved = termios.tcgetattr(fd)
    try:
        tty.setcbreak(fd)
        yield fd
    finally:
        termios.tcsetattr(fd, termios.TCSADRAIN, saved)


def _live(live: LiveRun, every: float) -> int:
    out = sys.stdout
    out.write("\x1b[?25l")  # hide the cursor
    try:
        with _keys() as fd:
            while True:
                size = shutil.get_terminal_size()
                lines = screen(live, overview(live), width=size.columns, height=size.lines)
                out.write("\x1b[H\x1b[2J" + "\n".join(lines))
                out.flush()
                deadline = time.monotonic() + every
                while (left := deadline - time.monotonic()) > 0:
                    if fd is None:
                        time.sleep(left)
                        break
                    ready, _, _ = select.select([fd], [], [], left)
                    if ready and os.read(fd, 1).lower() == b"q":
                        return 0
                live.refresh()
    except KeyboardInterrupt:
        return 0
    finally:
        out.write("\x1b[?25h\n")
        out.flush()
