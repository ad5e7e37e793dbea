"""Each benchmark (benchmarks/) and each study (studies/) writes its own results page,
docs/results/<name>.md, and the index.

A script ends with ``report.run(main, __file__, __doc__, title=...)``: its output still
goes to the terminal, and once ``main`` returns the page is written with a header (the
title, what the script measures from its docstring, the exact command, the machine, the
date, the load average at start and at the end, the wall time) and, below it, what the
script printed: markdown tables and prose as they are, column-aligned text in a code
block, and the figures it wrote (``report.figure``) as images linked relatively. Then
docs/results/index.md is rewritten to list every page present. ``--no-page`` (taken out
of the arguments before the script sees them) prints only.
"""

from __future__ import annotations

import inspect
import io
import os
import re
import shlex
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TextIO

from _machine import describe

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "docs" / "results"
NO_PAGE = "--no-page"
#: The marker line of a generated page (the index and the tests look for it).
MARKER = "<!-- Written by {script} through benchmarks/_report.py: run it again, "
#: Header fields, in order (tests/test_results_pages.py reads them).
FIELDS = ("Script", "Command", "Machine", "Date", "Load average", "Wall time")
_FIGURE = "\x00figure\x00"


@dataclass(frozen=True)
class Header:
    """What a page says of its run: everything but the output."""

    title: str
    script: str  # the script's path from the repository root, e.g. benchmarks/bus.py
    about: str  # what it measures (markdown)
    command: str
    machine: str
    date: str  # UTC, minutes
    load: str
    wall: str


def about(doc: str | None) -> str:
    """The docstring as markdown, without its ``Run:`` paragraph (the header gives the
    command): a paragraph starting "Run:" is left out up to the next blank line."""
    out: list[str] = []
    skipping = False
    for line in inspect.cleandoc(doc or "").splitlines():
        if line.startswith("Run:"):
            skipping = True
        elif not line.strip():
            skipping = False
        if not skipping:
            out.append(line)
    return re.sub(r"\n{3,}", "\n\n", "\n".join(out)).strip()


def command(argv: Sequence[str], script: str) -> str:
    """The command line as run from the repository root (``script``: its path from there)."""
    exe = Path(sys.executable)
    venv = ROOT / ".venv"
    python = str(Path(".venv") / exe.relative_to(venv)) if exe.is_relative_to(venv) else "python"
    return shlex.join([python, script, *argv])


def load_average() -> str:
    one, five, fifteen = os.getloadavg()
    return f"{one:.2f}, {five:.2f}, {fifteen:.2f}"


def duration(seconds: float) -> str:
    if seconds < 60:
        return f"{seconds:.1f} s"
    minutes, s = divmod(round(seconds), 60)
    if minutes < 60:
        return f"{minutes} min {s:02d} s"
    hours, minutes = divmod(minutes, 60)
    return f"{hours} h {minutes:02d} min"


def render_header(h: Header) -> str:
    values = (f"`{h.script}`", f"`{h.command}`", h.machine, h.date, h.load, h.wall)
    fields = "\n".join(f"- **{k}:** {v}" for k, v in zip(FIELDS, values, strict=True))
    return (
        f"# {h.title}\n\n"
        f"{MARKER.format(script=h.script)}do not edit. -->\n\n"
        f"{h.about}\n\n{fields}\n"
    )


def _aligned(lines: list[str]) -> bool:
    """Column-aligned text (two spaces inside a line, or a leading indent)."""
    return any(re.search(r"\S {2,}\S", ln) or ln.startswith("  ") for ln in lines)


def render_body(output: str) -> str:
    """What the script printed, as markdown: blocks of ``|`` rows and prose as printed,
    column-aligned blocks fenced, figure markers as images, "== " lines as headings."""
    blocks: list[list[str]] = [[]]
    for line in output.rstrip().splitlines():
        if line.strip():
            blocks[-1].append(line.rstrip())
        elif blocks[-1]:
            blocks.append([])
    out: list[str] = []
    for block in blocks:
        if not block:
            continue
        chunk: list[str] = []
        kind = ""
        for line in [*block, None]:
            this = "" if line is None else _kind(line)
            if chunk and this != kind:
                out.append(_render(kind, chunk))
                chunk = []
            if line is not None:
                chunk.append(line)
                kind = this
    return "\n\n".join(out) + "\n"


def _kind(line: str) -> str:
    if line.startswith(_FIGURE):
        return "figure"
    if line.lstrip().startswith("|"):
        return "table"
    if line.startswith("== "):
        return "heading"
    return "text"


def _render(kind: str, lines: list[str]) -> str:
    if kind == "figure":
        return "\n\n".join(line[len(_FIGURE) :] for line in lines)
    if kind == "heading":
        return "\n\n".join(f"### {line[3:].strip()}" for line in lines)
    if kind == "table" or not _aligned(lines):
        return "\n".join(line.strip() if kind == "table" else line for line in lines)
    return "```text\n" + "\n".join(lines) + "\n```"


class _Tee(io.TextIOBase):
    """Writes to the terminal and keeps a copy."""

    def __init__(self, stream: TextIO) -> None:
        self.stream = stream
        self.copy = io.StringIO()

    def write(self, s: str) -> int:
        self.copy.write(s)
        return self.stream.write(s)

    def flush(self) -> None:
        self.stream.flush()


_tee: _Tee | None = None
_folder = RESULTS  # where the page being written goes (figure links are relative to it)


