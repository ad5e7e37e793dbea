"""The unmodified ROBOTIS SDK talking to the emulator over a real pty, and the CLI."""

from __future__ import annotations

import os
import re
import select
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import dynamixel_sdk as sdk
import pytest
from dynamixel_sdk import (
    COMM_RX_CORRUPT,
    COMM_RX_TIMEOUT,
    COMM_SUCCESS,
    GroupBulkRead,
    GroupBulkWrite,
    GroupSyncRead,
    GroupSyncWrite,
)

import sim.peers.dynamixel.emulator as emulator_module
from sim.clock import ManualClock
from sim.peers.dynamixel.emulator import DxlEmulator, Fault
from sim.peers.dynamixel.protocol import ALERT, StatusError

Emulator = Callable[..., DxlEmulator]
Port = Callable[..., Any]
ROOT = Path(__file__).resolve().parents[4]

GOAL, PRESENT, TORQUE, LED = 116, 132, 64, 65


def le(value: int, size: int = 4) -> list[int]:
    return list(value.to_bytes(size, "little", signed=value < 0))


def signed32(value: int) -> int:
    return value - (1 << 32) if value >= 1 << 31 else value


# -- single motors ------------------------------------------------------------------------


def test_the_sdk_sends_the_e_manual_bytes(emulator: Emulator, sdk_port: Port, ph: Any) -> None:
    """What the unmodified SDK puts on the wire, byte for byte, for the e-manual's
    example instructions (recorded by the emulator)."""
    emu = emulator(ids=(1,), record=True)
    emu.motors[1].set("present_position", 166)
    port = sdk_port(emu)
    assert ph.ping(port, 1)[1] == COMM_SUCCESS
    assert ph.read4ByteTxRx(port, 1, PRESENT)[:2] == (166, COMM_SUCCESS)
    assert ph.write4ByteTxRx(port, 1, GOAL, 512)[0] == COMM_SUCCESS
    assert ph.reboot(port, 1)[0] == COMM_SUCCESS
    sent = [data for direction, data in emu.transcript if direction == "rx"]
    assert [d.hex(" ").upper() for d in sent] == [
        "FF FF FD 00 01 03 00 01 19 4E",
        "FF FF FD 00 01 07 00 02 84 00 04 00 1D 15",
        "FF FF FD 00 01 09 00 03 74 00 00 02 00 00 CA 89",
        "FF FF FD 00 01 03 00 08 2F 4E",
    ]
    received = [data for direction, data in emu.transcript if direction == "tx"]
    assert received[1].hex(" ").upper() == "FF FF FD 00 01 08 00 55 00 A6 00 00 00 8C C0"


def test_ping_and_register_access(emulator: Emulator, sdk_port: Port, ph: Any) -> None:
    emu = emulator((1, 2))
    port = sdk_port(emu)
    assert ph.ping(port, 1) == (1020, COMM_SUCCESS, 0)
    assert ph.ping(port, 3)[1] == COMM_RX_TIMEOUT
    assert ph.write1ByteTxRx(port, 2, LED, 1) == (COMM_SUCCESS, 0)
    assert ph.read1ByteTxRx(port, 2, LED) == (1, COMM_SUCCESS, 0)
    assert ph.write2ByteTxRx(port, 2, 84, 1234) == (COMM_SUCCESS, 0)  # Position P Gain
    assert ph.read2ByteTxRx(port, 2, 84) == (1234, COMM_SUCCESS, 0)
    assert ph.write4ByteTxRx(port, 2, GOAL, 1000) == (COMM_SUCCESS, 0)
    assert ph.read4ByteTxRx(port, 2, GOAL) == (1000, COMM_SUCCESS, 0)
    assert ph.readTxRx(port, 1, 6, 2) == ([46, 1], COMM_SUCCESS, 0)  # firmware, ID


