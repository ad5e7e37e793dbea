"""Read-side checks of a run file's contents (docs/reference/damaged-files.md):
every value `gonio.store.open_run` hands on is of the type, and in the range, the writer
gives it, or the run is refused with one line naming the file and the field.

SQLite's own checks catch a damaged structure (a truncated file, a page of garbage:
"database disk image is malformed"); these catch what a damaged or edited page can
still say: a JSON text that does not parse or parses to another shape, a number where a
text belongs, a sample of a target the plan does not have, a missing column. Each
checker takes the value and ``where`` (the field, as the message names it) and returns
the value as the readers use it, or raises `Bad`.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Mapping
from typing import Any

from gonio.config import excerpt


class Bad(ValueError):
    """A stored value that is not what the writer stores: ``str`` is "FIELD: expected
    …, got …" (the caller prefixes the file)."""


Check = Callable[[Any, str], Any]


def _refuse(constant: str) -> Any:
    raise ValueError(f"{constant} is not JSON")


def json_value(text: Any, where: str) -> Any:
    """The JSON value of a stored text (strict JSON: no NaN or Infinity)."""
    if isinstance(text, bytes):
        try:
            text = text.decode("utf-8")
        except UnicodeDecodeError:
            raise Bad(f"{where}: expected JSON text, got bytes that are not UTF-8") from None
    if not isinstance(text, str):
        raise Bad(f"{where}: expected JSON text, got {excerpt(text)}")
    try:
        return json.loads(text, parse_constant=_refuse)
    except (ValueError, RecursionError):
        raise Bad(f"{where}: expected JSON text, got {excerpt(text)}") from None


def number(value: Any, where: str) -> float:
    """A finite number (not a bool)."""
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise Bad(f"{where}: expected a finite number, got {excerpt(value)}")
    return float(value)


def positive(value: Any, where: str) -> float:
    if number(value, where) <= 0.0:
        raise Bad(f"{where}: expected a positive number, got {excerpt(value)}")
    return float(value)


