"""The peers' own commands (``python -m sim.dynamixel.emulator``, ``python -m
sim.serial_photometer``) load the byte-level peers, not the virtual instrument: the
suite starts them as processes, and the instrument's physics (scipy) would cost each a
half second of imports."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]

#: What a peer's command never needs.
HEAVY = ("sim.virtual", "scipy", "numba", "gonio.planner", "gonio.store")


def test_the_peers_commands_load_no_virtual_instrument() -> None:
    code = (
        "import json, sys\n"
        "import sim.dynamixel.emulator.__main__, sim.serial_photometer.__main__\n"
        "print(json.dumps(sorted(m for m in json.loads(sys.argv[1]) if m in sys.modules)))\n"
    )
    r = subprocess.run(
        [sys.executable, "-c", code, json.dumps(HEAVY)],
        capture_output=True,
        text=True,
        timeout=60,
        cwd=ROOT,
    )
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout) == []
