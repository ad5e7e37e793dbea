"""Figures (matplotlib, installed with the ``plot`` extra; drawn off-screen to files)."""

from __future__ import annotations

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