def test_error_numbers_reach_the_sdk(emulator: Emulator, sdk_port: Port, ph: Any) -> None:
    port = sdk_port(emulator((1,)))
    assert ph.write1ByteTxRx(port, 1, TORQUE, 1) == (COMM_SUCCESS, 0)
    assert ph.write1ByteTxRx(port, 1, 11, 4) == (COMM_SUCCESS, StatusError.ACCESS)  # EEPROM
    assert ph.write4ByteTxRx(port, 1, GOAL, 5000) == (COMM_SUCCESS, StatusError.DATA_LIMIT)
    assert ph.write1ByteTxRx(port, 1, LED, 7) == (COMM_SUCCESS, StatusError.DATA_RANGE)
    assert ph.write2ByteTxRx(port, 1, GOAL, 7) == (COMM_SUCCESS, StatusError.DATA_LENGTH)
    # A refused read carries no data, but the SDK slices the CRC in as "data" (and
    # read4ByteTxRx, short of bytes, raises IndexError).
    data, result, error = ph.readTxRx(port, 1, 660, 4)  # past the end of the table (661)
    assert (len(data), result, error) == (2, COMM_SUCCESS, StatusError.ACCESS)
    with pytest.raises(IndexError):
        ph.read4ByteTxRx(port, 1, 660)
    assert "out of range" in ph.getRxPacketError(StatusError.DATA_RANGE)


def test_motion_seen_through_the_sdk(
    emulator: Emulator, sdk_port: Port, ph: Any, clock: ManualClock
) -> None:
    port = sdk_port(emulator((1,)))
    ph.write1ByteTxRx(port, 1, 11, 4)  # extended position mode
    ph.write1ByteTxRx(port, 1, TORQUE, 1)
    ph.write4ByteTxRx(port, 1, 112, 100)  # Profile Velocity
    assert ph.write4ByteTxRx(port, 1, GOAL, -3000) == (COMM_SUCCESS, 0)
    assert ph.read1ByteTxRx(port, 1, 122) == (1, COMM_SUCCESS, 0)  # Moving
    clock.advance(10)
    position, result, _ = ph.read4ByteTxRx(port, 1, PRESENT)
    assert (signed32(position), result) == (-3000, COMM_SUCCESS)
    assert ph.read1ByteTxRx(port, 1, 122) == (0, COMM_SUCCESS, 0)


def test_reboot_and_factory_reset(emulator: Emulator, sdk_port: Port, ph: Any) -> None:
    emu = emulator((1, 2))
    port = sdk_port(emu)
    ph.write1ByteTxRx(port, 1, TORQUE, 1)
    assert ph.reboot(port, 1) == (COMM_SUCCESS, 0)
    assert ph.read1ByteTxRx(port, 1, TORQUE)[0] == 0
    ph.write1ByteTxRx(port, 2, 9, 0)  # Return Delay Time
    assert ph.factoryReset(port, 2, 0x01) == (COMM_SUCCESS, 0)  # all but the ID
    assert ph.read1ByteTxRx(port, 2, 9) == (250, COMM_SUCCESS, 0)
    assert ph.factoryReset(port, 2, 0x04) == (COMM_SUCCESS, StatusError.DATA_RANGE)


def test_baud_rate_change_through_the_sdk(emulator: Emulator, sdk_port: Port, ph: Any) -> None:
    emu = emulator((1,), baud=57_600)
    port = sdk_port(emu)
    assert ph.write1ByteTxRx(port, 1, 8, 3) == (COMM_SUCCESS, 0)  # 1 Mbit/s from now on
    assert ph.ping(port, 1)[1] == COMM_RX_TIMEOUT
    assert port.setBaudRate(1_000_000)
    assert ph.ping(port, 1) == (1020, COMM_SUCCESS, 0)


def test_broadcast_ping(emulator: Emulator, sdk_port: Port, ph: Any) -> None:
    # The SDK always waits its whole window (about 0.8 s at 1 Mbit/s).
    port = sdk_port(emulator((3, 1, 2), model=1030, firmware=38, baud=1_000_000))
    found, result = ph.broadcastPing(port)
    assert result == COMM_SUCCESS
    assert found == {1: [1030, 38], 2: [1030, 38], 3: [1030, 38]}


