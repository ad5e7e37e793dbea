"""A folder's listing as a test compares it before and after a command: each entry's
name and, for a file, its size, modification time and content hash (a sparse or huge
file by its size and time only)."""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

#: Files larger than this are compared by size and time, not content.
HASHED_BYTES = 64 << 20


def listing(folder: Path) -> dict[str, tuple[object, ...]]:
    """Every entry under ``folder`` (recursively, links not followed): name → (kind,
    size, mtime ns, sha256 of the content) for a file, (kind, target) for a link."""
    out: dict[str, tuple[object, ...]] = {}
    for path in sorted(folder.rglob("*")):
        name = str(path.relative_to(folder))
        st = os.lstat(path)
        if path.is_symlink():
            out[name] = ("link", os.readlink(path))
        elif path.is_dir():
            out[name] = ("dir",)
        elif st.st_size > HASHED_BYTES:
            out[name] = ("file", st.st_size, st.st_mtime_ns)
        else:
            digest = hashlib.sha256(path.read_bytes()).hexdigest()
            out[name] = ("file", st.st_size, st.st_mtime_ns, digest)
    return out
