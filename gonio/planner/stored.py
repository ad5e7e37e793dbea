"""The stored plan: one UTF-8 text file that reads back as the same `Plan`, bit for bit
(`write_plan`, `read_plan`; the plan file a user writes is `gonio.planner.files`'s).
Reading one builds nothing: a run's reader loads neither the builder nor its samplers.

A stored plan is a header of ``# KEY: JSON`` lines, then the targets as CSV
(docs/reference/planner.md)::

    # gonio-plan v1
    # spec: {...}          the validated PlanSpec, every field (JSON)
    # plan_text: "..."     the plan file's text (a JSON string)
    # rig: "arch-4axis"    the rig's name
    # rig_text: "..."      the rig file's text (a JSON string)
    # alignment_text: "…"  the alignment file's text the rig file names (only then)
    # summary: {...}       the `Summary` (JSON)
    # sweeps: {...}        a fly plan's segments (`Sweeps`, JSON; only in a fly plan)
    # hashes: {"plan_sha256": …, "rig_sha256": …, "content": …, "file_sha256": …}
    index,generated,hbar,k,…
    0,1234,0.51…,…

Floats are written with ``repr`` (the shortest text that reads back as the same
double), in the CSV and in the JSON. ``content`` is `content_hash` of the two texts;
``file_sha256`` covers every byte of the file but the hashes line itself, so an edited
or truncated file is refused. The file is written to a temporary name beside it, flushed
to the disk and renamed (`gonio.output`), so a crash never leaves half a plan under the
real name.
"""

from __future__ import annotations

import csv
import dataclasses
import io
import json
import math
from pathlib import Path
from typing import Any

import numpy as np
from pydantic import TypeAdapter, ValidationError

from gonio.config import ConfigError, describe
from gonio.output import reserve_output
from gonio.planner.model import (
    Plan,
    Summary,
    content_hash,
    sha256,
)
from gonio.planner.schema import PlanSpec
from gonio.planner.sweeps_header import parse_sweeps, sweeps_header
from gonio.rig import Rig

#: The first line of every stored plan; the version names this layout.
MAGIC = "# gonio-plan v1"
#: The header's keys, in the order they are written.
KEYS = ("spec", "plan_text", "rig", "rig_text", "alignment_text", "summary", "sweeps", "hashes")
#: Header keys a stored plan may leave out (a stop-and-go plan has no sweeps).
OPTIONAL = frozenset({"sweeps", "alignment_text"})
HASHES = ("plan_sha256", "rig_sha256", "content", "file_sha256")
#: Integer columns (every other column is a float64 written with repr).
INTEGER = frozenset({"index", "generated", "averages"})
#: Targets turned into text at a time (the cells of a block as strings, not the plan's).
ROWS = 4096

_SUMMARY = TypeAdapter(Summary)
#: Wall times that older stored plans kept in their summary (figures of the machine and
#: its load; a stored plan is now the same bytes on any machine): read and dropped.
WALL_TIMES = frozenset({"ordering_s", "bound_wall_s"})


def columns(coordinate_names: tuple[str, ...], axes: tuple[str, ...]) -> list[str]:
    """The CSV columns of a plan with these coordinates on a rig with these axes."""
    return [
        "index", "generated", *coordinate_names,
        "wi_x", "wi_y", "wi_z", "wo_x", "wo_y", "wo_z",
        *(f"{a}_rad" for a in axes),
        "exposure_s", "averages", "travel_s", "arrival_s",
    ]  # fmt: skip


def _table(plan: Plan) -> list[np.ndarray]:
    """The columns' values, one 1-d array per column."""
    n = len(plan)
    return [
        np.arange(n, dtype=np.int64),
        plan.generated,
        *plan.coords.T,
        *plan.wi.T,
        *plan.wo.T,
        *plan.angles.T,
        plan.exposure_s,
        plan.averages,
        plan.travel_s,
        plan.arrival_s,
    ]


def _json(value: Any) -> str:
    return json.dumps(value, ensure_ascii=False, allow_nan=False)


