"""Watching a run live: `gonio serve` against its targets.

1. Time for a committed sample to appear: a `gonio acquire` (simulated, paced to
   ``--pace`` wall seconds per target) served by `gonio serve` (another process); a
   client polls the run's overview every second, as the page does, and each sample's
   delay is the poll that first counted it minus its commit time (the journal's UTC
   stamp). Target: ≤ 2 s.
2. Time to open a run of a million samples (the quickstart run's 300 samples and plan
   tiled to 10⁶ rows, written once): the first overview and the first decimated samples
   from a fresh server, as the page asks for them. Target: ≤ 3 s.
3. The acquisition's per-sample time (engine + journal, measured as
   benchmarks/acquire.py does: between the first and the last sample's commit) of a
   Sobol plan on the glossy metal scene, with no client, then with five clients polling
   the run as the page does (overview every second, samples when they changed), each in
   a process of its own as a browser is, through a `gonio serve` in its own process
   (which fits and reconstructs the run every 200 new samples, its default, as it
   serves it; and again with a server that does not, to tell the two costs apart).
   Target: no difference beyond the noise (the repeats' spread is printed).
4. The server's derivation of part 3's run: one fit (``lambert+ggx``, one start) and
   one ``rbf`` reconstruction's slice from the at most 1,500 samples it uses, the work
   its worker process does (at nice 19) every ``--refit-every`` new samples (here in
   the benchmark's own process, at its priority).

With ``--screenshot PNG`` (and Chromium at /usr/bin/chromium with Playwright), the page
of the paced run of part 1 is saved there at 1280 px (a sample hovered), and at 1920 px
beside it (``PNG-1920``), as the docs show it, with the time the page takes to redraw its
sample panels.

Run: .venv/bin/python benchmarks/live.py [--repeat 5] [--screenshot docs/img/live-page.png]
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import io
import json
import os
import signal
import socket
import sqlite3
import subprocess
import sys
import tempfile
import threading
import time
import urllib.request
from datetime import datetime
from pathlib import Path
from typing import Any

import _report
import numpy as np
import yaml
from _machine import describe
from acquire import engine as acquire_engine  # benchmarks/acquire.py

from gonio.cli import main as gonio
from gonio.live import LiveRun, derived, values
from gonio.planner import ARRAYS, Plan, load_plan_source, plan_bytes
from gonio.store import Journal, open_run
from gonio.workflows import session

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # tests.support: the browser the browser tests drive
from tests.support.browser import ARGS as BROWSER_ARGS  # noqa: E402
from tests.support.browser import CHROMIUM  # noqa: E402

GLOSSY = ROOT / "configs/scenes/glossy_metal.yaml"
QUICKSTART = ROOT / "configs/plans/quickstart.yaml"


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@contextlib.contextmanager
def served(folder: Path, *options: str) -> Any:
    """``gonio serve FOLDER [OPTIONS]`` in its own process; its base URL."""
    port = free_port()
    proc = subprocess.Popen(
        [sys.executable, "-m", "gonio", "serve", str(folder), "--port", str(port), *options],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )
    base = f"http://127.0.0.1:{port}"
    try:
        for _ in range(300):
            with contextlib.suppress(OSError):
                urllib.request.urlopen(base + "/", timeout=5).close()  # opens no run
                break
            time.sleep(0.05)
        yield base
    finally:
        proc.send_signal(signal.SIGINT)
        proc.communicate(timeout=10)


def get(url: str) -> Any:
    with urllib.request.urlopen(url, timeout=30) as r:
        return json.loads(r.read())


def plan_file(folder: Path, targets: int, name: str) -> Path:
    spec = {
        "name": name,
        "rig": str(ROOT / "configs/rigs/arch.yaml"),
        "sampling": {"strategy": "sobol", "target": targets, "seed": 3},
        "exposure": {"seconds": 0.05},
        "kicks": 0,
        "time_budget_s": 60,
    }
    path = folder / f"{name}.yaml"
    path.write_text(yaml.safe_dump(spec))
    return path


def paced(args: list[str], pace_s: float) -> subprocess.Popen[str]:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.Popen(
        [sys.executable, "-m", "tests.gonio.live.paced", str(pace_s), *args],
        cwd=ROOT,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
        text=True,
    )


def _epoch(utc: str) -> float:
    return datetime.fromisoformat(utc).timestamp()


def latency(folder: Path, pace_s: float, screenshot: Path | None) -> None:
    plan = plan_file(folder, 300, "paced")
    run = folder / "paced.sqlite"
    child = paced(["acquire", str(plan), "--scene", str(GLOSSY), "-o", str(run)], pace_s)
    assert child.stdout is not None
    url = next(t for t in child.stdout if t.startswith("watch and control")).split()[-1]
    seen: dict[int, float] = {}
    counted: dict[int, float] = {}
    first: float | None = None
    with served(folder) as base:
        shot = None
        if screenshot is not None:
            shot = threading.Thread(target=take_screenshot, args=(url, base, screenshot))
            shot.start()
        give_up = time.monotonic() + 600
        while time.monotonic() < give_up:  # until the run completed
            o = get(f"{base}/api/overview?run=paced.sqlite")
            now = time.time()
            if first is None:
                first = now  # what was committed before the first poll is not counted
            if o["measured"] > len(seen):
                r = open_run(run)
                for target, utc in zip(r.target.tolist(), r.samples["utc"], strict=True):
                    seen.setdefault(int(target), now - _epoch(str(utc)))
                    if _epoch(str(utc)) > first and int(target) not in counted:
                        counted[int(target)] = seen[int(target)]
            if o["state"] == "completed":
                break
            time.sleep(1.0)
        if shot is not None:
            shot.join()
    child.communicate()
    delays = np.array(list(counted.values()))
    print("\n1. A committed sample on the page (polled every second, as the page does)\n")
    print("| samples | pace (s/target) | median delay (s) | 95th percentile (s) | max (s) |")
    print("|---:|---:|---:|---:|---:|")
    q50, q95 = np.percentile(delays, [50, 95])
    print(f"| {len(delays)} | {pace_s:g} | {q50:.2f} | {q95:.2f} | {delays.max():.2f} |")
    for ms, shown in DRAWN:
        print(
            f"\nThe page redraws its sample panels (hemisphere, in-plane, fit, slice) with "
            f"{shown} samples in {ms:.0f} ms (its own clock, Chromium at 1280 px)."
        )


#: (ms, samples) of each redraw of the page's sample panels that `take_screenshot` timed.
DRAWN: list[tuple[float, int]] = []


def take_screenshot(url: str, base: str, path: Path) -> None:
    try:
        from playwright.sync_api import sync_playwright  # the test extra
    except ImportError:
        print("no screenshot: playwright is not installed")
        return
    with tempfile.TemporaryDirectory() as profile, sync_playwright() as p:
        context = p.chromium.launch_persistent_context(
            profile,
            executable_path=CHROMIUM,
            args=BROWSER_ARGS,
            headless=True,
            viewport={"width": 1300, "height": 1000},
        )
        page = context.new_page()
        page.set_viewport_size({"width": 1280, "height": 900})
        page.goto(url.replace("http://127.0.0.1:8765", base))
        page.wait_for_function(
            "Number(document.getElementById('hemisphere').dataset.samples) >= 40 && "
            "Number(document.getElementById('slice').dataset.filled) > 0 && "
            "document.getElementById('fit').dataset.fitted"
        )
        # Redrawing every panel of the samples (Plotly.react), in the page's own clock.
        ms = page.evaluate(
            "() => { const t = performance.now(); drawSamples(); return performance.now() - t; }"
        )
        shown = page.evaluate("state.points.shown")
        DRAWN.append((float(ms), int(shown)))
        page.evaluate("Plotly.Fx.hover('hemisphere', [{curveNumber: 1, pointNumber: 0}], 'polar')")
        page.screenshot(path=str(path), full_page=True)
        page.set_viewport_size({"width": 1920, "height": 1080})
        page.wait_for_timeout(500)  # the plots follow the window's size
        page.screenshot(path=str(path.with_name(f"{path.stem}-1920{path.suffix}")), full_page=True)
        context.close()


def million(folder: Path, n: int) -> Path:
    """A run file of ``n`` samples: the quickstart run's samples and plan tiled."""
    small = folder / "quickstart.sqlite"
    with contextlib.redirect_stdout(io.StringIO()):
        args = ["acquire", str(QUICKSTART), "--scene", str(GLOSSY), "-o", str(small), "-q"]
        assert gonio(args) == 0
    run = open_run(small)
    reps = -(-n // len(run.plan))
    plan: Plan = run.plan
    big = dataclasses.replace(
        plan,
        summary=dataclasses.replace(plan.summary, kept=n, requested=n, target=n),
        **{k: np.concatenate([getattr(plan, k)] * reps)[:n] for k in ARRAYS},
    )
    path = folder / "million.sqlite"
    conn = sqlite3.connect(small)
    skip = ("plan_file", "schema_version")
    meta = {
        k: json.loads(v) for k, v in conn.execute("SELECT key, value FROM meta") if k not in skip
    }
    cursor = conn.execute("SELECT * FROM samples ORDER BY target")
    names = [d[0] for d in cursor.description]
    rows = cursor.fetchall()
    events = conn.execute("SELECT kind, target, t_s, utc, data FROM events ORDER BY id").fetchall()
    conn.close()
    span = max(float(r[names.index("ended_s")]) for r in rows) + 1.0
    t_cols = [names.index(c) for c in ("settled_s", "started_s", "ended_s")]
    with Journal.create(path, meta, plan_bytes(big), durable=False, overwrite=True) as journal:
        journal.start_session("2026-01-01T00:00:00+00:00", {})
        for kind, target, t_s, utc, data in events:
            journal.event(kind, t_s, utc, json.loads(data), target)
        placeholders = ", ".join("?" * len(names))
        quoted = ", ".join(f'"{c}"' for c in names)
        with journal.transaction():

            def tiled() -> Any:
                for i in range(n):
                    row = list(rows[i % len(rows)])
                    row[0] = i
                    for j in t_cols:
                        row[j] = float(row[j]) + span * (i // len(rows))
                    yield row

            journal.conn.executemany(
                f"INSERT INTO samples ({quoted}) VALUES ({placeholders})", tiled()
            )
        journal.end_session("2026-01-01T01:00:00+00:00", "completed")
    return path


def opening(folder: Path, n: int) -> None:
    path = million(folder, n)
    print(f"\n2. Opening a run of {n:,} samples ({path.stat().st_size / 1e6:.0f} MB)\n")
    print("| repeat | overview (s) | samples, decimated (s) | both (s) | points sent |")
    print("|---:|---:|---:|---:|---:|")
    for k in range(3):
        with served(path) as base:
            t = time.perf_counter()
            o = get(f"{base}/api/overview?run={path.name}")
            a = time.perf_counter() - t
            p = get(f"{base}/api/points?run={path.name}")
            b = time.perf_counter() - t - a
            assert o["measured"] == n
            print(f"| {k + 1} | {a:.2f} | {b:.2f} | {a + b:.2f} | {p['shown']:,} |")


#: One client, as a browser's page polls: the overview every second, the samples when
#: they changed (a process of its own, as a browser is).
CLIENT = """
import json, sys, time, urllib.request
base, run = sys.argv[1], sys.argv[2]
version = -1
while True:
    try:
        with urllib.request.urlopen(f"{base}/api/overview?run={run}", timeout=30) as r:
            o = json.loads(r.read())
        if o["version"] != version:
            version = o["version"]
            with urllib.request.urlopen(f"{base}/api/points?run={run}", timeout=30) as r:
                json.loads(r.read())
    except (OSError, ValueError, KeyError):
        pass
    time.sleep(1.0)
"""


@contextlib.contextmanager
def clients(base: str, run: str, count: int) -> Any:
    """``count`` clients polling ``run`` on ``base``, each in its own process."""
    procs = [subprocess.Popen([sys.executable, "-c", CLIENT, base, run]) for _ in range(count)]
    try:
        time.sleep(1.0)  # they have started polling
        yield
    finally:
        for proc in procs:
            proc.terminate()
            proc.wait()


def engine_s(folder: Path, plan: Plan, files: session.Files, scene: Any) -> float:
    """Wall seconds of the engine per sample (benchmarks/acquire.py's measure)."""
    return acquire_engine(files, plan, scene, folder) / len(plan)


def overhead(folder: Path, targets: int, repeat: int) -> None:
    source = load_plan_source(plan_file(folder, targets, "overhead"))
    plan = source.build()
    scene, text = session.load_scene_file(GLOSSY, source.rig)
    files = session.Files(
        source.path, source.text, source.rig.source, source.rig.text, GLOSSY, text
    )
    work = folder / "served"
    work.mkdir()
    engine_s(work, plan, files, scene)  # warm: the optics, the imports
    alone, watched, unfitted = [], [], []
    for _ in range(repeat):
        alone.append(engine_s(work, plan, files, scene))
        with served(work) as base, clients(base, "bench.sqlite", 5):
            watched.append(engine_s(work, plan, files, scene))
        with served(work, "--refit-every", "1000000000") as base, clients(base, "bench.sqlite", 5):
            unfitted.append(engine_s(work, plan, files, scene))
    print(f"\n3. The acquisition's time per sample, {targets:,} targets, {repeat} repeats\n")
    print("| clients | best (µs/sample) | median (µs/sample) | worst (µs/sample) |")
    print("|---|---:|---:|---:|")
    rows = (
        ("none", alone),
        ("5 polling through gonio serve", watched),
        ("5 polling, the server not fitting (--refit-every 10⁹)", unfitted),
    )
    for label, xs in rows:
        a = 1e6 * np.array(xs)
        print(f"| {label} | {a.min():.0f} | {np.median(a):.0f} | {a.max():.0f} |")
    live = LiveRun(work / "bench.sqlite")
    print(f"\n4. The server's derivation from {derived.SAMPLES:,} of part 3's samples\n")
    print("| repeat | fit and slice (s) | samples used | χ²/dof | slice points with a value |")
    print("|---:|---:|---:|---:|---:|")
    for k in range(3):
        t = time.perf_counter()
        result = derived.derive(derived.inputs_of(live, values))
        took = time.perf_counter() - t
        assert result.slice is not None and result.chi2_red is not None, result.summary()
        shaded = sum(v is not None for v in result.slice["f"])
        print(f"| {k + 1} | {took:.2f} | {result.used:,} | {result.chi2_red:.3g} | {shaded:,} |")
    live.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--pace", type=float, default=0.1, help="part 1: s per target")
    parser.add_argument("--samples", type=int, default=1_000_000, help="part 2's run")
    parser.add_argument("--targets", type=int, default=5_000, help="part 3's plan")
    parser.add_argument("--screenshot", type=Path, help="save the page of part 1's run")
    args = parser.parse_args()
    print(describe())
    with tempfile.TemporaryDirectory() as tmp:
        latency(Path(tmp), args.pace, args.screenshot)
    if args.screenshot is not None and args.screenshot.exists():
        _report.figure(args.screenshot, "the page of a run being acquired, 1280 px wide")
        wide = args.screenshot.with_name(f"{args.screenshot.stem}-1920{args.screenshot.suffix}")
        if wide.exists():
            _report.figure(wide, "the same page 1920 px wide")
    with tempfile.TemporaryDirectory() as tmp:
        opening(Path(tmp), args.samples)
    with tempfile.TemporaryDirectory() as tmp:
        overhead(Path(tmp), args.targets, args.repeat)


if __name__ == "__main__":
    _report.run(main, __file__, __doc__, title="Watching a run live")
