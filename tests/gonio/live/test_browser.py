"""The page as a person uses it, in a real browser: headless Chromium (Debian's
``chromium``, driven by Playwright through ``executable_path``; Playwright's own browser
download is never used) opens the URL ``gonio acquire`` printed for a run it is
acquiring (held paused until the page is up, however slow the machine), resumes it,
sees the sample count and the hemisphere plot change, pauses the run (the page shows
it paused, the journal records who asked), resumes it, and the run completes; then the
reconstruction's slice is drawn and the samples turn to their residuals against the
fit.
Screenshots are checked by content. Skipped, with the reason, only where no browser is
installed and not in CI (``make test`` installs it where it can)."""

from __future__ import annotations

import io
import os
import shutil
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from gonio.acquire import control
from gonio.live import server
from gonio.store.read import open_run
from tests.gonio.live.conftest import paced_acquire, printed_url
from tests.support.acquire import MATTE, plan_file

CHROMIUM = os.environ.get("GONIO_CHROMIUM", "/usr/bin/chromium")
ARGS = [
    "--no-sandbox", "--headless", "--disable-gpu", "--disable-background-networking",
    "--disable-component-update", "--no-first-run", "--disable-sync",
]  # fmt: skip


def _why_not() -> str | None:
    try:
        import playwright.sync_api  # noqa: F401  (the test extra)
    except ImportError:
        return "playwright is not installed (pip install -e '.[test]')"
    if not (os.path.exists(CHROMIUM) or shutil.which("chromium")):
        return f"no Chromium at {CHROMIUM} (apt-get install chromium; make test does as root)"
    return None


@pytest.fixture(scope="module")
def browser(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Any]:
    why = _why_not()
    if why is not None:
        if os.environ.get("CI") == "true":
            pytest.fail(f"the browser tests must run in CI: {why}")
        pytest.skip(why)
    from playwright.sync_api import sync_playwright  # the test extra

    profile = tmp_path_factory.mktemp("chromium-profile")
    with sync_playwright() as p:
        context = p.chromium.launch_persistent_context(
            str(profile), executable_path=CHROMIUM, args=ARGS, headless=True,
            viewport={"width": 1300, "height": 1000},
        )  # fmt: skip
        try:
            yield context
        finally:
            context.close()


def _ink(png: bytes) -> int:
    """Pixels of a screenshot that are neither white nor the page's background."""
    from PIL import Image  # with matplotlib (the test extra)

    pixels = np.asarray(Image.open(io.BytesIO(png)).convert("RGB"), dtype=np.int64)
    light = (pixels > 235).all(axis=2)
    return int((~light).sum())


def _until(check: Callable[[], bool], timeout_s: float = 30.0) -> None:
    give_up = time.monotonic() + timeout_s
    while not check():
        assert time.monotonic() < give_up, "timed out"
        time.sleep(0.1)


@pytest.mark.slow
def test_watch_pause_resume_in_a_browser(
    browser: Any, tmp_path: Path, serve: Callable[[server.Served], Iterator[str]]
) -> None:
    folder = tmp_path / "runs"
    folder.mkdir()
    plan = plan_file(tmp_path, target=80)
    path = folder / "live.sqlite"
    child = paced_acquire(["acquire", str(plan), "--scene", str(MATTE), "-o", str(path)], 0.05)
    try:
        url = printed_url(child)
        _until(lambda: path.exists() and len(open_run(path)) >= 2)
        # Held until the page is up, however slow the machine: it resumes from the page.
        control.post_request(path, "pause", "the test")
        with serve(server.Served(folder, refit_every=20)) as base:
            page = browser.new_page()
            page.goto(url.replace("http://127.0.0.1:8765", base))
            assert "#token" not in page.url  # taken out of the address bar at once
            page.wait_for_function("document.getElementById('state').dataset.state === 'paused'")
            page.wait_for_function("document.getElementById('hemisphere').dataset.samples")
            first = int(page.inner_text("#count"))
            plotted = page.get_attribute("#hemisphere", "data-samples")
            assert first >= 2 and plotted == str(first)
            page.click("#resume")
            page.wait_for_function(
                f"Number(document.getElementById('count').textContent) > {first} && "
                f"document.getElementById('hemisphere').dataset.samples !== '{plotted}'"
            )
            assert page.get_attribute("#state", "data-state") == "running"
            shot = page.screenshot(full_page=True)
            assert _ink(shot) > 20_000
            assert _ink(page.locator("#hemisphere").screenshot()) > 500
            assert page.is_visible("#pause") and page.is_enabled("#pause")

            page.click("#pause")
            page.wait_for_function("document.getElementById('state').dataset.state === 'paused'")
            held = int(page.inner_text("#count"))
            time.sleep(0.6)
            assert int(page.inner_text("#count")) == held == len(open_run(path))
            assert page.is_enabled("#resume") and not page.is_enabled("#pause")
            page.wait_for_selector("#events tr.pause")
            pause = open_run(path).of_kind("pause")[-1]  # the page's
            assert pause.data["reason"] == "request" and pause.data["action"] == "pause"
            assert pause.data["by"].startswith("127.0.0.1 via gonio serve")

            page.click("#resume")
            page.wait_for_function(
                "document.getElementById('state').dataset.state === 'completed'", timeout=60_000
            )
            assert page.inner_text("#count") == "80"
            # the samples are fetched after the figures: drawn a moment later
            page.wait_for_function("document.getElementById('hemisphere').dataset.samples === '80'")
            assert _ink(page.locator("#inplane").screenshot()) > 200
            # The reconstruction's slice and the residuals against the fit (every 20).
            page.wait_for_function("Number(document.getElementById('slice').dataset.filled) > 0")
            assert _ink(page.locator("#slice").screenshot()) > 500
            page.select_option("#colour", "residual")
            page.wait_for_function(
                "document.getElementById('hemisphere').dataset.colour === 'residual'"
            )
            assert "residual" in page.inner_text("#unit")
            assert page.is_hidden("#control")
            page.close()
        assert child.wait(30) == 0
    finally:
        child.kill()
        child.communicate()
    run = open_run(path)
    assert run.complete and len(run) == 80
    resume = [e for e in run.of_kind("resume") if e.data.get("reason") == "request"]
    assert len(resume) == 2 and resume[1].data["paused_s"] >= 0.6
    assert all(e.data["by"].startswith("127.0.0.1 via gonio serve") for e in resume)
