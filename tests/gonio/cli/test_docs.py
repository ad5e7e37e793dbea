"""The docs mention only what exists: every option written after a `gonio CMD` in the
README, the docs pages and configs/README.md is one of that command's options, every
command named exists, and every configs/ folder the configs README names is there."""

from __future__ import annotations

import argparse
import re
from pathlib import Path

import pytest

from gonio.cli import build_parser

ROOT = Path(__file__).resolve().parents[3]
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md")), ROOT / "configs" / "README.md"]
COMMAND = re.compile(r"gonio ((?:motors|detector) [a-z-]+|[a-z]+)\b([^`\n]*)")
OPTION = re.compile(r"(?<![\w-])(--[a-z][a-z-]*|-[a-zA-Z])\b")
NOT_COMMANDS = {"import", "content", "run", "reads", "uses", "locks", "adds", "never"}


def _choices(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    return {}


def _options() -> dict[str, set[str]]:
    out: dict[str, set[str]] = {}
    for name, sub in _choices(build_parser("*")).items():
        out[name] = {o for a in sub._actions for o in a.option_strings}
        for action, parser in _choices(sub).items():
            out[f"{name} {action}"] = {o for a in parser._actions for o in a.option_strings}
    return out


def _mentions() -> list[tuple[str, str, str]]:
    """(where, command, option) of every option written after a `gonio CMD`."""
    found = []
    for path in DOCS:
        for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            for match in COMMAND.finditer(line):
                command, rest = match.group(1), match.group(2).split("#")[0]
                if command.split()[0] in NOT_COMMANDS:
                    continue
                where = f"{path.relative_to(ROOT)}:{n}"
                found.append((where, command, ""))
                found += [(where, command, o) for o in OPTION.findall(rest)]
    return found


def test_every_documented_command_and_option_exists() -> None:
    options = _options()
    wrong = [
        f"{where}: gonio {command} {option}".rstrip()
        for where, command, option in _mentions()
        if command not in options or (option and option not in options[command])
    ]
    assert wrong == []


@pytest.mark.parametrize("command", ["move", "home", "torque", "set-id"])
def test_the_bring_up_commands_are_documented(command: str) -> None:
    for doc in (ROOT / "README.md", ROOT / "docs" / "how-to" / "bring-up-motors.md"):
        assert f"gonio motors {command} " in doc.read_text(encoding="utf-8"), doc


def test_the_configs_readme_names_only_folders_that_exist() -> None:
    text = (ROOT / "configs" / "README.md").read_text(encoding="utf-8")
    for folder in re.findall(r"`([a-z_]+)/`", text):
        assert (ROOT / "configs" / folder).is_dir(), folder


def test_the_readme_is_a_short_front_door_that_speaks_of_the_project() -> None:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    assert len(text.encode("utf-8")) <= 8 * 1024
    assert not re.search(r"\bissues?\b|\bseed \d{3}\b", text, re.IGNORECASE)


def test_relative_links_in_the_docs_reach_a_file() -> None:
    broken = []
    for doc in DOCS:
        for target in re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", doc.read_text(encoding="utf-8")):
            if "://" not in target and not (doc.parent / target).exists():
                broken.append(f"{doc.relative_to(ROOT)}: {target}")
    assert broken == []
