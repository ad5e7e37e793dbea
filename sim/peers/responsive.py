"""Keep an in-process device server responsive to a host that busy-waits.

The ROBOTIS SDK polls its port in a tight loop while it waits for a reply. When the
emulated device serves from another thread of the same process, every hand-off of the
GIL to the server (waking on the request, each write of a reply) waits for the
interpreter's switch interval, 5 ms by default. While any server runs, the interval
is lowered to `SERVING_SWITCH_INTERVAL_S`; the previous interval comes back when the
last server stops. `benchmarks/handoff.py` measures a 4-motor SYNC_READ both ways.
"""

from __future__ import annotations

import sys
import threading

#: The interpreter's switch interval while an in-process server runs (s).
SERVING_SWITCH_INTERVAL_S = 0.0002

_lock = threading.Lock()
_serving = 0
_previous = 0.0


def serving_started() -> None:
    """A server thread started: lower the switch interval (counted, re-entrant)."""
    global _serving, _previous
    with _lock:
        if _serving == 0:
            _previous = sys.getswitchinterval()
            sys.setswitchinterval(min(_previous, SERVING_SWITCH_INTERVAL_S))
        _serving += 1


def serving_stopped() -> None:
    """A server thread stopped: restore the interval once none is left."""
    global _serving
    with _lock:
        if _serving == 0:
            return
        _serving -= 1
        if _serving == 0:
            sys.setswitchinterval(_previous)
