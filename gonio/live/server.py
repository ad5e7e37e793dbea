"""``gonio serve``: the local web page of the runs in a folder (or of one run file), as
JSON endpoints over the read model (`gonio.live.model`) and one static page whose
script, style sheet and plotting library (Plotly.js) are served from the installed
packages (no CDN: a lab PC has no internet).

Endpoints (``RUN``: a run file's path relative to the served folder):

- ``GET /`` and ``GET /run/RUN``: the page (the same bytes for everyone; it holds no
  data); ``GET /static/…``: its script and style sheet; ``GET /vendor/plotly.min.js``:
  the Plotly.js bundle the installed ``plotly`` package ships (the page's plots);
- ``GET /api/runs``: the runs under the served path, their state, progress and ETA (a
  run file that cannot be read: ``unreadable`` and the one line why);
- ``GET /api/overview?run=RUN``: a run's figures (`gonio.live.views.overview`);
- ``GET /api/points?run=RUN``: its samples, decimated, with their residuals against the
  fit and the reconstruction's slice that `gonio.live.derived` made last
  (`gonio.live.views.points`);
- a run file that cannot be read or shown: HTTP 422, ``{"error": …}`` naming the file;
- ``POST /api/control?run=RUN`` with ``{"action": "pause" | "resume" | "stop"}``: a
  request the acquiring process reads between targets (`gonio.acquire.control`).

Security (docs/how-to/watch-a-run.md): the server binds 127.0.0.1 unless told
otherwise and then answers only requests addressed to a loopback name (a page of
another site cannot reach it through DNS rebinding). A control request needs the run's
token (written owner-only beside the run file by ``gonio acquire``) in the
``X-Gonio-Token`` header, compared in constant time; no cookie is ever set, so no
cross-site request carries it, and no CORS header is sent, so no other origin's script
reads an answer or sends the header. On a non-loopback host the server refuses to start
without a token, and then every ``/api/`` request needs it. Only run files under the
served path are reachable; control requests are rate-limited per run and journaled by
the acquiring process (who asked, when).
"""

from __future__ import annotations

import contextlib
import hmac
import importlib.util
import ipaddress
import json
import threading
import time
from collections.abc import AsyncIterator, Awaitable, Callable, MutableMapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from starlette.applications import Starlette
from starlette.requests import Request
from starlette.responses import FileResponse, JSONResponse, Response
from starlette.routing import Mount, Route
from starlette.staticfiles import StaticFiles

from gonio.acquire import control
from gonio.errors import GonioError
from gonio.live import derived
from gonio.live.model import LiveRun
from gonio.live.views import overview, points, values

STATIC = Path(__file__).resolve().parent / "static"
#: Where the installed ``plotly`` package keeps the Plotly.js bundle it ships.
PLOTLY_JS = ("package_data", "plotly.min.js")
#: The header that carries a token (never a cookie, never the URL).
TOKEN_HEADER = "x-gonio-token"
#: How often a run file is read again at most (s): every client shares the reads.
REFRESH_S = 0.5
#: Control requests per run: a burst of ``BURST``, then one per ``EVERY_S`` seconds.
BURST = 5
EVERY_S = 2.0
#: The most run files a folder's listing shows.
MAX_RUNS = 200

Scope = MutableMapping[str, Any]
Receive = Callable[[], Awaitable[MutableMapping[str, Any]]]
Send = Callable[[MutableMapping[str, Any]], Awaitable[None]]
ASGIApp = Callable[[Scope, Receive, Send], Awaitable[None]]


def plotly_js() -> Path:
    """The Plotly.js bundle the installed ``plotly`` package ships (the page's plots,
    served from here: no CDN); `GonioError` (one line) when it is not installed."""
    spec = importlib.util.find_spec("plotly")  # found, not imported
    for folder in (spec.submodule_search_locations or []) if spec else []:
        path = Path(folder).joinpath(*PLOTLY_JS)
        if path.is_file():
            return path
    raise GonioError("gonio serve needs Plotly.js from plotly: pip install 'gonio[live]'")


def is_loopback(host: str) -> bool:
    """Whether binding ``host`` keeps the server to this machine."""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False


def _same(a: str, b: str) -> bool:
    return hmac.compare_digest(a.encode("utf-8", "replace"), b.encode("utf-8", "replace"))


class Refused(GonioError):
    """A request refused: its HTTP status and one line why."""

    def __init__(self, status: int, message: str) -> None:
        super().__init__(message)
        self.status = status


@dataclass
class _Entry:
    live: LiveRun
    lock: threading.Lock = field(default_factory=threading.Lock)
    read_at: float = 0.0
    #: Per view: the version it was made at, the view and its JSON.
    cache: dict[str, tuple[tuple[int, int], dict[str, Any], bytes]] = field(default_factory=dict)
    bucket: float = BURST
    bucket_at: float = field(default_factory=time.monotonic)


