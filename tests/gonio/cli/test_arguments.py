"""Every option that takes a number refuses what no number option may take (not a number,
an infinity, a value beyond float64, a count beyond 64 bits) in argparse's one line,
before any work; and the shared argument types keep their bounds."""

from __future__ import annotations

import argparse
from collections.abc import Iterator

import pytest

from gonio.cli import arguments
from gonio.config import MAX_SECONDS
from tools.reference_cli import commands

#: Text no number option accepts.
NEVER = ("nan", "inf", "-inf", "1e400", "", "12abc")
#: Text no whole-number option accepts (beyond what SQLite and numpy's int64 hold).
NEVER_WHOLE = (str(2**63), str(2**64), "1e19")
#: Types that convert text without bounds (a path, a name): not number options.
TEXT_TYPES = {None, str}


def typed_options() -> Iterator[tuple[str, argparse.Action]]:
    """(command words, action) of every option whose text a function converts, as the
    reference page's walk over the real parsers records them."""
    for command in commands().walk():
        for action in command.parser.arguments:
            if action.nargs == 0 or action.type in TEXT_TYPES or action.choices is not None:
                continue
            if getattr(action.type, "__name__", "") != "Path":
                yield " ".join(command.words), action


OPTIONS = list(typed_options())


def test_the_walk_finds_the_number_options() -> None:
    names = {f"{words} {'/'.join(a.option_strings) or a.dest}" for words, a in OPTIONS}
    for expected in ("fit --starts", "watch --every", "plan --test-pairs", "acquire --speedup"):
        assert expected in names, names


@pytest.mark.parametrize(
    ("words", "action"),
    OPTIONS,
    ids=[f"{w} {'/'.join(a.option_strings) or a.dest}" for w, a in OPTIONS],
)
def test_no_number_option_takes_what_is_not_a_finite_number(
    words: str, action: argparse.Action
) -> None:
    assert action.type is not None and callable(action.type)
    whole = isinstance(_converted(action, "1"), int)
    for text in NEVER + (NEVER_WHOLE if whole else ()):
        assert _converted(action, text) is None, text


def _converted(action: argparse.Action, text: str) -> object:
    """What ``action``'s type makes of ``text``; None if it refuses it."""
    assert callable(action.type)
    try:
        return action.type(text)
    except (argparse.ArgumentTypeError, ValueError):
        return None


def test_durations_stop_where_a_clock_can_still_wait() -> None:
    assert arguments.positive_seconds(str(MAX_SECONDS)) == MAX_SECONDS
    for text in ("1e10", "1e300", "0", "-1"):
        with pytest.raises(argparse.ArgumentTypeError, match="at most 1e\\+09"):
            arguments.positive_seconds(text)
    with pytest.raises(argparse.ArgumentTypeError, match=r"in \[1, 1,000\], got '1001'"):
        arguments.count("1001", "starts", 1000)
