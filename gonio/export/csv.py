"""``--format csv``: one row per sample, one column per `gonio.export.columns` column,
the header row naming each with its unit suffix (docs/reference/formats.md#csv).

Floats are written with 17 significant digits (read back bit for bit); a value the
run does not have (NaN: a spread the device did not give) is an empty cell; booleans
are 0/1. UTF-8, comma-separated, ``\\n`` line ends, no comment lines (any CSV reader
takes it as is).
"""

from __future__ import annotations

import csv
import io
from typing import TYPE_CHECKING

import numpy as np

from gonio.export.columns import Column, sample_columns
from gonio.export.steps import step
from gonio.output import PendingOutput
from gonio.store import Run

if TYPE_CHECKING:
    from gonio.export import Options


def cells(column: Column) -> list[str]:
    """The column's values as CSV cells (see the module docstring)."""
    values = column.values
    if values.dtype == np.bool_:
        return ["1" if v else "0" for v in values.tolist()]
    if values.dtype.kind == "f":
        return ["" if np.isnan(v) else repr(v) for v in values.tolist()]
    return [str(v) for v in values.tolist()]


def to_text(columns: list[Column]) -> str:
    """The CSV text of ``columns``: a header row of keys, then one row per sample."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow([c.key for c in columns])
    writer.writerows(zip(*(cells(c) for c in columns), strict=True))
    return buffer.getvalue()


def export_run(run: Run, out: PendingOutput, options: Options) -> str:
    with step(f"writing {len(run):,} samples"):
        columns = sample_columns(run)
        out.write_bytes(to_text(columns).encode())
    return f"wrote {len(run)} samples × {len(columns)} columns to {out.path} (csv)"
