"""The command-line reference, docs/reference/cli.md, generated from the parser `gonio`
itself runs: every command and subcommand with its purpose, description, usage line,
arguments (value, type, choices, default, help) and exit codes.

``python -m tools.reference_cli`` rewrites the page; ``--check`` only says (exit code 1)
whether the committed page differs from what the parser gives.

How the arguments are found: argparse has no public way to list a parser's arguments or
subcommands (reading ``parser._actions`` would be reading a private attribute, and the
text of ``--help`` says neither an argument's type nor its default). So the parser is
built by `gonio.cli.build_parser` itself, the real code, with a subclass of its parser
class that keeps what it is told through argparse's public methods: the `argparse.Action`
each ``add_argument`` call returns (whose attributes are argparse's documented ones), and
the name, help and parser of each subcommand ``add_parser`` makes. The one private name
touched is the class of the subcommands action (``argparse._SubParsersAction``, which
``add_subparsers(action=...)`` is given a subclass of to extend its one documented
method, ``add_parser``); gonio's command modules name it already, in their signatures.
"""

from __future__ import annotations

import argparse
import inspect
import sys
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from gonio.cli import UsageParser, build_parser

ROOT = Path(__file__).resolve().parents[1]
#: The page this script writes.
PAGE = ROOT / "docs" / "reference" / "cli.md"
#: Width of the usage lines on the page (columns): fixed, so that the page does not
#: depend on the terminal it is generated in.
WIDTH = 100

#: What the page calls the types argparse is given (others: their docstring's first line).
TYPE_NAMES: dict[object, str] = {
    None: "text",
    str: "text",
    int: "integer",
    float: "number",
    Path: "path",
}

if TYPE_CHECKING:
    _SubParsersAction = argparse._SubParsersAction[argparse.ArgumentParser]
else:
    _SubParsersAction = argparse._SubParsersAction


@dataclass(frozen=True)
class Command:
    """One command: its words after ``gonio``, its one-line help (the purpose ``gonio
    --help`` lists) and the parser that records its arguments."""

    words: tuple[str, ...]
    purpose: str | None
    parser: RecordingParser
    subcommands: list[Command] = field(default_factory=list)

    @property
    def name(self) -> str:
        return " ".join(("gonio", *self.words))

    @property
    def anchor(self) -> str:
        """The heading's anchor on the page (MkDocs' slug of its title)."""
        return "-".join(("gonio", *self.words))

    def walk(self) -> list[Command]:
        """This command and every subcommand under it, in the parser's order."""
        return [self, *(c for sub in self.subcommands for c in sub.walk())]


class Subcommands(_SubParsersAction):
    """The subcommands action of a `RecordingParser`: it keeps, in order, the name, help
    and parser of each subcommand ``add_parser`` makes."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.made: list[tuple[str, str | None, argparse.ArgumentParser]] = []

    def add_parser(self, name: str, **kwargs: Any) -> argparse.ArgumentParser:
        parser = super().add_parser(name, **kwargs)
        self.made.append((name, kwargs.get("help"), parser))
        return parser


class RecordingParser(UsageParser):
    """A `UsageParser` that keeps the actions its ``add_argument`` returns (``-h``
    included, in the order given) and its subcommands action; help at `WIDTH` columns."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        self.arguments: list[argparse.Action] = []  # before argparse adds -h
        self.subcommands: Subcommands | None = None
        kwargs.setdefault("formatter_class", _formatter)
        super().__init__(*args, **kwargs)

    def add_argument(self, *args: Any, **kwargs: Any) -> argparse.Action:
        action = super().add_argument(*args, **kwargs)
        self.arguments.append(action)
        return action

    def add_subparsers(self, **kwargs: Any) -> Any:
        kwargs.setdefault("action", Subcommands)
        action = super().add_subparsers(**kwargs)
        if not isinstance(action, Subcommands):
            raise TypeError(f"{self.prog}: subcommands made by {type(action).__name__}")
        self.subcommands = action
        return action


def _formatter(prog: str) -> argparse.HelpFormatter:
    return argparse.HelpFormatter(prog, width=WIDTH)


def commands() -> Command:
    """The ``gonio`` command with every subcommand, from `gonio.cli.build_parser`
    (every command module imported)."""
    root = build_parser("*", parser_class=RecordingParser)
    if not isinstance(root, RecordingParser):
        raise TypeError(f"build_parser made a {type(root).__name__}")
    return _command((), None, root)


def _command(words: tuple[str, ...], purpose: str | None, parser: RecordingParser) -> Command:
    command = Command(words, purpose, parser)
    for name, help_, sub in parser.subcommands.made if parser.subcommands else ():
        if not isinstance(sub, RecordingParser):
            raise TypeError(f"{sub.prog}: made by {type(sub).__name__}")
        command.subcommands.append(_command((*words, name), help_, sub))
    return command


def render() -> str:
    """The page's text."""
    root = commands()
    every = root.walk()
    lines = [
        "# Command line",
        "",
        "<!-- Generated by tools/reference_cli.py from gonio's parser: do not edit. -->",
        "",
        "This page is generated from the parser the `gonio` program runs, so it says what "
        "the commands accept; do not edit it by hand. After changing a command, regenerate "
        "it from the repository's root with",
        "",
        "```sh",
        "python -m tools.reference_cli",
        "```",
        "",
        "(a test fails while the committed page differs). Every command also takes `-h` "
        "(`--help`), which prints its usage and options. A default of `None` means the "
        "option is unset; its help says what is used then.",
        "",
        "Commands: "
        + ", ".join(f"[`{c.name}`](#{c.anchor})" for c in every[1:] if len(c.words) == 1)
        + "; [exit codes](#exit-codes).",
        "",
    ]
    lines += _section(root)
    lines += [
        "## Exit codes",
        "",
        "Every command exits with one of these codes; a command that gives a code a more "
        "precise meaning, or uses another, lists its own in its section.",
        "",
        *_exit_codes(root.parser.exit_codes),
    ]
    for command in every[1:]:
        lines += _section(command)
    return "\n".join(lines).rstrip("\n") + "\n"