@dataclass
class Served:
    """What one ``gonio serve`` serves: ``root`` (a folder, or one run file), whether it
    is bound to a loopback address only, and the server's ``token`` (None: the runs'
    own tokens only)."""

    root: Path
    loopback: bool = True
    token: str | None = None
    refit_every: int = derived.EVERY
    fit_model: str = derived.MODEL
    _runs: dict[Path, _Entry] = field(default_factory=dict)
    _lock: threading.Lock = field(default_factory=threading.Lock)
    _deriver: derived.Deriver = field(init=False)

    def __post_init__(self) -> None:
        self._deriver = derived.Deriver(values, every=self.refit_every, spec=self.fit_model)
        self.root = self.root.resolve()
        if not self.loopback and not self.token:
            raise GonioError(
                "gonio serve: a non-loopback --host needs a token (--token-file FILE); "
                "every request must then carry it"
            )

    def close(self) -> None:
        """Stop the worker that derives fits and slices (the server's end)."""
        self._deriver.close()

    # -- paths ---------------------------------------------------------------------------
    def run_path(self, name: str | None) -> Path:
        """The run file ``name`` names under the served path (`Refused` 404 otherwise:
        missing, outside it, or not a run file)."""
        if not name or "\x00" in name:
            raise Refused(404, "no such run")
        if self.root.is_file():
            if name != self.root.name:
                raise Refused(404, "no such run")
            return self.root
        path = (self.root / name).resolve()
        if not path.is_relative_to(self.root) or path.suffix != ".sqlite" or not path.is_file():
            raise Refused(404, "no such run")
        return path

    def names(self) -> list[str]:
        """The run files under the served path (a folder and its subfolders, by name;
        not a link out of it, which `run_path` refuses)."""
        if self.root.is_file():
            return [self.root.name]
        found = sorted(
            p
            for p in self.root.rglob("*.sqlite")
            if p.is_file() and p.resolve().is_relative_to(self.root)
        )
        return [str(p.relative_to(self.root)) for p in found[:MAX_RUNS]]

    def name_of(self, path: Path) -> str:
        return path.name if self.root.is_file() else str(path.relative_to(self.root))

    # -- runs ----------------------------------------------------------------------------
    def entry(self, path: Path) -> _Entry:
        """The run's entry; a new one when the file was replaced (a run started again
        over it with ``--overwrite``)."""
        with self._lock:
            entry = self._runs.get(path)
            if entry is not None and entry.live.replaced():
                entry = None  # the old one closes when no request holds it any more
            if entry is None:
                entry = self._runs[path] = _Entry(LiveRun(path))
                entry.read_at = time.monotonic()
        return entry

    def view(self, path: Path, which: str) -> bytes:
        """The JSON of ``which`` view of a run (``overview`` or ``points``), read again
        at most every `REFRESH_S` and made once per change, whoever asks; `GonioError`
        (one line naming the file) if the run file cannot be read or shown."""
        return self._made(path, which)[2]

    def _made(self, path: Path, which: str) -> tuple[tuple[int, int], dict[str, Any], bytes]:
        """`view`'s cache entry: its version, the view and its JSON."""
        try:
            return self._view(path, which)
        except GonioError as exc:
            if path.name in str(exc):
                raise
            raise GonioError(f"{path}: {exc}") from None

    def _view(self, path: Path, which: str) -> tuple[tuple[int, int], dict[str, Any], bytes]:
        entry = self.entry(path)
        with entry.lock:
            now = time.monotonic()
            if now - entry.read_at >= REFRESH_S:
                entry.live.refresh()
                entry.read_at = now
            if which == "points":  # the runs whose samples someone looks at
                self._deriver.ask(str(path), entry.live)
            version = (entry.live.version, self._deriver.generation)
            cached = entry.cache.get(which)
            if cached is None or cached[0] != version:
                if which == "overview":
                    value = overview(entry.live)
                    value["derived"] = self._deriver.generation
                else:
                    value = points(entry.live, derived=self._deriver.latest(str(path)))
                value["name"] = self.name_of(path)
                text = json.dumps(value, allow_nan=False, separators=(",", ":")).encode()
                cached = entry.cache[which] = (version, value, text)
        return cached

    def listing(self) -> list[dict[str, Any]]:
        out = []
        for name in self.names():
            path = self.run_path(name)
            try:
                o = self._made(path, "overview")[1]
            except GonioError as exc:
                out.append({"name": name, "state": "unreadable", "error": str(exc)})
                continue
            keys = ("state", "plan", "targets", "measured", "progress", "eta_s", "fly")
            out.append({"name": name, **{k: o[k] for k in keys}})
        return out

    # -- access --------------------------------------------------------------------------
    def check_read(self, request: Request, path: Path | None) -> None:
        """On a non-loopback bind every API request needs a token: the server's, or the
        run's for that run's views."""
        if self.loopback:
            return
        given = request.headers.get(TOKEN_HEADER, "")
        if self.token and _same(given, self.token):
            return
        run_token = None if path is None else control.read_token(path)
        if run_token and _same(given, run_token):
            return
        raise Refused(401, "this server needs a token (the X-Gonio-Token header)")

    def check_control(self, request: Request, path: Path) -> None:
        """A control request: same origin, JSON, the run's token (or the server's), within
        the rate limit."""
        origin = request.headers.get("origin")
        host = request.headers.get("host", "")
        if origin is not None and origin.split("://", 1)[-1] != host:
            raise Refused(403, "a control request from another origin is refused")
        if request.headers.get("content-type", "").split(";")[0].strip() != "application/json":
            raise Refused(415, "a control request is JSON (Content-Type: application/json)")
        given = request.headers.get(TOKEN_HEADER, "")
        run_token = control.read_token(path)
        ok = bool(given) and (
            (run_token is not None and _same(given, run_token))
            or (self.token is not None and _same(given, self.token))
        )
        if not ok:
            raise Refused(403, "control needs the run's token (the X-Gonio-Token header)")
        entry = self.entry(path)
        with entry.lock:
            now = time.monotonic()
            entry.bucket = min(BURST, entry.bucket + (now - entry.bucket_at) / EVERY_S)
            entry.bucket_at = now
            if entry.bucket < 1.0:
                raise Refused(429, "too many control requests; wait a few seconds")
            entry.bucket -= 1.0


