"""`DynamixelLink` and `DynamixelBus` end to end: the unmodified SDK over a real pty
against the byte-level emulator. No hardware, no mocks of the SDK."""

from __future__ import annotations

import _thread
import math
import re
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import dynamixel_sdk as sdk
import pytest

from drivers.dynamixel import wire
from drivers.dynamixel.axis import AxisConfig
from drivers.dynamixel.bus import DynamixelBus
from drivers.dynamixel.control_table import RAD_PER_TICK
from drivers.dynamixel.latency import sdk_latency_timer
from drivers.dynamixel.link import DynamixelLink
from drivers.errors import CommError, DriverError, LimitError, MotionTimeout, MotorFault
from sim.peers.dynamixel.emulator import DxlEmulator
from sim.peers.dynamixel.faults import Fault
from tests.support.dynamixel import axes

Emulator = Callable[..., DxlEmulator]
ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture
def bus_on(
    emulator: Emulator, latency_timer: int
) -> Callable[..., tuple[DxlEmulator, DynamixelBus]]:
    """Factory: an emulator of len(axes) motors running on real time, and a bus on it."""

    def make(
        config: list[AxisConfig] | None = None, **bus_kw: object
    ) -> tuple[DxlEmulator, DynamixelBus]:
        config = config or axes()
        emu = emulator(ids=tuple(a.motor_id for a in config), clock=time.monotonic)
        bus_kw.setdefault("latency_ms", latency_timer)
        return emu, DynamixelBus(emu.path, config, **bus_kw)  # type: ignore[arg-type]

    return make


# -- the link --------------------------------------------------------------------------


def test_link_pings_reads_writes_and_scans(emulator: Emulator, latency_timer: int) -> None:
    emu = emulator(ids=(1, 2, 7))
    with DynamixelLink(emu.path, latency_ms=latency_timer) as link:
        assert link.ping(7) == 1020
        assert link.read(2, "present_temperature") == 30
        link.write(2, "led", 1)
        assert emu.motors[2].get("led") == 1
        emu.motors[1].set("present_position", -5)
        assert link.read(1, "present_position") == -5  # signed from the SDK's unsigned
        assert set(link.scan()) == {1, 2, 7}


def test_link_refuses_out_of_range_values_before_sending(emulator: Emulator) -> None:
    emu = emulator()
    with DynamixelLink(emu.path) as link:
        before = emu.stats.packets_in
        with pytest.raises(LimitError, match="outside the range"):
            link.write(1, "operating_mode", 300)
        with pytest.raises(LimitError, match="operating_mode = 2"):  # a gap in the modes
            link.write(1, "operating_mode", 2)
        with pytest.raises(DriverError, match="read-only"):
            link.write(1, "present_position", 0)
        assert emu.stats.packets_in == before


def test_link_reports_a_status_error_in_words(emulator: Emulator) -> None:
    emu = emulator()
    with DynamixelLink(emu.path) as link:
        emu.motors[1].set("torque_enable", 1)  # torque on behind the link's back
        with pytest.raises(
            DriverError, match=r"motor 1 refused writing operating_mode = 4: access error"
        ):
            link.write(1, "operating_mode", 4)  # EEPROM with torque on


@pytest.mark.parametrize("fault", [Fault.NO_REPLY, Fault.CORRUPT_CRC, Fault.GARBAGE])
def test_link_retries_then_succeeds(emulator: Emulator, fault: Fault) -> None:
    emu = emulator()
    emu.inject(fault, motor_id=1, count=2)
    with DynamixelLink(emu.path, retries=3) as link:
        assert link.read(1, "present_temperature") == 30


@pytest.mark.parametrize(
    ("fault", "result"),
    [
        (Fault.NO_REPLY, sdk.COMM_RX_TIMEOUT),
        (Fault.CORRUPT_CRC, sdk.COMM_RX_CORRUPT),
        # A status from another ID is not the answer (the SDK alone would skip it and
        # then time out).
        (Fault.WRONG_ID, sdk.COMM_RX_CORRUPT),
    ],
)
def test_link_gives_up_with_a_comm_error_naming_port_motor_and_result(
    emulator: Emulator, fault: Fault, result: int
) -> None:
    emu = emulator(ids=(1, 4))
    emu.inject(fault, motor_id=4, count=None)
    link = DynamixelLink(emu.path, retries=2, names={4: "detector"})
    with link, pytest.raises(CommError) as err:
        link.read(4, "present_position")
    message = str(err.value)
    assert emu.path in message
    assert "motor 4 (axis 'detector')" in message
    assert "after 3 attempts" in message
    assert f"(SDK result {result})" in message
    assert err.value.result == result
    assert err.value.motor_id == 4


