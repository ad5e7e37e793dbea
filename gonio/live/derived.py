"""What ``gonio serve`` derives from a run's samples as they land: a model fitted to
them (`gonio.reconstruct.fit`, as ``gonio fit`` fits) and the reconstruction's slice
in the plan's coordinates (`gonio.reconstruct.reconstruct` by ``rbf``, as
``gonio evaluate --method rbf`` reconstructs), recomputed every ``every`` new samples
and once more when the run ends, never per request.

Bounded, so the acquisition does not feel it (docs/results/live.md): at most `SAMPLES`
samples (evenly spaced in commit order, the newest among them) are fitted, from one
start, and reconstructed; the slice is `RESOLUTION`² points; the work runs in one worker
process of the server (`Deriver`) at the lowest CPU priority (nice 19), which ends with
the server however it ends, one job per run at a time, while requests are answered at
once from what was derived last. The residual of a shown sample is (f − f_fit)/σ,
evaluated when the samples' view is made.
"""

from __future__ import annotations

import math
import multiprocessing
import os
import threading
import time
import weakref
from collections.abc import Callable
from concurrent.futures import Future, ProcessPoolExecutor
from dataclasses import dataclass, field
from multiprocessing.process import BaseProcess
from typing import Any

import numpy as np

from gonio import params
from gonio.analysis import Measured
from gonio.brdf import BRDF
from gonio.errors import GonioError
from gonio.live.model import LiveRun
from gonio.reconstruct import fit, reconstruct
from gonio.rig import Rig
from gonio.types import FloatArray

Values = Callable[[LiveRun, np.ndarray], tuple[FloatArray, FloatArray, str]]

#: New samples between two fits and reconstructions (``gonio serve --refit-every``).
EVERY = 200
#: The model family fitted (``gonio serve --fit-model``; docs/explanations/fitting.md).
MODEL = "lambert+ggx"
#: At most this many samples are fitted and reconstructed.
SAMPLES = 1500
#: Points per side of the slice.
RESOLUTION = 48
#: Fewer samples than this are not fitted nor reconstructed yet.
MINIMUM = 20
#: How often the worker looks whether its server is still there (s).
ORPHAN_CHECK_S = 0.5


@dataclass(frozen=True)
class Result:
    """What was derived at ``measured`` samples: the fitted model (None, and ``error``
    one line, when the fit failed), its spec and χ²_red, and the slice (JSON values;
    None with ``slice_error`` when the reconstruction failed)."""

    measured: int
    used: int
    spec: str
    model: BRDF | None
    chi2_red: float | None
    error: str | None
    slice: dict[str, Any] | None
    slice_error: str | None

    def summary(self) -> dict[str, Any]:
        return {
            "measured": self.measured,
            "used": self.used,
            "model": self.spec,
            "chi2_red": rounded(self.chi2_red) if self.chi2_red is not None else None,
            "error": self.error,
            "slice_error": self.slice_error,
        }


def rounded(v: float) -> float | None:
    """``v`` to 5 significant digits (None if not finite), as the page shows it."""
    return float(f"{v:.5g}") if math.isfinite(v) else None


def pick(n: int, limit: int) -> np.ndarray:
    """At most ``limit`` of ``n`` indices, evenly spaced, the last one among them."""
    if n <= limit:
        return np.arange(n)
    return np.unique(np.linspace(0, n - 1, limit).round().astype(np.int64))


@dataclass(frozen=True)
class Inputs:
    """What `derive` works on, copied out of the run (it crosses to another process):
    the samples' directions, BRDF values and 1σ, the plan's parametrization, whether
    it is isotropic, the rig, the run's name, how many samples it held, the family."""

    wi: FloatArray
    wo: FloatArray
    f: FloatArray
    sigma: FloatArray
    parametrization: str
    isotropic: bool
    rig: Rig
    source: str
    measured: int
    spec: str = MODEL
    resolution: int = RESOLUTION


