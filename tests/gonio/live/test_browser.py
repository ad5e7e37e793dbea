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
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from gonio.acquire import control
from gonio.cli import main
from gonio.live import server
from gonio.store.read import open_run
from tests.gonio.live.conftest import paced_acquire, printed_url
from tests.support.acquire import MATTE, plan_file
from tests.support.browser import chromium


@pytest.fixture(scope="module")
def browser(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Any]:
    """One browser for the module (`tests.support.browser`), 1300 × 1000 px."""
    with chromium(tmp_path_factory.mktemp("chromium-profile"), 1300, 1000) as context:
        yield context


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
                "document.getElementById('message').textContent.includes('resume requested')"
            )
            page.wait_for_function(
                "document.getElementById('state').dataset.state === 'completed'", timeout=60_000
            )
            assert page.inner_text("#count") == "80"
            assert page.inner_text("#message") == ""  # the request's message went with the run
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
            assert "(f − f_fit)/σ" in page.inner_text("#unit")
            assert "(f − fit)/σ" in _svg_text(page, "#hemisphere .colorbar")
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


def _shot(png: bytes) -> np.ndarray:
    from PIL import Image  # with matplotlib (the test extra)

    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"), dtype=np.int64)


def _panel_boxes(page: Any) -> dict[str, dict[str, float]]:
    """Each panel's box in the page (CSS px, from the document's top left)."""
    return dict(
        page.evaluate(
            """() => Object.fromEntries([...document.querySelectorAll('figure.panel')].map((f) => {
                 const r = f.getBoundingClientRect();
                 const box = {x: r.left + scrollX, y: r.top + scrollY, w: r.width, h: r.height};
                 return [f.dataset.panel, box];
               }))"""
        )
    )


def _texts(page: Any, selector: str) -> list[str]:
    return list(page.eval_on_selector_all(selector, "els => els.map((e) => e.textContent)"))


def _svg_text(page: Any, selector: str) -> str:
    """The text of the plot's SVG nodes ``selector`` selects (no innerText in SVG)."""
    return " ".join(_texts(page, selector))


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Two finished runs of one folder (a matte sample, 80 targets in Rusinkiewicz's
    coordinates and 40 in the hybrid ones) and the first's csv export beside it."""
    root = tmp_path_factory.mktemp("panels")
    runs = root / "runs"
    runs.mkdir()
    for name, target in (("a", 80), ("b", 40)):
        (root / name).mkdir()
        plan = plan_file(root / name, target=target)
        if name == "a":  # its slice in angles: θh against θd
            text = plan.read_text().replace("hybrid", "rusinkiewicz")
            plan.write_text(text)
        out = runs / f"{name}.sqlite"
        assert main(["acquire", str(plan), "--scene", str(MATTE), "-o", str(out), "-q"]) == 0
    csv = root / "a.csv"
    assert main(["export", str(runs / "a.sqlite"), "--format", "csv", "-o", str(csv), "-q"]) == 0
    return root


