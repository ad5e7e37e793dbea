"""Fixtures of the trade-off tests: sweep files written into a folder (the shipped rig
and scenes named by absolute paths), and one small sweep run once per session in this
process, the reference every other way of running it must reproduce."""

from __future__ import annotations

import contextlib
import io
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
import yaml

from gonio.cli import main
from gonio.tradeoff.runner import WALL_COLUMNS
from tests.conftest import CONFIGS

#: A sweep of four combinations of 100 samples on the matte scene.
SMALL: dict[str, Any] = {
    "name": "small",
    "rig": str(CONFIGS / "rigs" / "arch.yaml"),
    "scenes": [str(CONFIGS / "scenes" / "matte.yaml")],
    "axes": {
        "parametrization": ["hybrid", "rusinkiewicz"],
        "sampling": ["sobol", "warped"],
        "samples": [100],
    },
    "plan": {"kicks": 20, "acquisition": {"calibration": {"averages": 4}}},
    "evaluation": {"pairs": 2000},
}
#: The error target of the reference run (the matte scene's 100-sample plans reach ~0.02).
TARGET = 0.05


def write_sweep(folder: Path, file: str = "sweep", **changes: Any) -> Path:
    """`SMALL` with top-level fields replaced (None: removed), as ``folder/FILE.yaml``."""
    data = {**SMALL, **changes}
    data = {k: v for k, v in data.items() if v is not None}
    path = folder / f"{file}.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    return path


def rows_of(folder: Path) -> dict[str, dict[str, Any]]:
    """The rows of an output folder's results.jsonl by id, without the wall times."""
    out = {}
    for line in (folder / "results.jsonl").read_text(encoding="utf-8").splitlines():
        row = json.loads(line)
        out[row["id"]] = {k: v for k, v in row.items() if k not in WALL_COLUMNS}
    return out


@dataclass(frozen=True)
class Reference:
    """`SMALL` run in this process with ``--target-error TARGET``: its sweep file,
    output folder and what the command printed."""

    sweep: Path
    out: Path
    stdout: str


@pytest.fixture(scope="session")
def reference(tmp_path_factory: pytest.TempPathFactory) -> Reference:
    folder = tmp_path_factory.mktemp("tradeoff")
    sweep, out = write_sweep(folder), folder / "out"
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        code = main(
            ["tradeoff", str(sweep), "-o", str(out), "-j", "1", "-q", "--target-error", str(TARGET)]
        )
    assert code == 0, printed.getvalue()
    return Reference(sweep, out, printed.getvalue())
