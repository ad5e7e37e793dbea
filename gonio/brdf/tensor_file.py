"""The ``tensor_file`` container (Mitsuba's tensor files; the RGL material database's
``.bsdf`` files are one): named n-dimensional arrays in one little-endian file.

Layout (docs/reference/formats.md#rgl): the 12 bytes ``tensor_file\\0``, the version
as two uint8 (1, 0), the field count as uint32; then per field its name length
(uint16), its name (UTF-8), its rank (uint16), its type code (uint8: 1 uint8, 2 int8,
3 uint16, 4 int16, 5 uint32, 6 int32, 7 uint64, 8 int64, 9 float16, 10 float32,
11 float64), the byte offset of its data from the file's start (uint64) and its shape
(rank × uint64); the data of each field, C-ordered (last index fastest), at its
offset. `write` aligns each field's data to 8 bytes, as Mitsuba's writer does.

`read` bounds every size the file states by the file's byte count before allocating
anything, so a truncated or corrupt file is one `GonioError` line naming the file.
"""

from __future__ import annotations

import struct
from collections.abc import Mapping
from pathlib import Path
from typing import BinaryIO

import numpy as np

from gonio.errors import GonioError

MAGIC = b"tensor_file\0"
VERSION = (1, 0)
#: Type code → numpy dtype (little-endian).
DTYPES: dict[int, np.dtype] = {
    code: np.dtype(name).newbyteorder("<")
    for code, name in enumerate(
        ("u1", "i1", "u2", "i2", "u4", "i4", "u8", "i8", "f2", "f4", "f8"), start=1
    )
}
#: Bytes before the first field's header.
PREAMBLE = len(MAGIC) + 2 + 4
#: The smallest field header (empty name, rank 0).
MIN_FIELD_HEADER = 2 + 2 + 1 + 8
#: The highest rank a field may state.
MAX_RANK = 16
ALIGN = 8


def _code(dtype: np.dtype) -> int:
    for code, known in DTYPES.items():
        if known.kind == dtype.kind and known.itemsize == dtype.itemsize:
            return code
    raise GonioError(f"tensor_file: no type code for {dtype}")


