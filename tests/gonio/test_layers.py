"""The layering rule at run time: what a package loads when it is imported (the import
contracts in pyproject.toml check the static graph; these check what Python really
loads, package ``__init__``s included)."""

from __future__ import annotations

import subprocess
import sys

import pytest

HEAVY = ("serial", "dynamixel_sdk", "sim")


@pytest.mark.parametrize(
    "package",
    [
        "gonio.planner",
        "gonio.rig",
        "gonio.scene",
        "gonio.store",
        "gonio.analysis",
        "gonio.reconstruct",
    ],
)
def test_planning_and_analysis_load_neither_the_serial_stack_nor_the_simulator(
    package: str,
) -> None:
    code = f"import sys, {package}\nprint(','.join(m for m in {HEAVY!r} if m in sys.modules))"
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=60, check=True
    )
    assert out.stdout.strip() == ""
