"""Helpers of the figure tests: read a written PNG back, and a small analytic surface
with a support mask."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np

from gonio.plots import DPI
from gonio.types import BoolArray, FloatArray


def png_size(path: Path) -> tuple[int, int]:
    """(width, height) in pixels of the PNG at ``path``, read back by matplotlib (which
    fails on a file that is not a whole PNG)."""
    from matplotlib.image import imread

    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    image = imread(path)
    assert np.isfinite(image).all()
    return image.shape[1], image.shape[0]


def pixels(figsize: tuple[float, float]) -> tuple[int, int]:
    """The pixels of a figure of ``figsize`` inches at `DPI`."""
    return round(figsize[0] * DPI), round(figsize[1] * DPI)


class Lobe:
    """An isotropic, reciprocal BRDF (sr⁻¹) that is supported only where both
    directions are within 60° of the normal."""

    def eval(self, wi: FloatArray, wo: FloatArray) -> FloatArray:
        mirror = wi * np.array([-1.0, -1.0, 1.0])
        cos = np.sum(mirror * wo, axis=-1)
        return np.asarray(0.05 + 3.0 * np.maximum(cos, 0.0) ** 20, dtype=np.float64)

    def supported(self, wi: FloatArray, wo: FloatArray) -> BoolArray:
        return np.asarray((wi[..., 2] > 0.5) & (wo[..., 2] > 0.5), dtype=np.bool_)


def capture(monkeypatch: object, module: object) -> list[object]:
    """The figures ``module`` saves (its ``save`` still writes them), for tests that
    check what was drawn, not only what was computed."""
    import gonio.plots

    figures: list[object] = []

    def spy(fig: object, path: object, format: str | None = None) -> None:
        figures.append(fig)
        gonio.plots.save(fig, path, format)  # type: ignore[arg-type]

    monkeypatch.setattr(module, "save", spy)  # type: ignore[attr-defined]
    return figures


def texts(fig: Any) -> list[str]:
    """Every non-empty string a figure shows: titles, axis labels, tick labels (as
    drawn), legends, colour bars and free text."""
    from matplotlib.text import Text

    fig.canvas.draw()  # tick labels are set when drawn
    return [t.get_text() for t in fig.findobj(Text) if t.get_visible() and t.get_text()]


def assert_angles_in_degrees(fig: Any) -> None:
    """Every text that names an angle (θ, φ) says its unit in degrees, none says
    radians, and every axis labelled in degrees spans more than 2π (its data are in
    degrees, not radians under a degree label)."""
    for text in texts(fig):
        assert not re.search(r"\brad\b|radian", text), text
        if "θ" in text or "φ" in text:
            assert "°" in text or "degrees" in text, text
    for ax in fig.axes:
        for axis_label, limits in (
            (ax.get_xlabel(), ax.get_xlim()),
            (ax.get_ylabel(), ax.get_ylim()),
        ):
            if "°" in axis_label:
                assert abs(limits[1] - limits[0]) > 2 * np.pi, (axis_label, limits)
