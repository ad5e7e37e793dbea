"""A fly plan's segments in a stored plan's header (`gonio.planner.stored`): written as
JSON (`sweeps_header`) and read back with every field checked (`parse_sweeps`). The
path fields (each segment's set-points) are written only when a segment has them, so a
plan of axis sweeps keeps the bytes it had before path segments existed.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from gonio.config import ConfigError
from gonio.planner.model import PATH_ARRAYS, SWEEP_ARRAYS, Sweeps


def sweeps_header(w: Sweeps) -> dict[str, Any]:
    """The header's JSON of the segments ``w``."""
    out: dict[str, Any] = {
        **{name: getattr(w, name).tolist() for name in SWEEP_ARRAYS},
        "period_s": w.period_s,
        "integration_s": w.integration_s,
    }
    if w.has_paths:
        out |= {
            **{name: getattr(w, name).tolist() for name in PATH_ARRAYS},
            "path": w.path.tolist(),
            "path_period_s": w.path_period_s,
        }
    return out


def _positive(path: Path, line: int, name: str, x: Any) -> float:
    """``x`` as a positive finite number, else `ConfigError` naming ``sweeps.name``."""
    if not isinstance(x, float | int) or isinstance(x, bool) or not 0 < x < math.inf:
        raise ConfigError(f"{path}:{line}: sweeps.{name}: expected a positive number")
    return float(x)


def parse_sweeps(path: Path, data: Any, line: int, axes: int, targets: int) -> Sweeps:
    """A fly plan's segments from the header's JSON (line ``line`` of ``path``), every
    field checked: `ConfigError` naming the field."""
    fields = [*SWEEP_ARRAYS, "period_s", "integration_s"]
    if isinstance(data, dict) and "streamed" not in data and "count" in data:
        data = {**data, "streamed": data["count"]}  # written before the thinning
    paths = [*PATH_ARRAYS, "path", "path_period_s"]
    if isinstance(data, dict) and "path" in data:
        fields += paths
    if not isinstance(data, dict) or sorted(data) != sorted(fields):
        raise ConfigError(f"{path}:{line}: sweeps: expected exactly {', '.join(fields)}")
    arrays: dict[str, Any] = {}
    for name, dtype in {**SWEEP_ARRAYS, **(PATH_ARRAYS if "path" in data else {})}.items():
        try:
            value = np.array(data[name], dtype=dtype)
        except (TypeError, ValueError, OverflowError):
            raise ConfigError(f"{path}:{line}: sweeps.{name}: expected numbers") from None
        rows = ("first", "count", "cruise_at_s", "streamed", *PATH_ARRAYS)
        shape = (len(data["first"]),) if name in rows else None
        wanted = shape or (len(data["first"]), axes)
        if value.shape != wanted or (
            dtype is np.int64
            and not all(isinstance(x, int) and not isinstance(x, bool) for x in data[name])
        ):
            raise ConfigError(
                f"{path}:{line}: sweeps.{name}: expected {'×'.join(map(str, wanted))} "
                f"{'integers' if dtype is np.int64 else 'numbers'}"
            )
        if dtype is np.float64 and not np.all(np.isfinite(value)):
            raise ConfigError(f"{path}:{line}: sweeps.{name}: expected finite numbers")
        arrays[name] = value
    for name in ("period_s", "integration_s"):
        _positive(path, line, name, data[name])
    count, first = arrays["count"], arrays["first"]
    expected = np.concatenate([[0], np.cumsum(count)[:-1]])
    if (
        np.any(count < 1)
        or np.any(arrays["streamed"] < count)
        or not np.array_equal(first, expected)
        or count.sum() > targets
    ):
        raise ConfigError(
            f"{path}:{line}: sweeps: first and count must split the first of the {targets} "
            "targets into consecutive segments"
        )
    extra: dict[str, Any] = {}
    if "path" in data:
        extra = _path_fields(path, data, line, axes, arrays)
    return Sweeps(
        **arrays,
        period_s=float(data["period_s"]),
        integration_s=float(data["integration_s"]),
        **extra,
    )


def _path_fields(
    path: Path, data: dict[str, Any], line: int, axes: int, arrays: dict[str, np.ndarray]
) -> dict[str, Any]:
    """The path segments' set-points of a fly plan's header, every field checked."""
    try:
        points = np.array(data["path"], dtype=np.float64)
    except (TypeError, ValueError, OverflowError):
        raise ConfigError(f"{path}:{line}: sweeps.path: expected numbers") from None
    if points.ndim != 2 or points.shape[1:] != (axes,) or not np.all(np.isfinite(points)):
        raise ConfigError(f"{path}:{line}: sweeps.path: expected rows of {axes} finite numbers")
    first, count = arrays["path_first"], arrays["path_count"]
    if (
        np.any(count < 0)
        or np.any(first < 0)
        or np.any(first + count > len(points))
        or (np.any((count > 0) & (count < 2)))
    ):
        raise ConfigError(
            f"{path}:{line}: sweeps.path_first, path_count: expected runs of at least 2 "
            f"set-points inside the {len(points)} of sweeps.path"
        )
    return {
        "path": points,
        "path_period_s": _positive(path, line, "path_period_s", data["path_period_s"]),
    }
