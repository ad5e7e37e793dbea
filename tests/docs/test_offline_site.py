"""The documentation site as the README says to read it: built by mkdocs (``--strict``, once
for the module, into a temporary folder, or the one `make test` has just built) and opened
from the file system (``file://…/index.html``) in headless Chromium with every network
request refused. Three links are followed (each lands on its page, not a folder's
listing), a search finds pages, and wide tables and code blocks scroll in their own box at
1280 px (the page never scrolls sideways, nothing runs under the table of contents)."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from tests.support.browser import chromium

ROOT = Path(__file__).resolve().parents[2]
HARDWARE = "Hardware: Dynamixel arms and a serial detector"

# The tests share one built site: one xdist worker builds it once.
pytestmark = [pytest.mark.slow, pytest.mark.xdist_group("built-site")]


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The site as ``make docs`` builds it, into a temporary folder; or the one it has just
    built, where ``GONIO_BUILT_SITE`` names it (as `make test` does after its checks)."""
    built = os.environ.get("GONIO_BUILT_SITE")
    if built:
        assert (Path(built) / "index.html").is_file(), f"no site built in {built}"
        return Path(built)
    out = tmp_path_factory.mktemp("site")
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1", "PYTHONPATH": str(ROOT)}
    done = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "-q", "-d", str(out)],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr
    return out


@pytest.fixture(scope="module")
def browser(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Any]:
    with chromium(tmp_path_factory.mktemp("chromium-profile"), width=1280) as context:
        yield context


@pytest.fixture
def page(browser: Any) -> Iterator[Any]:
    """A page that may load only files: every http(s) request is refused and recorded
    (the test fails if any was made)."""
    refused: list[str] = []

    def refuse(route: Any) -> None:
        refused.append(route.request.url)
        route.abort()

    browser.route(re.compile(r"^(https?|wss?)://"), refuse)
    page = browser.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda error: errors.append(str(error)))
    try:
        yield page
    finally:
        page.close()
        browser.unroute(re.compile(r"^(https?|wss?)://"))
    assert refused == [], f"the site asked the network for {refused}"
    assert errors == [], errors


#: A link or a source in a page: the attribute's value.
LINK = re.compile(r'<(?:a|link|script|img)\b[^>]*?\b(?:href|src)="([^"]*)"')


def test_every_link_in_the_site_names_a_file(site: Path) -> None:
    """Opened as files, a link to a folder shows its listing: every page's links and
    sources that stay in the site name a file that is there (fragments and queries
    aside), none a folder."""
    checked = 0
    for html in site.rglob("*.html"):
        if html.name == "404.html":  # a server's answer, its links from the site's root
            continue
        for target in LINK.findall(html.read_text(encoding="utf-8")):
            if re.match(r"^([a-z]+:|#|//)", target) or not target:
                continue
            path = (html.parent / target.split("#")[0].split("?")[0]).resolve()
            assert path.is_file(), f"{html.relative_to(site)}: {target}"
            checked += 1
    assert checked > 10_000


def _landed(page: Any, path: str, heading: str) -> None:
    """The page at ``path`` (relative to the site) is shown, with its ``heading``."""
    page.wait_for_load_state()
    assert page.url.split("#")[0].endswith(path), page.url
    assert not page.title().startswith("Index of"), page.title()  # a folder's listing
    assert page.inner_text("article h1").strip().removesuffix("¶") == heading  # its permalink


