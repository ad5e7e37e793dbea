"""The noise-free curves pages have their figure: studies/_curves_figure.py reads every
row of a page's tables back, draws one panel per scene with one line per plan, and links
the figure where studies/study.py prints it (once, however often it runs)."""

from __future__ import annotations

import importlib.util
import re
import sys
from pathlib import Path
from types import ModuleType

import pytest

from tests.support.figures import png_size

ROOT = Path(__file__).resolve().parents[1]
STUDIES = ROOT / "studies"
PAGES = sorted((ROOT / "docs" / "results").glob("study-curves*.md"))


@pytest.fixture(scope="module")
def curves() -> ModuleType:
    saved = list(sys.path)
    sys.path.insert(0, str(STUDIES))
    try:
        spec = importlib.util.spec_from_file_location(
            "_curves_figure", STUDIES / "_curves_figure.py"
        )
        assert spec is not None and spec.loader is not None
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
    finally:
        sys.path[:] = saved
    return module


@pytest.mark.parametrize("page", PAGES, ids=[p.stem for p in PAGES])
def test_a_curves_page_links_its_figure_above_its_tables(curves: ModuleType, page: Path) -> None:
    text = page.read_text(encoding="utf-8")
    rows = curves.rows_of_page(text)
    computed, read = map(
        int, re.search(r"(\d+) rows computed in this run, (\d+) read", text).groups()
    )  # type: ignore[union-attr]
    assert len(rows) == computed + read == 256
    assert {r["scene"] for r in rows} == {
        "matte",
        "glossy_metal",
        "brushed_metal",
        "seed000_specular",
    }
    link = f"![{curves.alt_text(rows)}](../img/{page.stem}.png)"
    assert text.count(link) == 1
    assert text.index(link) < text.index("\n### ")
    assert png_size(ROOT / "docs" / "img" / f"{page.stem}.png") == (832, 576)


def test_drawn_from_a_page_once_however_often(
    curves: ModuleType, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(curves, "IMG", tmp_path / "img")
    (tmp_path / "img").mkdir()
    page = tmp_path / "results" / "study-curves.md"
    page.parent.mkdir()
    original = (ROOT / "docs" / "results" / "study-curves.md").read_text(encoding="utf-8")
    link = "![log-RMSE against samples, uniform](../img/study-curves.png)\n\n"
    page.write_text(original.replace(link, ""), encoding="utf-8")
    assert curves.add_to_page(page) == tmp_path / "img" / "study-curves.png"
    assert page.read_text(encoding="utf-8") == original
    curves.add_to_page(page)
    assert page.read_text(encoding="utf-8") == original
    assert png_size(tmp_path / "img" / "study-curves.png") == (832, 576)


def test_a_row_is_a_cell_of_the_table(curves: ModuleType) -> None:
    text = """### matte (noise-free, log-RMSE)

| sampling | parametrization | method | 250 | 1,000 | n for 0.01 |
|---|---|---|---:|---:|---:|
| sobol | hybrid | rbf | 0.0106 | — | 359 |
"""
    assert curves.rows_of_page(text) == [
        {
            "scene": "matte",
            "sampling": "sobol",
            "parametrization": "hybrid",
            "method": "rbf",
            "samples": "250",
            "log_rmse": "0.0106",
        }
    ]
    assert curves.targets_of_page(text) == (0.01,)
