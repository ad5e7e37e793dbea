"""``python -m gonio ARGS…`` as a real process, and what a user's mistake must look like
there: exit 2, one line on stderr, no traceback, and the folder it would write to as it
was (nothing written or left behind)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from tests.conftest import CliResult

ROOT = Path(__file__).resolve().parents[2]


def gonio_process(*args: str, timeout: float = 120) -> CliResult:
    """Run ``python -m gonio ARGS…`` from the repository's root."""
    done = subprocess.run(
        [sys.executable, "-m", "gonio", *args],
        capture_output=True,
        text=True,
        timeout=timeout,
        cwd=ROOT,
        stdin=subprocess.DEVNULL,
    )
    return CliResult(done.returncode, done.stdout, done.stderr)


def listing(folder: Path) -> list[tuple[str, int]]:
    """(relative path, size) of every file under ``folder``, sorted."""
    return sorted(
        (str(p.relative_to(folder)), p.stat().st_size) for p in folder.rglob("*") if p.is_file()
    )


def refused(folder: Path, *args: str) -> str:
    """Run ``gonio ARGS…``, assert it refused the way a user's mistake is refused and
    left ``folder`` as it was; the one line it printed."""
    before = listing(folder)
    result = gonio_process(*args)
    lines = result.stderr.strip().splitlines()
    assert result.returncode == 2, result.stderr[-2000:]
    assert len(lines) == 1 and "Traceback" not in result.stderr, result.stderr[-2000:]
    assert listing(folder) == before
    return lines[0]