def test_three_links_lead_to_their_pages(site: Path, page: Any) -> None:
    page.goto((site / "index.html").as_uri())
    _landed(page, "/index.html", "gonio")

    # A link in the page's text (a relative link to a section's index).
    page.locator("article").get_by_role("link", name="How-to guides", exact=True).click()
    _landed(page, "/how-to/index.html", "How-to guides")

    # The navigation: a page of another section, from the sidebar.
    sidebar = page.locator(".md-sidebar--primary")
    sidebar.get_by_role("link", name="Hardware", exact=True).click()
    _landed(page, "/reference/hardware.html", HARDWARE)

    # A link to a heading of another page: that page, scrolled to the heading.
    page.locator("article").get_by_role("link", name="the models", exact=True).first.click()
    _landed(page, "/reference/emulator.html", "The Dynamixel bus emulator")
    assert page.url.endswith("/reference/emulator.html#the-models"), page.url
    top = page.eval_on_selector("#the-models", "e => e.getBoundingClientRect().top")
    assert 0 <= top < 300  # the heading at the top of the window, below the header


def test_search_finds_pages(site: Path, page: Any) -> None:
    page.goto((site / "index.html").as_uri())
    assert page.evaluate("window.Worker === window.IFrameWorker")  # the shipped shim
    page.click(".md-search__input")
    page.keyboard.type("emulator")  # typed: the search listens to the keys
    results = page.locator(".md-search-result__item")
    results.first.wait_for(timeout=30_000)
    assert results.count() >= 3
    meta = page.inner_text(".md-search-result__meta")
    assert re.search(r"\d+ matching documents?", meta), meta
    results.first.locator("a").first.click()
    page.wait_for_load_state()
    assert page.url.startswith("file://") and ".html" in page.url, page.url
    assert not page.title().startswith("Index of")


#: Measured in the page: the page's sideways overflow, the box (its overflow-x, its left and
#: right edges, its hidden width), the element's right edge before and after the box is
#: scrolled to its end, the table of contents' left edge (px).
LAYOUT = """([selector, last]) => {
  const doc = document.documentElement;
  const element = document.querySelector(selector);
  const box = element.closest('.md-typeset__scrollwrap') || element;
  const end = () => (last ? element.querySelector(last) : element).getBoundingClientRect();
  const before = end().right;
  box.scrollLeft = box.scrollWidth;
  const rect = box.getBoundingClientRect();
  return {
    page: doc.scrollWidth - doc.clientWidth, overflow: getComputedStyle(box).overflowX,
    left: rect.left, right: rect.right, hidden: box.scrollWidth - box.clientWidth,
    before: before, after: end().right, width: element.getBoundingClientRect().width,
    toc: document.querySelector('.md-sidebar--secondary').getBoundingClientRect().left,
  };
}"""


def test_a_wide_table_scrolls_in_its_own_box_at_1280_px(site: Path, page: Any) -> None:
    page.goto((site / "results" / "study-curves.html").as_uri())
    assert page.viewport_size["width"] == 1280
    m = page.evaluate(LAYOUT, ["article table", "tr:first-child th:last-child"])
    assert m["page"] == 0 and m["overflow"] == "auto", m
    assert m["right"] <= m["toc"], m  # the box ends before the table of contents
    assert m["hidden"] > 0 and m["before"] > m["right"], m  # the last column hidden at first
    assert m["left"] < m["after"] <= m["right"] + 1, m  # and shown once scrolled to
    # 19 columns kept compact: under 1.7 times the text column's width (2.4 wide open)
    assert m["width"] < 1.7 * (m["right"] - m["left"]), m


def test_a_wide_code_block_scrolls_in_its_own_box_at_1280_px(site: Path, page: Any) -> None:
    page.goto((site / "explanations" / "radiometry.html").as_uri())
    widest = page.evaluate("""() => {
      const codes = Array.from(document.querySelectorAll('article pre > code'));
      const widest = codes.reduce((a, b) => (b.scrollWidth > a.scrollWidth ? b : a));
      widest.id = 'widest';
      return widest.scrollWidth;
    }""")
    m = page.evaluate(LAYOUT, ["#widest", ""])
    assert m["page"] == 0 and m["overflow"] == "auto", m
    assert m["right"] <= m["toc"], m
    assert widest > 2 * (m["right"] - m["left"]) and m["hidden"] > 0, (widest, m)