def inputs_of(
    live: LiveRun, values: Values, *, spec: str = MODEL, samples: int = SAMPLES
) -> Inputs:
    """At most ``samples`` of the run's samples (evenly spaced), with their BRDF and 1σ
    (``values``: `gonio.live.views.values`)."""
    index = pick(len(live.samples["target"]), samples)
    f, sigma, _ = values(live, index)
    s = live.samples
    wi = np.stack([s[f"wi_{c}"][index] for c in "xyz"], axis=1)
    wo = np.stack([s[f"wo_{c}"][index] for c in "xyz"], axis=1)
    keep = np.isfinite(f) & np.isfinite(sigma) & (f >= 0) & (wi[:, 2] >= 0) & (wo[:, 2] >= 0)
    info = live.info
    return Inputs(
        wi[keep],
        wo[keep],
        f[keep],
        np.maximum(sigma[keep], 0.0),
        info.parametrization,
        info.isotropic,
        info.rig,
        str(live.path),
        live.measured,
        spec,
    )


def derive(inputs: Inputs) -> Result:
    """Fit the family to the samples (one start) and reconstruct them by ``rbf``; a
    failure of either is its one line in the `Result`."""
    measured = Measured(
        wi=inputs.wi,
        wo=inputs.wo,
        f=inputs.f,
        sigma=inputs.sigma,
        parametrization=inputs.parametrization,
        isotropic=inputs.isotropic,
        rig=inputs.rig,
        scene_text=None,
        band="luminance",
        source=inputs.source,
    )
    model, chi2, error = None, None, None
    try:
        result = fit(measured, inputs.spec, starts=1, seed=0)
        model, chi2 = result.model, result.chi2_red
    except GonioError as exc:
        error = str(exc)
    picture, slice_error = None, None
    try:
        picture = _slice(measured, inputs.resolution)
    except GonioError as exc:
        slice_error = str(exc)
    used = len(measured)
    return Result(inputs.measured, used, inputs.spec, model, chi2, error, picture, slice_error)


def _slice(measured: Measured, n: int) -> dict[str, Any]:
    """The ``rbf`` reconstruction on an n × n grid over the plan's first two coordinates
    (their whole range), the others at the middle of theirs: JSON values (f in sr⁻¹,
    None outside the domain or where the samples do not support it)."""
    rec = reconstruct(measured, method="rbf")
    p = params.get(measured.parametrization)
    names = p.iso_names if measured.isotropic else p.names
    bounds = np.asarray(p.iso_bounds if measured.isotropic else p.bounds, dtype=np.float64)
    x = np.linspace(bounds[0, 0], bounds[0, 1], n)
    y = np.linspace(bounds[1, 0], bounds[1, 1], n)
    gx, gy = np.meshgrid(x, y, indexing="xy")
    mid = bounds[2:].mean(axis=1)
    grid = np.concatenate(
        [gx[..., None], gy[..., None], np.broadcast_to(mid, (*gx.shape, len(mid)))], axis=-1
    ).reshape(-1, len(bounds))
    valid = p.valid_iso(grid) if measured.isotropic else p.valid(grid)
    out = np.full(len(grid), np.nan)
    if valid.any():
        wi, wo = p.inverse_iso(grid[valid]) if measured.isotropic else p.inverse(grid[valid])
        f, _, ok = rec.evaluate(wi, wo)
        out[valid] = np.where(ok, np.asarray(f, np.float64).reshape(-1), np.nan)
    return {
        "names": list(names[:2]),
        "fixed": {str(k): float(v) for k, v in zip(names[2:], mid, strict=True)},
        "x": [float(bounds[0, 0]), float(bounds[0, 1])],
        "y": [float(bounds[1, 0]), float(bounds[1, 1])],
        "n": n,
        "f": [rounded(v) for v in out.tolist()],
        "samples": len(measured),
    }


def residuals(
    model: BRDF, wi: FloatArray, wo: FloatArray, f: FloatArray, sigma: FloatArray
) -> FloatArray:
    """(f − f_model)/σ per sample (NaN where σ is not positive or a value not finite)."""
    with np.errstate(invalid="ignore", divide="ignore"):
        fitted = np.asarray(model.eval(wi, wo), np.float64).reshape(-1)
        r = (f - fitted) / np.where(sigma > 0, sigma, np.nan)
    return np.asarray(r, np.float64)


