"""Output files that cannot fail late and are never left half written.

`reserve_output(path, option)` is called before any work: it creates the temporary file
the output will be written to, beside ``path`` (same folder, so the final rename is
atomic), which proves the folder accepts a new file — `os.access` does not: under
``/sys`` it calls a folder writable where the kernel refuses to create anything, and
the refusal came after minutes of planning. The work done, `PendingOutput.write_bytes`
(or `write_with`, for a writer that wants a path) writes the temporary file, flushes it
to the disk and renames it over ``path`` (`os.replace`): readers see the old file or the
whole new one, never a truncated one; an interrupted or refused write removes the
temporary file and leaves ``path`` as it was.

``path`` that exists and is not a regular file (``/dev/null``, ``/dev/stdout``, a named
pipe) is opened for writing instead, also before the work, and written in place:
replacing a device node by a regular file would be worse than a partial write. A
symbolic link is followed: its target is replaced, the link stays.
"""

from __future__ import annotations

import contextlib
import os
import stat
import tempfile
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from typing import IO

from gonio.config import ConfigError

#: The temporary file's name ends with this and the output's own suffix (so a writer
#: that picks the format from the suffix, as matplotlib does, still sees it).
PARTIAL = ".partial"


class PendingOutput:
    """An output reserved by `reserve_output`: write it once, or discard it."""

    def __init__(self, path: Path, option: str) -> None:
        self.path = path
        self.option = option
        self.partial: Path | None = None
        self._stream: IO[bytes] | None = None
        self._mode = 0o666
        self.target = path
        self.done = False

    def _open(self) -> None:
        path = self.path
        if path.is_dir():
            raise ConfigError(f"{self.option} {path}: is a directory; expected a file name")
        target = Path(os.path.realpath(path)) if path.is_symlink() else path
        try:
            info = target.stat()
        except FileNotFoundError:
            info = None
        except OSError as exc:
            raise ConfigError(f"{self.option} {path}: {exc.strerror or exc}") from None
        if info is not None and not stat.S_ISREG(info.st_mode):
            try:  # a device or a pipe: written in place
                self._stream = open(target, "wb")  # noqa: SIM115 (closed by write or discard)
            except OSError as exc:
                raise ConfigError(
                    f"{self.option} {path}: cannot write it: {exc.strerror or exc}"
                ) from None
            return
        folder = target.parent if str(target.parent) else Path(".")
        if not folder.is_dir():
            raise ConfigError(f"{self.option} {path}: the folder {folder} does not exist")
        try:
            fd, name = tempfile.mkstemp(
                dir=folder, prefix=f".{target.name}.", suffix=PARTIAL + target.suffix
            )
        except OSError as exc:
            raise ConfigError(
                f"{self.option} {path}: cannot create a file in {folder}: {exc.strerror or exc}"
            ) from None
        os.close(fd)
        self.partial = Path(name)
        self._mode = stat.S_IMODE(info.st_mode) if info is not None else 0o666 & ~_umask()
        self.target = target

    def write_bytes(self, data: bytes) -> None:
        """Write ``data`` to the output (atomically where it is a regular file)."""
        stream = self._stream
        if stream is not None:  # a device or a pipe, opened by `reserve_output`
            self._stream = None
            with stream:
                self._guard(lambda: stream.write(data))
            self.done = True
            return

        def write(path: Path) -> None:
            with open(path, "wb") as out:
                out.write(data)

        self.write_with(write)

    def write_with(self, writer: Callable[[Path], None]) -> None:
        """Let ``writer`` write the temporary file (given its path), then flush it to the
        disk and rename it over the output. `ConfigError` (one line) if the disk refuses;
        the output is then as it was."""
        if self.done:
            raise RuntimeError(f"{self.path} was already written")
        if self._stream is not None:  # a device: the writer writes to it by name
            stream, self._stream = self._stream, None
            stream.close()
            self._guard(lambda: writer(self.path))
            self.done = True
            return
        partial = self.partial
        assert partial is not None

        def commit() -> None:
            writer(partial)
            os.chmod(partial, self._mode)
            with open(partial, "rb") as written:
                os.fsync(written.fileno())
            os.replace(partial, self.target)
            _fsync_folder(self.target.parent)

        try:
            self._guard(commit)
        except BaseException:
            self.discard()
            raise
        self.partial = None
        self.done = True

    def _guard(self, call: Callable[[], object]) -> None:
        try:
            call()
        except OSError as exc:
            raise ConfigError(
                f"{self.option} {self.path}: cannot write it: {exc.strerror or exc}; "
                "nothing was written"
            ) from None

    def discard(self) -> None:
        """Remove the temporary file (the output stays as it was); safe to call twice."""
        if self._stream is not None:
            stream, self._stream = self._stream, None
            with contextlib.suppress(OSError):
                stream.close()
        if self.partial is not None:
            with contextlib.suppress(OSError):
                self.partial.unlink()
            self.partial = None


def refuse_inputs(path: Path | str, option: str, inputs: Iterable[Path | str | None]) -> None:
    """`ConfigError` if the output ``path`` is one of the command's ``inputs`` (the same
    file, through any link or spelling): a command never writes over what it reads."""
    out = Path(path)
    for given in inputs:
        if given is None:
            continue
        source = Path(given)
        if out.exists() and source.exists():
            same = os.path.samefile(out, source)
        else:
            same = out.resolve() == source.resolve()
        if same and not _is_device(out):
            raise ConfigError(
                f"{option} {out}: is {source}, an input of this command; give another path"
            )


def _is_device(path: Path) -> bool:
    """Output written in place (``/dev/null``, a pipe), never replaced."""
    try:
        return not stat.S_ISREG(os.stat(path).st_mode)
    except OSError:
        return False


@contextlib.contextmanager
def reserve_output(
    path: Path | str, option: str, *, inputs: Iterable[Path | str | None] = ()
) -> Iterator[PendingOutput]:
    """The output ``path`` (named ``option`` in messages, e.g. ``-o``), reserved now:
    `ConfigError` at once if it cannot be created or is one of ``inputs``; discarded on
    leaving the block unless written."""
    refuse_inputs(path, option, inputs)
    pending = PendingOutput(Path(path), option)
    pending._open()
    try:
        yield pending
    finally:
        pending.discard()


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _fsync_folder(folder: Path) -> None:
    """Make the rename itself durable (where the system allows opening a folder)."""
    with contextlib.suppress(OSError):
        fd = os.open(folder, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)
