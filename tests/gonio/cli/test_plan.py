"""`gonio plan` as a user runs it: the summary table, the CSV, the coverage PNG, and a
clear line when matplotlib is missing (checked before any planning work)."""

from __future__ import annotations

import csv
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

CONFIGS = Path(__file__).resolve().parents[3] / "configs"
GONIO = Path(sys.executable).with_name("gonio")


def run(*args: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [str(GONIO), *args], capture_output=True, text=True, timeout=300,
        stdin=subprocess.DEVNULL, env=env,
    )  # fmt: skip


def test_quick_plan_end_to_end(tmp_path: Path) -> None:
    out_csv, out_png = tmp_path / "plan.csv", tmp_path / "coverage.png"
    r = run(
        "plan", str(CONFIGS / "plans" / "quick.yaml"), "-o", str(out_csv), "--plot", str(out_png)
    )
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert lines[0] == "plan 'quick': isotropic hybrid, sobol, rig 'arch-4axis'"
    counts = {
        " ".join(line.split()[:-1]): int(line.split()[-1])
        for line in lines[1:10]
        if line.strip() and line.split()[-1].isdigit()
    }
    assert counts["kept"] == 500
    refused = sum(v for k, v in counts.items() if k.startswith("refused:"))
    assert counts["requested"] == counts["outside the domain"] + refused + 500
    duration = next(line for line in lines if "predicted duration" in line).split()[2]
    h, m, s = (int(x) for x in duration.split(":"))
    assert 0 < h * 3600 + m * 60 + s < 24 * 3600
    assert f"wrote 500 targets to {out_csv}" in r.stdout
    with out_csv.open(encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 500
    arrival = np.array([float(row["arrival_s"]) for row in rows])
    assert np.all(np.diff(arrival) > 0)
    # A real PNG of the figure's size.
    assert out_png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    import matplotlib.image

    image = matplotlib.image.imread(out_png)
    assert image.shape[0] >= 600 and image.shape[1] >= 1200
    assert image[..., :3].std() > 0.05  # not blank


def test_anisotropic_plan_with_the_other_rig(tmp_path: Path) -> None:
    r = run(
        "plan", str(CONFIGS / "plans" / "quick.yaml"),
        "--rig", str(CONFIGS / "rigs" / "in_plane.yaml"), "--plot", str(tmp_path / "c.png"),
    )  # fmt: skip
    assert r.returncode == 0, r.stderr
    assert "rig 'in-plane-4axis'" in r.stdout
    assert (tmp_path / "c.png").stat().st_size > 10_000


def test_missing_matplotlib_is_one_line_before_any_work(tmp_path: Path) -> None:
    """A matplotlib that cannot be imported (shadowed on PYTHONPATH) gives one line
    saying how to install the plot extra, and no plan is written."""
    shadow = tmp_path / "shadow" / "matplotlib"
    shadow.mkdir(parents=True)
    (shadow / "__init__.py").write_text("raise ImportError('no matplotlib here')\n")
    env = {**os.environ, "PYTHONPATH": str(shadow.parent)}
    out_csv = tmp_path / "plan.csv"
    r = run(
        "plan", str(CONFIGS / "plans" / "quick.yaml"), "-o", str(out_csv),
        "--plot", str(tmp_path / "c.png"), env=env,
    )  # fmt: skip
    assert r.returncode == 2
    assert r.stdout == ""
    assert r.stderr == (
        "gonio: error: plotting needs matplotlib: pip install 'gonio[plot]' "
        "(or pip install matplotlib)\n"
    )
    assert not out_csv.exists()


@pytest.mark.parametrize("args", [["plan"], ["plan", "a.yaml", "--frobnicate"]])
def test_usage_errors(args: list[str]) -> None:
    r = run(*args)
    assert r.returncode == 2
    assert "usage: gonio" in r.stderr
    assert "Traceback" not in r.stderr