def test_link_turns_the_alert_bit_into_a_named_motor_fault(emulator: Emulator) -> None:
    emu = emulator(ids=(1, 2))
    emu.inject(Fault.OVERLOAD, motor_id=2)
    emu.inject(Fault.OVERHEATING, motor_id=2)
    with DynamixelLink(emu.path, names={2: "light"}) as link:
        with pytest.raises(MotorFault) as err:
            link.read(2, "present_position")
        assert err.value.flags == ("overheating", "overload")
        assert err.value.motor_id == 2
        assert err.value.axis == "light"
        assert "motor 2 (axis 'light') reports a hardware error: overheating, overload" in str(
            err.value
        )
        with pytest.raises(MotorFault):
            link.sync_read([1, 2], "moving", "present_position")
        link.reboot(2)
        assert link.hardware_error(2) == ()


def test_port_missing_and_busy_are_one_clear_error(emulator: Emulator) -> None:
    with pytest.raises(CommError, match="/dev/does-not-exist does not exist"):
        DynamixelLink("/dev/does-not-exist").open()
    emu = emulator()
    with DynamixelLink(emu.path), pytest.raises(CommError, match="is busy"):
        DynamixelLink(emu.path).open()
    with DynamixelLink(emu.path) as link:  # released: opens at once
        assert link.ping(1) == 1020


def test_unsupported_baud_is_refused(emulator: Emulator) -> None:
    emu = emulator()
    with pytest.raises(CommError, match="12345 is not one"):
        DynamixelLink(emu.path, 12345).open()


def test_baud_mismatch_is_a_timeout_not_a_hang(emulator: Emulator, latency_timer: int) -> None:
    emu = emulator(baud=1_000_000)
    with DynamixelLink(emu.path, 57_600, retries=0, latency_ms=latency_timer) as link:
        started = time.monotonic()
        with pytest.raises(CommError, match=r"There is no status packet"):
            link.ping(1)
        waited = time.monotonic() - started
        # The reply timeout is the behaviour: at least 2 × the latency timer (the SDK's
        # formula), at most 3 × that + 1 s (only a guard: a busy machine adds time).
        timeout = 2 * link.latency_timer_ms / 1000
        assert timeout <= waited <= 3 * timeout + 1.0
    with DynamixelLink(emu.path, 1_000_000) as link:
        assert link.ping(1) == 1020


# -- the bus ---------------------------------------------------------------------------


def test_open_configures_and_holds_without_a_jump(
    bus_on: Callable[..., tuple[DxlEmulator, DynamixelBus]],
) -> None:
    emu, bus = bus_on()
    for m in emu.motors.values():
        m.set("goal_position", 100)  # a stale goal that torque-on must not chase
    with bus:
        bus.positions()  # a read: the emulator has served the (unanswered) sync writes
        for m in emu.motors.values():
            assert m.get("torque_enable") == 1
            assert m.get("goal_position") == m.get("present_position") == 2048
            assert m.get("operating_mode") == 3
            low, high = axes()[0].tick_limits()
            assert (m.get("min_position_limit"), m.get("max_position_limit")) == (low, high)
            assert m.get("profile_velocity") == axes()[0].profile_registers()[0]
        assert bus.models == dict.fromkeys(bus.axes, "XM430-W350")


def test_eeprom_is_written_only_when_it_differs(
    bus_on: Callable[..., tuple[DxlEmulator, DynamixelBus]],
) -> None:
    emu, bus = bus_on()
    with bus:
        pass
    emu.reset_stats()
    with DynamixelBus(emu.path, axes(), latency_ms=16):
        pass
    writes = emu.stats.instructions.get("WRITE", 0)
    assert writes == 0  # second open: operating mode, drive mode, limits already right


