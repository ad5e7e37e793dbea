"""The results pages: benchmarks/_report.py writes the header every page has, and every page
in docs/results/ comes from a script in benchmarks/ (a speed benchmark) or studies/ (an
accuracy study) that `make bench` (or `make bench-studies`) runs, with the index listing
exactly the pages present."""

from __future__ import annotations

import ast
import importlib.util
import re
import sys
from pathlib import Path
from types import ModuleType

import pytest

ROOT = Path(__file__).resolve().parents[1]
BENCHMARKS = ROOT / "benchmarks"
RESULTS = ROOT / "docs" / "results"
PAGES = sorted(p for p in RESULTS.glob("*.md") if p.name != "index.md")


@pytest.fixture(scope="module")
def report() -> ModuleType:
    """benchmarks/_report.py, loaded as a script loads it (its `_machine` beside it)."""
    sys.path.insert(0, str(BENCHMARKS))
    try:
        spec = importlib.util.spec_from_file_location("_report", BENCHMARKS / "_report.py")
        assert spec is not None and spec.loader is not None
        module = importlib.util.module_from_spec(spec)
        sys.modules.setdefault("_report", module)
        spec.loader.exec_module(module)
    finally:
        sys.path.remove(str(BENCHMARKS))
    return module


def bench_scripts() -> set[str]:
    """The scripts the Makefile's bench and bench-studies recipes run, as paths from the
    repository root."""
    text = (ROOT / "Makefile").read_text(encoding="utf-8").replace("\\\n", " ")
    scripts: set[str] = set()
    target = None
    for line in text.splitlines():
        if match := re.match(r"^([\w-]+):", line):
            target = match.group(1)
        elif line.startswith("\t") and target in {"bench", "bench-studies"}:
            scripts.update(re.findall(r"\b(?:benchmarks|studies)/\w+\.py", line))
    return scripts


def test_a_page_has_every_header_field_and_what_the_script_printed(
    report: ModuleType, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    image = tmp_path / "img" / "plot.png"
    image.parent.mkdir()
    image.write_bytes(b"\x89PNG")

    def main() -> None:
        print("| a | b |\n| --- | ---: |\n| x | 1 |\n")
        print("name     value\nalpha        1")
        report.figure(image, "a plot")

    doc = """What it measures.

    More words.

    Run: .venv/bin/python benchmarks/thing.py [--n N]
    """
    pages = tmp_path / "results"
    monkeypatch.setattr(sys, "argv", ["benchmarks/thing.py", "--n", "3"])
    report.run(main, str(BENCHMARKS / "thing.py"), doc, title="A thing", folder=pages)
    page = pages / "thing.md"
    head = report.read_header(page)
    assert head["Title"] == "A thing"
    assert all(head[key] for key in report.FIELDS), head
    assert head["Script"] == "`benchmarks/thing.py`"
    assert head["Command"].endswith("benchmarks/thing.py --n 3`")
    assert re.fullmatch(r"\d{4}-\d\d-\d\d \d\d:\d\d UTC", head["Date"])
    assert "at start" in head["Load average"] and head["Wall time"].endswith(" s")
    text = page.read_text(encoding="utf-8")
    assert "What it measures." in text and "Run:" not in text
    assert "| x | 1 |" in text and "```text\nname     value\nalpha        1\n```" in text
    assert "![a plot](../img/plot.png)" in text
    assert (pages / "index.md").read_text(encoding="utf-8") == report.index(pages)
    assert "[A thing](thing.md)" in report.index(pages)


def test_no_page_prints_only(
    report: ModuleType, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    seen: list[list[str]] = []
    monkeypatch.setattr(sys, "argv", ["thing.py", "--no-page", "--n", "3"])
    report.run(lambda: seen.append(sys.argv[1:]), "thing.py", "", title="T", folder=tmp_path)
    assert seen == [["--n", "3"]] and list(tmp_path.iterdir()) == []


def test_a_part_and_a_variant_name_their_own_page(report: ModuleType) -> None:
    assert report.page_name("study.py", ["curves", "-o", "x"], part=True) == "study-curves"
    assert report.page_name("study.py", ["--help"], part=True) == "study"
    assert report.option(["--sampling", "sobol", "adaptive", "-o", "x"], "--sampling") == [
        "sobol",
        "adaptive",
    ]
    assert report.option(["--tables=memory"], "--tables") == ["memory"]


@pytest.mark.parametrize("page", PAGES, ids=[p.stem for p in PAGES])
def test_every_page_names_a_script_that_make_bench_runs(report: ModuleType, page: Path) -> None:
    head = report.read_header(page)
    assert all(head[key] for key in ("Title", *report.FIELDS)), head
    script = head["Script"].strip("`")
    assert (ROOT / script).is_file()
    assert script in bench_scripts()
    for link in re.findall(r"!\[[^\]]*\]\(([^)]+)\)", page.read_text(encoding="utf-8")):
        assert (page.parent / link).is_file(), link
    # What the page says it measures is the script's docstring as it is now.
    doc = ast.get_docstring(ast.parse((ROOT / script).read_text(encoding="utf-8")))
    assert f"\n\n{report.about(doc)}\n\n" in page.read_text(encoding="utf-8"), (
        f"{page.name}: the script's docstring changed; run it again"
    )


def test_the_index_lists_every_page_present(report: ModuleType) -> None:
    assert (RESULTS / "index.md").read_text(encoding="utf-8") == report.index()
