"""The paths that tests/conftest.py puts in xdist groups exist: a module moved without
its entry would silently leave its group (the pty tests would then share the bus with
each other, a shared fixture would be built by every worker)."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.conftest import PTY_TESTS, SHARED_SETUP

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("path", [*PTY_TESTS, *SHARED_SETUP])
def test_every_grouped_path_exists(path: str) -> None:
    assert (ROOT / path).exists(), path
