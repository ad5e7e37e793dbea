"""Dataset export: a run written in another program's format (docs/reference/formats.md).

``export(run_path, name, out_path, options)`` reads the run, writes the format ``name``
to ``out_path`` atomically (`gonio.output`) and returns a one-line summary. Each format
is one module with ``export_run(run, out, options) -> str``, imported only when used
(h5py and event-model are optional extras).
"""

from __future__ import annotations

import importlib
import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from gonio import params
from gonio.analysis import realigned
from gonio.errors import GonioError, UnknownNameError
from gonio.faces import lazy_face
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

#: The format an output file's suffix (lower case) says, where ``--format`` is not given.
SUFFIXES: dict[str, str] = {
    ".csv": "csv",
    ".h5": "hdf5",
    ".hdf5": "hdf5",
    ".binary": "merl",
    ".bsdf": "rgl",
    ".factored": "factored",
    ".alta": "alta",
    ".jsonl": "bluesky",
}


def format_of(output: str | Path, given: str | None) -> str:
    """The export format: ``given`` in any case, else the one ``output``'s suffix says
    (`SUFFIXES`); `UnknownNameError` (one line) when neither names one."""
    if given is not None:
        name = given.lower()
        if name not in FORMATS:
            raise UnknownNameError(
                f"--format {given}: unknown export format; expected one of {', '.join(FORMATS)}"
            )
        return name
    suffix = Path(output).suffix.lower()
    if suffix not in SUFFIXES:
        known = ", ".join(f"{k} ({v})" for k, v in SUFFIXES.items())
        raise UnknownNameError(
            f"-o {output}: the suffix {suffix or '(none)'!r} names no format; give --format "
            f"({', '.join(FORMATS)}) or a suffix that says it: {known}"
        )
    return SUFFIXES[suffix]


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
    allow_sparse: bool = False
    alignment: str | None = None  # an alignment file to re-derive the run's pairs with


#: The least share of a format's grid (its bins, pairs or nodes that have a direction
#: pair) the run's samples must support (`gonio.reconstruct`'s support: within its
#: distance of a sample) for the export to be written without ``allow_sparse``: below
#: it, most of the file would be the reconstruction's extrapolation, not the run. The
#: support is generous (one sample supports 23 % of the RGL pairs, 30 % of the MERL
#: bins, 46 % of a hybrid grid; eight samples 28 % and 37 %; sixty well-spread samples
#: 53 %, 57 % and 71 %, the RGL pairs capped near 55 % by the grazing angles no rig
#: reaches), so the bound sits between a handful of samples and a few dozen.
MIN_SUPPORTED = 0.4
#: Bytes the HDF5 grid takes per node while it is evaluated: its coordinates, the two
#: directions, the values of up to three channels and their masked copy, the support
#: and validity masks (float64 each), with a margin for the evaluation's blocks.
GRID_BYTES_PER_NODE = 8 * (3 + 6 + 3 + 3) + 2 + 64
#: The factored format's table sizes (`gonio.export.factored.Resolution`'s defaults):
#: outgoing θ × φ rows, half-vector θ × φ columns. The outer terms factor a rows ×
#: columns matrix, so at most min(rows, columns) of them; the inner terms each a θ × φ
#: matrix, so at most min(θ, φ).
FACTORED_ROWS = 16 * 32
FACTORED_COLUMNS = 32 * 64
MAX_OUTER = min(FACTORED_ROWS, FACTORED_COLUMNS)
MAX_INNER = min(32, 64)


def memory_bytes() -> int:
    """The machine's physical memory (bytes)."""
    return os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")


def check_options(name: str, options: Options) -> None:
    """`GonioError` (one line) for an option of format ``name`` beyond what it means:
    the HDF5 grid's points beyond the memory its evaluation would need, the factored
    format's terms beyond the rank its tables allow."""
    if name == "hdf5" and options.grid is not None:
        points = options.grid_points
        if points < 2:
            raise GonioError(f"--grid-points {points}: expected at least 2")
        dims = len(params.get(options.grid).iso_bounds)
        need = points**dims * GRID_BYTES_PER_NODE
        have = memory_bytes()
        if need > have:
            raise GonioError(
                f"--grid-points {points}: a {dims}-dimensional grid of {points}^{dims} nodes "
                f"needs about {_size(need)} of memory to evaluate; this machine has "
                f"{_size(have)}"
            )
    if name == "factored" and not (
        1 <= options.outer <= MAX_OUTER and 1 <= options.inner <= MAX_INNER
    ):
        raise GonioError(
            f"--outer {options.outer} --inner {options.inner}: expected 1 to {MAX_OUTER} "
            f"outer terms (the rank of the {FACTORED_ROWS} × {FACTORED_COLUMNS} table they "
            f"factor) and 1 to {MAX_INNER} inner terms"
        )


def _size(n: float) -> str:
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB"):
        if n < 1024 or unit == "PiB":
            return f"{n:.3g} {unit}" if unit != "B" else f"{n:.0f} B"
        n /= 1024
    return f"{n:.3g} EiB"


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
    check_options(name, options or Options())
    module = importlib.import_module(FORMATS[name][0])
    with reserve_output(out_path, "-o", inputs=[run_path]) as out:
        run = open_run(run_path)
        if options is not None and options.alignment is not None:
            run = realigned(run, options.alignment)
        summary: str = module.export_run(run, out, options or Options())
    return summary


if TYPE_CHECKING:  # the names for the type checker (`as`: re-exported)
    from gonio.export.factored import Resolution as Resolution
    from gonio.export.factored import factorize as factorize
    from gonio.export.rgl import SAMPLES as SAMPLES
    from gonio.export.rgl import THETA_I as THETA_I
    from gonio.export.rgl import write as write

#: The names of the face that load with their module when first used
#: (`gonio.faces`), by module.
WHERE = {
    "Resolution": "factored",
    "SAMPLES": "rgl",
    "THETA_I": "rgl",
    "factorize": "factored",
    "write": "rgl",
}
__all__ = [
    "ALTA_PARAMS",
    "FORMATS",
    "MAX_INNER",
    "MAX_OUTER",
    "MERL_FILLS",
    "MIN_SUPPORTED",
    "Options",
    "RGL_COLORS",
    "SUFFIXES",
    "check_options",
    "export",
    "format_of",
    "names",
    *WHERE,
]
if not TYPE_CHECKING:
    __getattr__, __dir__ = lazy_face(__name__, WHERE)