def integer(value: Any, where: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise Bad(f"{where}: expected a whole number, got {excerpt(value)}")
    return value


def text(value: Any, where: str) -> str:
    if not isinstance(value, str):
        raise Bad(f"{where}: expected a text, got {excerpt(value)}")
    return value


def boolean(value: Any, where: str) -> bool:
    if not isinstance(value, bool):
        raise Bad(f"{where}: expected true or false, got {excerpt(value)}")
    return value


def mapping(value: Any, where: str) -> dict[str, Any]:
    if not isinstance(value, dict):
        raise Bad(f"{where}: expected a JSON object, got {excerpt(value)}")
    return value


def _list(value: Any, where: str) -> list[Any]:
    if not isinstance(value, list):
        raise Bad(f"{where}: expected a list, got {excerpt(value)}")
    return value


def names(value: Any, where: str) -> list[str]:
    """A list of distinct non-empty texts (a rig's axes, a plan's coordinates)."""
    if not isinstance(value, list) or not all(isinstance(v, str) and v for v in value):
        raise Bad(f"{where}: expected a list of names, got {excerpt(value)}")
    if len(set(value)) != len(value):
        raise Bad(f"{where}: expected distinct names, got {excerpt(value)}")
    return value


def optional(check: Check) -> Check:
    """``check``, or None."""

    def checked(value: Any, where: str) -> Any:
        return None if value is None else check(value, where)

    return checked


def vector(length: int) -> Check:
    """A list of ``length`` finite numbers."""

    def checked(value: Any, where: str) -> list[float]:
        if not isinstance(value, list) or len(value) != length:
            raise Bad(f"{where}: expected a list of {length} numbers, got {excerpt(value)}")
        return [number(v, f"{where}.{i}") for i, v in enumerate(value)]

    return checked


#: How far a stored direction's length may be from 1 (the writer's are within 1e-15).
UNIT_TOLERANCE = 1e-9


def unit_vector(value: Any, where: str) -> list[float]:
    """A direction: three finite numbers of length 1."""
    x, y, z = vector(3)(value, where)
    if abs(x * x + y * y + z * z - 1.0) > UNIT_TOLERANCE:
        raise Bad(f"{where}: expected a unit vector, got {excerpt(value)}")
    return [x, y, z]


def fields(required: Mapping[str, Check], optional_: Mapping[str, Check] | None = None) -> Check:
    """A JSON object with the ``required`` keys and maybe the ``optional_`` ones, each
    checked (other keys are left as they are: a newer writer of the same version may add
    some)."""

    def checked(value: Any, where: str) -> dict[str, Any]:
        data = mapping(value, where)
        for key, check in required.items():
            if key not in data:
                raise Bad(f"{where}.{key}: missing")
            check(data[key], f"{where}.{key}")
        for key, check in (optional_ or {}).items():
            if key in data:
                check(data[key], f"{where}.{key}")
        return data

    return checked


#: The ``meta`` keys every journal holds (`gonio.store.Journal.create` needs them).
META_REQUIRED: dict[str, Check] = {
    "axes": names,
    "coordinate_names": names,
    "schema_version": integer,
}
#: The keys a run started by `gonio acquire` holds (`gonio.workflows.session`), which the
#: commands read: all of them, or (a journal written by other code) none.
META_SESSION: dict[str, Check] = {
    "backend": text,
    "created_utc": text,
    "started_unix": number,
    "rig_text": text,
    "hashes": mapping,
}
META_OPTIONAL: dict[str, Check] = {
    "plan_name": optional(text),
    "rig_name": optional(text),
    "seed": optional(integer),
    "host": optional(text),
    "user": optional(text),
    "versions": optional(mapping),
    "plan_path": optional(text),
    "rig_path": optional(text),
    "scene_path": optional(text),
    "plan_text": optional(text),
    "scene_text": optional(text),
    "speedup": optional(positive),
    "any_detector": optional(boolean),
    "alignment_path": optional(text),
    "alignment_text": optional(text),
    "alignment_sha256": optional(text),
}
#: The backends a run may name.
BACKENDS = ("simulated", "hardware", "rehearsal")


def check_meta(meta: dict[str, Any]) -> None:
    """`Bad` unless the decoded ``meta`` holds what the readers use, as the writer
    stores it. (A stored text edited but well-formed is read: a resume refuses it,
    `gonio.workflows.session.check_stored_texts`.)"""
    session = any(key in meta for key in META_SESSION)
    required = {**META_REQUIRED, **(META_SESSION if session else {})}
    fields(required, {**META_OPTIONAL, **META_SESSION})(meta, "meta")
    if "backend" in meta and meta["backend"] not in BACKENDS:
        raise Bad(
            f"meta.backend: expected one of {', '.join(BACKENDS)}, got {excerpt(meta['backend'])}"
        )
    hashes = meta.get("hashes", {})
    for key, value in hashes.items():
        optional(text)(value, f"meta.hashes.{key}")


#: A journaled reading (a calibration's reference or dark).
READING = fields(
    {
        "value": number,
        "n": integer,
        "exposure_s": positive,
        "started_s": number,
        "ended_s": number,
    },
    {"std": optional(number), "phase_deg": optional(number)},
)
#: The payloads of the events the read commands use, by kind.
EVENT_DATA: dict[str, Check] = {
    "calibration": fields(
        {
            "albedo": positive,
            "source_kind": text,
            "wi": unit_vector,
            "wo": unit_vector,
            "reference": READING,
            "dark": optional(READING),
        },
        {"unit": text, "dark_reason": optional(text)},
    ),
    "fault": fields({"message": text}),
    # a motor's recovery step (`gonio.acquire.recovery`; `gonio info` formats these)
    "recovery": fields(
        {"axis": text, "step": text},
        {
            "flags": lambda value, where: [text(v, where) for v in _list(value, where)],
            "temperature_c": optional(number),
            "load_pct": optional(number),
            "waited_s": optional(number),
            "deviation_deg": optional(number),
        },
    ),
    "skip": fields({}, {"reason": text}),
}


def event_data(kind: str, raw: Any, where: str) -> dict[str, Any]:
    """The payload of an event of ``kind`` (a JSON object; checked further for the kinds
    the read commands use)."""
    data = mapping(json_value(raw, where), where)
    check = EVENT_DATA.get(kind)
    if check is not None:
        check(data, where)
    return data