# -- groups -------------------------------------------------------------------------------


def test_sync_write_then_sync_read(
    emulator: Emulator, sdk_port: Port, ph: Any, clock: ManualClock
) -> None:
    ids = (1, 2, 3, 4)
    emu = emulator(ids)
    port = sdk_port(emu)
    torque = GroupSyncWrite(port, ph, TORQUE, 1)
    goals = GroupSyncWrite(port, ph, GOAL, 4)
    for i in ids:
        assert torque.addParam(i, [1])
        assert goals.addParam(i, le(1000 * i))
    assert torque.txPacket() == COMM_SUCCESS
    assert goals.txPacket() == COMM_SUCCESS
    # A broadcast write returns before the bus has acted: a PING is the barrier.
    assert ph.ping(port, 1)[1] == COMM_SUCCESS
    clock.advance(5)
    reader = GroupSyncRead(port, ph, PRESENT, 4)
    for i in ids:
        reader.addParam(i)
    assert reader.txRxPacket() == COMM_SUCCESS
    assert [reader.getData(i, PRESENT, 4) for i in ids] == [1000, 2000, 3000, 4000]
    assert reader.fastSyncRead() == COMM_SUCCESS
    assert [reader.getData(i, PRESENT, 4) for i in ids] == [1000, 2000, 3000, 4000]
    assert emu.stats.instructions["FAST_SYNC_READ"] == 1


def test_bulk_write_then_bulk_read(emulator: Emulator, sdk_port: Port, ph: Any) -> None:
    emu = emulator((1, 2))
    port = sdk_port(emu)
    writer = GroupBulkWrite(port, ph)
    assert writer.addParam(1, LED, 1, [1])
    assert writer.addParam(2, 84, 2, le(900, 2))
    assert writer.txPacket() == COMM_SUCCESS
    reader = GroupBulkRead(port, ph)
    assert reader.addParam(1, LED, 1)
    assert reader.addParam(2, 84, 2)
    assert reader.txRxPacket() == COMM_SUCCESS
    assert (reader.getData(1, LED, 1), reader.getData(2, 84, 2)) == (1, 900)
    emu.motors[1].set("led", 0)
    assert reader.fastBulkRead() == COMM_SUCCESS
    assert (reader.getData(1, LED, 1), reader.getData(2, 84, 2)) == (0, 900)


def test_the_sdk_does_not_stuff_what_it_sends_but_unstuffs_what_it_receives(
    emulator: Emulator, sdk_port: Port, ph: Any
) -> None:
    """dynamixel-sdk 4.x: ``txPacket`` ignores what ``addStuffing`` returns, and that is
    a new, longer list whenever stuffing is needed, so FF FF FD in the parameters goes
    out unstuffed; the emulator refuses it as corrupt (our link sends it stuffed, see
    tests/drivers/test_dynamixel_safety.py). Statuses are stuffed and the SDK reads
    them correctly."""
    emu = emulator((1,), record=True)
    port = sdk_port(emu)
    header_value = -131073 & 0xFFFFFFFF  # FF FF FD FF
    assert ph.write4ByteTxRx(port, 1, 20, header_value) == (COMM_SUCCESS, StatusError.CRC)
    sent = [data for direction, data in emu.transcript if direction == "rx"]
    assert bytes.fromhex("14 00 FF FF FD FF") in sent[-1]  # not stuffed
    assert emu.motors[1].get("homing_offset") == 0
    emu.motors[1].set("homing_offset", -131073)
    assert ph.read4ByteTxRx(port, 1, 20) == (header_value, COMM_SUCCESS, 0)
    received = [data for direction, data in emu.transcript if direction == "tx"]
    assert bytes.fromhex("FF FF FD FD FF") in received[-1]


# -- faults as the SDK sees them ----------------------------------------------------------


