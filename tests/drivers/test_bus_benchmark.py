"""benchmarks/bus.py counts the bytes a poll really puts on the line."""

from __future__ import annotations

import importlib.util
from collections.abc import Callable
from pathlib import Path
from types import ModuleType

from drivers.dynamixel.bus import DynamixelBus
from sim.peers.dynamixel.emulator import DxlEmulator

BENCHMARK = Path(__file__).resolve().parents[2] / "benchmarks" / "bus.py"


def load_benchmark() -> ModuleType:
    spec = importlib.util.spec_from_file_location("bus_benchmark", BENCHMARK)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_theoretical_minimum_counts_the_bytes_of_a_poll(
    emulator: Callable[..., DxlEmulator], latency_timer: int
) -> None:
    bench = load_benchmark()
    emu = emulator(ids=(1, 2, 3, 4))
    with DynamixelBus(emu.path, bench.AXES, latency_ms=latency_timer) as bus:
        bus.positions()
        emu.reset_stats()
        bus.positions()
        stats = emu.stats
    # SYNC_READ: header 4, ID, LEN 2, INST, address 2, length 2, 4 IDs, CRC 2 = 18 bytes;
    # each status: 11 bytes around 14 data bytes (Moving … Present Position).
    assert (stats.bytes_in, stats.bytes_out) == (18, 4 * 25)
    assert stats.bytes_in + stats.bytes_out == bench.POLL_BYTES