def _line(exc: BaseException) -> str:
    text = str(exc) if isinstance(exc, GonioError) else f"{type(exc).__name__}: {exc}"
    return " ".join(text.split())[:300]


def _worker_start() -> None:
    """In the worker process: the lowest CPU priority (after the acquisition and the
    server), and an end of its own once its server is gone, however the server ended
    (SIGTERM, SIGKILL): it never outlives it."""
    os.nice(19)
    server = os.getppid()
    threading.Thread(target=_orphaned, args=(server,), daemon=True).start()


def _orphaned(server: int, every_s: float = ORPHAN_CHECK_S) -> None:
    while os.getppid() == server:
        time.sleep(every_s)
    os._exit(0)


@dataclass
class Deriver:
    """One worker process (spawned at the first need, at nice 19) deriving, for each run
    asked for, its `Result` every ``every`` new samples, one job per run at a time
    (module docstring). `latest` answers at once with what was derived last."""

    values: Values
    every: int = EVERY
    spec: str = MODEL
    _results: dict[str, Result] = field(default_factory=dict)
    _asked: dict[str, int] = field(default_factory=dict)  # measured when last submitted
    _running: set[str] = field(default_factory=set)
    _lock: threading.Lock = field(default_factory=threading.Lock)
    _pool: ProcessPoolExecutor | None = None
    _workers: list[BaseProcess] = field(default_factory=list)  # the pool's, to end them
    generation: int = 0  # changes whenever a result lands

    def latest(self, key: str) -> Result | None:
        with self._lock:
            return self._results.get(key)

    def ask(self, key: str, live: LiveRun) -> None:
        """Submit ``live`` (the caller holds what guards it) when it has `every` new
        samples since it was last submitted (or was never and has `MINIMUM`, or no
        process acquires it any more and it has any new one), unless its last job is
        still running."""
        with self._lock:
            last = self._asked.get(key)
            if last is not None and live.measured < last:  # the run was started again
                last = None
            if last is None:
                due = live.measured >= MINIMUM
            else:  # and once more when the run ends (completed, stopped), whatever it had
                ended = not live.writing and live.measured != last
                due = live.measured - last >= self.every or ended
            if not due or key in self._running:
                return
            self._asked[key] = live.measured
            self._running.add(key)
            if self._pool is None:
                self._pool = ProcessPoolExecutor(
                    1, mp_context=multiprocessing.get_context("spawn"), initializer=_worker_start
                )
                weakref.finalize(self, self._pool.shutdown, wait=False, cancel_futures=True)
            pool = self._pool
        try:
            before = {p.pid for p in multiprocessing.active_children()}
            future = pool.submit(derive, inputs_of(live, self.values, spec=self.spec))
            with self._lock:  # the pool starts its worker at its first job
                self._workers += [
                    p for p in multiprocessing.active_children() if p.pid not in before
                ]
        except (GonioError, RuntimeError) as exc:  # the pool broke: a new one next time
            line = _line(exc)
            self._done(key, Result(live.measured, 0, self.spec, None, None, line, None, line))
            with self._lock:
                self._pool = None
            return
        measured = live.measured
        future.add_done_callback(lambda f: self._done(key, self._result(f, measured)))

    def close(self) -> None:
        """Stop the worker: the jobs not begun are dropped, the one running ends with it
        (`gonio serve`'s end). The worker is killed, not asked: at nice 19 on a busy
        machine, a fit it is running could take minutes to reach a point where it
        would notice."""
        with self._lock:
            pool, self._pool = self._pool, None
            workers, self._workers = self._workers, []
        if pool is not None:
            pool.shutdown(wait=False, cancel_futures=True)
        for worker in workers:
            worker.kill()

    def _result(self, future: Future[Result], measured: int) -> Result:
        try:
            return future.result()
        except Exception as exc:  # the worker's failure is a line on the page, not a crash
            line = _line(exc)
            return Result(measured, 0, self.spec, None, None, line, None, line)

    def _done(self, key: str, result: Result) -> None:
        with self._lock:
            self._results[key] = result
            self._running.discard(key)
            self.generation += 1
