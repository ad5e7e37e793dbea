"""`--ids` of `gonio motors`: what it accepts and the one line it says otherwise (no
port is opened: these are usage errors)."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from gonio.cli.motors import motor_ids
from tests.conftest import CliResult

Gonio = Callable[..., CliResult]


@pytest.mark.parametrize(
    ("text", "ids"),
    [("1", [1]), ("1,2,5-7", [1, 2, 5, 6, 7]), (" 3 - 4 ", [3, 4]), ("0", [0]), ("252", [252])],
)
def test_ids_accepted(text: str, ids: list[int]) -> None:
    assert motor_ids(text) == ids


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("1-", "expected IDs like 1,2,5-7, got '1-'"),
        ("-1", "expected IDs like 1,2,5-7, got '-1'"),
        ("1--3", "expected IDs like 1,2,5-7, got '1--3'"),
        ("1,,2", "expected IDs like 1,2,5-7, got '1,,2'"),
        ("²", "expected IDs like 1,2,5-7, got '²'"),
        ("4-1", "the range '4-1' goes down; write 1-4"),
        ("253", "motor IDs must be in 0…252, got '253'"),
        ("1-99999999999999999", "motor IDs must be in 0…252, got '1-99999999999999999'"),
    ],
    ids=[
        "open-range",
        "negative",
        "double-dash",
        "empty-item",
        "unicode-digit",
        "downward",
        "too-large",
        "huge-range",
    ],
)
def test_ids_refused_in_one_line(run_gonio: Gonio, text: str, message: str) -> None:
    r = run_gonio("motors", "status", "--port", "/dev/null-port", "--ids", text)
    assert r.returncode == 2
    assert r.stdout == ""
    assert r.stderr == (
        f"gonio: error: motors status: argument --ids: {message} (see gonio motors status --help)\n"
    )
