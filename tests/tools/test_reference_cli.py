"""The command-line reference page: the committed text is what the parser gives, and it
has a section for every command and subcommand ``--help`` lists, with every option."""

from __future__ import annotations

import contextlib
import io
import re

import pytest

from gonio.cli import COMMANDS, EXIT_CODES, main
from tools import reference_cli

HEADING = re.compile(r"^#{2,4} (gonio(?: [a-z-]+)*)$", re.MULTILINE)
#: A subcommand listed by --help: indented four spaces under the COMMAND (ACTION) metavar.
LISTED = re.compile(r"^    ([a-z][a-z-]*)(?:  |$)", re.MULTILINE)
OPTION = re.compile(r"(?<![\w-])(--?[a-zA-Z][\w-]*)")


def _help(words: list[str]) -> str:
    """What ``gonio WORDS --help`` prints (the real parser, not the page's recorder)."""
    out = io.StringIO()
    with contextlib.redirect_stdout(out), pytest.raises(SystemExit) as exit_:
        main([*words, "--help"])
    assert exit_.value.code == 0
    return out.getvalue()


def _listed(words: list[str]) -> dict[str, str]:
    """{"gonio WORDS": its --help} for the command and every subcommand under it."""
    text = _help(words)
    found = {" ".join(["gonio", *words]): text}
    for name in LISTED.findall(text.partition("positional arguments:")[2].split("\n\n")[0]):
        found |= _listed([*words, name])
    return found


@pytest.fixture(scope="module")
def page() -> str:
    return reference_cli.PAGE.read_text(encoding="utf-8")


@pytest.fixture(scope="module")
def sections(page: str) -> dict[str, str]:
    parts = HEADING.split(page)
    return dict(zip(parts[1::2], parts[2::2], strict=True))


def test_the_committed_page_is_what_the_parser_gives(page: str) -> None:
    assert reference_cli.render() == page, "stale: run python -m tools.reference_cli"
    assert reference_cli.main(["--check"]) == 0


def test_the_page_does_not_depend_on_the_terminal(
    page: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("COLUMNS", "40")
    assert reference_cli.render() == page


def test_every_command_help_lists_has_a_section_with_every_option(
    sections: dict[str, str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("COLUMNS", "200")  # one line per listed subcommand
    helps = _listed([])
    assert {f"gonio {name}" for name in COMMANDS} < set(helps)
    assert {"gonio motors scan", "gonio motors set-id"} < set(helps)
    assert list(sections) == list(helps)  # the parser's order, nothing more, nothing less
    for name, text in helps.items():
        usage = text.partition("\n\n")[0]
        rows = [line for line in sections[name].splitlines() if line.startswith("| `")]
        documented = {o for row in rows for o in OPTION.findall(row.split("|")[1])}
        assert set(OPTION.findall(usage)) - {"-h"} <= documented, name


def test_the_exit_codes_are_listed_for_the_program_and_per_command(
    page: str, sections: dict[str, str]
) -> None:
    program = page.partition("## Exit codes")[2].partition("\n## ")[0]
    assert [int(c) for c in re.findall(r"^\| (\d+) \|", program, re.MULTILINE)] == list(EXIT_CODES)
    assert {0, 1, 2, 130, 141} <= set(EXIT_CODES)
    own = {
        name: [int(c) for c in re.findall(r"^\| (\d+) \|", text, re.MULTILINE)]
        for name, text in sections.items()
    }
    assert own["gonio acquire"] == [0, 2, 3, 130]
    assert own["gonio motors scan"] == own["gonio motors status"] == [0, 1]
    assert own["gonio motors set-id"] == [0, 1]
    assert "exit codes: 0 the run completed" in " ".join(_help(["acquire"]).split())


def test_anchors_are_the_command_words(page: str) -> None:
    assert "[`gonio acquire`](#gonio-acquire)" in page
    assert "[`gonio motors set-id`](#gonio-motors-set-id)" in page
    assert "### gonio motors set-id\n" in page
