"""`gonio serve [RUN.sqlite | FOLDER]`: a local web page of runs that updates as samples
are committed, with pause, resume and stop of a running acquisition for whoever holds
its token (`gonio.live.server`; docs/how-to/watch-a-run.md)."""

from __future__ import annotations

import argparse
import os
import stat
from pathlib import Path

from gonio.acquire import control
from gonio.brdf import parse
from gonio.cli import arguments
from gonio.config import ConfigError
from gonio.live import LiveRun, listen
from gonio.planner import MAX_TARGETS


def port(text: str) -> int:
    """A TCP port, 1–65535."""
    value = int(text) if text.isdigit() else 0
    if not 0 < value < 65536:
        raise argparse.ArgumentTypeError(f"expected a port number 1–65535, got {text!r}")
    return value


def add_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser], help_: str) -> None:
    p = sub.add_parser(
        "serve",
        help=help_,
        description="Serve a local web page of the run files in a folder (or of one run "
        "file) that updates as samples are committed: progress, ETA, the samples on the "
        "hemisphere (coloured by value or by residual against a fit), the reconstruction's "
        "slice, the in-plane curve, the motors' health, the calibrations and the events; "
        "pause, resume and stop a running acquisition with the token it printed. "
        "Binds 127.0.0.1 unless --host says otherwise; a non-loopback --host needs "
        "--token-file, and every request must then carry that token.",
    )
    p.add_argument(
        "path",
        type=Path,
        nargs="?",
        default=Path("."),
        help="a run file, or a folder of run files (default: the current folder)",
    )
    p.add_argument("--host", default="127.0.0.1", help="the address to bind (default 127.0.0.1)")
    p.add_argument("--port", type=port, default=8765, help="the port (default 8765)")
    p.add_argument(
        "--token-file",
        type=Path,
        metavar="FILE",
        help="a file (owner-only) holding the token every request needs on a non-loopback "
        "--host; it also allows control of every served run",
    )
    p.add_argument(
        "--refit-every",
        type=_count,
        default=200,
        metavar="N",
        help="new samples between two fits of --fit-model and two reconstructions of a "
        "run's slice, done in the server at the lowest priority (default 200)",
    )
    p.add_argument(
        "--fit-model",
        default="lambert+ggx",
        metavar="SPEC",
        help="the model family fitted to a run's samples for the residuals, as gonio fit "
        "--model takes it (default lambert+ggx)",
    )
    p.set_defaults(func=cmd_serve)


def _count(text: str) -> int:
    """A whole number of samples, 1 to 1,000,000.

    The bound is `MAX_TARGETS`, the most a plan holds: a larger one would never refit."""
    return arguments.count(text, "samples", MAX_TARGETS)


def cmd_serve(args: argparse.Namespace) -> int:
    try:
        import uvicorn  # optional: the live extra

        from gonio.live import server  # optional: the live extra (Starlette)
    except ImportError:
        raise ConfigError(
            "gonio serve needs Starlette and uvicorn: pip install 'gonio[live]'"
        ) from None
    server.plotly_js()  # the page's plots: one line if plotly is missing
    path: Path = args.path
    _check_served(path)
    token = None
    if args.token_file is not None:
        token = _token_file(args.token_file)
    family, ip = listen.address(args.host)
    loopback = server.is_loopback(ip)
    if not loopback and token is None and path.is_file():
        token = control.read_token(path)  # the run's own token gates the whole server
    parse(args.fit_model)  # an unknown family: one line before anything is served
    served = server.Served(
        path,
        loopback=loopback,
        token=token,
        refit_every=args.refit_every,
        fit_model=args.fit_model,
    )
    sock = listen.listen(family, ip, args.port)
    try:
        name = args.host.strip().strip("[]")
        url = f"http://{f'[{name}]' if ':' in name else name}:{args.port}/"
        if path.is_file():
            url += f"run/{path.name}"
        print(f"serving {path} at {url} (Ctrl-C to stop)", flush=True)
        if not loopback:
            print("every request needs the token (the page takes it as #token=… in its URL)")
        config = uvicorn.Config(
            server.app(served),
            host=ip,
            port=args.port,
            log_level="warning",
            server_header=False,
            date_header=False,
        )
        uvicorn.Server(config).run(sockets=[sock])
    finally:
        sock.close()
    return 0


def _check_served(path: Path) -> None:
    """`ConfigError` (one line) unless ``path`` is a folder or a readable run file, read
    as the page reads it (`gonio.live.model.LiveRun`: the checks of
    `gonio.store.open_run`), leaving nothing beside it. A folder may hold no run yet."""
    if path.is_dir():
        return
    if not path.exists():
        raise ConfigError(f"{path}: no such run file or folder")
    if not path.is_file() or path.suffix != ".sqlite":
        raise ConfigError(f"{path}: expected a run file (.sqlite) or a folder")
    LiveRun(path).close()  # JournalError: one line naming the file


def _token_file(path: Path) -> str:
    """The token in ``path`` (`ConfigError` unless it is an owner-only file holding one
    of 16 characters or more)."""
    try:
        st = os.stat(path)
        text = path.read_text(encoding="ascii").strip()
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(f"--token-file {path}: cannot read it: {exc}") from None
    if stat.S_IMODE(st.st_mode) & 0o077:
        raise ConfigError(f"--token-file {path}: readable by others; chmod 600 it")
    if len(text) < 16:
        raise ConfigError(f"--token-file {path}: expected a token of 16 characters or more")
    return text
