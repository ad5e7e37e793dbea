"""A full disk, real not patched in: a filler file on a size-limited tmpfs, or a file
size limit (RLIMIT_FSIZE) on the acquiring process."""

from __future__ import annotations

import contextlib
import os
import resource
import signal
import subprocess
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Literal

DiskMode = Literal["tmpfs", "rlimit"]


def fill(folder: Path, leave_bytes: int) -> Path:
    """A filler file taking all the free space of ``folder``'s filesystem but
    ``leave_bytes``."""
    filler = folder / "filler.bin"
    stats = os.statvfs(folder)
    free = stats.f_bavail * stats.f_frsize
    size = max(free - leave_bytes, 0)
    with open(filler, "wb") as f:
        os.posix_fallocate(f.fileno(), 0, max(size, 1))
    return filler


def fsize_limit(path: Path, extra: int) -> Callable[[], None]:
    """A ``preexec_fn`` that limits the child's file sizes to ``extra`` bytes beyond
    the largest of the run's files now."""
    sizes = [Path(f"{path}{s}").stat().st_size for s in ("", "-wal") if Path(f"{path}{s}").exists()]
    limit = max(sizes, default=0) + extra

    def limited() -> None:
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past the limit fails (EFBIG)
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, resource.RLIM_INFINITY))

    return limited


@contextlib.contextmanager
def tmpfs(folder: Path, size_mb: int) -> Iterator[bool]:
    """A size-limited tmpfs mounted on ``folder`` for the block (root only); yields
    whether it was mounted (else ``folder`` is a plain folder)."""
    folder.mkdir(parents=True, exist_ok=True)
    mounted = False
    if os.geteuid() == 0:
        result = subprocess.run(
            ["mount", "-t", "tmpfs", "-o", f"size={size_mb}m", "soak", str(folder)],
            capture_output=True,
        )
        mounted = result.returncode == 0
    try:
        yield mounted
    finally:
        if mounted:
            subprocess.run(["umount", str(folder)], capture_output=True)