def test_move_settle_and_read_back(bus_on: Callable[..., tuple[DxlEmulator, DynamixelBus]]) -> None:
    emu, bus = bus_on()
    targets = {"axis1": 0.3, "axis2": -0.25, "axis3": 0.0}
    with bus:
        bus.positions()  # a read: everything open sent has been served
        emu.reset_stats()
        bus.move_to(targets)
        bus.wait_settled(timeout_s=3.0)
        got = bus.positions()
        assert emu.stats.instructions.get("SYNC_WRITE") == 1  # all goals in one packet
    for name, target in targets.items():
        assert abs(got[name] - target) <= 0.5 * RAD_PER_TICK + 1e-12
    assert emu.stats.instructions.get("SYNC_READ", 0) >= 1


def test_a_hold_step_sends_what_the_step_budget_counts(
    bus_on: Callable[..., tuple[DxlEmulator, DynamixelBus]],
) -> None:
    """A step that does not move (goal = present position): one SYNC_WRITE of the goals,
    the poll that finds the axes settled and the read back, byte for byte what
    `wire.step_seconds` times for a step without motion."""
    emu, bus = bus_on()
    with bus:
        here = bus.positions()  # a read: everything open sent has been served
        emu.reset_stats()
        bus.move_to(here)
        bus.wait_settled(timeout_s=3.0)
        bus.positions()
        stats = emu.stats
    motors, baud = 3, 57_600
    assert stats.instructions == {"SYNC_WRITE": 1, "SYNC_READ": 2}
    assert stats.bytes_in == wire.sync_write_bytes(motors, wire.GOAL_BYTES) + 2 * (
        wire.sync_read_bytes(motors)
    )
    assert stats.bytes_out == 2 * motors * wire.status_bytes(wire.STATE_BYTES)
    on_the_line = (stats.bytes_in + stats.bytes_out) * wire.BITS_PER_BYTE / baud
    delays = stats.packets_out * wire.DEFAULT_RETURN_DELAY_S
    assert wire.step_seconds(motors, baud, 0.0) == pytest.approx(on_the_line + delays, rel=1e-12)


def test_targets_outside_limits_are_refused_before_any_byte(
    bus_on: Callable[..., tuple[DxlEmulator, DynamixelBus]],
) -> None:
    emu, bus = bus_on()
    with bus:
        bus.positions()  # a read: everything open sent has been served
        before = emu.stats.packets_in
        for bad in (1.0001, -2.0, math.nan, math.inf):
            with pytest.raises(LimitError, match="nothing was sent"):
                bus.move_to({"axis1": 0.0, "axis2": bad})
        with pytest.raises(DriverError, match="unknown axis 'elbow'"):
            bus.move_to({"elbow": 0.0})
        assert emu.stats.packets_in == before


def test_extended_position_mode_reaches_negative_positions(
    bus_on: Callable[..., tuple[DxlEmulator, DynamixelBus]],
) -> None:
    config = axes(1, mode="extended_position", zero_offset_rad=0.0, min_rad=-8.0, max_rad=8.0,
                  profile_velocity_rad_s=4.5, profile_acceleration_rad_s2=60.0)  # fmt: skip
    emu, bus = bus_on(config)
    with bus:
        assert emu.motors[1].get("operating_mode") == 4
        bus.move_to({"axis1": -0.4})
        bus.wait_settled(3.0)
        assert emu.motors[1].get("present_position") < 0
        assert bus.positions()["axis1"] == pytest.approx(-0.4, abs=RAD_PER_TICK)


def test_gear_ratio_and_direction_reach_the_motor(
    bus_on: Callable[..., tuple[DxlEmulator, DynamixelBus]],
) -> None:
    config = axes(1, gear_ratio=2.0, direction=-1, zero_offset_rad=2.5, min_rad=1.0, max_rad=2.0)
    emu, bus = bus_on(config)
    with bus:
        bus.move_to({"axis1": 1.7})
        bus.wait_settled(3.0)
        expected_ticks = round(-1 * (1.7 - 2.5) * 2.0 / RAD_PER_TICK)
        assert emu.motors[1].get("present_position") == expected_ticks
        assert bus.positions()["axis1"] == pytest.approx(1.7, abs=RAD_PER_TICK / 2)


