"""Figures (matplotlib, installed with the ``plot`` extra; drawn off-screen to files)."""

from __future__ import annotations

from pathlib import Path
from types import ModuleType

from gonio.errors import GonioError


class PlotUnavailable(GonioError):
    """matplotlib is not installed."""


def require_matplotlib() -> ModuleType:
    """``matplotlib.pyplot`` on the off-screen Agg backend, or `PlotUnavailable` saying
    how to install it (checked before any long computation starts)."""
    try:
        import matplotlib
    except ImportError:
        raise PlotUnavailable(
            "plotting needs matplotlib: pip install 'gonio[plot]' (or pip install matplotlib)"
        ) from None
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def check_figure_format(path: Path, option: str) -> None:
    """`PlotUnavailable` unless matplotlib is installed, and `GonioError` unless it can
    write the format ``path``'s suffix names (no suffix: PNG); both before any work."""
    require_matplotlib()
    from matplotlib.backend_bases import FigureCanvasBase

    formats = FigureCanvasBase.get_supported_filetypes()
    suffix = path.suffix.lower().removeprefix(".")
    if suffix and suffix not in formats:
        raise GonioError(
            f"{option} {path}: matplotlib cannot write '.{suffix}' figures; "
            f"name a file ending in one of {', '.join('.' + f for f in sorted(formats))}"
        )
