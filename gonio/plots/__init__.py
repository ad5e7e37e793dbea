"""Figures (matplotlib, installed with the ``plot`` extra; drawn off-screen to files)."""

from __future__ import annotations

from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from gonio.errors import GonioError
from gonio.faces import lazy_face
from gonio.types import BoolArray, FloatArray


class PlotUnavailable(GonioError):
    """matplotlib is not installed."""


def require_matplotlib() -> ModuleType:
    """``matplotlib.pyplot`` on the off-screen Agg backend, or `PlotUnavailable` saying
    how to install it (checked before any long computation starts)."""
    try:
        import matplotlib  # optional: the plot extra
    except ImportError:
        raise PlotUnavailable(
            "plotting needs matplotlib: pip install 'gonio[plot]' (or pip install matplotlib)"
        ) from None
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # optional: the plot extra

    return plt


def check_figure_format(path: Path, option: str) -> None:
    """`PlotUnavailable` unless matplotlib is installed, and `GonioError` unless it can
    write the format ``path``'s suffix names (no suffix: PNG); both before any work."""
    require_matplotlib()
    from matplotlib.backend_bases import FigureCanvasBase  # optional: the plot extra

    formats = FigureCanvasBase.get_supported_filetypes()
    suffix = path.suffix.lower().removeprefix(".")
    if suffix and suffix not in formats:
        raise GonioError(
            f"{option} {path}: matplotlib cannot write '.{suffix}' figures; "
            f"name a file ending in one of {', '.join('.' + f for f in sorted(formats))}"
        )


#: Resolution of every figure of `gonio plot` (a figure of W × H inches is W·DPI × H·DPI
#: pixels: the figures are saved without tight cropping).
DPI = 100

#: The coordinates of the parametrizations that are angles (radians in code): every
#: figure draws them in degrees.
ANGLES = frozenset({
    "phi_h", "phi_k", "phi_k_minus_phi_h", "theta_h", "theta_d", "phi_d",
    "theta_i", "theta_o", "phi_i", "phi_o", "phi_o_minus_phi_i",
})  # fmt: skip

#: The symbols of the parametrizations' coordinate names.
SYMBOLS = {
    "hbar": "‖h̄‖",
    "k": "‖k‖",
    "kbar": "‖k̄‖",
    "phi_h": "φh",
    "phi_k": "φk",
    "phi_k_minus_phi_h": "φk − φh",
    "theta_h": "θh",
    "theta_d": "θd",
    "phi_d": "φd",
    "theta_i": "θi",
    "theta_o": "θo",
    "phi_i": "φi",
    "phi_o": "φo",
    "phi_o_minus_phi_i": "φo − φi",
}

#: Axis labels: the symbol, with the unit of an angle (°; the others are lengths of unit
#: vectors' projections, without a unit).
LABELS = {name: f"{s} (°)" if name in ANGLES else s for name, s in SYMBOLS.items()}


def label(name: str) -> str:
    """The axis label of a coordinate name (the name itself if it has none)."""
    return LABELS.get(name, name)


def symbol(name: str) -> str:
    """The symbol of a coordinate name, without a unit (the name itself if it has none)."""
    return SYMBOLS.get(name, name)


def drawn(name: str, values: object) -> FloatArray:
    """A coordinate's values (any shape) as a figure draws them: an angle (`ANGLES`, rad
    in code) in degrees, any other as it is."""
    v = np.asarray(values, dtype=np.float64)
    return np.asarray(np.degrees(v) if name in ANGLES else v, dtype=np.float64)


def quantity(name: str, value: float) -> str:
    """A coordinate's value as a caption writes it: an angle in degrees with its unit
    (``22.5°``), any other to three decimals."""
    return f"{float(drawn(name, value)):.4g}°" if name in ANGLES else f"{value:.3f}"


def save(fig: Any, path: str | Path, format: str | None = None) -> None:
    """Write ``fig`` at `DPI` (``format``: matplotlib's name, default from the suffix,
    PNG without one) and close it."""
    plt = require_matplotlib()
    try:
        fig.savefig(path, dpi=DPI, format=format or _format_of(Path(path)))
    finally:
        plt.close(fig)


def _format_of(path: Path) -> str:
    return path.suffix.lower().removeprefix(".") or "png"


class Surface(Protocol):
    """What the figures draw: a BRDF f(ωi, ωo) (a reconstruction, a model) in sr⁻¹ for
    pairs (N, 3); a reconstruction may also say where it has data (``supported``)."""

    def eval(self, wi: FloatArray, wo: FloatArray) -> FloatArray: ...


def one_channel(values: object) -> FloatArray:
    """Values (N,) as drawn: an RGB value (N, 3) is drawn as the mean of its channels."""
    f = np.asarray(values, dtype=np.float64)
    return np.asarray(f.mean(axis=-1) if f.ndim == 2 else f, dtype=np.float64)


def values(surface: Surface, wi: FloatArray, wo: FloatArray) -> FloatArray:
    """``surface``'s values (N,) at the pairs (`one_channel`)."""
    return one_channel(surface.eval(wi, wo))


def supported(surface: object, wi: FloatArray, wo: FloatArray) -> BoolArray:
    """Where ``surface`` has data: its ``supported(wi, wo)``, or everywhere."""
    fn = getattr(surface, "supported", None)
    if fn is None:
        return np.ones(len(wi), dtype=np.bool_)
    return np.asarray(fn(wi, wo), dtype=np.bool_).reshape(len(wi))


if TYPE_CHECKING:  # the names for the type checker (`as`: re-exported)
    from gonio.plots import error as error
    from gonio.plots import polar as polar
    from gonio.plots import samples as samples
    from gonio.plots import slices as slices
    from gonio.plots.coverage import plot_coverage as plot_coverage
    from gonio.plots.polar import DEFAULT_THETA_I_DEG as DEFAULT_THETA_I_DEG
    from gonio.plots.slices import DEFAULT_ANGLES_DEG as DEFAULT_ANGLES_DEG
    from gonio.plots.slices import check_angles as check_angles

#: The names of the face that load with their module when first used
#: (`gonio.faces`), by module.
WHERE = {
    "DEFAULT_ANGLES_DEG": "slices",
    "DEFAULT_THETA_I_DEG": "polar",
    "check_angles": "slices",
    "error": "error",
    "plot_coverage": "coverage",
    "polar": "polar",
    "samples": "samples",
    "slices": "slices",
}
__all__ = [
    "ANGLES",
    "DPI",
    "LABELS",
    "PlotUnavailable",
    "SYMBOLS",
    "Surface",
    "check_figure_format",
    "drawn",
    "label",
    "one_channel",
    "quantity",
    "require_matplotlib",
    "save",
    "supported",
    "symbol",
    "values",
    *WHERE,
]
if not TYPE_CHECKING:
    __getattr__, __dir__ = lazy_face(__name__, WHERE)