def test_reply_faults(emulator: Emulator, sdk_port: Port, ph: Any) -> None:
    emu = emulator((1,))
    port = sdk_port(emu)
    emu.inject(Fault.NO_REPLY, motor_id=1)
    assert ph.ping(port, 1)[1] == COMM_RX_TIMEOUT
    emu.inject(Fault.CORRUPT_CRC, motor_id=1)
    assert ph.ping(port, 1)[1] == COMM_RX_CORRUPT
    emu.inject(Fault.WRONG_ID, motor_id=1)
    assert ph.ping(port, 1)[1] == COMM_RX_TIMEOUT  # the SDK skips other IDs, then times out
    emu.inject(Fault.GARBAGE, motor_id=1)
    assert ph.ping(port, 1) == (1020, COMM_SUCCESS, 0)  # the SDK resynchronizes
    emu.inject(Fault.SILENT)
    assert ph.ping(port, 1)[1] == COMM_RX_TIMEOUT
    emu.clear_faults()
    assert ph.ping(port, 1) == (1020, COMM_SUCCESS, 0)


def test_hardware_alert(emulator: Emulator, sdk_port: Port, ph: Any) -> None:
    emu = emulator((1, 2))
    port = sdk_port(emu)
    ph.write1ByteTxRx(port, 1, TORQUE, 1)
    emu.inject(Fault.OVERLOAD, motor_id=1)
    status, result, error = ph.read1ByteTxRx(port, 1, 70)
    assert (status, result, error) == (0x20, COMM_SUCCESS, ALERT)
    assert "Hardware error" in ph.getRxPacketError(error)
    assert ph.read1ByteTxRx(port, 1, TORQUE) == (0, COMM_SUCCESS, ALERT)
    assert ph.write1ByteTxRx(port, 1, TORQUE, 1) == (COMM_SUCCESS, ALERT | StatusError.RESULT_FAIL)
    assert ph.ping(port, 2) == (1020, COMM_SUCCESS, 0)
    # Group reads drop every status's error byte: the alert does not show there.
    reader = GroupSyncRead(port, ph, 70, 1)
    reader.addParam(1)
    assert reader.txRxPacket() == COMM_SUCCESS
    assert reader.getData(1, 70, 1) == 0x20
    assert ph.reboot(port, 1) == (COMM_SUCCESS, ALERT)
    assert ph.write1ByteTxRx(port, 1, TORQUE, 1) == (COMM_SUCCESS, 0)


def test_group_reads_with_a_lost_reply(emulator: Emulator, sdk_port: Port, ph: Any) -> None:
    emu = emulator((1, 2, 3))
    port = sdk_port(emu)
    reader = GroupSyncRead(port, ph, PRESENT, 4)
    for i in (1, 2, 3):
        reader.addParam(i)
    emu.inject(Fault.NO_REPLY, motor_id=2)
    assert reader.txRxPacket() == COMM_RX_TIMEOUT
    assert not reader.isAvailable(1, PRESENT, 4)
    emu.inject(Fault.NO_REPLY, motor_id=2)
    assert reader.fastSyncRead() == COMM_RX_CORRUPT  # the chain is cut short
    emu.inject(Fault.WRONG_ID, motor_id=3)
    assert reader.fastSyncRead() == COMM_RX_CORRUPT  # an unexpected ID in the chain
    assert reader.fastSyncRead() == COMM_SUCCESS


# -- timing -------------------------------------------------------------------------------


def best_round_trip(port: Any, call: Callable[[], object], ok: object, tries: int = 5) -> float:
    """The fastest of ``tries`` calls that returned ``ok`` (s). Each starts on a quiet,
    flushed port, so a late reply to an earlier call cannot pass for a fast one."""
    best = float("inf")
    for _ in range(tries):
        time.sleep(0.02)
        port.clearPort()
        start = time.perf_counter()
        result = call()
        elapsed = time.perf_counter() - start
        if result == ok:
            best = min(best, elapsed)
    assert best < float("inf"), "no call succeeded"
    return best