def plan_bytes(plan: Plan) -> bytes:
    """``plan`` in the stored format (module docstring), as the file's bytes."""
    names = columns(plan.coordinate_names, plan.rig.axes)
    table = _table(plan)
    body = io.StringIO()
    out = csv.writer(body, lineterminator="\n")
    out.writerow(names)
    parts = []
    for lo in range(0, len(plan), ROWS):  # a block of rows at a time: the text of a block
        cells = [
            [(str if name in INTEGER else repr)(v) for v in c[lo : lo + ROWS].tolist()]
            for name, c in zip(names, table, strict=True)
        ]
        out.writerows(zip(*cells, strict=True))
        parts.append(body.getvalue().encode("utf-8"))
        body.seek(0)
        body.truncate()
    targets = b"".join([*parts, body.getvalue().encode("utf-8")])
    s = plan.summary
    summary = {
        **{f.name: getattr(s, f.name) for f in dataclasses.fields(s)},
        "refused": dict(s.refused),
        "grid_shape": None if s.grid_shape is None else list(s.grid_shape),
    }
    if s.fly is None:
        del summary["fly"]  # a stop-and-go plan's bytes as before fly plans existed
    else:
        summary["fly"] = dataclasses.asdict(s.fly)
    if s.timing == "rig" and s.bus_s == 0.0:
        del summary["bus_s"], summary["timing"]  # bytes as before the bus was counted
    header = {
        "spec": plan.spec.model_dump(mode="json"),
        "plan_text": plan.plan_text.decode("utf-8"),
        "rig": plan.rig.spec.name,
        "rig_text": plan.rig.text.decode("utf-8"),
        "summary": summary,
    }
    if plan.rig.alignment_text is not None:
        header["alignment_text"] = plan.rig.alignment_text.decode("utf-8")
    if plan.sweeps is not None:
        header["sweeps"] = sweeps_header(plan.sweeps)
    lines = [MAGIC, *(f"# {key}: {_json(header[key])}" for key in KEYS[:-1] if key in header)]
    before = ("\n".join(lines) + "\n").encode("utf-8")
    hashes = {
        "plan_sha256": sha256(plan.plan_text),
        "rig_sha256": sha256(plan.rig.text),
        "content": plan.content_hash(),
        "file_sha256": sha256(before + targets),
    }
    return before + f"# hashes: {_json(hashes)}\n".encode() + targets


def write_plan(plan: Plan, path: str | Path) -> None:
    """Write ``plan`` to ``path`` in the stored format (module docstring), atomically: a
    temporary file beside it, flushed to the disk, then renamed (`gonio.output`)."""
    with reserve_output(path, "plan file") as out:
        out.write_bytes(plan_bytes(plan))


def _refuse_constant(name: str) -> float:
    raise ValueError(f"{name} is not a finite number")


def _header(path: Path, raw: bytes) -> tuple[dict[str, Any], dict[str, int], int, bytes]:
    """(header values, the line of each key, the byte offset where the CSV starts, the
    file's bytes without the hashes line)."""
    first, _, _ = raw.partition(b"\n")
    if first.rstrip(b"\r") != MAGIC.encode():
        if first.startswith(b"# gonio-plan "):
            got = first.decode("utf-8", "replace").removeprefix("# gonio-plan ").strip()
            raise ConfigError(
                f"{path}:1: format version {got!r}; this gonio reads {MAGIC[2:]!r} only"
            )
        raise ConfigError(f"{path}:1: not a stored gonio plan: expected {MAGIC!r} on line 1")
    values: dict[str, Any] = {}
    lines: dict[str, int] = {}
    offset, number = len(first) + 1, 1
    hashed = raw
    while raw.startswith(b"#", offset):
        end = raw.find(b"\n", offset)
        end = len(raw) if end < 0 else end
        number += 1
        line = raw[offset:end].decode("utf-8")
        if line.startswith("# hashes:"):
            hashed = raw[:offset] + raw[end + 1 :]
        offset = end + 1
        key, sep, value = line.removeprefix("#").strip().partition(":")
        if not sep or key not in KEYS:
            raise ConfigError(
                f"{path}:{number}: expected a header line '# KEY: JSON' with KEY one of "
                f"{', '.join(KEYS)}; got {line[:60]!r}"
            )
        if key in values:
            raise ConfigError(f"{path}:{number}: {key}: given twice in the header")
        try:
            values[key] = json.loads(value, parse_constant=_refuse_constant)
        except ValueError as exc:
            raise ConfigError(f"{path}:{number}: {key}: not valid JSON: {exc}") from None
        lines[key] = number
    missing = [k for k in KEYS if k not in values and k not in OPTIONAL]
    if missing:
        raise ConfigError(f"{path}: header: expected a '# {missing[0]}: …' line before the CSV")
    return values, lines, offset, hashed


