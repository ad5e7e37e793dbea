"""Dataset export: a run written in another program's format (docs/reference/formats.md).

``export(run_path, name, out_path, options)`` reads the run, writes the format ``name``
to ``out_path`` atomically (`gonio.output`) and returns a one-line summary. Each format
is one module with ``export_run(run, out, options) -> str``, imported only when used
(h5py and event-model are optional extras).
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from pathlib import Path

from gonio.errors import UnknownNameError
from gonio.output import reserve_output
from gonio.store import open_run

#: name → (module, what it writes).
FORMATS: dict[str, tuple[str, str]] = {
    "csv": ("gonio.export.csv", "one row per sample, units in the column names"),
    "hdf5": ("gonio.export.hdf5", "samples, events, metadata and plan (needs h5py)"),
    "merl": ("gonio.export.merl", "the reconstruction tabulated in MERL's binary layout"),
    "rgl": (
        "gonio.export.rgl",
        "the reconstruction as an RGL material (Dupuy & Jakob 2018; Mitsuba 3's measured "
        "plugin), spectral or RGB",
    ),
    "factored": (
        "gonio.export.factored",
        "the reconstruction factored (Lawrence et al. 2004) with its sampling CDFs (needs "
        "scikit-learn)",
    ),
    "alta": ("gonio.export.alta", "ALTA's text data format with confidence intervals"),
    "bluesky": ("gonio.export.bluesky", "event-model documents, JSON lines (needs event-model)"),
}

#: ALTA input parametrizations `gonio.export.alta` writes.
ALTA_PARAMS = ("stark_3d", "rusin_th_td_pd")
#: The RGL export's colour: a spectrum, or RGB.
RGL_COLORS = ("spectral", "rgb")
#: What the MERL export writes in bins outside the measured support.
MERL_FILLS = ("missing", "extrapolate")


@dataclass(frozen=True)
class Options:
    """Format options: ALTA's input parametrization; MERL's bins outside the measured
    support (written missing, or the reconstruction's extrapolation); the HDF5 file's
    reconstruction grid (a parametrization name, and points per coordinate); the
    factored format's outer and inner terms; the RGL file's colour (a spectrum, or RGB);
    the reconstruction method of the formats that tabulate one
    (`gonio.reconstruct.methods`)."""

    alta_param: str = "stark_3d"
    merl_fill: str = "missing"
    grid: str | None = None
    grid_points: int = 32
    outer: int = 2
    inner: int = 2
    rgl_color: str = "spectral"
    method: str = "linear"


def names() -> list[str]:
    """The format names."""
    return list(FORMATS)


def export(
    run_path: str | Path, name: str, out_path: str | Path, options: Options | None = None
) -> str:
    """Write the run at ``run_path`` as ``name`` to ``out_path``; the output is reserved
    first (a bad ``-o`` fails before any work) and written whole or not at all."""
    if name not in FORMATS:
        raise UnknownNameError(
            f"unknown export format {name!r}; expected one of {', '.join(FORMATS)}"
        )
    module = importlib.import_module(FORMATS[name][0])
    with reserve_output(out_path, "-o", inputs=[run_path]) as out:
        run = open_run(run_path)
        summary: str = module.export_run(run, out, options or Options())
    return summary


__all__ = ["ALTA_PARAMS", "FORMATS", "MERL_FILLS", "RGL_COLORS", "Options", "export", "names"]
