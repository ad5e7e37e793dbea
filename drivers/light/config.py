"""`SerialLightConfig`: how to talk to a serial light switch (no port is opened here:
the rig file is checked against it without the serial stack)."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass


@dataclass(frozen=True)
class SerialLightConfig:
    """How to talk to one serial light switch (regular expressions match anywhere in a
    received line unless anchored; times in seconds)."""

    port: str
    baud: int = 9600
    on: str = "ON"
    off: str = "OFF"
    ack: str | None = r"^OK\b"
    error_reply: str | None = r"^ERR"
    query: str | None = None
    on_reply: str | None = None
    off_reply: str | None = None
    line_ending: str = "\n"
    timeout_s: float = 1.0
    retries: int = 1
    warmup_s: float = 0.0

    def __post_init__(self) -> None:
        for name in ("ack", "error_reply", "on_reply", "off_reply"):
            pattern = getattr(self, name)
            if pattern is None:
                continue
            try:
                re.compile(pattern)
            except re.error as exc:
                raise ValueError(f"{name}: not a regular expression ({exc}): {pattern!r}") from None
        if not (self.on.strip() and self.off.strip()):
            raise ValueError("on and off must be non-empty commands")
        if (self.query is None) != (self.on_reply is None) or (self.query is None) != (
            self.off_reply is None
        ):
            raise ValueError("query, on_reply and off_reply go together (all or none)")
        if self.line_ending not in ("\n", "\r\n", "\r"):
            raise ValueError(f"line_ending must be \\n, \\r\\n or \\r, got {self.line_ending!r}")
        if not (0 < self.timeout_s < math.inf) or not (0 <= self.warmup_s < math.inf):
            raise ValueError("timeout_s must be > 0 and warmup_s ≥ 0, both finite")
        if self.retries < 0 or self.baud <= 0:
            raise ValueError("retries must be ≥ 0 and baud > 0")