def _section(command: Command) -> list[str]:
    parser = command.parser
    level = "#" * min(2 + max(len(command.words) - 1, 0), 4)
    lines = [f"{level} {command.name}", ""]
    if command.purpose:
        lines += [f"*{_text(command.purpose)}*", ""]
    if parser.description:
        lines += [_text(parser.description), ""]
    lines += ["```text", parser.format_usage().rstrip("\n"), "```", ""]
    arguments = [a for a in parser.arguments if "-h" not in a.option_strings]
    if arguments:
        lines += [
            "| argument | value | type | default | meaning |",
            "| --- | --- | --- | --- | --- |",
            *(_row(parser, a) for a in arguments),
            "",
        ]
    if command.subcommands and parser.subcommands is not None:
        given = parser.subcommands.metavar
        metavar = given if isinstance(given, str) else "COMMAND"
        need = "required" if parser.subcommands.required else "optional"
        lines += [
            f"`{metavar}` ({need}), one of:",
            "",
            f"| {metavar.lower()} | what it does |",
            "| --- | --- |",
            *(
                f"| [`{c.name}`](#{c.anchor}) | {_cell(c.purpose or '')} |"
                for c in command.subcommands
            ),
            "",
        ]
    if parser.exit_codes and command.words:
        lines += [
            "Exit codes of this command (the others as for [every command](#exit-codes)):",
            "",
            *_exit_codes(parser.exit_codes),
        ]
    return lines


def _row(parser: argparse.ArgumentParser, action: argparse.Action) -> str:
    names = ", ".join(f"`{o}`" for o in action.option_strings) or f"`{action.dest}`"
    cells = (names, _value(action), _type(action), _default(parser, action), _help(action))
    return "| " + " | ".join(_cell(c) for c in cells) + " |"


def _value(action: argparse.Action) -> str:
    """What follows the option on the command line: its metavar (argparse's default:
    the dest, upper-cased for an option) or its choices, and how many."""
    if action.nargs == 0:
        return ""
    if action.choices is not None and action.metavar is None:
        shown = "one of " + ", ".join(f"`{c}`" for c in action.choices)
    else:
        metavar = action.metavar
        if metavar is None:
            metavar = action.dest.upper() if action.option_strings else action.dest
        shown = " ".join(f"`{m}`" for m in ((metavar,) if isinstance(metavar, str) else metavar))
    counts = {"?": "optional", "+": "one or more", "*": "any number"}
    if isinstance(action.nargs, int):
        return f"{shown} ({action.nargs} values)"
    if isinstance(action.nargs, str) and action.nargs in counts:
        return f"{shown} ({counts[action.nargs]})"
    return shown


def _type(action: argparse.Action) -> str:
    """The type's name: a flag, a builtin's name, or the first line of the docstring of
    the function that converts the text (without its full stop)."""
    if action.nargs == 0:
        return "flag"
    if action.type in TYPE_NAMES:
        return TYPE_NAMES[action.type]
    doc = inspect.getdoc(action.type)
    if not doc:
        raise ValueError(
            f"{', '.join(action.option_strings) or action.dest}: its type {action.type!r} has "
            "no docstring, whose first line would name it on the reference page"
        )
    summary = doc.splitlines()[0].rstrip(".")
    return summary[:1].lower() + summary[1:]


def _default(parser: argparse.ArgumentParser, action: argparse.Action) -> str:
    """The value argparse gives an argument not on the command line (a string default is
    converted by the type, as argparse converts it)."""
    if action.required:
        return "required"
    if action.default is argparse.SUPPRESS:
        return ""
    value = parser.get_default(action.dest)
    if isinstance(value, str) and callable(action.type):
        value = action.type(value)
    if isinstance(value, list | tuple):
        value = " ".join(map(str, value))
    return f"`{value}`"


def _help(action: argparse.Action) -> str:
    text = action.help or ""
    if "%(" in text:  # argparse's own substitutions: this page does not make them
        raise ValueError(f"{action.option_strings or action.dest}: write the help with an f-string")
    return text.replace("%%", "%")


def _exit_codes(codes: dict[int, str]) -> list[str]:
    return [
        "| code | meaning |",
        "| --- | --- |",
        *(f"| {code} | {_cell(what)} |" for code, what in codes.items()),
        "",
    ]


def _text(text: str) -> str:
    """A paragraph on one line (argparse re-wraps the help's text anyway)."""
    return " ".join(text.split())


def _cell(text: str) -> str:
    return _text(text).replace("|", "\\|")


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m tools.reference_cli", description=__doc__)
    parser.add_argument(
        "--check", action="store_true", help="write nothing; exit 1 if the page is stale"
    )
    args = parser.parse_args(argv)
    text = render()
    current = PAGE.read_text(encoding="utf-8") if PAGE.is_file() else None
    if args.check:
        if text != current:
            print(f"{PAGE.relative_to(ROOT)} is stale: run python -m tools.reference_cli")
            return 1
        return 0
    if text != current:
        PAGE.write_text(text, encoding="utf-8", newline="\n")
        print(f"wrote {PAGE.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
