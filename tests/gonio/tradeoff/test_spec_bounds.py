"""Every numeric axis of a sweep is held to the bounds its physics or this machine
allows, and a fly axis to the plan's and the rig's: one line naming the file, the
line, the axis and the bound, when the sweep is read, before anything runs."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from gonio.config import ConfigError
from gonio.tradeoff.grid import load_sweep
from tests.conftest import CONFIGS
from tests.gonio.tradeoff.conftest import SMALL, write_sweep

FLY_AXES = {"motion": ["fly"], "minutes": [5.0]}

# (axes changed, the field refused, expected words)
CASES: list[tuple[dict[str, Any], str, str]] = [
    (
        {"minutes": [1e-9]},
        "axes.minutes.0",
        "expected at least 0.00417 min, the time of one sample on this rig (0.25 s",
    ),
    ({"minutes": [1_000_000]}, "axes.minutes.0", "expected at most 1440 (a day"),
    ({**FLY_AXES, "blur_deg": [1e-9]}, "axes.blur_deg.0", "expected at least 0.01 (below"),
    (
        {**FLY_AXES, "blur_deg": [0.5, 0.015]},
        "axes.blur_deg.1",
        "expected at least 0.0254° for detector_arc (the quantization of detector_elevation's",
    ),
    ({**FLY_AXES, "rate_hz": [0.01]}, "axes.rate_hz.0", "expected at least 1 (below one"),
    ({"velocity_scale": [1e-9]}, "axes.velocity_scale.0", "expected at least 0.01 (a hundredth"),
    ({"velocity_scale": [1e6]}, "axes.velocity_scale.0", "expected at most 100"),
    ({"averages": [10**6]}, "axes.averages.0", "expected at most 1000 averages"),
    ({"exposure_s": [1e6]}, "axes.exposure_s.0", "expected at most 3600"),
]


@pytest.mark.parametrize(("axes", "field", "expected"), CASES, ids=[c[1] for c in CASES])
def test_a_numeric_axis_out_of_its_bounds_is_one_line_naming_it(
    tmp_path: Path, axes: dict[str, Any], field: str, expected: str
) -> None:
    path = write_sweep(tmp_path, axes={**SMALL["axes"], **axes})
    with pytest.raises(ConfigError) as info:
        load_sweep(path)
    message = str(info.value)
    assert "\n" not in message and message.startswith(f"{path}:"), message
    assert f": {field}: {expected}" in message, message


def test_fly_combinations_on_a_scene_whose_detector_cannot_stream_are_refused(
    tmp_path: Path,
) -> None:
    lockin = str(CONFIGS / "scenes" / "matte_lockin.yaml")
    path = write_sweep(tmp_path, scenes=[lockin], axes={**SMALL["axes"], **FLY_AXES})
    with pytest.raises(ConfigError) as info:
        load_sweep(path)
    assert f": scenes.0: {lockin}: detector.kind: the simulated lockin detector cannot " in str(
        info.value
    )


def test_the_shipped_sweeps_are_within_every_bound() -> None:
    for path in sorted((CONFIGS / "sweeps").glob("*.yaml")):
        assert load_sweep(path).tasks, path