def to_bytes(fields: Mapping[str, np.ndarray | bytes | str]) -> bytes:
    """The file of ``fields`` (name → array; a string or bytes is a uint8 array), in
    the given order, each field's data aligned to 8 bytes."""
    arrays = {}
    for name, value in fields.items():
        if isinstance(value, str):
            value = value.encode()
        if isinstance(value, bytes):
            value = np.frombuffer(value, dtype=np.uint8)
        arrays[name] = np.asarray(value, order="C")
    # name length, name, rank, type code, offset, shape
    headers = [2 + len(name.encode()) + 2 + 1 + 8 + 8 * a.ndim for name, a in arrays.items()]
    offset = PREAMBLE + sum(headers)
    parts = [MAGIC, struct.pack("<BBI", *VERSION, len(arrays))]
    data = []
    for name, a in arrays.items():
        offset = -(-offset // ALIGN) * ALIGN
        label = name.encode()
        parts.append(struct.pack("<H", len(label)) + label)
        parts.append(struct.pack("<HBQ", a.ndim, _code(a.dtype), offset))
        parts.append(struct.pack(f"<{a.ndim}Q", *a.shape))
        data.append((offset, a.astype(a.dtype.newbyteorder("<"), copy=False).tobytes()))
        offset += a.nbytes
    out = bytearray(b"".join(parts))
    for start, blob in data:
        out.extend(b"\0" * (start - len(out)))
        out.extend(blob)
    return bytes(out)


class _Cursor:
    """Reads the field headers from ``stream``, never past the file's end."""

    def __init__(self, path: Path, stream: BinaryIO, size: int) -> None:
        self.path, self.stream, self.size = path, stream, size

    def _bytes(self, n: int, what: str) -> bytes:
        at = self.stream.tell()
        raw = self.stream.read(n) if n <= self.size - at else b""
        if len(raw) != n:
            raise GonioError(
                f"{self.path}: not a tensor_file: truncated in {what} at byte {at} "
                f"({self.size} bytes)"
            )
        return raw

    def take(self, fmt: str, what: str) -> tuple[int, ...]:
        return struct.unpack(fmt, self._bytes(struct.calcsize(fmt), what))

    def name(self, length: int, index: int) -> str:
        raw = self._bytes(length, f"field {index}'s name")
        try:
            return raw.decode()
        except UnicodeDecodeError:
            raise GonioError(f"{self.path}: tensor_file field name {raw!r} is not UTF-8") from None


def read(path: str | Path) -> dict[str, np.ndarray]:
    """The fields of the tensor file at ``path`` (name → read-only array); `GonioError`
    (one line naming the file) for anything the layout does not allow."""
    path = Path(path)
    try:
        with open(path, "rb") as stream:
            size = stream.seek(0, 2)
            stream.seek(0)
            return _read(path, stream, size)
    except OSError as exc:
        raise GonioError(f"{path}: cannot read the tensor file: {exc.strerror or exc}") from None


def _read(path: Path, stream: BinaryIO, size: int) -> dict[str, np.ndarray]:
    if size < PREAMBLE:
        raise GonioError(f"{path}: not a tensor_file: {size} bytes, shorter than its header")
    head = stream.read(PREAMBLE)
    if head[: len(MAGIC)] != MAGIC:
        raise GonioError(
            f"{path}: not a tensor_file: the file does not start with 'tensor_file\\0'"
        )
    version = tuple(head[len(MAGIC) : len(MAGIC) + 2])
    if version != VERSION:
        raise GonioError(f"{path}: tensor_file version {version}, expected {VERSION}")
    (count,) = struct.unpack_from("<I", head, len(MAGIC) + 2)
    if count * MIN_FIELD_HEADER > size - PREAMBLE:
        raise GonioError(
            f"{path}: tensor_file states {count} fields, more than its {size} bytes can hold"
        )
    cursor = _Cursor(path, stream, size)
    specs: list[tuple[str, np.dtype, int, tuple[int, ...]]] = []
    for index in range(count):
        (length,) = cursor.take("<H", f"field {index}'s name length")
        name = cursor.name(length, index)
        rank, code, offset = cursor.take("<HBQ", f"field {name!r}'s header")
        if code not in DTYPES:
            raise GonioError(f"{path}: tensor_file field {name!r}: unknown type code {code}")
        if rank > MAX_RANK:
            raise GonioError(f"{path}: tensor_file field {name!r}: rank {rank} > {MAX_RANK}")
        shape = cursor.take(f"<{rank}Q", f"field {name!r}'s shape")
        nbytes = DTYPES[code].itemsize
        for n in shape:  # Python integers: no overflow
            nbytes *= n
        if offset > size or nbytes > size - offset:
            raise GonioError(
                f"{path}: tensor_file field {name!r} of shape {list(shape)} at byte {offset} "
                f"({nbytes} bytes) runs past the end of the file ({size} bytes; truncated?)"
            )
        if any(n > size for n in shape):  # beside a 0 (no bytes): no array of such a side
            raise GonioError(
                f"{path}: tensor_file field {name!r} of shape {list(shape)}: a side longer "
                f"than the file's {size} bytes"
            )
        if name in (s[0] for s in specs):
            raise GonioError(f"{path}: tensor_file field {name!r} appears twice")
        specs.append((name, DTYPES[code], offset, shape))
    fields = {}
    for name, dtype, offset, shape in specs:
        stream.seek(offset)
        count_values = int(np.prod(shape, dtype=np.int64)) if shape else 1
        raw = stream.read(count_values * dtype.itemsize)
        fields[name] = np.frombuffer(raw, dtype=dtype, count=count_values).reshape(shape)
    return fields
