"""Bus hygiene before the first move of a run on Dynamixel motors (hardware, and the
rehearsal's real drivers on emulated ports): the checks of `drivers.dynamixel.hygiene`
on the rig's port, rate and axes. A problem (a port this user cannot open, a motor that
does not answer or is not the one the rig file expects, a Status Return Level or Return
Delay Time the driver cannot work with) refuses the run, one line each; a warning (the
USB adapter's latency timer above 1 ms) is shown and the run goes on.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence
from typing import IO

from drivers.dynamixel.bus import DynamixelBus
from drivers.dynamixel.hygiene import Finding, blocking, check_bus
from gonio.errors import GonioError
from gonio.rig import Rig
from gonio.workflows.backends import Backend

__all__ = ["Finding", "backend_findings", "rig_findings", "warn"]


def rig_findings(rig: Rig, port: str | None = None) -> list[Finding]:
    """The checks on the rig's bus (on ``port`` if given: a rehearsal's pty), with the
    rig's retries per transaction (those its run will have)."""
    bus = rig.spec.bus
    return check_bus(port or bus.port, bus.baud, rig.bus_axes(), retries=bus.retries)


def backend_findings(rig: Rig, backend: Backend) -> list[Finding]:
    """The checks on a backend's Dynamixel bus (none for simulated motors); `GonioError`
    with one line per problem if any blocks the run. Nothing moves."""
    bus = backend.devices.bus
    if not isinstance(bus, DynamixelBus):
        return []
    findings = rig_findings(rig, bus.port)
    problems = blocking(findings)
    if len(problems) == 1:
        raise GonioError(problems[0].text)
    if problems:
        where = rig.source or "rig"
        lines = "\n".join(f"  {f.text}" for f in problems)
        raise GonioError(
            f"{len(problems)} problems with the motors of {where} (nothing moved):\n{lines}"
        )
    return findings


def warn(findings: Sequence[Finding], out: IO[str] | None = None) -> None:
    """Show the warnings among ``findings`` on ``out`` (stderr), one line each."""
    for finding in findings:
        if finding.level == "warning":
            print(f"gonio: warning: {finding.text}", file=out or sys.stderr, flush=True)