def _texts(
    path: Path, header: dict[str, Any], line: dict[str, int]
) -> tuple[bytes, bytes, bytes | None]:
    """The plan, rig and alignment (None: the rig names none) texts, checked against
    their hashes."""
    hashes = header["hashes"]
    if not isinstance(hashes, dict) or sorted(hashes) != sorted(HASHES):
        raise ConfigError(f"{path}:{line['hashes']}: hashes: expected exactly {', '.join(HASHES)}")
    texts = []
    for key, digest in (("plan_text", "plan_sha256"), ("rig_text", "rig_sha256")):
        if not isinstance(header[key], str):
            raise ConfigError(f"{path}:{line[key]}: {key}: expected the file's text as a string")
        text = header[key].encode("utf-8")
        if sha256(text) != hashes[digest]:
            raise ConfigError(
                f"{path}:{line[key]}: {key}: does not match hashes.{digest}; the file was changed"
            )
        texts.append(text)
    aligned = header.get("alignment_text")
    if aligned is not None and not isinstance(aligned, str):
        raise ConfigError(
            f"{path}:{line['alignment_text']}: alignment_text: expected the file's text as a string"
        )
    alignment = None if aligned is None else aligned.encode("utf-8")
    if content_hash(texts[0], texts[1], None, alignment) != hashes["content"]:
        raise ConfigError(f"{path}:{line['hashes']}: hashes.content: does not match the texts")
    return texts[0], texts[1], alignment


def _rig(
    path: Path, given: Rig | str | Path | None, text: bytes, aligned: bytes | None, line: int
) -> Rig:
    """The rig the plan was built for: rebuilt from its stored texts (the rig file's and
    its alignment file's), or the one given after checking that its files' bytes are
    those the plan was built from."""
    if given is None:
        return Rig.from_yaml(Path(f"{path}#rig_text"), text, aligned)
    rig = given if isinstance(given, Rig) else Rig.from_yaml(given)
    if rig.text != text:
        built_for = Rig.from_yaml(Path(f"{path}#rig_text"), text, aligned).spec.name
        raise ConfigError(
            f"{path}:{line}: rig: the plan was built for rig {built_for!r} (sha256 "
            f"{sha256(text)[:12]}…); the rig given, {rig.spec.name!r}, hashes "
            f"{sha256(rig.text)[:12]}…: not the same rig file"
        )
    if rig.alignment_text != aligned:
        raise ConfigError(
            f"{path}:{line}: rig: the plan was built with another alignment file than the "
            f"given rig's ({rig.alignment_path or 'none'}): plan it again"
        )
    return rig


def _summary(path: Path, data: Any, line: int) -> Summary:
    fields = {f.name for f in dataclasses.fields(Summary)}
    if isinstance(data, dict) and "second_pass" not in data:
        data = {**data, "second_pass": None}  # stored before the field existed
    if isinstance(data, dict) and "fly" not in data:
        data = {**data, "fly": None}  # a stop-and-go plan
    if isinstance(data, dict) and "timing" not in data and "bus_s" not in data:
        data = {**data, "bus_s": 0.0, "timing": "rig"}  # the rig file's rates, no bus
    if isinstance(data, dict) and WALL_TIMES & set(data):  # stored before they left it
        data = {k: v for k, v in data.items() if k not in WALL_TIMES}
    if not isinstance(data, dict) or set(data) != fields:
        got = set(data) if isinstance(data, dict) else set()
        detail = ", ".join(sorted(fields ^ got)) or type(data).__name__
        raise ConfigError(f"{path}:{line}: summary: expected the Summary's fields ({detail})")
    try:
        summary = _SUMMARY.validate_python(data, strict=False)
    except ValidationError as exc:
        raise ConfigError(
            f"{path}:{line}: summary.{describe(exc.errors(include_url=False)[0])}"
        ) from None
    return summary