def figure(path: Path, alt: str) -> None:
    """Say that the script wrote the figure ``path``: on the terminal its path, on the page
    the image, linked relatively."""
    path = Path(path).resolve()
    shown = path.relative_to(ROOT) if path.is_relative_to(ROOT) else path
    said = f"wrote {shown} ({path.stat().st_size / 1024:.0f} KB)"
    if _tee is None:
        print(said)
        return
    _tee.stream.write(said + "\n")
    link = os.path.relpath(path, _folder)
    _tee.copy.write(f"\n{_FIGURE}![{alt}]({link})\n\n")


def option(argv: Sequence[str], name: str) -> list[str]:
    """The values given after option ``name`` in ``argv`` (``--name=v`` too), or []."""
    for i, arg in enumerate(argv):
        if arg.startswith(f"{name}="):
            return [arg.split("=", 1)[1]]
        if arg == name:
            rest = list(argv[i + 1 :])
            stop = next((j for j, a in enumerate(rest) if a.startswith("-")), len(rest))
            return rest[:stop]
    return []


def page_name(script: str, argv: Sequence[str], part: bool) -> str:
    """``<script>`` or, for a script whose first argument names a part, ``<script>-<part>``."""
    stem = Path(script).stem
    return f"{stem}-{argv[0]}" if part and argv and not argv[0].startswith("-") else stem


def run(
    main: Callable[[], None],
    file: str,
    doc: str | None,
    *,
    title: str | Callable[[Sequence[str]], str],
    part: bool = False,
    variant: Callable[[Sequence[str]], str | None] | None = None,
    folder: Path | None = None,
) -> None:
    """Run ``main`` and write its page (unless ``--no-page`` is among the arguments).

    Parameters
    ----------
    main
        The script's main function; it parses ``sys.argv`` itself.
    file, doc
        The script's ``__file__`` and ``__doc__``.
    title
        The page's title: what the script measures, in a few words; or, given the
        arguments, the title of the page they write.
    part
        The first argument names a part (a subcommand): one page per part.
    variant
        Given the arguments, a suffix naming a separate page (e.g. another table), or None.
    folder
        Where the page goes (docs/results by default).
    """
    global _tee, _folder
    _folder = RESULTS if folder is None else folder
    argv = sys.argv[1:]
    if NO_PAGE in argv:
        sys.argv = [sys.argv[0], *(a for a in argv if a != NO_PAGE)]
        main()
        return
    path = Path(file).resolve()
    script = path.relative_to(ROOT).as_posix() if path.is_relative_to(ROOT) else path.name
    name = page_name(script, argv, part)
    suffix = variant(argv) if variant else None
    if suffix:
        name = f"{name}-{suffix}"
    if callable(title):
        title = title(argv)
    start_load = load_average()
    nice = os.nice(0)
    date = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    started = time.perf_counter()
    _tee = _Tee(sys.stdout)
    sys.stdout = _tee
    try:
        main()
    finally:
        sys.stdout = _tee.stream
    wall = time.perf_counter() - started
    output = _tee.copy.getvalue()
    _tee = None
    machine = describe()
    for prefix in ("machine: ", ""):  # the machine line the script printed is in the header
        output = output.replace(f"{prefix}{machine}\n", "", 1)
    niceness = f", niceness {nice}" if nice else ""
    header = Header(
        title=title,
        script=script,
        about=about(doc),
        command=command(argv, script),
        machine=machine,
        date=date,
        load=(
            f"{start_load} at start, {load_average()} at the end (1, 5 and 15 min; "
            f"{os.cpu_count()} cores shared with other work{niceness})"
        ),
        wall=duration(wall),
    )
    write_page(name, header, output, folder)


def write_page(name: str, header: Header, output: str, folder: Path | None = None) -> Path:
    """Write ``folder/<name>.md`` (docs/results by default) and the index; the page's path."""
    folder = RESULTS if folder is None else folder
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{name}.md"
    text = render_header(header) + "\n## Output\n\n" + render_body(output)
    path.write_text(text, encoding="utf-8")
    (folder / "index.md").write_text(index(folder), encoding="utf-8")
    print(f"wrote {path.relative_to(ROOT) if path.is_relative_to(ROOT) else path}")
    return path


def read_header(path: Path) -> dict[str, str]:
    """The title and the header fields of a page (empty values where missing)."""
    lines = path.read_text(encoding="utf-8").splitlines()
    out = {"Title": lines[0].removeprefix("# ") if lines and lines[0].startswith("# ") else ""}
    for key in FIELDS:
        prefix = f"- **{key}:** "
        out[key] = next((ln[len(prefix) :] for ln in lines if ln.startswith(prefix)), "")
    return out


def index(folder: Path | None = None) -> str:
    """docs/results/index.md: every page present in ``folder``, one line each."""
    folder = RESULTS if folder is None else folder
    lines = [
        "# Results",
        "",
        "Each page below is written by the script it names, a speed benchmark in benchmarks/",
        "or an accuracy study in studies/: `make bench` runs them, `make bench-studies` the",
        "trade-off study's (studies/study.py, studies/study_engine.py: the `gonio tradeoff`",
        "sweeps first). The command, the machine, the date, the load on the shared machine",
        "and the wall time are in each page's header; the tables and figures are what the",
        "script printed. This list is written with the pages.",
        "",
    ]
    for path in sorted(folder.glob("*.md")):
        if path.name == "index.md":
            continue
        head = read_header(path)
        lines.append(f"- [{head['Title']}]({path.name}) ({head['Script']})")
    return "\n".join(lines) + "\n"