@pytest.mark.slow
def test_the_panels_hover_overlays_save_and_layout(
    browser: Any, folder: Path, serve: Callable[[server.Served], Iterator[str]]
) -> None:
    with serve(server.Served(folder / "runs", refit_every=20)) as base:
        page = browser.new_page()
        page.set_viewport_size({"width": 1280, "height": 900})
        page.goto(f"{base}/run/a.sqlite")
        page.wait_for_function("document.getElementById('fit').dataset.fitted === '80'")
        p = page.evaluate("state.points")
        # The header: the plan, the rig and the scene.
        assert page.inner_text("#plan") == "small" and page.inner_text("#rig") == "arch-4axis"
        assert page.inner_text("#scene") == "matte"

        # The hemisphere: θ rings and φ ticks labelled, a colour bar with units, the
        # isotropic plan on the half it covers.
        rings = _texts(page, "#hemisphere .radial-axis .xtick text, #hemisphere .radialaxis text")
        assert {"30°", "60°", "90°"} <= set(rings), rings
        marks = _texts(page, "#hemisphere .angular-axis text, #hemisphere .angularaxis text")
        assert {"0°", "90°", "180°"} <= set(marks), marks
        assert "270°" not in marks  # the lower half is not drawn
        assert page.evaluate("document.getElementById('hemisphere').layout.polar.sector") == [
            0,
            180,
        ]
        assert all(0 <= a <= 180 for a in p["phi_deg"])
        assert "sr⁻¹" in _svg_text(page, "#hemisphere .colorbar")

        # Hover: the pair in degrees, the value with its σ, the sample's index and time.
        k = len(p["value"]) // 2
        page.evaluate(
            f"Plotly.Fx.hover('hemisphere', [{{curveNumber: 1, pointNumber: {k}}}], 'polar')"
        )
        label = _svg_text(page, "#hemisphere .hoverlayer")
        for field, value in (("θi", p["theta_i_deg"][k]), ("θo", p["theta_o_deg"][k])):
            assert f"{field} {value:.1f}°" in label, label
        assert f"φi {p['phi_i_deg'][k]:.1f}°" in label and f"φo {p['phi_o_deg'][k]:.1f}°" in label
        assert f"f = {p['value'][k]:.4g}".rstrip("0") in label and "± " in label
        assert f"sample {p['index'][k]} (target {p['target'][k]})" in label
        assert f"t = {p['t_s'][k]:.1f} s" in label

        # The plane of incidence: a curve per θi, with error bars; log and linear.
        inplane = page.evaluate("document.getElementById('inplane').data")
        assert inplane and all(t["error_y"]["visible"] for t in inplane)
        assert all(t["name"].startswith("θi ") for t in inplane)
        assert sum(len(t["x"]) for t in inplane) == len(p["in_plane"]["value"])
        assert "signed θo (°)" in _svg_text(page, "#inplane .xtitle")
        assert page.evaluate("document.getElementById('inplane').layout.yaxis.type") == "log"
        page.select_option("#scale", "linear")
        assert page.evaluate("document.getElementById('inplane').layout.yaxis.type") == "linear"
        page.select_option("#scale", "log")
        # The fit's curves and the slice, axes in degrees.
        assert _svg_text(page, "#slice .xtitle") == "θh (°)"
        assert _svg_text(page, "#slice .ytitle") == "θd (°)"
        assert int(page.get_attribute("#slice", "data-filled") or 0) > 100
        fit = page.evaluate("document.getElementById('fit').data")
        assert any(t["name"].startswith("lambert+ggx") for t in fit)

        # Overlays: another run of the folder, then the first run's own csv export (its
        # samples fall on the run's own).
        page.select_option("#overlay", "b.sqlite")
        page.wait_for_function(
            "document.getElementById('hemisphere').dataset.overlay === 'b.sqlite'"
        )
        traces = page.evaluate("document.getElementById('hemisphere').data")
        assert len(traces) == 3 and len(traces[2]["r"]) == 40
        names = [t["name"] for t in page.evaluate("document.getElementById('inplane').data")]
        assert any(n.endswith("· b.sqlite") for n in names)
        page.set_input_files("#overlay-file", str(folder / "a.csv"))
        page.wait_for_function("document.getElementById('hemisphere').dataset.overlay === 'a.csv'")
        traces = page.evaluate("document.getElementById('hemisphere').data")
        assert sorted(traces[2]["r"]) == pytest.approx(sorted(traces[1]["r"]), abs=0.006)
        assert sorted(traces[2]["theta"]) == pytest.approx(sorted(traces[1]["theta"]), abs=0.006)

        # Save: PNG and SVG downloads made by Plotly, checked by their data.
        with page.expect_download() as got:
            page.click("[data-save='hemisphere.png']")
        png = Path(got.value.path()).read_bytes()
        assert png.startswith(b"\x89PNG") and _ink(png) > 20_000
        with page.expect_download() as got:
            page.click("[data-save='inplane.svg']")
        svg = Path(got.value.path()).read_text()
        assert svg.startswith("<svg") and "signed θo (°)" in svg and "θi " in svg
        assert got.value.suggested_filename == "a.sqlite-inplane.svg"

        # The layout uses the window: 2 columns at 1280 px, 3 at 1920 px, each panel inked.
        for width, columns in ((1280, 2), (1920, 3)):
            page.set_viewport_size({"width": width, "height": 1000})
            page.wait_for_function(
                "Math.abs(document.querySelector('#hemisphere .main-svg').clientWidth"
                " - document.getElementById('hemisphere').clientWidth) < 2"
            )
            boxes = _panel_boxes(page)
            assert len({round(b["x"]) for b in boxes.values()}) == columns
            right = max(b["x"] + b["w"] for b in boxes.values())
            assert right > width - 40 and min(b["x"] for b in boxes.values()) < 40
            pixels = _shot(page.screenshot(full_page=True))
            for name, b in boxes.items():
                crop = pixels[
                    int(b["y"]) : int(b["y"] + b["h"]), int(b["x"]) : int(b["x"] + b["w"])
                ]
                ink = int((~(crop > 235).all(axis=2)).sum())
                assert ink > 0.01 * crop.shape[0] * crop.shape[1], (width, name, ink)
            # the plots fill their panels: the hemisphere's disc is as wide as its box allows
            assert page.evaluate("document.querySelector('#hemisphere .main-svg').clientWidth") > (
                0.9 * boxes["hemisphere"]["w"]
            )
        page.close()