class _Guard:
    """ASGI middleware: on a loopback bind, only requests addressed to a loopback name
    (the Host header), so a page of another site cannot reach the server through DNS
    rebinding; refused requests are answered as JSON ``{"error": …}``."""

    def __init__(self, app: ASGIApp, served: Served) -> None:
        self.app = app
        self.served = served

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] == "http" and self.served.loopback:
            headers = dict(scope.get("headers") or [])
            host = headers.get(b"host", b"").decode("latin-1")
            name = host.rsplit(":", 1)[0] if not host.endswith("]") else host
            if not is_loopback(name):
                response = JSONResponse({"error": "unknown host"}, status_code=403)
                await response(scope, receive, send)
                return
        await self.app(scope, receive, send)


#: The Plotly.js bundle changes only with the installed package: checked once an hour.
_CACHED = {"Cache-Control": "max-age=3600"}


def _who(request: Request) -> str:
    client = request.client.host if request.client else "unknown"
    agent = request.headers.get("user-agent", "")[:80]
    return f"{client} via gonio serve" + (f" ({agent})" if agent else "")


def app(served: Served) -> ASGIApp:
    """The ASGI application of ``served``."""

    def refused(exc: Refused) -> JSONResponse:
        return JSONResponse({"error": str(exc)}, status_code=exc.status)

    def page(request: Request) -> Response:
        return FileResponse(STATIC / "index.html", headers={"Cache-Control": "no-cache"})

    plotly = plotly_js()

    def script(request: Request) -> Response:
        return FileResponse(plotly, media_type="text/javascript", headers=_CACHED)

    def runs(request: Request) -> Response:
        try:
            served.check_read(request, None)
            return JSONResponse({"runs": served.listing(), "single": served.root.is_file()})
        except Refused as exc:
            return refused(exc)

    def view(which: str) -> Callable[[Request], Response]:
        def endpoint(request: Request) -> Response:
            try:
                path = served.run_path(request.query_params.get("run"))
                served.check_read(request, path)
                body = served.view(path, which)
            except Refused as exc:
                return refused(exc)
            except GonioError as exc:
                return JSONResponse({"error": str(exc)}, status_code=422)
            return Response(body, media_type="application/json")

        return endpoint

    async def post_control(request: Request) -> Response:
        try:
            path = served.run_path(request.query_params.get("run"))
            served.check_read(request, path)
            served.check_control(request, path)
            try:
                body = json.loads(await request.body())
            except ValueError:
                raise Refused(400, 'expected a JSON body {"action": …}') from None
            action = body.get("action") if isinstance(body, dict) else None
            if action not in control.ACTIONS:
                raise Refused(400, f"action: expected one of {', '.join(control.ACTIONS)}")
            entry = served.entry(path)
            with entry.lock:
                entry.live.refresh()
                if not entry.live.writing:
                    raise Refused(409, "the run is not being acquired now")
            posted = control.post_request(path, action, _who(request))
        except Refused as exc:
            return refused(exc)
        return JSONResponse({"posted": posted.id, "action": posted.action}, status_code=202)

    routes = [
        Route("/", page),
        Route("/run/{name:path}", page),
        Route("/api/runs", runs),
        Route("/api/overview", view("overview")),
        Route("/api/points", view("points")),
        Route("/api/control", post_control, methods=["POST"]),
        Route("/vendor/plotly.min.js", script),
        Mount("/static", StaticFiles(directory=STATIC), name="static"),
    ]

    @contextlib.asynccontextmanager
    async def lifespan(_: Starlette) -> AsyncIterator[None]:
        try:
            yield
        finally:  # SIGTERM or Ctrl-C: the server shuts down, its worker with it
            served.close()

    return _Guard(Starlette(routes=routes, lifespan=lifespan), served)