def test_stop_holds_mid_motion(bus_on: Callable[..., tuple[DxlEmulator, DynamixelBus]]) -> None:
    """stop() mid-move: the axis brakes, comes back to where it was told to hold, and
    stays there, well short of the target."""
    config = axes(1, profile_velocity_rad_s=0.5, profile_acceleration_rad_s2=5.0)
    _, bus = bus_on(config)
    with bus:
        bus.move_to({"axis1": 0.9})
        deadline = time.monotonic() + 2.0
        while bus.positions()["axis1"] < 0.05 and time.monotonic() < deadline:
            time.sleep(0.01)
        bus.stop()
        bus.wait_settled(2.0)
        held = bus.positions()["axis1"]
        assert 0.04 < held < 0.6
        time.sleep(0.05)
        assert bus.positions()["axis1"] == pytest.approx(held, abs=RAD_PER_TICK)


def test_settle_timeout_holds_and_names_the_axis(
    bus_on: Callable[..., tuple[DxlEmulator, DynamixelBus]],
) -> None:
    config = axes(2, profile_velocity_rad_s=0.2, profile_acceleration_rad_s2=1.0)
    emu, bus = bus_on(config)
    with bus:
        bus.move_to({"axis2": 0.8})
        with pytest.raises(MotionTimeout, match=r"within 0.1 s \(axis2 moving"):
            bus.wait_settled(0.1)
        bus.positions()  # a read: the emulator has served the hold (an unanswered sync write)
        goal = emu.motors[2].get("goal_position")
        assert abs(goal - emu.motors[2].get("present_position")) < 40  # told to hold


def test_motor_fault_during_motion_names_motor_and_axis_and_releases(
    bus_on: Callable[..., tuple[DxlEmulator, DynamixelBus]],
) -> None:
    emu, bus = bus_on()
    with pytest.raises(MotorFault) as err, bus:  # noqa: PT012 (the fault comes mid-sequence)
        bus.move_to({"axis3": 0.5})
        emu.inject(Fault.OVERLOAD, motor_id=3)
        bus.wait_settled(3.0)
    assert err.value.axis == "axis3"
    assert err.value.flags == ("overload",)
    assert emu.motors[3].get("torque_enable") == 0  # overload is in the Shutdown mask
    with DynamixelLink(emu.path) as link:  # the port was released
        link.reboot(3)


def test_open_refuses_a_faulted_or_missing_motor(
    bus_on: Callable[..., tuple[DxlEmulator, DynamixelBus]],
) -> None:
    emu, bus = bus_on()
    emu.inject(Fault.INPUT_VOLTAGE, motor_id=2)
    with pytest.raises(MotorFault, match=r"motor 2 .*axis2.*input_voltage"):
        bus.open()
    emu.clear_faults(alerts=True)
    spare = AxisConfig("spare", 9, -1.0, 1.0, zero_offset_rad=-math.pi)
    missing = DynamixelBus(emu.path, [*axes(), spare], latency_ms=16, retries=1)
    with pytest.raises(CommError, match="motor 9 \\(axis 'spare'\\)"):
        missing.open()
    with bus:  # nothing was left open
        pass


def test_health_reports_without_raising(
    bus_on: Callable[..., tuple[DxlEmulator, DynamixelBus]],
) -> None:
    emu, bus = bus_on()
    with bus:
        emu.motors[1].set("present_temperature", 61)
        emu.inject(Fault.OVERHEATING, motor_id=1)
        health = bus.health()
        assert health["axis1"].temperature_c == 61
        assert health["axis1"].error_flags == ("overheating",)
        assert not health["axis1"].ok
        assert health["axis2"].voltage_v == pytest.approx(12.0)
        assert health["axis2"].ok
        with pytest.raises(MotorFault, match="axis1"):
            bus.check()
        emu.clear_faults(alerts=True)


def test_transient_noise_is_retried_transparently(
    bus_on: Callable[..., tuple[DxlEmulator, DynamixelBus]],
) -> None:
    emu, bus = bus_on()
    with bus:
        emu.inject(Fault.CORRUPT_CRC, motor_id=2, count=2)
        emu.inject(Fault.NO_REPLY, motor_id=3, count=1)
        assert set(bus.positions()) == set(bus.axes)


def test_silent_bus_is_a_comm_error_after_bounded_retries(
    bus_on: Callable[..., tuple[DxlEmulator, DynamixelBus]],
) -> None:
    """The failed poll is tried 1 + retries times; then the bus tries to hold the axes,
    as the contract asks, which fails too and says so in a note."""
    emu, bus = bus_on(retries=2)
    with bus:
        emu.inject(Fault.SILENT)
        with pytest.raises(CommError, match=r"after 3 attempts.*no answer from motor 1") as info:
            bus.positions()
        assert "and holding the axes: could not hold axis1, axis2, axis3" in "".join(
            getattr(info.value, "__notes__", [])
        )
        emu.clear_faults()