def test_round_trips_include_wire_time(emulator: Emulator, sdk_port: Port, ph: Any) -> None:
    # The SDK's sync-read timeout leaves out the instruction's own wire time and the
    # return delays: at 57600 baud it relies on its latency allowance.
    emu = emulator((1, 2, 3, 4), wire_time=True, return_delay=True)
    port = sdk_port(emu)
    ping = best_round_trip(port, lambda: ph.ping(port, 1), (1020, COMM_SUCCESS, 0))
    assert ping >= (10 + 14) * 10 / 57_600 + 500e-6
    reader = GroupSyncRead(port, ph, PRESENT, 4)
    for i in (1, 2, 3, 4):
        reader.addParam(i)
    sync = best_round_trip(port, reader.txRxPacket, COMM_SUCCESS, tries=3)
    assert sync >= (18 + 4 * 15) * 10 / 57_600 + 4 * 500e-6


# -- the command line ---------------------------------------------------------------------


def start_cli(*args: str) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-m", "sim.dynamixel.emulator", *args],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def test_cli_serves_until_interrupted(latency_timer: int, ph: Any) -> None:
    with start_cli("--ids", "1,2,3,4", "--baud", "1000000", "--no-wire-time") as proc:
        assert proc.stdout is not None and proc.stderr is not None
        ready, _, _ = select.select([proc.stdout], [], [], 10)
        assert ready, "the emulator printed nothing"
        line = proc.stdout.readline()
        match = re.fullmatch(r"serving 4 motors on (\S+) at 1000000 baud; Ctrl-C to stop\n", line)
        assert match, line
        port = sdk.PortHandler(match.group(1))
        try:
            assert port.openPort() and port.setBaudRate(1_000_000)
            assert [ph.ping(port, i)[:2] for i in (1, 4)] == [(1020, COMM_SUCCESS)] * 2
        finally:
            port.closePort()
        proc.send_signal(signal.SIGINT)
        assert proc.wait(timeout=5) == 0
        assert proc.stderr.read() == ""


@pytest.mark.parametrize(
    "args",
    [("--ids", "1,x"), ("--ids", "1,1"), ("--ids", "300"), ("--baud", "12345"), ("--speedup", "0")],
)
def test_cli_bad_arguments_give_one_line_and_status_2(
    args: tuple[str, ...], capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """Argument parsing alone, in-process (the real process is proven above and below)."""

    def serve(*args: object, **kwargs: object) -> None:
        raise AssertionError("bad arguments were accepted")

    monkeypatch.setattr(emulator_module, "DxlEmulator", serve)
    sigterm = signal.getsignal(signal.SIGTERM)
    try:
        with pytest.raises(SystemExit) as info:
            emulator_module.main(list(args))
    finally:
        signal.signal(signal.SIGTERM, sigterm)
    out, err = capsys.readouterr()
    assert info.value.code == 2
    assert out == ""
    assert len(err.splitlines()) == 1, err
    assert err.startswith("python -m sim.dynamixel.emulator: error:")


def test_cli_exits_cleanly_on_sigterm() -> None:
    with start_cli("--ids", "1") as proc:
        assert proc.stdout is not None
        select.select([proc.stdout], [], [], 10)
        assert proc.stdout.readline().startswith("serving 1 motors on /dev/")
        os.kill(proc.pid, signal.SIGTERM)
        assert proc.wait(timeout=5) == 0


def test_the_cli_stops_on_sigint_even_when_started_with_it_ignored() -> None:
    """Started with ``&`` from a non-interactive shell, a program inherits SIGINT
    ignored, and Python then installs no KeyboardInterrupt handler; the emulator's CLI
    restores it, so SIGINT still stops it."""
    command = f"trap '' INT; exec {sys.executable} -m sim.dynamixel.emulator --ids 1"
    with subprocess.Popen(
        ["sh", "-c", command],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    ) as proc:
        try:
            assert proc.stdout is not None
            select.select([proc.stdout], [], [], 10)
            assert proc.stdout.readline().startswith("serving 1 motors on /dev/")
            proc.send_signal(signal.SIGINT)
            assert proc.wait(timeout=3) == 0
        finally:
            proc.kill()
