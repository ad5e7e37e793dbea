"""Where a sweep's combinations run: in this process (one job), on a local process pool
(`concurrent.futures.ProcessPoolExecutor`, the default), or on a Dask cluster
(`dask.distributed`, the optional ``distributed`` extra) given its scheduler's address.
Each finished row is handed to ``done`` in this process as it arrives (in the order
they finish), so the caller can store it at once; `gonio.tradeoff.runner.run` makes the
same row wherever it runs.

The pool's workers are forked from a server process that imported the runner once
(``forkserver`` with the runner preloaded): a worker starts in milliseconds, and no
thread of this process is forked. Dask workers need gonio installed (the same version);
a task carries its sweep's file bytes, so they need none of its files.
"""

from __future__ import annotations

import asyncio
import importlib
import ipaddress
import multiprocessing
import re
from collections.abc import Callable, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from typing import Any

from gonio import tradeoff  # its face: the runner (planner, simulator) loads when a task runs
from gonio.config import ConfigError, excerpt
from gonio.tradeoff.grid import Task

Done = Callable[[dict[str, Any]], None]

#: A scheduler's address: [PROTOCOL://]HOST:PORT (an IPv6 host in brackets).
ADDRESS = re.compile(r"([a-z][a-z0-9+.-]*://)?(\[[0-9a-fA-F:.]+\]|[^\s/:\[\]]+):[0-9]{1,5}")
#: Seconds to wait for a Dask scheduler to answer (`run_dask`'s ``timeout_s``).
CONNECT_TIMEOUT_S = 30.0
#: Tasks queued ahead per worker of the local pool (a killed sweep loses what is queued
#: too: it is in flight).
AHEAD = 2


def run_here(tasks: Sequence[Task], done: Done) -> None:
    """One after the other in this process."""
    for task in tasks:
        done(tradeoff.runner.run(task))


def run_local(tasks: Sequence[Task], jobs: int, done: Done) -> None:
    """On ``jobs`` local worker processes, at most `AHEAD` tasks queued per worker."""
    context = multiprocessing.get_context("forkserver")
    context.set_forkserver_preload(["gonio.tradeoff.runner"])
    pending: set[Future[dict[str, Any]]] = set()
    queue = iter(tasks)
    with ProcessPoolExecutor(max_workers=jobs, mp_context=context) as pool:
        try:
            while True:
                for task in queue:
                    pending.add(pool.submit(tradeoff.runner.run, task))
                    if len(pending) >= AHEAD * jobs:
                        break
                if not pending:
                    return
                finished, pending = wait(pending, return_when=FIRST_COMPLETED)
                for future in finished:
                    done(future.result())
        except BaseException:
            pool.shutdown(wait=False, cancel_futures=True)
            raise


def check_address(scheduler: str) -> str:
    """``scheduler`` if it can be a scheduler's address: [PROTOCOL://]HOST:PORT with a port
    in 1…65535 and, where the host is written as an IP address, a valid one; else
    `ConfigError` (at once, not after `CONNECT_TIMEOUT_S`)."""
    match = ADDRESS.fullmatch(scheduler)
    if match is None:
        raise ConfigError(f"--scheduler {excerpt(scheduler)}: expected an address tcp://HOST:PORT")
    host, port = match.group(2), int(scheduler.rsplit(":", 1)[1])
    if not 1 <= port <= 65535:
        raise ConfigError(f"--scheduler {scheduler}: port {port}: expected 1…65535")
    written_as_ip = host.startswith("[") or all(part.isdigit() for part in host.split("."))
    if written_as_ip:
        try:
            ipaddress.ip_address(host.strip("[]"))
        except ValueError:
            raise ConfigError(f"--scheduler {scheduler}: {host} is not an IP address") from None
    return scheduler


def run_dask(
    tasks: Sequence[Task], scheduler: str, done: Done, *, timeout_s: float | None = None
) -> None:
    """On the Dask cluster whose scheduler is at ``scheduler`` (``tcp://HOST:PORT``),
    once it answered within ``timeout_s`` seconds (default `CONNECT_TIMEOUT_S`;
    `check_scheduler`)."""
    check_address(scheduler)
    timeout = CONNECT_TIMEOUT_S if timeout_s is None else timeout_s
    try:  # (untyped: used through Any)
        distributed: Any = importlib.import_module("distributed")
    except ImportError:
        raise ConfigError(
            "--scheduler needs dask.distributed: pip install 'gonio[distributed]'"
        ) from None
    check_scheduler(scheduler, timeout)
    try:
        client = distributed.Client(scheduler, timeout=timeout, set_as_default=False)
    except (OSError, TimeoutError, ValueError, MemoryError) as exc:
        raise ConfigError(f"--scheduler {scheduler}: cannot reach the scheduler: {exc}") from None
    with client:
        futures = client.map(tradeoff.runner.run, list(tasks), pure=False)
        try:
            for future in distributed.as_completed(futures, loop=client.loop):
                done(future.result())
        except BaseException:
            client.cancel(futures)
            raise


def check_scheduler(scheduler: str, timeout_s: float) -> None:
    """`ConfigError` (one line) unless a Dask scheduler at ``scheduler`` answers its
    identity within ``timeout_s`` seconds (s), all told: connecting, the handshake and
    the answer. `distributed.Client`'s own timeout covers only the connection: a peer
    that accepts and never speaks holds it forever, and one that answers with other
    bytes can make it allocate what they say (both refused here)."""
    comm: Any = importlib.import_module("distributed.comm")

    async def identity() -> Any:
        channel = await comm.connect(scheduler, timeout=timeout_s)
        try:
            await channel.write({"op": "identity", "reply": True})
            return await channel.read()
        finally:
            channel.abort()

    async def bounded() -> Any:
        return await asyncio.wait_for(identity(), timeout_s)

    why = None
    try:
        answer = asyncio.run(bounded())
    except TimeoutError:
        why = f"no answer within {timeout_s:g} s"
    except MemoryError:  # a length field of another protocol's bytes
        why = "it answered with bytes that are not Dask's protocol"
    except (OSError, ValueError, EOFError) as exc:
        why = " ".join(str(exc).split())[:200] or type(exc).__name__
    except Exception as exc:  # a peer speaking another protocol: whatever its bytes raise
        why = f"not a Dask scheduler ({type(exc).__name__})"
    else:
        if not (isinstance(answer, dict) and answer.get("type") == "Scheduler"):
            why = "it answered, but not as a Dask scheduler"
    if why is not None:
        raise ConfigError(f"--scheduler {scheduler}: cannot reach the scheduler: {why}")