def test_ctrl_c_mid_transaction_releases_the_port(
    bus_on: Callable[..., tuple[DxlEmulator, DynamixelBus]],
) -> None:
    """KeyboardInterrupt inside the SDK's wait for a reply: the SDK's busy flag would
    stay set ("port is in use"); the bus must release the port and hold the motors."""
    emu, bus = bus_on()
    with pytest.raises(KeyboardInterrupt), bus:  # noqa: PT012 (interrupted mid-sequence)
        bus.move_to({"axis1": 0.2})
        emu.inject(Fault.NO_REPLY, motor_id=1, count=None)  # the next read waits for a timeout
        threading.Timer(0.01, _thread.interrupt_main).start()
        bus.positions()
    emu.clear_faults()
    with DynamixelBus(emu.path, axes(), latency_ms=16) as second:  # opens at once
        assert set(second.positions()) == set(second.axes)


@pytest.fixture
def emulator_process() -> Iterator[str]:
    """A real-time emulator (wire time and return delays on) in its own process, so that
    its timing does not share a GIL with the SDK's busy-waiting reads."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "sim.dynamixel.emulator", "--ids", "1-4", "--baud", "57600"],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert proc.stdout is not None
        line = proc.stdout.readline()
        path = re.search(r"on (\S+) at", line)
        assert path, line
        yield path.group(1)
    finally:
        proc.send_signal(signal.SIGINT)
        proc.communicate(timeout=10)


def test_reply_timeout_covers_a_goal_write_still_on_the_wire(
    emulator_process: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """With real wire time at 57 600 baud and no USB latency, the SDK's reply timeout
    (2 × LATENCY_TIMER + 2 ms + the replies' bytes) leaves out the instruction's own wire
    time, the motors' return delays and a SYNC_WRITE of goals still on the line before
    the next SYNC_READ: a 4-motor poll needs 22 ms against a 21.4 ms budget (28 ms after
    a goal write). The link's margin covers it; with the margin removed the polls time
    out. On an idle machine every one does; a host descheduled past the deadline finds the
    late reply already waiting (on a 2-core machine with three busy processes, about
    half the polls got through within three retries), so the check counts single
    attempts."""
    config = axes(4)
    # Real time on a shared machine: the driver's own retries cover an emulator process
    # descheduled past a deadline (a loaded CI host starved it twice in a row).
    with DynamixelBus(emulator_process, config, latency_ms=0.0) as bus:
        here = bus.positions()
        for _ in range(5):
            bus.move_to(here)
            bus.positions()
    monkeypatch.setattr("drivers.dynamixel.latency.OUTBOUND_MARGIN_BYTES", 0)
    ids = [axis.motor_id for axis in config]
    attempts, failed = 20, 0
    with DynamixelLink(emulator_process, 57_600, latency_ms=0.0, retries=0) as link:
        for _ in range(attempts):
            link.sync_write("goal_position", dict.fromkeys(ids, 2048))
            try:
                link.sync_read(ids, "moving", "present_position")
            except CommError:
                failed += 1
    assert failed >= attempts // 2, f"only {failed} of {attempts} polls timed out"


@pytest.mark.parametrize("baud", [57_600, 115_200, 1_000_000, 4_000_000])
def test_latency_margin_covers_the_worst_exchange_on_paper(baud: int) -> None:
    """The budget the SDK allows for a 4-motor SYNC_READ right after a 4-motor SYNC_WRITE
    of goals, with the link's LATENCY_TIMER, exceeds what the exchange needs on the wire
    (instructions + 4 × (return delay + reply)) for any adapter latency."""
    byte_ms = 10_000 / baud
    needed = (34 + 18) * byte_ms + 4 * (0.5 + 25 * byte_ms)
    for adapter_ms in (0.0, 1.0, 16.0):
        timer = sdk_latency_timer(adapter_ms, baud)
        budget = 100 * byte_ms + 2 * timer + 2.0 - 2 * adapter_ms  # what is left for the line
        assert budget > needed, (adapter_ms, budget, needed)