def _rows(path: Path, text: str, names: list[str], first_line: int) -> list[np.ndarray]:
    """The CSV's columns as arrays (int64 or float64), every value checked."""
    reader = csv.reader(io.StringIO(text))
    got = next(reader, None)
    if got != names:
        got = got or []
        missing = [n for n in names if n not in got]
        what = (
            f"missing column {missing[0]!r}"
            if missing
            else f"unexpected columns or order {[n for n in got if n not in names] or got}"
        )
        raise ConfigError(f"{path}:{first_line}: columns: {what}; expected {','.join(names)}")
    rows = list(reader)
    for i, row in enumerate(rows):
        if len(row) != len(names):
            raise ConfigError(
                f"{path}:{first_line + 1 + i}: expected {len(names)} fields, got {len(row)}"
            )
    out = []
    for j, name in enumerate(names):
        cells = [row[j] for row in rows]
        kind = int if name in INTEGER else float
        try:
            values = [kind(c) for c in cells]
        except ValueError:
            i = next(i for i, c in enumerate(cells) if not _parses(kind, c))
            raise ConfigError(
                f"{path}:{first_line + 1 + i}: {name}: expected "
                f"{'an integer' if kind is int else 'a number'}, got {cells[i]!r}"
            ) from None
        if kind is float and not all(map(math.isfinite, values)):
            i = next(i for i, v in enumerate(values) if not math.isfinite(v))
            raise ConfigError(
                f"{path}:{first_line + 1 + i}: {name}: expected a finite number, got {cells[i]!r}"
            )
        out.append(np.array(values, dtype=np.int64 if kind is int else np.float64))
    return out


def _parses(kind: type, cell: str) -> bool:
    try:
        kind(cell)
    except ValueError:
        return False
    return True


def read_plan(path: str | Path, rig: Rig | str | Path | None = None) -> Plan:
    """The plan stored at ``path`` (by `write_plan`), identical to the one written.

    ``rig``: the rig (or its file) to attach; its file's bytes must be those the plan
    was built from (checked by hash). Without it the rig is rebuilt from the text the
    plan file carries. Any problem (not a stored plan, another format version, a header
    line missing, a text or the targets not matching their hash, a missing column, a
    value that is not a finite number, a different rig) raises `ConfigError` with one
    line naming the file. ``ordering`` (the search's diagnostics) is not stored: None.
    """
    path = Path(path)
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise ConfigError(f"{path}: cannot read the plan: {exc.strerror or exc}") from None
    return parse_plan(raw, path, rig)


def parse_plan(raw: bytes, path: str | Path, rig: Rig | str | Path | None = None) -> Plan:
    """The plan stored in ``raw`` (the bytes of a stored plan; ``path`` names them in
    messages): `read_plan` without reading a file."""
    path = Path(path)
    try:
        header, line, offset, hashed = _header(path, raw)
        body = raw[offset:].decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ConfigError(f"{path}: not UTF-8 text: {exc.reason}") from None
    plan_text, rig_text, aligned = _texts(path, header, line)
    if sha256(hashed) != header["hashes"]["file_sha256"]:
        raise ConfigError(
            f"{path}: the file does not match hashes.file_sha256: it was changed or cut short"
        )
    try:
        spec = PlanSpec.model_validate(header["spec"])
    except ValidationError as exc:
        first = exc.errors(include_url=False)[0]
        raise ConfigError(f"{path}:{line['spec']}: spec.{describe(first)}") from None
    plan_rig = _rig(path, rig, rig_text, aligned, line["rig"])
    summary = _summary(path, header["summary"], line["summary"])
    names = spec.coordinates()
    table = _rows(path, body, columns(names, plan_rig.axes), len(line) + 2)
    n = len(table[0])
    if n != summary.kept:
        raise ConfigError(f"{path}: expected {summary.kept} targets (summary.kept), got {n}")
    if not np.array_equal(table[0], np.arange(n)):
        raise ConfigError(f"{path}: index: expected 0, 1, 2, … in order")
    cols = iter(table[1:])

    def take(k: int) -> np.ndarray:
        return np.stack([next(cols) for _ in range(k)], axis=1)

    generated = next(cols)
    coords, wi, wo, angles = take(len(names)), take(3), take(3), take(len(plan_rig.axes))
    exposure_s, averages, travel_s, arrival_s = cols
    sweeps = None
    if "sweeps" in header:
        sweeps = parse_sweeps(path, header["sweeps"], line["sweeps"], len(plan_rig.axes), n)
    if (sweeps is None) != (spec.sampling.strategy != "fly"):
        raise ConfigError(f"{path}: sweeps: a fly plan stores its sweeps, a stop-and-go plan none")
    return Plan(
        spec=spec,
        rig=plan_rig,
        coordinate_names=names,
        coords=coords,
        generated=generated,
        wi=wi,
        wo=wo,
        angles=angles,
        exposure_s=exposure_s,
        averages=averages,
        travel_s=travel_s,
        arrival_s=arrival_s,
        summary=summary,
        plan_text=plan_text,
        sweeps=sweeps,
    )
